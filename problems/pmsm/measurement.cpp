#include "problems/pmsm/measurement.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <mutex>

#include <fmt/format.h>

#include "framework/input_error.hpp"
#include "problems/pmsm/column_map.hpp"
#include "problems/pmsm/measurement_file_columns.hpp"
#include "problems/pmsm/text_file.hpp"

namespace mhb::pmsm {
namespace {

std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
    // Spreadsheet exports quote fields; a quoted field is taken as its content (no embedded commas).
    if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = s.substr(1, s.size() - 2);
    return s;
}

std::vector<std::string_view> split_fields(std::string_view line) {
    std::vector<std::string_view> fields;
    std::size_t start = 0;
    while (true) {
        const std::size_t comma = line.find(',', start);
        fields.push_back(trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
        if (comma == std::string_view::npos) break;
        start = comma + 1;
    }
    return fields;
}

// What a header without the required columns most likely means, when the file uses another separator.
std::string separator_hint(std::string_view header_line) {
    if (header_line.find(';') != std::string_view::npos)
        return "; the header is separated by ';': mhbench reads comma-separated values with '.' as the decimal mark "
               "(export the CSV with ',' as separator and '.' as decimal point)";
    if (header_line.find('\t') != std::string_view::npos)
        return "; the header is separated by tabs: mhbench reads comma-separated values";
    return "";
}

bool is_blank(std::string_view line) {
    for (char c : line)
        if (c != ' ' && c != '\t' && c != '\r') return false;
    return true;
}

enum class ColumnRole { Numeric, Segment, Ignored };

struct ColumnPlan {
    std::string name;  // as messages show it: the file's name, and mhbench's when they differ
    ColumnRole role = ColumnRole::Ignored;
    Eigen::VectorXd* target = nullptr;
    UnitConversion to_mhbench_unit;
    std::vector<double> values;
};

// The vector that holds mhbench's numeric column `name` in `m`, created for an optional column.
Eigen::VectorXd* numeric_column(Measurement& m, const std::string& name) {
    if (name == "i_d") return &m.i_d;
    if (name == "i_q") return &m.i_q;
    if (name == "u_d") return &m.u_d;
    if (name == "u_q") return &m.u_q;
    if (name == "omega_e") return &m.omega_e;
    auto& slot = name == "t" ? m.t : name == "theta_e" ? m.theta_e : name == "temp_winding" ? m.temp_winding : m.temp_magnet;
    slot.emplace();
    return &*slot;
}

// A value converted to mhbench's unit, refused when the conversion leaves the range of a double.
double converted(const UnitConversion& conversion, double value, const std::string& source, long line,
                 const std::string& field, const std::string& row) {
    const double out = conversion(value);
    if (!std::isfinite(out))
        throw InputError(source, line, field,
                         fmt::format("{}{} {} is beyond the range of a double after conversion", row, value, conversion.unit()));
    return out;
}

// Segment labels in order of first appearance, and each row's index into them.
struct SegmentLabels {
    std::vector<std::string> labels;
    std::map<std::string, int, std::less<>> index;
    std::vector<int> rows;

    void add(std::string_view label) {
        auto it = index.find(label);
        if (it == index.end()) {
            it = index.emplace(std::string(label), static_cast<int>(labels.size())).first;
            labels.emplace_back(label);
        }
        rows.push_back(it->second);
    }
    void move_into(Measurement& m) {
        if (labels.empty()) return;
        m.segment_labels = std::move(labels);
        m.segment = Eigen::Map<const Eigen::VectorXi>(rows.data(), static_cast<Eigen::Index>(rows.size()));
    }
};

}  // namespace

void Measurement::resize(Eigen::Index n) {
    for (auto* v : {&i_d, &i_q, &u_d, &u_q, &omega_e}) v->resize(n);
    for (auto* v : {&t, &theta_e, &temp_winding, &temp_magnet})
        if (*v) (*v)->resize(n);
    if (has_segments()) segment.resize(n);
}

Measurement parse_measurement(const std::string& text, const std::string& source, const ColumnMap& map) {
    std::string_view all(text);
    if (all.size() >= 3 && all.substr(0, 3) == "\xEF\xBB\xBF") all.remove_prefix(3);  // UTF-8 byte-order mark
    if (all.find_first_not_of(" \t\r\n") == std::string_view::npos)
        throw InputError(source, 0, "", "empty file: expected a header row and data rows");
    if (const auto nul = all.find('\0'); nul != std::string_view::npos)
        throw InputError(source, 1 + static_cast<long>(std::count(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(nul), '\n')),
                         "", "binary data (a NUL byte), not a CSV text file");

    std::vector<std::string_view> lines;
    for (std::size_t start = 0; start <= all.size();) {
        const std::size_t nl = all.find('\n', start);
        if (nl == std::string_view::npos) {
            if (start < all.size()) lines.push_back(all.substr(start));
            break;
        }
        lines.push_back(all.substr(start, nl - start));
        start = nl + 1;
    }

    // Checked before any column is filled, so that an oversized file costs no more memory than its text.
    if (static_cast<std::int64_t>(lines.size()) - 1 > max_measurement_rows)
        throw InputError(source, 0, "", fmt::format("{} rows after the header; the limit is {} rows", lines.size() - 1,
                                                     max_measurement_rows));

    Measurement m;
    m.source = source;
    const auto header = split_fields(lines[0]);
    std::vector<ColumnPlan> plan(header.size());
    std::map<std::string, std::size_t, std::less<>> seen;
    std::vector<std::string> names;
    for (std::size_t c = 0; c < header.size(); ++c) {
        const std::string name(header[c]);
        if (name.empty())
            throw InputError(source, 1, fmt::format("column {}", c + 1), "empty column name in the header");
        if (auto it = seen.find(name); it != seen.end())
            throw InputError(source, 1, printable_field(name), fmt::format("duplicate column (columns {} and {})", it->second + 1, c + 1));
        seen.emplace(name, c);
        names.push_back(name);
    }
    const auto bound = bind_columns(names, map, source, 1, "column", separator_hint(lines[0]));
    std::size_t i_d_column = 0;
    for (std::size_t c = 0; c < header.size(); ++c) {
        plan[c].name = printable_field(column_label(names[c], bound[c]));
        if (bound[c].empty()) {
            m.warnings.push_back(fmt::format("{}: column '{}' is not used by mhbench and was ignored", source, printable_field(names[c])));
        } else if (bound[c] == "segment") {
            plan[c].role = ColumnRole::Segment;
        } else {
            plan[c].role = ColumnRole::Numeric;
            plan[c].target = numeric_column(m, bound[c]);
            plan[c].to_mhbench_unit = unit_conversion(map, bound[c]);
            if (bound[c] == "i_d") i_d_column = c;
        }
    }

    SegmentLabels segments;
    long blank_lines = 0;
    for (std::size_t l = 1; l < lines.size(); ++l) {
        const long line_no = static_cast<long>(l + 1);
        if (is_blank(lines[l])) {
            ++blank_lines;
            continue;
        }
        const auto fields = split_fields(lines[l]);
        if (fields.size() != header.size())
            throw InputError(source, line_no, "",
                             fmt::format("row has {} fields but the header has {}{}", fields.size(), header.size(),
                                         fields.size() > header.size() ? " (a decimal comma? numbers must use '.' as the decimal mark)" : ""));
        for (std::size_t c = 0; c < fields.size(); ++c) {
            const auto f = fields[c];
            switch (plan[c].role) {
                case ColumnRole::Ignored: break;
                case ColumnRole::Segment: {
                    if (f.empty()) throw InputError(source, line_no, plan[c].name, "empty segment label");
                    segments.add(f);
                    break;
                }
                case ColumnRole::Numeric: {
                    if (f.empty()) throw InputError(source, line_no, plan[c].name, "empty value");
                    std::string_view digits = f;
                    if (digits.front() == '+') digits.remove_prefix(1);
                    double value = 0.0;
                    const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
                    if (ec == std::errc::result_out_of_range)
                        throw InputError(source, line_no, plan[c].name, fmt::format("value out of range: '{}'", printable_field(f)));
                    if (ec != std::errc() || ptr != digits.data() + digits.size())
                        throw InputError(source, line_no, plan[c].name, fmt::format("not a number: '{}'", printable_field(f)));
                    if (!std::isfinite(value))
                        throw InputError(source, line_no, plan[c].name, fmt::format("not a finite number: '{}'", printable_field(f)));
                    plan[c].values.push_back(converted(plan[c].to_mhbench_unit, value, source, line_no, plan[c].name, ""));
                    break;
                }
            }
        }
    }
    const std::size_t rows = plan[i_d_column].values.size();
    if (rows == 0) throw InputError(source, static_cast<long>(lines.size()), "", "no data rows after the header");
    if (blank_lines > 0)
        m.warnings.push_back(fmt::format("{}: {} blank line(s) skipped", source, blank_lines));

    for (auto& p : plan)
        if (p.role == ColumnRole::Numeric) *p.target = Eigen::Map<const Eigen::VectorXd>(p.values.data(), static_cast<Eigen::Index>(rows));
    segments.move_into(m);
    return m;
}

namespace {

// The file's format by its first bytes. A MAT v7.3 file is HDF5 behind a 512-byte MATLAB header;
// HDF5 looks for its signature at 0, 512, 1024, 2048, ... (after a user block), and so does this.
MeasurementFormat format_of(std::ifstream& in, std::uintmax_t size) {
    char head[20] = {};
    in.read(head, sizeof head);
    const std::string_view start(head, static_cast<std::size_t>(in.gcount()));
    if (start.starts_with("MATLAB 5.0 MAT-file")) return MeasurementFormat::Mat5;
    constexpr std::string_view hdf5_signature("\x89HDF\r\n\x1a\n", 8);
    for (std::uintmax_t offset = 0; offset + hdf5_signature.size() <= size; offset = offset == 0 ? 512 : 2 * offset) {
        char signature[8] = {};
        in.clear();
        in.seekg(static_cast<std::streamoff>(offset));
        in.read(signature, sizeof signature);
        if (in.gcount() == sizeof signature && std::string_view(signature, sizeof signature) == hdf5_signature)
            return offset > 0 && start.starts_with("MATLAB") ? MeasurementFormat::Mat73 : MeasurementFormat::Hdf5;
    }
    return start.starts_with("MATLAB") ? MeasurementFormat::OtherMat : MeasurementFormat::Csv;
}

Measurement measurement_from_file_columns(FileColumns file, const ColumnMap& map, const std::string& source) {
    std::vector<std::string> names;
    for (const auto& c : file.columns) names.push_back(c.name);
    const auto bound = bind_columns(names, map, source, 0, "variable");
    Measurement m;
    m.source = source;
    m.warnings = std::move(file.notes);
    std::size_t rows = 0;
    std::string first;
    SegmentLabels segments;
    for (std::size_t k = 0; k < file.columns.size(); ++k) {
        auto& column = file.columns[k];
        if (bound[k].empty()) {
            m.warnings.push_back(fmt::format("{}: variable '{}' is not used by mhbench and was ignored", source, printable_field(column.name)));
            continue;
        }
        const std::string field = printable_field(column_label(column.name, bound[k]));
        if (!column.unusable.empty()) throw InputError(source, 0, field, column.unusable);
        const std::size_t n = column.labels ? column.labels->size() : column.numbers.size();
        if (n == 0) throw InputError(source, 0, field, "empty: no rows");
        if (first.empty()) {
            rows = n;
            first = field;
        } else if (n != rows) {
            throw InputError(source, 0, field, fmt::format("{} rows, but {} has {}; every column must have one value per row", n, first, rows));
        }
        auto row = [](std::size_t r) { return fmt::format("row {}: ", r + 1); };
        if (bound[k] == "segment") {
            for (std::size_t r = 0; r < n; ++r) {
                if (!column.labels && !std::isfinite(column.numbers[r]))
                    throw InputError(source, 0, field, fmt::format("{}not a finite number: {}", row(r), column.numbers[r]));
                const std::string label = column.labels ? (*column.labels)[r] : fmt::format("{}", column.numbers[r]);
                if (label.empty()) throw InputError(source, 0, field, row(r) + "empty segment label");
                segments.add(label);
            }
            continue;
        }
        if (column.labels) throw InputError(source, 0, field, "holds text; mhbench reads numbers here (only segment may be text)");
        const auto conversion = unit_conversion(map, bound[k]);
        for (std::size_t r = 0; r < n; ++r) {
            double& value = column.numbers[r];
            if (!std::isfinite(value)) throw InputError(source, 0, field, fmt::format("{}not a finite number: {}", row(r), value));
            value = converted(conversion, value, source, 0, field, row(r));
        }
        *numeric_column(m, bound[k]) = Eigen::Map<const Eigen::VectorXd>(column.numbers.data(), static_cast<Eigen::Index>(n));
        std::vector<double>().swap(column.numbers);
    }
    segments.move_into(m);
    return m;
}

}  // namespace

MeasurementFormat measurement_format(const std::filesystem::path& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) return MeasurementFormat::Csv;
    std::ifstream in(path, std::ios::binary);
    if (!in) return MeasurementFormat::Csv;
    const auto size = std::filesystem::is_regular_file(path, ec) ? std::filesystem::file_size(path, ec) : 0;
    return format_of(in, ec ? 0 : size);
}

