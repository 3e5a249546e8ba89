#include "problems/pmsm/data/measurement.hpp"

#include <fstream>

#include <fmt/format.h>

#include "framework/input_error.hpp"
#include "problems/pmsm/data/measurement_file_columns.hpp"

namespace mhb::pmsm {

std::string format_measurement(const Measurement& m) {
    // Column order: time and operating point first, then the angles, the required signals, temperatures.
    // A null column pointer stands for the segment label.
    std::vector<std::pair<const char*, const Eigen::VectorXd*>> columns;
    if (m.t) columns.emplace_back("t", &*m.t);
    if (m.has_segments()) columns.emplace_back("segment", nullptr);
    if (m.theta_e) columns.emplace_back("theta_e", &*m.theta_e);
    if (m.theta_m) columns.emplace_back("theta_m", &*m.theta_m);
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
        if (label.empty() || label.find_first_of(",\"\n\r") != std::string::npos || label != csv_field_text(label))
            throw InputError(path.string(), 0, "segment",
                             fmt::format("label '{}' cannot be written to CSV (empty, a comma, a quote, a line break "
                                         "or surrounding spaces)", label));
    std::ofstream out(path, std::ios::binary);
    if (!out) throw InputError(path.string(), 0, "", "cannot open the file for writing");
    out << format_measurement(m);
    if (!out) throw InputError(path.string(), 0, "", "write failed");
}

}  // namespace mhb::pmsm
