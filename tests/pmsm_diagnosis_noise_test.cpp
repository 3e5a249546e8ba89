// The noise estimate alone (problems/pmsm/diagnosis/noise.hpp) on residuals made by hand with a known
// standard deviation and long-run variance.
#include <catch2/catch.hpp>

#include "problems/pmsm/diagnosis/noise.hpp"
#include "tests/pmsm_synthetic_residual.hpp"

using namespace mhb::pmsm;
using namespace mhb::pmsm::testing;

namespace {

// AR(1), x_k = phi x_{k-1} + e_k with e of standard deviation `innovation`, started stationary.
Eigen::VectorXd ar1(Eigen::Index n, double phi, double innovation, std::mt19937_64& random) {
    const Eigen::VectorXd e = white_noise(n, innovation, random);
    Eigen::VectorXd x(n);
    x[0] = e[0] / std::sqrt(1.0 - phi * phi);
    for (Eigen::Index k = 1; k < n; ++k) x[k] = phi * x[k - 1] + e[k];
    return x;
}

}  // namespace

TEST_CASE("on white noise the estimate finds its standard deviation, no serial correlation and every sample", "[pmsm][diagnosis][noise]") {
    std::mt19937_64 random(11);
    const auto data = segmented_rows(10, 2000);
    const Eigen::Index n = data.size();
    Eigen::VectorXd residual = white_residual(n, 0.01, 0.03, random);
    // Segment offsets are the model's failure, not noise: they must not count.
    for (Eigen::Index k = 0; k < n; ++k) residual[k] += 0.5 * data.segment[k];
    const NoiseEstimate noise = estimate_noise(data, fit_with_residual(data, residual));
    CHECK(noise.model == "base");
    CHECK(noise.sigma[0] == Approx(0.01).epsilon(0.03));
    CHECK(noise.sigma[1] == Approx(0.03).epsilon(0.03));
    CHECK(noise.long_run[0] == Approx(0.01).epsilon(0.1));
    CHECK(noise.long_run[1] == Approx(0.03).epsilon(0.1));
    CHECK(noise.long_run[0] >= noise.sigma[0]);
    CHECK(noise.effective_samples == Approx(2.0 * static_cast<double>(n)).epsilon(0.2));
    CHECK(noise.dispersion == 1.0);
}

TEST_CASE("on AR(1) noise the long-run standard deviation is innovation / (1 - phi)", "[pmsm][diagnosis][noise]") {
    std::mt19937_64 random(5);
    const double phi = 0.6, innovation = 0.02;
    const auto data = segmented_rows(8, 5000);
    const Eigen::Index n = data.size();
    Eigen::VectorXd residual(2 * n);
    residual.head(n) = ar1(n, phi, innovation, random);
    residual.tail(n) = ar1(n, phi, innovation, random);
    const NoiseEstimate noise = estimate_noise(data, fit_with_residual(data, residual));
    const double marginal = innovation / std::sqrt(1.0 - phi * phi), long_run = innovation / (1.0 - phi);
    for (int a = 0; a < 2; ++a) {
        CHECK(noise.sigma[a] == Approx(marginal).epsilon(0.03));
        CHECK(noise.long_run[a] == Approx(long_run).epsilon(0.12));
    }
    // Each sample is worth (1 - phi)^2 / (1 - phi^2) = 0.25 of an independent one.
    CHECK(noise.effective_samples == Approx(2.0 * static_cast<double>(n) * 0.25).epsilon(0.25));
}

TEST_CASE("the likelihood ratio is the fall in RSS in long-run variances, divided by the dispersion", "[pmsm][diagnosis][noise]") {
    ModelFit model, candidate;
    model.axis_rss = {10.0, 20.0};
    candidate.axis_rss = {6.0, 11.0};
    NoiseEstimate noise;
    noise.long_run = {2.0, 3.0};
    CHECK(likelihood_ratio(model, candidate, noise) == Approx(4.0 / 4.0 + 9.0 / 9.0));
    noise.dispersion = 4.0;
    CHECK(likelihood_ratio(model, candidate, noise) == Approx(0.5));
}