Measurement read_measurement(const std::filesystem::path& path, const ColumnMap& map) {
    const std::string source = path.string();
    // HDF5's thread safety covers its C library, not the C++ API read through here, and matio keeps
    // process-wide state; trials may read their data in parallel, so binary files are read one at a
    // time, which costs little next to a fit.
    static std::mutex binary_reader;
    switch (measurement_format(path)) {
        case MeasurementFormat::Mat5:
        case MeasurementFormat::Mat73: {
            std::unique_lock lock(binary_reader);
            auto columns = read_mat_columns(path);
            lock.unlock();
            return measurement_from_file_columns(std::move(columns), map, source);
        }
        case MeasurementFormat::Hdf5: {
            std::unique_lock lock(binary_reader);
            auto columns = read_hdf5_columns(path);
            lock.unlock();
            return measurement_from_file_columns(std::move(columns), map, source);
        }
        case MeasurementFormat::OtherMat:
            throw InputError(source, 0, "",
                             "a MATLAB file that is neither v5/v7 nor v7.3; save it with save(file, '-v7') or '-v7.3'");
        case MeasurementFormat::Csv: break;
    }
    // Directories and unreadable files are refused here, with the system's reason.
    const std::string text = read_text_file(path, "measurement file");
    if (text.find('\0') != std::string::npos && text.find('\0') < 4096)
        throw InputError(source, 0, "", "binary data that is neither CSV text, a MAT file (v5, v7, v7.3) nor HDF5");
    return parse_measurement(text, source, map);
}

