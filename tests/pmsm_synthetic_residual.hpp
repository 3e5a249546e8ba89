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
