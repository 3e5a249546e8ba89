#pragma once
// Measurements whose residual is made by hand, for testing the diagnosis' statistics alone: rows in
// segments with zero currents, speed and voltages, and a fit that carries the residual itself.
#include <cmath>
#include <numbers>
#include <random>
#include <string>

#include "problems/pmsm/diagnosis/diagnosis.hpp"
#include "problems/pmsm/diagnosis/segments.hpp"

namespace mhb::pmsm::testing {

// `segments` segments of `rows` rows each, labelled s0, s1, ...; with a logged angle turning
// `turns_per_segment` electrical periods through each segment when that is positive.
inline Measurement segmented_rows(int segments, Eigen::Index rows, double turns_per_segment = 0.0) {
    Measurement m;
    const Eigen::Index n = segments * rows;
    m.i_d = m.i_q = m.u_d = m.u_q = m.omega_e = Eigen::VectorXd::Zero(n);
    m.segment.resize(n);
    for (int s = 0; s < segments; ++s) {
        m.segment_labels.push_back("s" + std::to_string(s));
        m.segment.segment(s * rows, rows).setConstant(s);
    }
    if (turns_per_segment > 0.0) {
        m.theta_e = Eigen::VectorXd(n);
        for (Eigen::Index k = 0; k < n; ++k)
            (*m.theta_e)[k] = wrap_angle(2.0 * std::numbers::pi * turns_per_segment * static_cast<double>(k % rows) / static_cast<double>(rows));
    }
    return m;
}

// A shaft turning through segments of a drive, with its exact angle: `segments` segments of `rows`
// rows `dt` apart, each starting at another shaft angle and turning `turns` turns (alternately
// forwards and backwards) at a speed that ripples by a tenth around its mean, three ripples a
// segment. The rows log t (each segment after a gap of a second), omega_e and theta_e of a machine
// of `pole_pairs`; `exact` is the shaft angle, unwrapped.
struct TurningShaft {
    Measurement data;
    Eigen::VectorXd exact;
    double third_derivative = 0.0;  // the largest |d^3 theta_m / dt^3| (rad/s^3)
};
inline TurningShaft turning_shaft(int segments, Eigen::Index rows, double dt, int pole_pairs, double turns) {
    TurningShaft s;
    s.data = segmented_rows(segments, rows);
    const Eigen::Index n = s.data.size();
    s.data.t = Eigen::VectorXd(n);
    s.data.theta_e = Eigen::VectorXd(n);
    s.exact = Eigen::VectorXd(n);
    const double duration = static_cast<double>(rows) * dt, ripple = 3.0 * 2.0 * std::numbers::pi / duration;
    for (int g = 0; g < segments; ++g) {
        const double mean_speed = (g % 2 == 0 ? 1.0 : -1.0) * 2.0 * std::numbers::pi * turns / duration;
        const double start_angle = 0.7 * g + 0.3, start_time = g * (duration + 1.0);
        s.third_derivative = std::max(s.third_derivative, std::abs(0.1 * mean_speed * ripple * ripple));
        for (Eigen::Index k = 0; k < rows; ++k) {
            const Eigen::Index row = g * rows + k;
            const double tau = static_cast<double>(k) * dt;
            // theta_m = theta_0 + w tau + 0.1 w (1 - cos(W tau)) / W, whose derivative is w (1 + 0.1 sin(W tau)).
            s.exact[row] = start_angle + mean_speed * tau + 0.1 * mean_speed * (1.0 - std::cos(ripple * tau)) / ripple;
            s.data.omega_e[row] = pole_pairs * mean_speed * (1.0 + 0.1 * std::sin(ripple * tau));
            (*s.data.t)[row] = start_time + tau;
            (*s.data.theta_e)[row] = wrap_angle(pole_pairs * s.exact[row]);
        }
    }
    return s;
}

// A fit of the base model, none of its parameters free, whose residual (u_d rows, then u_q rows) is
// `residual`; residual_of returns it as it is. Its segments are `data`'s, with their mean residuals.
inline ModelFit fit_with_residual(const Measurement& data, const Eigen::VectorXd& residual) {
    ModelFit fit;
    fit.spec = parse_model_spec("base");
    fit.samples = data.size();
    fit.residual = residual;
    const Eigen::Index n = data.size();
    fit.axis_rss = {residual.head(n).squaredNorm(), residual.tail(n).squaredNorm()};
    for (const auto& r : segment_ranges(data)) {
        SegmentResidual s;
        s.label = data.has_segments() ? data.segment_labels[static_cast<std::size_t>(data.segment[r.first])] : "all";
        s.first = r.first;
        s.rows = r.rows;
        s.mean = {residual.segment(r.first, r.rows).mean(), residual.segment(n + r.first, r.rows).mean()};
        fit.segments.push_back(s);
    }
    return fit;
}

// `n` samples of white Gaussian noise of standard deviation `sigma`.
inline Eigen::VectorXd white_noise(Eigen::Index n, double sigma, std::mt19937_64& random) {
    std::normal_distribution<double> normal(0.0, sigma);
    Eigen::VectorXd v(n);
    for (auto& x : v) x = normal(random);
    return v;
}

// A residual of `n` rows per axis: white noise of `sigma_d` on u_d, then of `sigma_q` on u_q.
inline Eigen::VectorXd white_residual(Eigen::Index n, double sigma_d, double sigma_q, std::mt19937_64& random) {
    Eigen::VectorXd r(2 * n);
    r.head(n) = white_noise(n, sigma_d, random);
    r.tail(n) = white_noise(n, sigma_q, random);
    return r;
}

}  // namespace mhb::pmsm::testing
