// The design questions alone (problems/pmsm/diagnosis/design.hpp): the unique fraction against an
// analytic projection, the design made of a measurement, hypothetical operating points and the
// experiments proposed.
#include <catch2/catch.hpp>

#include <limits>
#include <random>

#include <Eigen/Dense>

#include "problems/pmsm/diagnosis/design.hpp"
#include "tests/pmsm_synthetic_residual.hpp"

using namespace mhb::pmsm;
using namespace mhb::pmsm::testing;

TEST_CASE("the unique fraction is the part of a column outside the span of the others", "[pmsm][diagnosis][design]") {
    Eigen::MatrixXd axes = Eigen::MatrixXd::Zero(3, 2);
    axes(0, 0) = 5.0;  // scaled columns span the same plane
    axes(1, 1) = 0.01;
    CHECK(unique_fraction(axes, Eigen::Vector3d(1.0, 1.0, 1.0)) == Approx(1.0 / std::sqrt(3.0)));
    CHECK(unique_fraction(axes, Eigen::Vector3d(0.0, 0.0, 2.0)) == Approx(1.0));
    CHECK(unique_fraction(axes, Eigen::Vector3d(3.0, -4.0, 0.0)) == Approx(0.0).margin(1e-12));
    CHECK(std::isnan(unique_fraction(axes, Eigen::Vector3d::Zero())));
    CHECK(unique_fraction(Eigen::MatrixXd(3, 0), Eigen::Vector3d(1.0, 2.0, 3.0)) == 1.0);

    // Against the projection by the normal equations on random columns.
    std::mt19937_64 random(8);
    std::normal_distribution<double> normal;
    Eigen::MatrixXd others(40, 4);
    for (auto& x : others.reshaped()) x = normal(random);
    Eigen::VectorXd column(40);
    for (auto& x : column) x = normal(random);
    const Eigen::VectorXd coefficients = (others.transpose() * others).ldlt().solve(others.transpose() * column);
    const double expected = (column - others * coefficients).norm() / column.norm();
    CHECK(unique_fraction(others, column) == Approx(expected).epsilon(1e-9));
    // A column in their span, and a rank-deficient set of others.
    CHECK(unique_fraction(others, others * Eigen::Vector4d(1.0, -2.0, 0.5, 3.0)) < 1e-10);
    Eigen::MatrixXd repeated(40, 5);
    repeated << others, others.col(0) * 2.0;
    CHECK(unique_fraction(repeated, column) == Approx(expected).epsilon(1e-9));
}

TEST_CASE("the most distinct fraction ignores the parameters without a signature", "[pmsm][diagnosis][design]") {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    CHECK(most_distinct({nan, 0.2, 0.5, nan, 0.1}) == 0.5);
    CHECK(std::isnan(most_distinct({nan, nan})));
    CHECK(std::isnan(most_distinct({})));
}

TEST_CASE("the design holds each segment's currents and speed at their means and its temperatures on a line", "[pmsm][diagnosis][design]") {
    auto data = segmented_rows(3, 20);
    std::mt19937_64 random(6);
    data.i_d = white_noise(data.size(), 1.0, random);
    data.omega_e = white_noise(data.size(), 100.0, random);
    data.temp_winding = white_noise(data.size(), 1.0, random);
    for (Eigen::Index k = 0; k < data.size(); ++k) (*data.temp_winding)[k] += 40.0 + 0.5 * static_cast<double>(k % 20);
    const Measurement design = design_of(data);
    REQUIRE(design.size() == data.size());
    for (int s = 0; s < 3; ++s) {
        const auto i_d = design.i_d.segment(20 * s, 20), omega = design.omega_e.segment(20 * s, 20);
        CHECK((i_d.array() == i_d[0]).all());
        CHECK(i_d[0] == Approx(data.i_d.segment(20 * s, 20).mean()));
        CHECK(omega[0] == Approx(data.omega_e.segment(20 * s, 20).mean()));
        // A straight line through the segment's temperatures: constant steps, the same mean, the
        // least-squares residual orthogonal to time.
        const Eigen::VectorXd t = design.temp_winding->segment(20 * s, 20), logged = data.temp_winding->segment(20 * s, 20);
        const Eigen::VectorXd steps = t.tail(19) - t.head(19);
        CHECK((steps.array() - steps[0]).abs().maxCoeff() < 1e-9);
        CHECK(t.mean() == Approx(logged.mean()));
        const Eigen::VectorXd time = Eigen::VectorXd::LinSpaced(20, 0.0, 19.0);
        CHECK((logged - t).dot(time) == Approx(0.0).margin(1e-8));
    }
    // Without segments the samples are the design.
    auto unsegmented = data;
    unsegmented.segment_labels.clear();
    unsegmented.segment.resize(0);
    CHECK(design_of(unsegmented).i_d == data.i_d);
}

