#include "problems/pmsm/data/settled_measurement.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include <fmt/format.h>

#include "framework/input_error.hpp"

namespace mhb::pmsm {

namespace {

// The rows of `from` listed in `rows` into `to`, which may be `from` itself when `rows` ascend
// strictly: each row then moves down or stays, and is read before anything is written over it.
void pick_rows(const Measurement& from, Measurement& to, const std::vector<Eigen::Index>& rows) {
    const auto n = static_cast<Eigen::Index>(rows.size());
    auto pick = [&](const auto& v, auto& out) {
        if (&out != &v) out.resize(n);
        for (Eigen::Index k = 0; k < n; ++k) out[k] = v[rows[static_cast<std::size_t>(k)]];
        if (out.size() != n) out.conservativeResize(n);
    };
    pick(from.i_d, to.i_d);
    pick(from.i_q, to.i_q);
    pick(from.u_d, to.u_d);
    pick(from.u_q, to.u_q);
    pick(from.omega_e, to.omega_e);
    auto pick_optional = [&](const std::optional<Eigen::VectorXd>& v, std::optional<Eigen::VectorXd>& out) {
        if (!v) return;
        if (!out) out.emplace();
        pick(*v, *out);
    };
    pick_optional(from.t, to.t);
    pick_optional(from.theta_e, to.theta_e);
    pick_optional(from.temp_winding, to.temp_winding);
    pick_optional(from.temp_magnet, to.temp_magnet);
    pick_optional(from.theta_m, to.theta_m);
    if (from.has_segments()) {
        std::vector<int> renumber(from.segment_labels.size(), -1);
        std::vector<std::string> labels;
        if (&to != &from) to.segment.resize(n);
        for (Eigen::Index k = 0; k < n; ++k) {
            const auto old = static_cast<std::size_t>(from.segment[rows[static_cast<std::size_t>(k)]]);
            if (renumber[old] < 0) {
                renumber[old] = static_cast<int>(labels.size());
                labels.push_back(from.segment_labels[old]);
            }
            to.segment[k] = renumber[old];
        }
        if (to.segment.size() != n) to.segment.conservativeResize(n);
        to.segment_labels = std::move(labels);
    }
}

}  // namespace

Measurement select_rows(const Measurement& m, const std::vector<Eigen::Index>& rows) {
    Measurement out;
    out.source = m.source;
    out.warnings = m.warnings;
    out.current_loop_bandwidth = m.current_loop_bandwidth;
    out.current_loop_delay = m.current_loop_delay;
    pick_rows(m, out, rows);
    return out;
}

Measurement select_rows(Measurement&& m, const std::vector<Eigen::Index>& rows) {
    if (std::adjacent_find(rows.begin(), rows.end(), std::greater_equal<>()) != rows.end()) return select_rows(std::as_const(m), rows);
    pick_rows(m, m, rows);
    return std::move(m);
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

Measurement read_settled_measurement(const std::filesystem::path& path, double settle, const ColumnMap& map) {
    Measurement all = read_measurement(path, map);
    const auto rows = settled_rows(all, settle);
    if (rows.size() < 10)
        throw InputError(path.string(), 0, "settle",
                         fmt::format("dropping {} s after each segment start leaves {} samples; at least 10 are needed", settle, rows.size()));
    return select_rows(std::move(all), rows);
}

}  // namespace mhb::pmsm
