// The lack-of-fit test alone (problems/pmsm/diagnosis/lack_of_fit.hpp) on residuals made by hand: its
// p-value on pure noise, planted segment means and a planted harmonic of the electrical angle.
#include <catch2/catch.hpp>

#include "problems/pmsm/diagnosis/lack_of_fit.hpp"
#include "problems/pmsm/diagnosis/verdict.hpp"
#include "tests/pmsm_synthetic_residual.hpp"

using namespace mhb::pmsm;
using namespace mhb::pmsm::testing;

namespace {

// The noise as it is, not as estimated: the test is of lack_of_fit alone.
NoiseEstimate known_noise(double sigma) {
    NoiseEstimate noise;
    noise.sigma = {sigma, sigma};
    noise.long_run = {sigma, sigma};
    return noise;
}

}  // namespace

TEST_CASE("on pure noise the segment-mean p-value is uniform over seeds", "[pmsm][diagnosis][lack_of_fit]") {
    const auto data = segmented_rows(8, 50);
    const auto noise = known_noise(0.01);
    int below_tenth = 0, below_half = 0, significant = 0;
    constexpr int seeds = 200;
    for (int seed = 0; seed < seeds; ++seed) {
        std::mt19937_64 random(static_cast<std::uint64_t>(seed));
        const Eigen::VectorXd residual = white_residual(data.size(), 0.01, 0.01, random);
        const LackOfFit l = lack_of_fit(data, fit_with_residual(data, residual), residual, noise);
        REQUIRE(l.means_available);
        REQUIRE(l.dof == 16);  // two means per segment, no free parameter
        below_tenth += l.p_value < 0.1 ? 1 : 0;
        below_half += l.p_value < 0.5 ? 1 : 0;
        significant += l.significant ? 1 : 0;
    }
    // Binomial(200, p): three standard deviations either side.
    CHECK(below_tenth >= 8);
    CHECK(below_tenth <= 33);
    CHECK(below_half >= 79);
    CHECK(below_half <= 121);
    CHECK(significant <= 2);
}

TEST_CASE("free parameters take their degrees of freedom from the segment means", "[pmsm][diagnosis][lack_of_fit]") {
    const auto data = segmented_rows(2, 50);
    std::mt19937_64 random(1);
    const Eigen::VectorXd residual = white_residual(data.size(), 0.01, 0.01, random);
    ModelFit fit = fit_with_residual(data, residual);
    fit.free = {true, true, true};
    const LackOfFit l = lack_of_fit(data, fit, residual, known_noise(0.01));
    CHECK(l.dof == 1);
    CHECK(l.means_available);
    fit.free.push_back(true);
    const LackOfFit none = lack_of_fit(data, fit, residual, known_noise(0.01));
    CHECK_FALSE(none.means_available);
    CHECK(none.p_value == 1.0);
}

TEST_CASE("segment means beyond the noise are significant and named by the condition they follow", "[pmsm][diagnosis][lack_of_fit]") {
    auto data = segmented_rows(6, 100);
    const Eigen::Index n = data.size();
    std::mt19937_64 random(2);
    Eigen::VectorXd residual = white_residual(n, 0.01, 0.01, random);
    for (Eigen::Index k = 0; k < n; ++k) {
        data.i_d[k] = -0.1 * data.segment[k];
        residual[k] += 0.01 * data.segment[k];  // u_d means rising as i_d falls: up to 50 mV
    }
    const LackOfFit l = lack_of_fit(data, fit_with_residual(data, residual), residual, known_noise(0.01));
    CHECK(l.p_value < evidence::significance);
    CHECK(l.significant);
    CHECK(l.structure > 0.0);
    CHECK_THAT(l.signature, Catch::StartsWith("segment means of the u_d residual up to"));
    CHECK_THAT(l.signature, Catch::Contains("following i_d (r = -1.00)"));
    CHECK_THAT(l.signature, Catch::Contains("; segment means of the u_q residual"));
}

TEST_CASE("a harmonic of the electrical angle planted in noise is found at its order, with its amplitude", "[pmsm][diagnosis][lack_of_fit]") {
    const auto data = segmented_rows(6, 720, 10.0);
    const Eigen::Index n = data.size();
    std::mt19937_64 random(4);
    Eigen::VectorXd residual = white_residual(n, 0.01, 0.01, random);
    for (Eigen::Index k = 0; k < n; ++k) residual[k] += 0.004 * std::cos(3.0 * (*data.theta_e)[k] + 0.5);
    const auto noise = known_noise(0.01);
    const LackOfFit l = lack_of_fit(data, fit_with_residual(data, residual), residual, noise);
    REQUIRE(l.harmonics.size() == static_cast<std::size_t>(harmonic_orders));
    const double threshold = evidence::significance / (2.0 * harmonic_orders);
    for (const auto& h : l.harmonics) {
        if (h.order == 3) {
            CHECK(h.p_value < threshold);
            CHECK(h.amplitude[0] == Approx(0.004).epsilon(0.1));
            CHECK(h.amplitude[1] < 5.0 * h.standard_error);
        } else {
            CHECK(h.p_value >= threshold);
        }
        // Each amplitude component of a least-squares harmonic on n rows spread evenly over the angle: sigma sqrt(2 / n).
        CHECK(h.standard_error == Approx(0.01 * std::sqrt(2.0 / static_cast<double>(n))).epsilon(0.02));
    }
    CHECK(l.significant);
    CHECK_THAT(l.signature, Catch::StartsWith("harmonic 3 of the electrical angle"));
    // Its power, half the squared amplitude on one axis of two, against the noise's.
    CHECK(l.structure == Approx(0.5 * 0.004 * 0.004 / (2.0 * 0.01 * 0.01)).epsilon(0.2));
}

TEST_CASE("on pure noise no harmonic of the electrical angle is significant", "[pmsm][diagnosis][lack_of_fit]") {
    const auto data = segmented_rows(4, 360, 5.0);
    int significant = 0;
    for (int seed = 0; seed < 50; ++seed) {
        std::mt19937_64 random(static_cast<std::uint64_t>(1000 + seed));
        const Eigen::VectorXd residual = white_residual(data.size(), 0.01, 0.01, random);
        significant += lack_of_fit(data, fit_with_residual(data, residual), residual, known_noise(0.01)).significant ? 1 : 0;
    }
    // The whole test is at the 1e-3 level (means) plus 1e-3 over all harmonics.
    CHECK(significant <= 2);
}

TEST_CASE("the chi-squared survival function", "[pmsm][diagnosis][lack_of_fit]") {
    CHECK(chi_squared_survival(2.0 * std::log(2.0), 2.0) == Approx(0.5));  // exp(-x / 2) for two degrees of freedom
    CHECK(chi_squared_survival(-1.0, 3.0) == 1.0);
    CHECK(chi_squared_survival(5.0, 0.0) == 1.0);
}