TEST_CASE("a hypothetical operating point is one electrical period with a logged angle, two rows without", "[pmsm][diagnosis][design]") {
    const OperatingPoint p{50.0, -1.0, 2.0, 60.0, 70.0};
    auto with_angle_logged = segmented_rows(2, 10, 1.0);
    with_angle_logged.temp_winding = Eigen::VectorXd::Zero(20);
    const Measurement a = with_point(with_angle_logged, p);
    REQUIRE(a.size() == 20 + 72);
    CHECK(a.segment_labels.back() == "hypothetical");
    CHECK((a.segment.tail(72).array() == 2).all());
    CHECK((a.i_q.tail(72).array() == 2.0).all());
    CHECK((a.omega_e.tail(72).array() == 50.0).all());
    CHECK((a.temp_winding->tail(72).array() == 60.0).all());
    CHECK((*a.theta_e)[20 + 18] == Approx(std::numbers::pi / 2.0));
    const Measurement b = with_point(segmented_rows(2, 10), p);
    CHECK(b.size() == 22);
    CHECK_FALSE(b.theta_e);
    // Logging the angle sweeps one period through each segment.
    const Measurement c = with_angle(segmented_rows(2, 4));
    REQUIRE(c.theta_e);
    CHECK((*c.theta_e)[5] == Approx(std::numbers::pi / 2.0));
}

TEST_CASE("the experiments proposed vary the fastest operating point, one condition at a time", "[pmsm][diagnosis][design]") {
    std::vector<SegmentConditions> segments(2);
    segments[0].omega = 100.0;
    segments[0].i_q = 1.0;
    segments[1].omega = -300.0;
    segments[1].i_d = -0.5;
    segments[1].i_q = -2.0;
    auto names = [](const std::vector<Proposal>& proposals) {
        std::vector<std::string> out;
        for (const auto& p : proposals) out.push_back(p.experiment.name);
        return out;
    };
    const auto data = segmented_rows(2, 10);
    const auto proposals = experiment_proposals(data, segments);
    CHECK(names(proposals) ==
          std::vector<std::string>{"another speed", "the other direction", "another d-axis current", "another load", "logging theta_e"});
    // The fastest point is segment 1: half its speed, then reversed with its torque.
    CHECK(proposals[0].experiment.description == "omega_e = -150 rad/s, i_d = -0.5 A, i_q = -2 A");
    CHECK(proposals[1].experiment.description == "omega_e = 300 rad/s, i_d = -0.5 A, i_q = 2 A");
    // More d-axis current than any segment by half the largest current, more load in the load's direction.
    const double largest = std::hypot(0.5, 2.0);
    CHECK(proposals[2].apply(data).i_d.tail(2)[0] == Approx(-0.5 - 0.5 * largest));
    CHECK(proposals[3].apply(data).i_q.tail(2)[0] == Approx(-2.0 - 0.5 * largest));
    auto with_temperatures = segmented_rows(2, 10, 1.0);
    with_temperatures.temp_magnet = Eigen::VectorXd::Zero(20);
    CHECK(names(experiment_proposals(with_temperatures, segments)).back() == "a temperature change");
}
