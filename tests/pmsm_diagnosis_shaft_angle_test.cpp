// The shaft's mechanical angle for the harmonics at mechanical orders
// (problems/pmsm/diagnosis/shaft_angle.hpp): integrated from the speed against the exact angle, the
// electrical angle's steps, the pole pairs from two logged angles, and what is said without them.
#include <catch2/catch.hpp>

#include <random>

#include "problems/pmsm/diagnosis/shaft_angle.hpp"
#include "tests/pmsm_synthetic_residual.hpp"

using namespace mhb::pmsm;
using namespace mhb::pmsm::testing;

namespace {

// The largest difference between `angle` and the exact angle's travel since each segment's first row.
double largest_error(const Measurement& data, const Eigen::VectorXd& angle, const Eigen::VectorXd& exact) {
    double error = 0.0;
    for (const auto& r : segment_ranges(data))
        for (Eigen::Index k = r.first; k < r.first + r.rows; ++k) error = std::max(error, std::abs(angle[k] - (exact[k] - exact[r.first])));
    return error;
}

}  // namespace

TEST_CASE("the speed integrated over time within each segment follows the exact shaft angle", "[pmsm][diagnosis][shaft_angle]") {
    const int p = 4;
    const double dt = 1e-3;
    auto shaft = turning_shaft(4, 3000, dt, p, 2.5);
    shaft.data.theta_e.reset();
    const Eigen::VectorXd angle = integrated_shaft_angle(shaft.data, p);
    // The trapezoidal rule errs by at most dt^3 max|theta'''| / 12 a step, summed over a segment's steps.
    const double bound = 3000.0 * dt * dt * dt * shaft.third_derivative / 12.0;
    INFO("bound " << bound);
    CHECK(largest_error(shaft.data, angle, shaft.exact) <= bound);
    // A wrong integral misses it: the speed divided by a pole pair too many.
    CHECK(largest_error(shaft.data, integrated_shaft_angle(shaft.data, p + 1), shaft.exact) > 100.0 * bound);
}

TEST_CASE("with theta_e logged each step is the electrical angle's, exact even on a noisy speed", "[pmsm][diagnosis][shaft_angle]") {
    const int p = 16;
    auto shaft = turning_shaft(3, 2000, 1e-3, p, 1.5);
    std::mt19937_64 random(3);
    // Speed noise of 5 % of the speed: its steps err by far less than pi electrical, which the angle settles.
    const Eigen::VectorXd noise = white_noise(shaft.data.size(), 0.05 * std::abs(shaft.data.omega_e[0]), random);
    shaft.data.omega_e += noise;
    const Eigen::VectorXd angle = integrated_shaft_angle(shaft.data, p);
    CHECK(largest_error(shaft.data, angle, shaft.exact) < 1e-9);
    shaft.data.theta_e.reset();
    CHECK(largest_error(shaft.data, integrated_shaft_angle(shaft.data, p), shaft.exact) > 1e-4);  // the noise's walk, without the angle
}

TEST_CASE("the shaft angle is the logged theta_m, or integrated, or none with the reason", "[pmsm][diagnosis][shaft_angle]") {
    const int p = 4;
    auto shaft = turning_shaft(2, 500, 1e-3, p, 1.0);
    SECTION("integrated when theta_m is not logged and the pole pairs are known") {
        const ShaftAngle s = shaft_angle(shaft.data, p);
        REQUIRE(s.available());
        CHECK_FALSE(s.logged);
        CHECK_THAT(s.source, Catch::Contains("integrated from omega_e over t"));
    }
    SECTION("the logged theta_m, and the pole pairs from theta_e and theta_m when not given") {
        shaft.data.theta_m = Eigen::VectorXd(shaft.data.size());
        for (Eigen::Index k = 0; k < shaft.data.size(); ++k) (*shaft.data.theta_m)[k] = wrap_angle(shaft.exact[k]);
        const ShaftAngle s = shaft_angle(shaft.data, 0);
        REQUIRE(s.available());
        CHECK(s.logged);
        CHECK(s.pole_pairs == p);
        CHECK(s.angle == *shaft.data.theta_m);
        CHECK_THAT(s.source, Catch::Contains("4 pole pairs from the logged theta_e and theta_m"));
    }
    SECTION("none without the pole pairs, and none without t to integrate over") {
        const ShaftAngle unknown = shaft_angle(shaft.data, 0);
        CHECK_FALSE(unknown.available());
        CHECK_THAT(unknown.source, Catch::Contains("pole-pair count is not known"));
        shaft.data.t.reset();
        const ShaftAngle untimed = shaft_angle(shaft.data, p);
        CHECK_FALSE(untimed.available());
        CHECK_THAT(untimed.source, Catch::Contains("neither theta_m nor t"));
    }
}
