#include "problems/pmsm/data/column_map.hpp"

#include <algorithm>
#include <numbers>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "framework/closest_name.hpp"
#include "framework/input_error.hpp"
#include "problems/pmsm/data/measurement.hpp"
#include "problems/pmsm/data/text_file.hpp"

namespace mhb::pmsm {
namespace {

// A pole-pair count beyond this is a typo: the largest direct-drive machines have a few hundred.
constexpr int max_pole_pairs = 1000;

struct UnitChoice {
    const char* unit;
    double divisor, multiplier, offset;
};

struct ColumnUnits {
    const char* own;
    std::vector<UnitChoice> others;
};

// Units each column may be logged in besides mhbench's own. rpm's multiplier is per pole pair.
const std::map<std::string, ColumnUnits, std::less<>>& units_by_column() {
    static const std::map<std::string, ColumnUnits, std::less<>> table{
        {"i_d", {"A", {{"mA", 1000.0, 1.0, 0.0}}}},
        {"i_q", {"A", {{"mA", 1000.0, 1.0, 0.0}}}},
        {"u_d", {"V", {{"mV", 1000.0, 1.0, 0.0}}}},
        {"u_q", {"V", {{"mV", 1000.0, 1.0, 0.0}}}},
        {"omega_e", {"rad/s", {{"rpm", 1.0, std::numbers::pi / 30.0, 0.0}}}},
        {"theta_e", {"rad", {{"deg", 1.0, std::numbers::pi / 180.0, 0.0}}}},
        {"theta_m", {"rad", {{"deg", 1.0, std::numbers::pi / 180.0, 0.0}}}},
        {"temp_winding", {"degC", {{"K", 1.0, 1.0, -273.15}}}},
        {"temp_magnet", {"degC", {{"K", 1.0, 1.0, -273.15}}}},
        {"t", {"s", {{"ms", 1000.0, 1.0, 0.0}, {"us", 1e6, 1.0, 0.0}}}},
        {"segment", {"", {}}},
    };
    return table;
}

std::vector<std::string> mhbench_columns() {
    std::vector<std::string> names(std::begin(required_columns), std::end(required_columns));
    names.insert(names.end(), std::begin(optional_columns), std::end(optional_columns));
    return names;
}

std::string accepted_units(const ColumnUnits& units) {
    if (!*units.own) return "it takes no unit";
    std::string out = fmt::format("accepted: {} (mhbench's own)", units.own);
    for (const auto& u : units.others) out += fmt::format(", {}", u.unit);
    return out;
}

std::string_view trimmed(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
    return s;
}

// One "NAME=SOURCE[UNIT]" entry into `map`; `where` names it in messages.
void add_entry(ColumnMap& map, std::string_view entry, const std::string& origin, long line, const std::string& where) {
    entry = trimmed(entry);
    if (entry.empty()) throw InputError(origin, line, where, "empty entry; expected NAME=SOURCE, NAME=SOURCE[UNIT] or NAME[UNIT]");
    std::string unit;
    if (entry.back() == ']') {
        const auto open = entry.rfind('[');
        if (open == std::string_view::npos)
            throw InputError(origin, line, where, fmt::format("'{}': a ']' without '['; a unit is written as SOURCE[UNIT]", entry));
        unit = std::string(trimmed(entry.substr(open + 1, entry.size() - open - 2)));
        if (unit.empty()) throw InputError(origin, line, where, fmt::format("'{}': empty unit in '[]'", entry));
        entry = trimmed(entry.substr(0, open));
    }
    std::string column, source;
    if (const auto eq = entry.find('='); eq != std::string_view::npos) {
        column = std::string(trimmed(entry.substr(0, eq)));
        source = std::string(trimmed(entry.substr(eq + 1)));
        if (source.empty()) throw InputError(origin, line, where, fmt::format("'{}': no source name after '='", column));
    } else {
        column = std::string(entry);
        source = column;
    }
    const auto& table = units_by_column();
    const auto units = table.find(column);
    if (units == table.end()) {
        auto message = unknown_name_message("mhbench column", column, mhbench_columns());
        throw InputError(origin, line, where, message);
    }
    if (!unit.empty() && unit != units->second.own &&
        std::none_of(units->second.others.begin(), units->second.others.end(), [&](const UnitChoice& u) { return unit == u.unit; }))
        throw InputError(origin, line, where, fmt::format("{}: unknown unit '{}' ({})", column, unit, accepted_units(units->second)));
    if (map.columns.count(column)) throw InputError(origin, line, where, fmt::format("{} is mapped twice", column));
    map.columns[column] = {source, unit == units->second.own ? std::string() : unit};
    map.origin[column] = line > 0 ? fmt::format("{}:{}", origin, line) : where;
}

void check_column_map(const ColumnMap& map) {
    std::map<std::string, std::string> column_of_source;
    for (const auto& [column, source] : map.columns) {
        if (auto [it, fresh] = column_of_source.emplace(source.name, column); !fresh)
            throw InputError(map.origin.at(column), 0, column,
                             fmt::format("'{}' is already the source of {}; each file column feeds one mhbench column",
                                         source.name, it->second));
        if (source.unit == "rpm" && !map.pole_pairs)
            throw InputError(map.origin.at(column), 0, column,
                             "rpm is converted to electrical rad/s with the pole-pair count: give --pole-pairs N "
                             "(or pole_pairs = N in the columns file or among the problem's parameters)");
    }
}

}  // namespace

ColumnMap parse_column_map(std::string_view text, const std::string& origin, const std::string& option) {
    ColumnMap map;
    for (std::size_t start = 0;;) {
        const auto comma = text.find(',', start);
        add_entry(map, text.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start), origin, 0, option);
        if (comma == std::string_view::npos) break;
        start = comma + 1;
    }
    return map;
}

