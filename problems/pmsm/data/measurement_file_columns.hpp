#pragma once
// The variables of a binary measurement file (MAT, HDF5) as the format readers hand them to the
// measurement reader, which maps them onto mhbench's columns (problems/pmsm/data/measurement.cpp).
// A reader first lists every name the file holds, in one pass over the file's index, asks which of
// them feed mhbench's columns, checks what those declare (class, shape, rows, sizes) against the
// limits and the file's real size, and only then reads their data. Nothing else is read.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "problems/pmsm/data/column_map.hpp"
#include "problems/pmsm/data/measurement.hpp"

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

// For each name a file holds (in the file's order), the mhbench column it feeds, or "" for none:
// bind_columns under the user's column map, with its refusals of missing names.
using ColumnChoice = std::function<std::vector<std::string>(const std::vector<std::string>& names)>;

struct FileColumn {
    std::string name;    // the variable's name in the file (a struct's field, a group's dataset)
    std::string column;  // the mhbench column it feeds
    Eigen::VectorXd numbers;  // Eigen's, so that the measurement takes it over without a copy
    std::optional<TextColumn> labels;  // text (a cell array of strings, a char matrix, a string dataset)
};

struct FileColumns {
    std::vector<FileColumn> columns;  // the variables that feed a column, read, in the file's order
    std::vector<std::string> unused;  // the names of the others, never read
    std::vector<std::string> notes;   // what the reader passed over besides (other structs, groups, links)
};

// The longest label a segment column may hold, in bytes: a label names an operating point, and a
// longer one is damage (a length field gone wrong), not a name.
inline constexpr std::size_t max_label_bytes = 4096;
// The most variables (datasets, links) a binary file may list; a log has tens.
inline constexpr std::size_t max_file_variables = 1'000'000;

// The message field for a variable: "Id_meas (i_d)" when the file's name differs from the column's.
std::string variable_field(const std::string& name, const std::string& column);

// The row count every used variable must declare, checked before any of its data is read: at least
// one, at most max_measurement_rows, the same for all. Refusals name the file and the variable.
class DeclaredRows {
public:
    explicit DeclaredRows(std::string source) : source_(std::move(source)) {}
    void check(const std::string& field, std::uint64_t rows);

private:
    std::string source_, first_;
    std::uint64_t rows_ = 0;
};

// The rows of a MATLAB char matrix, stored column-major (`rows` × `width` characters), as UTF-8
// labels without the blanks MATLAB pads short rows with: 16-bit units are UTF-16, 8-bit ones bytes.
TextColumn char_matrix_labels(const std::uint16_t* units, std::size_t rows, std::size_t width);
TextColumn char_matrix_labels(const std::uint8_t* bytes, std::size_t rows, std::size_t width);

// A MAT v5 file (with v7's compression) through mhbench's own parser (mat_file_reader.cpp). The
// columns are the top-level variables; when the file holds one struct and nothing else, its fields.
FileColumns read_mat5_columns(const std::filesystem::path& path, const ColumnChoice& choose);

// How an HDF5 file's datasets are read: as HDF5 (numbers, strings), or as a MAT v7.3 file, which
// is HDF5 with MATLAB's classes in attributes (char as UTF-16, cell arrays as references).
enum class Hdf5Layout { plain, matlab };

// The reader of an HDF5 or MAT v7.3 file, through the HDF5 C library. The columns are the datasets
// at the root; when the root holds no dataset and exactly one group, that group's datasets. It is
// in libmhbench_hdf5.so (hdf5_file_reader.cpp), loaded by the first call (framework/optional_library.hpp),
// so that libhdf5 and the ~30 libraries it brings are loaded only by a command that reads such a
// file. Take it before a fork (read_in_child_process): the child then does not run the dynamic loader.
using Hdf5Reader = FileColumns (*)(const std::filesystem::path& path, const ColumnChoice& choose, Hdf5Layout layout);
Hdf5Reader hdf5_reader();

// `read` run in a child process, with at most 3 GB more address space than this process and
// `seconds` of wall time; its columns, or its refusal, come back through a pipe. A child ended by a
// signal (a fault inside `library`, named in the message) or by the time limit is a refusal of `file`.
FileColumns read_in_child_process(const std::string& file, const std::string& library, const std::function<FileColumns()>& read,
                                  unsigned seconds = 600);

// Where a binary file is parsed: libhdf5 (HDF5, MAT v7.3) in a child process by default, so that a
// fault inside it on a damaged file is a refusal; in this process for the fuzzers, which look for
// those faults and run thousands of inputs a second. MAT v5/v7 (mhbench's own parser) is always read
// in this process.
enum class Isolation { child_process, in_process };

// read_measurement for a file taken as `format` (Mat5, Mat73 or Hdf5) whatever its first bytes; the
// fuzzers drive each reader through it.
Measurement read_binary_measurement(const std::filesystem::path& path, MeasurementFormat format, const ColumnMap& map = {},
                                    Isolation isolation = Isolation::child_process);

// Shared by the CSV reader, the CSV writer and the mapping of binary files' columns (measurement.cpp).
// A CSV field as the reader takes it: without surrounding blanks, a quoted field as its content.
std::string_view csv_field_text(std::string_view s);
// The vector that holds mhbench's numeric column `name` in `m`, created for an optional column.
Eigen::VectorXd* numeric_column(Measurement& m, const std::string& name);
// A value converted to mhbench's unit, refused when the conversion leaves the range of a double.
double converted(const UnitConversion& conversion, double value, const std::string& source, long line,
                 const std::string& field, const std::string& row);

}  // namespace mhb::pmsm
