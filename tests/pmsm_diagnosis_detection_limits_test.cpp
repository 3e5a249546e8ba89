// Detection limits (problems/pmsm/diagnosis/detection_limits.hpp) against the exact least-squares
// projection of an effect's signature on the base model's columns, written out here from the
// steady-state equations (seed eq. 2), not from the model code.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/QR>

#include "problems/pmsm/diagnosis/detection_limits.hpp"
#include "problems/pmsm/diagnosis/verdict.hpp"
#include "tests/pmsm_synthetic_residual.hpp"

using namespace mhb::pmsm;
using namespace mhb::pmsm::testing;

namespace {

struct Point {
    double omega, i_d, i_q;
};

// Segments of `rows` rows held at each point.
Measurement held_points(const std::vector<Point>& points, Eigen::Index rows) {
    Measurement m = segmented_rows(static_cast<int>(points.size()), rows);
    for (std::size_t s = 0; s < points.size(); ++s) {
        const auto first = static_cast<Eigen::Index>(s) * rows;
        m.omega_e.segment(first, rows).setConstant(points[s].omega);
        m.i_d.segment(first, rows).setConstant(points[s].i_d);
        m.i_q.segment(first, rows).setConstant(points[s].i_q);
    }
    return m;
}

ModelFit base_fit(const Measurement& data) {
    ModelFit fit = fit_with_residual(data, Eigen::VectorXd::Zero(2 * data.size()));
    fit.values = Eigen::Vector4d(46.0, 0.02, 0.025, 0.044);
    fit.free = {true, true, true, true};
    return fit;
}

NoiseEstimate noise_of(double sigma_d, double sigma_q, double effective_samples) {
    NoiseEstimate noise;
    noise.sigma = {sigma_d, sigma_q};
    noise.long_run = noise.sigma;
    noise.effective_samples = effective_samples;
    return noise;
}

// The limit of a voltage offset on axis `axis` by hand: the u_d rows of the base model are
// Rs i_d - omega Lq i_q, its u_q rows Rs i_q + omega Ld i_d + omega psi_f; the offset's column is 1
// on its axis. Both in units of each axis' noise. The evidence's and the relevant size's.
struct ByHand {
    double by_evidence, by_relevant_size;
    double limit() const { return std::max(by_evidence, by_relevant_size); }
};

ByHand offset_limit_by_hand(const Measurement& data, Eigen::Index logged_rows, const NoiseEstimate& noise, int axis) {
    const Eigen::Index n = data.size();
    Eigen::MatrixXd base = Eigen::MatrixXd::Zero(2 * n, 4);
    base.col(0) << data.i_d, data.i_q;
    base.block(n, 1, n, 1) = (data.omega_e.array() * data.i_d.array()).matrix();
    base.block(0, 2, n, 1) = -(data.omega_e.array() * data.i_q.array()).matrix();
    base.block(n, 3, n, 1) = data.omega_e;
    Eigen::VectorXd column = Eigen::VectorXd::Zero(2 * n);
    column.segment(axis * n, n).setOnes();
    for (int a = 0; a < 2; ++a) {
        base.middleRows(a * n, n) /= noise.long_run[a];
        column.segment(a * n, n) /= noise.long_run[a];
    }
    const Eigen::VectorXd unique = column - base * base.householderQr().solve(column);
    const double weight = static_cast<double>(logged_rows) / static_cast<double>(n);
    const double needed = 2.0 * std::log(noise.effective_samples) - evidence::supported_bic;  // u_d and u_q: two parameters
    Eigen::VectorXd volts = unique;
    for (int a = 0; a < 2; ++a) volts.segment(a * n, n) *= noise.long_run[a];
    const double power = volts.squaredNorm() / (2.0 * static_cast<double>(n));
    const double resolution = std::sqrt(noise.sigma.squaredNorm() / 2.0);
    return {std::sqrt(needed / (weight * unique.squaredNorm())), evidence::relevant_voltage * resolution / std::sqrt(power)};
}

const DetectionLimit& limit_of(const std::vector<DetectionLimit>& limits, const std::string& parameter) {
    for (const auto& l : limits)
        if (l.parameter == parameter) return l;
    FAIL("no limit for " << parameter);
    return limits.front();
}

}  // namespace

TEST_CASE("a voltage offset's detection limit is its signature left by the base columns, in units of the noise",
          "[pmsm][diagnosis][detection_limits]") {
    const Measurement data = held_points({{80.0, 0.0, 0.1}, {80.0, -0.2, 0.15}, {-40.0, 0.0, -0.1}, {40.0, -0.1, 0.05}, {120.0, -0.3, 0.2},
                                          {-120.0, -0.2, -0.2}},
                                         40);
    const ModelFit fit = base_fit(data);
    const NoiseEstimate noise = noise_of(0.02, 0.05, 400.0);
    // Which test sets each limit: on the short log the evidence, on one fifty times as long (the
    // evidence grows with the rows, the relevant size does not) the relevant size.
    std::vector<bool> set_by_relevant_size;
    for (const Eigen::Index logged : {data.size(), 50 * data.size()}) {
        const auto limits = detection_limits(data, logged, fit, {"voltage_offset"}, noise);
        REQUIRE(limits.size() == 2);
        for (int axis = 0; axis < 2; ++axis) {
            const ByHand hand = offset_limit_by_hand(data, logged, noise, axis);
            const DetectionLimit& l = limit_of(limits, axis == 0 ? "voltage_offset.u_d" : "voltage_offset.u_q");
            CHECK(l.limit == Approx(hand.limit()).epsilon(1e-6));
            CHECK(l.set_by_relevant_size == (hand.by_relevant_size > hand.by_evidence));
            set_by_relevant_size.push_back(l.set_by_relevant_size);
        }
        CHECK(limit_of(limits, "voltage_offset.u_d").unit == "V");
    }
    CHECK(set_by_relevant_size == std::vector<bool>{false, false, true, true});
    // Noise twice as large: every limit twice as large (evidence and relevance both scale with it).
    const auto once = detection_limits(data, data.size(), fit, {"voltage_offset", "deadtime"}, noise);
    const auto twice = detection_limits(data, data.size(), fit, {"voltage_offset", "deadtime"}, noise_of(0.04, 0.1, 400.0));
    REQUIRE(once.size() == twice.size());
    for (std::size_t k = 0; k < once.size(); ++k) CHECK(twice[k].limit == Approx(2.0 * once[k].limit).epsilon(1e-6));
    // Only the effect's sizes: the dead time's voltage, not its band.
    CHECK(limit_of(once, "deadtime.voltage").limit > 0.0);
    for (const auto& l : once) CHECK(l.parameter != "deadtime.current_band");
}

TEST_CASE("an effect the base model absorbs whole shows at no size", "[pmsm][diagnosis][detection_limits]") {
    // One speed, no d current: a u_q offset is a change of psi_f, a u_d offset is not.
    const Measurement data = held_points({{80.0, 0.0, 0.1}, {80.0, 0.0, 0.2}, {80.0, 0.0, -0.1}}, 30);
    const auto limits = detection_limits(data, data.size(), base_fit(data), {"voltage_offset"}, noise_of(0.02, 0.02, 180.0));
    CHECK(std::isinf(limit_of(limits, "voltage_offset.u_q").limit));
    CHECK(std::isfinite(limit_of(limits, "voltage_offset.u_d").limit));
}
