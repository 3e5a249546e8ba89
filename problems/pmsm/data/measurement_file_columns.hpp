#pragma once
// The variables of a binary measurement file (MAT, HDF5) as the format readers hand them to the
// measurement reader, which maps them onto mhbench's columns (problems/pmsm/data/measurement.cpp).
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace mhb::pmsm {

// A column of text with each distinct text held once: a segment column repeats a few labels over a
// million rows, where a string a row would cost more than all the numeric columns together.
struct TextColumn {
    std::vector<std::string> texts;  // the distinct texts, in order of first appearance
    Eigen::VectorXi rows;            // each row's text, as an index into texts
    std::map<std::string, int, std::less<>> index;

    // The index of `text` in texts, where it is added when new.
    int index_of(std::string_view text) {
        auto it = index.find(text);
        if (it == index.end()) {
            it = index.emplace(std::string(text), static_cast<int>(texts.size())).first;
            texts.emplace_back(text);
        }
        return it->second;
    }
};

struct FileColumn {
    std::string name;
    Eigen::VectorXd numbers;  // Eigen's, so that the measurement takes it over without a copy
    std::optional<TextColumn> labels;  // text (a cell array of strings, a char matrix, a string dataset)
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

// Shared by the CSV reader, the CSV writer and the mapping of binary files' columns (measurement.cpp).
// A CSV field as the reader takes it: without surrounding blanks, a quoted field as its content.
std::string_view csv_field_text(std::string_view s);
struct Measurement;
class UnitConversion;
// The vector that holds mhbench's numeric column `name` in `m`, created for an optional column.
Eigen::VectorXd* numeric_column(Measurement& m, const std::string& name);
// A value converted to mhbench's unit, refused when the conversion leaves the range of a double.
double converted(const UnitConversion& conversion, double value, const std::string& source, long line,
                 const std::string& field, const std::string& row);

}  // namespace mhb::pmsm
