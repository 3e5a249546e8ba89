#include "problems/pmsm/measurement.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>

#include <fmt/format.h>

#include "framework/input_error.hpp"
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

// A field as it may appear in a message: bytes a terminal would act on are shown as \xNN, and a long
// field is cut, so that binary input never reaches the terminal raw.
std::string shown(std::string_view field) {
    constexpr std::size_t longest = 40;
    std::string out;
    for (std::size_t k = 0; k < field.size() && k < longest; ++k) {
        const auto c = static_cast<unsigned char>(field[k]);
        if (c < 0x20 || c >= 0x7f) out += fmt::format("\\x{:02X}", c);
        else out += static_cast<char>(c);
    }
    if (field.size() > longest) out += "...";
    return out;
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
    std::string name;
    ColumnRole role = ColumnRole::Ignored;
    Eigen::VectorXd* target = nullptr;
    std::vector<double> values;
};

}  // namespace

void Measurement::resize(Eigen::Index n) {
    for (auto* v : {&i_d, &i_q, &u_d, &u_q, &omega_e}) v->resize(n);
    for (auto* v : {&t, &theta_e, &temp_winding, &temp_magnet})
        if (*v) (*v)->resize(n);
    if (has_segments()) segment.resize(n);
}

Measurement parse_measurement(const std::string& text, const std::string& source) {
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
    const std::map<std::string, Eigen::VectorXd*, std::less<>> numeric_targets{
        {"i_d", &m.i_d}, {"i_q", &m.i_q}, {"u_d", &m.u_d}, {"u_q", &m.u_q}, {"omega_e", &m.omega_e}};
    for (std::size_t c = 0; c < header.size(); ++c) {
        const std::string name(header[c]);
        if (name.empty())
            throw InputError(source, 1, fmt::format("column {}", c + 1), "empty column name in the header");
        if (auto it = seen.find(name); it != seen.end())
            throw InputError(source, 1, shown(name), fmt::format("duplicate column (columns {} and {})", it->second + 1, c + 1));
        seen.emplace(name, c);
        plan[c].name = name;
        if (auto it = numeric_targets.find(name); it != numeric_targets.end()) {
            plan[c].role = ColumnRole::Numeric;
            plan[c].target = it->second;
        } else if (name == "t" || name == "theta_e" || name == "temp_winding" || name == "temp_magnet") {
            auto& slot = name == "t" ? m.t : name == "theta_e" ? m.theta_e : name == "temp_winding" ? m.temp_winding : m.temp_magnet;
            slot.emplace();
            plan[c].role = ColumnRole::Numeric;
            plan[c].target = &*slot;
        } else if (name == "segment") {
            plan[c].role = ColumnRole::Segment;
        } else {
            m.warnings.push_back(fmt::format("{}: column '{}' is not used by mhbench and was ignored", source, shown(name)));
        }
    }
    std::string header_text;
    for (const auto& h : header) {
        if (!header_text.empty()) header_text += ", ";
        header_text += shown(h);
    }
    for (const char* name : required_columns)
        if (!seen.count(name))
            throw InputError(source, 1, name,
                             fmt::format("missing required column (header has: {}){}", header_text, separator_hint(lines[0])));

    std::vector<std::string> labels;
    std::map<std::string, int, std::less<>> label_index;
    std::vector<int> segment_rows;
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
                    auto it = label_index.find(f);
                    if (it == label_index.end()) {
                        it = label_index.emplace(std::string(f), static_cast<int>(labels.size())).first;
                        labels.emplace_back(f);
                    }
                    segment_rows.push_back(it->second);
                    break;
                }
                case ColumnRole::Numeric: {
                    if (f.empty()) throw InputError(source, line_no, plan[c].name, "empty value");
                    std::string_view digits = f;
                    if (digits.front() == '+') digits.remove_prefix(1);
                    double value = 0.0;
                    const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
                    if (ec == std::errc::result_out_of_range)
                        throw InputError(source, line_no, plan[c].name, fmt::format("value out of range: '{}'", shown(f)));
                    if (ec != std::errc() || ptr != digits.data() + digits.size())
                        throw InputError(source, line_no, plan[c].name, fmt::format("not a number: '{}'", shown(f)));
                    if (!std::isfinite(value))
                        throw InputError(source, line_no, plan[c].name, fmt::format("not a finite number: '{}'", shown(f)));
                    plan[c].values.push_back(value);
                    break;
                }
            }
        }
    }
    const std::size_t rows = plan[seen.at("i_d")].values.size();
    if (rows == 0) throw InputError(source, static_cast<long>(lines.size()), "", "no data rows after the header");
    if (blank_lines > 0)
        m.warnings.push_back(fmt::format("{}: {} blank line(s) skipped", source, blank_lines));

    for (auto& p : plan)
        if (p.role == ColumnRole::Numeric) *p.target = Eigen::Map<const Eigen::VectorXd>(p.values.data(), static_cast<Eigen::Index>(rows));
    if (!labels.empty()) {
        m.segment_labels = std::move(labels);
        m.segment = Eigen::Map<const Eigen::VectorXi>(segment_rows.data(), static_cast<Eigen::Index>(rows));
    }
    return m;
}

Measurement read_measurement(const std::filesystem::path& path) {
    return parse_measurement(read_text_file(path, "measurement file"), path.string());
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