std::string format_measurement(const Measurement& m) {
    // Column order: time and operating point first, then the angle, the required signals, temperatures.
    // A null column pointer stands for the segment label.
    std::vector<std::pair<const char*, const Eigen::VectorXd*>> columns;
    if (m.t) columns.emplace_back("t", &*m.t);
    if (m.has_segments()) columns.emplace_back("segment", nullptr);
    if (m.theta_e) columns.emplace_back("theta_e", &*m.theta_e);
    columns.emplace_back("i_d", &m.i_d);
    columns.emplace_back("i_q", &m.i_q);
    columns.emplace_back("u_d", &m.u_d);
    columns.emplace_back("u_q", &m.u_q);
    columns.emplace_back("omega_e", &m.omega_e);
    if (m.temp_winding) columns.emplace_back("temp_winding", &*m.temp_winding);
    if (m.temp_magnet) columns.emplace_back("temp_magnet", &*m.temp_magnet);

    std::string out;
    for (std::size_t c = 0; c < columns.size(); ++c) {
        if (c) out += ',';
        out += columns[c].first;
    }
    out += '\n';
    for (Eigen::Index r = 0; r < m.size(); ++r) {
        for (std::size_t c = 0; c < columns.size(); ++c) {
            if (c) out += ',';
            if (columns[c].second) out += fmt::format("{}", (*columns[c].second)[r]);
            else out += m.segment_labels[static_cast<std::size_t>(m.segment[r])];
        }
        out += '\n';
    }
    return out;
}

