#include "problems/pmsm/diagnosis/shaft_angle.hpp"

#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "problems/pmsm/diagnosis/segments.hpp"
#include "problems/pmsm/machine/machine.hpp"

namespace mhb::pmsm {
namespace {

// The pole pairs the logged angles imply: the electrical angle's travel over the mechanical one's,
// each segment's counted in the direction it turned (so that segments turning both ways add up); 0
// when that is not near a whole number or the shaft hardly moved.
int pole_pairs_of_angles(const Measurement& data) {
    double electrical = 0.0, mechanical = 0.0;
    for (const auto& r : segment_ranges(data)) {
        double segment_electrical = 0.0, segment_mechanical = 0.0;
        for (Eigen::Index k = r.first + 1; k < r.first + r.rows; ++k) {
            segment_electrical += wrap_angle((*data.theta_e)[k] - (*data.theta_e)[k - 1]);
            segment_mechanical += wrap_angle((*data.theta_m)[k] - (*data.theta_m)[k - 1]);
        }
        electrical += segment_mechanical < 0.0 ? -segment_electrical : segment_electrical;
        mechanical += std::abs(segment_mechanical);
    }
    if (!(std::abs(mechanical) > 0.1)) return 0;
    const double ratio = electrical / mechanical;
    const double whole = std::round(ratio);
    return whole >= 1.0 && std::abs(ratio - whole) < 0.05 ? static_cast<int>(whole) : 0;
}

}  // namespace

Eigen::VectorXd integrated_shaft_angle(const Measurement& data, int pole_pairs) {
    const Eigen::VectorXd& t = *data.t;
    const Eigen::VectorXd& omega = data.omega_e;
    Eigen::VectorXd angle(data.size());
    for (const auto& r : segment_ranges(data)) {
        if (r.rows == 0) continue;
        double electrical = 0.0;
        angle[r.first] = 0.0;
        for (Eigen::Index k = r.first + 1; k < r.first + r.rows; ++k) {
            double step = 0.5 * (omega[k] + omega[k - 1]) * (t[k] - t[k - 1]);
            if (data.theta_e) step += wrap_angle((*data.theta_e)[k] - (*data.theta_e)[k - 1] - step);
            electrical += step;
            angle[k] = electrical / pole_pairs;
        }
    }
    return angle;
}

ShaftAngle shaft_angle(const Measurement& data, int pole_pairs) {
    ShaftAngle s;
    s.pole_pairs = pole_pairs;
    std::string inferred;
    if (s.pole_pairs <= 0 && data.theta_m && data.theta_e) {
        s.pole_pairs = pole_pairs_of_angles(data);
        if (s.pole_pairs > 0) inferred = fmt::format(", {} pole pairs from the logged theta_e and theta_m", s.pole_pairs);
    }
    if (s.pole_pairs <= 0) {
        s.source = "the pole-pair count is not known, so a mechanical order cannot be told from an electrical one (give --pole-pairs)";
        return s;
    }
    if (data.theta_m) {
        s.angle = *data.theta_m;
        s.logged = true;
        s.source = "the logged theta_m" + inferred;
    } else if (data.t) {
        s.angle = integrated_shaft_angle(data, s.pole_pairs);
        s.source = fmt::format("integrated from omega_e over t within each segment ({} pole pairs; its zero in each segment is unknown, "
                               "so a phase is per segment)",
                               s.pole_pairs);
    } else {
        s.source = "neither theta_m nor t is logged, so the shaft angle cannot be had";
    }
    return s;
}

}  // namespace mhb::pmsm
