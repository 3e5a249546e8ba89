#pragma once
// Small noise-free drive simulations for the PMSM tests.
#include <cmath>
#include <numbers>
#include <vector>

#include "problems/pmsm/simulation/drive_simulator.hpp"
#include "problems/pmsm/model/steady_state_model.hpp"

namespace mhb::pmsm::testing {

// The Table 1 drive with ideal sensors and no logging filter.
inline DriveSimulation quiet_drive(std::vector<Segment> segments) {
    DriveSimulation d;
    d.segments = std::move(segments);
    d.logging.temperatures = true;
    return d;
}

// Operating points of the Table 1 motor in both directions, three d currents and two speeds.
inline std::vector<Segment> seed_motor_points(std::int64_t samples = 60) {
    return {
        {"a", 10.0, 0.10, 0.0, 0.7, samples},
        {"b", 10.0, 0.10, -0.1, 0.25, samples},
        {"c", 16.7, 0.05, -0.2, 0.4, samples},
        {"d", -10.0, -0.08, 0.0, 0.7, samples},
        {"e", -16.7, -0.12, -0.15, 0.5, samples},
    };
}

inline double electrical_speed(const MotorParameters& m, double rpm) {
    return m.pole_pairs * rpm * 2.0 * std::numbers::pi / 60.0;
}

// Logged minus predicted voltages (both axes stacked) for the model at `parameters`.
inline Eigen::VectorXd model_residual(const SteadyStateModel& model, const Eigen::VectorXd& parameters) {
    ModelState s = model.make_state();
    model.predict(parameters.data(), s);
    const auto n = model.data().size();
    Eigen::VectorXd r(2 * n);
    r.head(n) = model.data().u_d - s.u_d.matrix();
    r.tail(n) = model.data().u_q - s.u_q.matrix();
    return r;
}

inline double rms(const Eigen::VectorXd& v) { return std::sqrt(v.squaredNorm() / static_cast<double>(v.size())); }

}  // namespace mhb::pmsm::testing
