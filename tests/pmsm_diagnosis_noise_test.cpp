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
    const NoiseEstimate on_clean = noise_of_best(data, {&worse, &better});
    CHECK(on_clean.model == "base");
    CHECK(on_clean.dispersion < 2.0);  // chi^2 / dof of pure noise: 1 give or take sqrt(2 / 24)
    // Alone, the fit that leaves offsets between segments: 400 rows x (5 mV)^2 / (10 mV)^2 = 100 per mean.
    const NoiseEstimate on_offsets = noise_of_best(data, {&worse});
    CHECK(on_offsets.model == "base+deadtime");
    CHECK(on_offsets.dispersion > 20.0);
}
