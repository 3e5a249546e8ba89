#pragma once
// Which variable or column of a user's measurement file holds each of mhbench's signals, and in which
// unit it was logged, so that logs are read as they are, without editing them (docs/data-format.md,
// "Column map and units"). The same map applies to CSV, MAT and HDF5 files.
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace mhb::pmsm {

struct ColumnSource {
    std::string name;  // the variable or column in the file
    std::string unit;  // as the user wrote it; empty means mhbench's own unit
};

struct ColumnMap {
    std::map<std::string, ColumnSource> columns;  // keyed by mhbench's column name
    std::optional<int> pole_pairs;                // needed by rpm
    // Where the map came from, for messages: "--columns" or "map.toml:3".
    std::map<std::string, std::string> origin;

    bool empty() const { return columns.empty() && !pole_pairs; }
};

// Parses "i_d=Id_meas[mA],omega_e=speed[rpm],temp_winding[K]": NAME=SOURCE, NAME=SOURCE[UNIT] or
// NAME[UNIT] (the file's column has mhbench's name). Refusals name `origin` (e.g. "command line")
// and `option` (e.g. "--columns").
ColumnMap parse_column_map(std::string_view text, const std::string& origin, const std::string& option);

// A TOML file: `pole_pairs = 16` and a [columns] table whose values use the syntax above,
// e.g. `i_d = "Id_meas[mA]"`, `temp_winding = "[K]"`. Refusals name the file, the line and the key.
ColumnMap read_column_map_file(const std::filesystem::path& path);

// `base` with every column and the pole-pair count that `overrides` sets replaced.
ColumnMap merge_column_maps(ColumnMap base, const ColumnMap& overrides);

// The command-line options --columns, --columns-file and --pole-pairs combined; the map empty when
// none was given. The command line wins over the file per column. `origin` and `option` name where
// `columns` came from in refusals (an experiment's problem parameter, say).
ColumnMap column_map_from_options(const std::string& columns, const std::string& columns_file, int pole_pairs,
                                  const std::string& origin = "command line", const std::string& option = "--columns");

// For each name present in a file, the mhbench column it feeds, or "" when none. A column the map
// names is read from its source; any other column from the file's column of the same name, unless
// that name is taken as another column's source. Refused (naming `source`, `line` and the column):
// a mapped source that is absent, a required column that is absent; both messages list the names
// present and the closest one. `kind` is "column" or "variable"; `hint` is appended to the message
// about a missing required column.
std::vector<std::string> bind_columns(const std::vector<std::string>& present, const ColumnMap& map,
                                      const std::string& source, long line, const std::string& kind,
                                      const std::string& hint = "");

// How a column's values reach mhbench's unit. Identity when no unit, or mhbench's own, was given.
class UnitConversion {
public:
    UnitConversion() = default;
    UnitConversion(std::string unit, double divisor, double multiplier, double offset)
        : unit_(std::move(unit)), divisor_(divisor), multiplier_(multiplier), offset_(offset) {}

    bool identity() const { return unit_.empty(); }
    const std::string& unit() const { return unit_; }
    // Division first: a value in mA or ms is divided by a power of ten, so it is rounded once, to the
    // double nearest to the exact value in A or s.
    double operator()(double x) const { return identity() ? x : (x / divisor_) * multiplier_ + offset_; }

private:
    std::string unit_;
    double divisor_ = 1.0, multiplier_ = 1.0, offset_ = 0.0;
};

// The conversion for one mhbench column under `map` (validated when the map was parsed).
UnitConversion unit_conversion(const ColumnMap& map, const std::string& column);

// A name or field as it may appear in a message: bytes a terminal would act on are shown as \xNN, and
// a long text is cut, so that binary input never reaches the terminal raw. (Defined, with
// column_label, in measurement_file_columns.cpp, which the HDF5 reader's library compiles too.)
std::string printable_field(std::string_view field);

// "Id_meas (i_d)" when the file's name differs from mhbench's, else the name: the field messages name.
std::string column_label(const std::string& name_in_file, const std::string& column);

}  // namespace mhb::pmsm