ColumnMap read_column_map_file(const std::filesystem::path& path) {
    const std::string file = path.string();
    const std::string text = read_text_file(path, "columns file", 1 << 20);
    toml::table root;
    try {
        root = toml::parse(text, file);
    } catch (const toml::parse_error& e) {
        throw InputError(file, static_cast<long>(e.source().begin.line), "", std::string(e.description()));
    }
    ColumnMap map;
    for (const auto& [key, node] : root) {
        const long line = static_cast<long>(node.source().begin.line);
        const std::string name(key.str());
        if (name == "pole_pairs") {
            const auto value = node.value<std::int64_t>();
            if (!node.is_integer() || !value || *value < 1 || *value > max_pole_pairs)
                throw InputError(file, line, name, fmt::format("expects a whole number in [1, {}]", max_pole_pairs));
            map.pole_pairs = static_cast<int>(*value);
        } else if (name == "columns") {
            const auto* columns = node.as_table();
            if (!columns) throw InputError(file, line, name, "expects a table: [columns] with lines such as i_d = \"Id_meas[mA]\"");
            for (const auto& [column_key, value] : *columns) {
                const std::string column(column_key.str());
                const long value_line = static_cast<long>(value.source().begin.line);
                const auto source = value.value<std::string>();
                if (!value.is_string())
                    throw InputError(file, value_line, "columns." + column, "expects a string such as \"Id_meas\", \"Id_meas[mA]\" or \"[mA]\"");
                const std::string entry = !source->empty() && source->front() == '[' ? column + *source : column + "=" + *source;
                add_entry(map, entry, file, value_line, "columns." + column);
            }
        } else {
            std::string message = unknown_name_message("key", name, {"columns", "pole_pairs"});
            throw InputError(file, line, name, message);
        }
    }
    check_column_map(map);
    return map;
}

ColumnMap merge_column_maps(ColumnMap base, const ColumnMap& overrides) {
    for (const auto& [column, source] : overrides.columns) {
        base.columns[column] = source;
        base.origin[column] = overrides.origin.at(column);
    }
    if (overrides.pole_pairs) base.pole_pairs = overrides.pole_pairs;
    return base;
}

ColumnMap column_map_from_options(const std::string& columns, const std::string& columns_file, int pole_pairs,
                                  const std::string& origin, const std::string& option) {
    ColumnMap map;
    if (!columns_file.empty()) map = read_column_map_file(columns_file);
    if (!columns.empty()) map = merge_column_maps(std::move(map), parse_column_map(columns, origin, option));
    if (pole_pairs > 0) map.pole_pairs = pole_pairs;
    check_column_map(map);
    return map;
}

std::vector<std::string> bind_columns(const std::vector<std::string>& present, const ColumnMap& map,
                                      const std::string& source, long line, const std::string& kind,
                                      const std::string& hint) {
    check_column_map(map);
    auto listing = [&] {
        std::string out;
        for (const auto& name : present) out += (out.empty() ? "" : ", ") + printable_field(name);
        return out;
    };
    auto suggestion = [&](const std::string& wanted) {
        const auto near = closest_name(wanted, present);
        return near.empty() ? std::string() : fmt::format("; did you mean '{}'?", near);
    };
    std::map<std::string, std::string> column_of_source;
    for (const auto& [column, from] : map.columns) column_of_source[from.name] = column;
    std::vector<std::string> bound(present.size());
    for (std::size_t k = 0; k < present.size(); ++k) {
        if (auto it = column_of_source.find(present[k]); it != column_of_source.end()) bound[k] = it->second;
        else if (!map.columns.count(present[k]) && units_by_column().count(present[k])) bound[k] = present[k];
    }
    for (const auto& [column, from] : map.columns)
        if (std::find(present.begin(), present.end(), from.name) == present.end())
            throw InputError(source, line, from.name,
                             fmt::format("no such {} (mapped to {} by {}){}; the file has: {}", kind, column,
                                         map.origin.at(column), suggestion(from.name), listing()));
    for (const char* column : required_columns)
        if (std::find(bound.begin(), bound.end(), column) == bound.end()) {
            const bool taken = column_of_source.count(column) > 0;
            throw InputError(source, line, column,
                             fmt::format("missing required {} ({}the file has: {}){}{}; map the file's own name with "
                                         "--columns {}=NAME",
                                         kind, taken ? fmt::format("its name is mapped to {}; ", column_of_source.at(column)) : "",
                                         listing(), suggestion(column), hint, column));
        }
    return bound;
}

UnitConversion unit_conversion(const ColumnMap& map, const std::string& column) {
    const auto it = map.columns.find(column);
    if (it == map.columns.end() || it->second.unit.empty()) return {};
    const auto& unit = it->second.unit;
    for (const auto& u : units_by_column().at(column).others)
        if (unit == u.unit)
            return {unit, u.divisor, unit == "rpm" ? u.multiplier * map.pole_pairs.value_or(0) : u.multiplier, u.offset};
    throw InputError(map.origin.at(column), 0, column, fmt::format("unknown unit '{}'", unit));
}

}  // namespace mhb::pmsm