TEST_CASE("the noise is measured on the best-fitting model, with the overdispersion its segment means leave", "[pmsm][diagnosis][noise]") {
    std::mt19937_64 random(3);
    const auto data = segmented_rows(12, 400);
    const Eigen::Index n = data.size();
    const Eigen::VectorXd clean = white_residual(n, 0.01, 0.01, random);
    Eigen::VectorXd offset = clean;
    for (Eigen::Index k = 0; k < n; ++k) offset[k] += 0.005 * (data.segment[k] % 2 == 0 ? 1.0 : -1.0);
    ModelFit worse = fit_with_residual(data, offset), better = fit_with_residual(data, clean);
    worse.spec = parse_model_spec("base+deadtime");
    const NoiseEstimate on_clean = noise_of_best(data, {&worse, &better}, window_noise(data, better));
    CHECK(on_clean.model == "base");
    CHECK(on_clean.dispersion < 2.0);  // chi^2 / dof of pure noise: 1 give or take sqrt(2 / 24)
    // Alone, the fit that leaves offsets between segments: 400 rows x (5 mV)^2 / (10 mV)^2 = 100 per mean.
    const NoiseEstimate on_offsets = noise_of_best(data, {&worse}, window_noise(data, worse));
    CHECK(on_offsets.model == "base+deadtime");
    CHECK(on_offsets.dispersion > 20.0);
}

namespace {

// A ripple locked to the electrical angle: a 6th harmonic five times the noise (the current ripple
// of the steady model's missing L di/dt) and dead time's steps at each sixth of a turn, as large as
// the noise.
double ripple(double angle, double noise) {
    return noise * (5.0 * std::sin(6.0 * angle + 0.4) + (std::sin(3.0 * angle) >= 0.0 ? 1.0 : -1.0));
}

}  // namespace

TEST_CASE("the data's noise is found under each segment's offset, trend and ripple locked to the angle", "[pmsm][diagnosis][noise]") {
    std::mt19937_64 random(17);
    const Eigen::Index rows = 3000;
    const auto data = segmented_rows(10, rows, 25.37);  // 118 rows a turn, the angles drifting from turn to turn
    const Eigen::Index n = data.size();
    Eigen::VectorXd residual = white_residual(n, 0.01, 0.03, random);
    for (Eigen::Index k = 0; k < n; ++k) {
        const double x = static_cast<double>(k % rows) / static_cast<double>(rows);
        residual[k] += 0.5 * data.segment[k] + 0.2 * x * x + ripple((*data.theta_e)[k], 0.01);
        residual[n + k] += -0.3 * data.segment[k] - 0.1 * x + ripple((*data.theta_e)[k] + 1.0, 0.03);
    }
    const WindowNoise noise = window_noise(data, fit_with_residual(data, residual));
    CHECK(noise.angle == "the logged theta_e");
    // What the bins leave: a step of h = 2 sigma keeps h^2 / 6 in the 6 of 256 bins it straddles
    // (1.6 % of the noise's variance), the sine its slope across a bin, (5 sigma 6 2 pi / 256)^2 / 12
    // (4.5 %): about 3 % of the standard deviation.
    CHECK(noise.sigma[0] == Approx(0.01).epsilon(0.04));
    CHECK(noise.sigma[1] == Approx(0.03).epsilon(0.04));
    CHECK(noise.correlation[0] < 0.05);
    CHECK(noise.dof == Approx(static_cast<double>(n - 10 * (256 + 3))));
    // The residual's own standard deviation within segments holds the ripple: five times the noise.
    CHECK(estimate_noise(data, fit_with_residual(data, residual)).sigma[0] > 3.0 * 0.01);
}

