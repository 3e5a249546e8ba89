#pragma once
// The variables of a binary measurement file (MAT, HDF5) as the format readers hand them to the
// measurement reader, which maps them onto mhbench's columns (problems/pmsm/measurement.cpp).
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace mhb::pmsm {

struct FileColumn {
    std::string name;
    std::vector<double> numbers;
    std::optional<std::vector<std::string>> labels;  // text (a cell array of strings, a string dataset)
    // Why the variable cannot be a column (e.g. "a 3x4 matrix"); empty when it can. Refused only when
    // the variable is used, so that a file may carry other data beside the log.
    std::string unusable;
};

struct FileColumns {
    std::vector<FileColumn> columns;
    std::vector<std::string> notes;  // what the reader passed over (other structs, groups), as warnings
};

// A MAT file, v5 (with v7's compression) or v7.3, through matio. The columns are the top-level
// variables; when the file holds one struct and nothing else, that struct's fields.
FileColumns read_mat_columns(const std::filesystem::path& path);

// An HDF5 file through the HDF5 C++ API. The columns are the datasets at the root; when the root
// holds no dataset and exactly one group, that group's datasets.
FileColumns read_hdf5_columns(const std::filesystem::path& path);

}  // namespace mhb::pmsm