void write_measurement(const std::filesystem::path& path, const Measurement& m) {
    for (const auto& label : m.segment_labels)
        if (label.empty() || label.find_first_of(",\"\n\r") != std::string::npos || label != trim(label))
            throw InputError(path.string(), 0, "segment",
                             fmt::format("label '{}' cannot be written to CSV (empty, a comma, a quote, a line break "
                                         "or surrounding spaces)", label));
    std::ofstream out(path, std::ios::binary);
    if (!out) throw InputError(path.string(), 0, "", "cannot open the file for writing");
    out << format_measurement(m);
    if (!out) throw InputError(path.string(), 0, "", "write failed");
}

Measurement select_rows(const Measurement& m, const std::vector<Eigen::Index>& rows) {
    Measurement out;
    out.source = m.source;
    out.warnings = m.warnings;
    const auto n = static_cast<Eigen::Index>(rows.size());
    auto pick = [&](const Eigen::VectorXd& v) {
        Eigen::VectorXd r(n);
        for (Eigen::Index k = 0; k < n; ++k) r[k] = v[rows[static_cast<std::size_t>(k)]];
        return r;
    };
    out.i_d = pick(m.i_d);
    out.i_q = pick(m.i_q);
    out.u_d = pick(m.u_d);
    out.u_q = pick(m.u_q);
    out.omega_e = pick(m.omega_e);
    if (m.t) out.t = pick(*m.t);
    if (m.theta_e) out.theta_e = pick(*m.theta_e);
    if (m.temp_winding) out.temp_winding = pick(*m.temp_winding);
    if (m.temp_magnet) out.temp_magnet = pick(*m.temp_magnet);
    if (m.has_segments()) {
        std::vector<int> renumber(m.segment_labels.size(), -1);
        out.segment.resize(n);
        for (Eigen::Index k = 0; k < n; ++k) {
            const int old = m.segment[rows[static_cast<std::size_t>(k)]];
            if (renumber[static_cast<std::size_t>(old)] < 0) {
                renumber[static_cast<std::size_t>(old)] = static_cast<int>(out.segment_labels.size());
                out.segment_labels.push_back(m.segment_labels[static_cast<std::size_t>(old)]);
            }
            out.segment[k] = renumber[static_cast<std::size_t>(old)];
        }
    }
    return out;
}

std::vector<Eigen::Index> settled_rows(const Measurement& m, double settle) {
    std::vector<Eigen::Index> rows;
    rows.reserve(static_cast<std::size_t>(m.size()));
    if (settle <= 0.0) {
        for (Eigen::Index k = 0; k < m.size(); ++k) rows.push_back(k);
        return rows;
    }
    if (!m.t || !m.has_segments())
        throw InputError(m.source, 0, "settle",
                         "dropping samples after segment changes needs the columns t and segment");
    const auto& t = *m.t;
    double start = 0.0;
    for (Eigen::Index k = 0; k < m.size(); ++k) {
        if (k == 0 || m.segment[k] != m.segment[k - 1]) start = t[k];
        // A nanosecond of slack: logged times are sums of periods and carry rounding.
        if (t[k] - start >= settle - 1e-9) rows.push_back(k);
    }
    return rows;
}

}  // namespace mhb::pmsm