TEST_CASE("without theta_e the angle is omega_e integrated over t, and without t either the trend alone is removed", "[pmsm][diagnosis][noise]") {
    std::mt19937_64 random(19);
    const Eigen::Index rows = 2000;
    auto data = segmented_rows(6, rows);
    const Eigen::Index n = data.size();
    data.t = Eigen::VectorXd(n);
    Eigen::VectorXd residual = white_residual(n, 0.02, 0.02, random);
    for (Eigen::Index k = 0; k < n; ++k) {
        const double t = 1e-4 * static_cast<double>(k), omega = 400.0 + 50.0 * data.segment[k];
        (*data.t)[k] = t;
        data.omega_e[k] = omega;
        residual[k] += ripple(omega * t, 0.02);
    }
    const WindowNoise integrated = window_noise(data, fit_with_residual(data, residual));
    CHECK(integrated.angle == "omega_e integrated over t");
    CHECK(integrated.sigma[0] == Approx(0.02).epsilon(0.04));
    data.t.reset();
    const WindowNoise trend_only = window_noise(data, fit_with_residual(data, residual));
    CHECK(trend_only.angle.empty());
    CHECK(trend_only.sigma[0] > 2.5 * 0.02);  // the ripple stays: nothing tells it from noise
    CHECK(trend_only.sigma[1] == Approx(0.02).epsilon(0.04));
}

TEST_CASE("on AR(1) noise the data's noise is its marginal standard deviation and phi its lag-one correlation", "[pmsm][diagnosis][noise]") {
    std::mt19937_64 random(23);
    const double phi = 0.6, innovation = 0.02;
    const auto data = segmented_rows(8, 5000, 12.3);
    const Eigen::Index n = data.size();
    Eigen::VectorXd residual(2 * n);
    residual.head(n) = ar1(n, phi, innovation, random);
    residual.tail(n) = ar1(n, phi, innovation, random);
    const WindowNoise noise = window_noise(data, fit_with_residual(data, residual));
    for (int a = 0; a < 2; ++a) {
        // A bin's rows lie a turn (406 rows) apart, so its mean spends the share of the variance
        // that the degrees of freedom count, correlated noise or not.
        CHECK(noise.sigma[a] == Approx(innovation / std::sqrt(1.0 - phi * phi)).epsilon(0.03));
        CHECK(noise.correlation[a] == Approx(phi).margin(0.05));
    }
}

TEST_CASE("a short segment whose ripple the bins cannot resolve does not move the data's noise", "[pmsm][diagnosis][noise]") {
    // Nine long segments, then one of 120 rows at speed, turning 30 times: 15 bins, four rows a turn.
    std::mt19937_64 random(29);
    const Eigen::Index rows = 2400, n = 9 * rows + 120;
    Measurement data = segmented_rows(1, n, 0.0);
    data.theta_e = Eigen::VectorXd(n);
    data.segment_labels = {"s0"};
    for (Eigen::Index k = 0; k < n; ++k) {
        data.segment[k] = k < 9 * rows ? static_cast<int>(k / rows) : 9;
        const double turns = k < 9 * rows ? 20.3 * static_cast<double>(k % rows) / rows : 30.0 * static_cast<double>(k - 9 * rows) / 120.0;
        (*data.theta_e)[k] = wrap_angle(2.0 * std::numbers::pi * turns);
    }
    for (int s = 1; s < 10; ++s) data.segment_labels.push_back("s" + std::to_string(s));
    Eigen::VectorXd residual = white_residual(n, 0.01, 0.01, random);
    for (Eigen::Index k = 9 * rows; k < n; ++k) residual[k] += ripple(7.0 * (*data.theta_e)[k], 0.2);
    const WindowNoise noise = window_noise(data, fit_with_residual(data, residual));
    CHECK(noise.sigma[0] == Approx(0.01).epsilon(0.03));
}

TEST_CASE("a segment longer than window_noise_max_rows is measured on its middle rows", "[pmsm][diagnosis][noise]") {
    std::mt19937_64 random(31);
    const Eigen::Index rows = 100000, middle = window_noise_max_rows, first = (rows - middle) / 2;
    const auto data = segmented_rows(1, rows, 300.7);
    Eigen::VectorXd residual = white_residual(rows, 0.05, 0.05, random);
    residual.segment(first, middle) *= 0.2;  // 0.01 in the middle rows only
    const WindowNoise noise = window_noise(data, fit_with_residual(data, residual));
    CHECK(noise.sigma[0] == Approx(0.01).epsilon(0.03));
    CHECK(noise.sigma[1] == Approx(0.05).epsilon(0.03));
    CHECK(noise.dof == Approx(static_cast<double>(middle - window_noise_bins - 3)));
}
