#include "problems/pmsm/diagnosis/noise.hpp"

#include <algorithm>
#include <cmath>

#include "problems/pmsm/diagnosis/lack_of_fit.hpp"
#include "problems/pmsm/diagnosis/segments.hpp"

namespace mhb::pmsm {

// Takes its own copy of the fit's residual, or moves the one it recomputes: on a long log this
// holds one row-sized array, not two.
NoiseEstimate estimate_noise(const Measurement& data, const ModelFit& fit) {
    const Eigen::Index n = data.size();
    const auto ranges = segment_ranges(data);
    Eigen::VectorXd storage;
    const Eigen::VectorXd& residual = residual_of(data, fit, storage);
    Eigen::VectorXd within = &residual == &storage ? std::move(storage) : residual;
    for (int a = 0; a < 2; ++a)
        for (const auto& r : ranges) {
            auto block = within.segment(a * n + r.first, r.rows);
            block.array() -= block.mean();
        }
    // The long-run variance of each axis' mean: the regression on one indicator per axis.
    RegressorBlocks indicators;
    indicators.columns = 2;
    indicators.fill = [](Eigen::Index, Eigen::Ref<Eigen::MatrixXd> rows) {
        const Eigen::Index size = rows.rows() / 2;
        rows.topRows(size).col(0).setOnes();
        rows.topRows(size).col(1).setZero();
        rows.bottomRows(size).col(0).setZero();
        rows.bottomRows(size).col(1).setOnes();
    };
    RowLayout layout;
    layout.samples = n;
    layout.axes = 2;
    if (data.has_segments()) layout.block = data.segment;
    const auto u = residual_uncertainty(indicators, within, Eigen::Vector2d::Zero(), layout, CovarianceMethod::NeweyWest);
    NoiseEstimate noise;
    noise.model = fit.spec.text();
    for (int a = 0; a < 2; ++a) {
        noise.sigma[a] = std::sqrt(within.segment(a * n, n).squaredNorm() / static_cast<double>(n));
        noise.long_run[a] = std::sqrt(std::max(u.covariance(a, a), 0.0) * static_cast<double>(n));
        // Correlation can only cost information here; a negative one is taken as none.
        noise.long_run[a] = std::max(noise.long_run[a], noise.sigma[a]);
        noise.effective_samples += static_cast<double>(n) * std::pow(noise.sigma[a] / noise.long_run[a], 2);
    }
    return noise;
}

void difference_noise(const Measurement& data, const Eigen::VectorXd& residual, NoiseEstimate& noise) {
    const Eigen::Index n = data.size();
    const auto same_segment = [&](Eigen::Index a, Eigen::Index b) { return !data.has_segments() || data.segment[a] == data.segment[b]; };
    for (int a = 0; a < 2; ++a) {
        const auto u = residual.segment(a * n, n);
        double g0 = 0.0, g1 = 0.0;
        Eigen::Index pairs = 0, lagged = 0;
        for (Eigen::Index k = 1; k < n; ++k) {
            if (!same_segment(k - 1, k)) continue;
            const double d = u[k] - u[k - 1];
            g0 += d * d;
            ++pairs;
            if (k >= 2 && same_segment(k - 2, k - 1)) {
                g1 += d * (u[k - 1] - u[k - 2]);
                ++lagged;
            }
        }
        if (pairs == 0) continue;
        g0 /= static_cast<double>(pairs);
        const double r = lagged > 0 && g0 > 0.0 ? g1 / static_cast<double>(lagged) / g0 : -0.5;
        const double rho = std::clamp(1.0 + 2.0 * r, 0.0, 0.9);
        noise.difference_sigma[a] = std::sqrt(g0 / (2.0 * (1.0 - rho)));
        noise.difference_correlation[a] = rho;
        noise.difference_pairs = static_cast<double>(pairs);
    }
}

double likelihood_ratio(const ModelFit& model, const ModelFit& candidate, const NoiseEstimate& noise) {
    double lr = 0.0;
    for (int a = 0; a < 2; ++a) lr += (model.rss_axis(a) - candidate.rss_axis(a)) / (noise.long_run[a] * noise.long_run[a]);
    return lr / noise.dispersion;
}

NoiseEstimate noise_of_best(const Measurement& data, const std::vector<const ModelFit*>& fits) {
    // Only a physically possible machine measures the noise: a flexible effect that buys a lower
    // residual with a negative inductance has fitted the noise itself (on two operating points the
    // saturation law's incremental inductances follow the controller's correlation of current and
    // voltage noise), and would set the floor below the sensors'.
    const auto possible = [](const ModelFit* f) { return f->values.size() < 4 || (f->values.head<4>().array() > 0.0).all(); };
    const ModelFit* best = fits.front();
    for (const auto* f : fits)
        if (possible(f) && (f->rss() < best->rss() || !possible(best))) best = f;
    NoiseEstimate noise = estimate_noise(data, *best);
    Eigen::VectorXd storage;
    const Eigen::VectorXd& residual = residual_of(data, *best, storage);
    difference_noise(data, residual, noise);
    // A residual well above the data's own noise holds structure (transients, a misfit within
    // segments) that would set the floor too high and hide effects: the evidence is then measured
    // in the noise of the data, first-order correlated as measured.
    noise.effective_samples = 0.0;
    for (int a = 0; a < 2; ++a) {
        const double s = noise.difference_sigma[a], rho = noise.difference_correlation[a];
        if (s > 0.0 && noise.sigma[a] > residual_structure_ratio * s) {
            noise.from_differences[a] = true;
            noise.sigma[a] = s;
            noise.long_run[a] = s * std::sqrt((1.0 + rho) / (1.0 - rho));
        }
        noise.effective_samples += static_cast<double>(data.size()) * std::pow(noise.sigma[a] / noise.long_run[a], 2);
    }
    const LackOfFit l = lack_of_fit(data, *best, residual, noise);
    if (l.means_available) noise.dispersion = std::max(1.0, l.statistic / l.dof);
    return noise;
}

}  // namespace mhb::pmsm
