#include "problems/pmsm/diagnosis/noise.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include <Eigen/Cholesky>
#include <fmt/format.h>

#include "problems/pmsm/diagnosis/lack_of_fit.hpp"
#include "problems/pmsm/diagnosis/segments.hpp"
#include "problems/pmsm/diagnosis/shaft_angle.hpp"

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

WindowAngles::WindowAngles(const Measurement& data) : data_(data), logged_(data.theta_e.has_value()) {
    if (!logged_ && data.t) integrated_ = integrated_shaft_angle(data, 1);
}

bool WindowAngles::available() const { return logged_ || integrated_.size() == data_.size(); }

double WindowAngles::operator[](Eigen::Index row) const { return logged_ ? (*data_.theta_e)[row] : integrated_[row]; }

std::string WindowAngles::text() const { return available() ? (logged_ ? "the logged theta_e" : "omega_e integrated over t") : ""; }

WindowProjection::WindowProjection(const Measurement& data, const WindowAngles& angles, Eigen::Index first, Eigen::Index rows)
    : first_(first),
      bins_(angles.available() ? static_cast<int>(std::min<Eigen::Index>(window_noise_bins, rows / window_noise_rows_per_bin)) : 0),
      x_(rows), bin_(static_cast<std::size_t>(rows)), bin_sum_(static_cast<std::size_t>(bins_)), bin_rows_(static_cast<std::size_t>(bins_)) {
    const Eigen::Index m = rows;
    for (Eigen::Index k = 0; k < m; ++k) x_[k] = data.t ? (*data.t)[first + k] : static_cast<double>(k);
    if (m > 0) {
        const double mid = 0.5 * (x_[0] + x_[m - 1]), half = 0.5 * (x_[m - 1] - x_[0]);
        if (half > 0.0) x_.array() = (x_.array() - mid) / half;
        else x_.setZero();
    }
    for (Eigen::Index k = 0; k < m && bins_ > 0; ++k) {
        const double a = angles[first + k];
        const double turn = a / (2.0 * std::numbers::pi) - std::floor(a / (2.0 * std::numbers::pi));
        bin_[static_cast<std::size_t>(k)] = std::min(bins_ - 1, static_cast<int>(turn * bins_));
    }
    Eigen::Matrix3d gram = Eigen::Matrix3d::Zero();
    for (Eigen::Index k = 0; k < m; ++k) {
        const Eigen::Vector3d p(1.0, x_[k], x_[k] * x_[k]);
        gram += p * p.transpose();
    }
    trend_.compute(gram);
}

bool WindowProjection::leaves_noise() const {
    const Eigen::Index m = x_.size();
    return m >= 8 && m - 3 - bins_ >= m / 2;
}

// Alternating projections onto two nearly orthogonal spaces, which converge to the projection onto
// their sum (four rounds; the tests hold the noise within 3-4 % of the truth with them).
int WindowProjection::remove(Eigen::Ref<Eigen::VectorXd> r) {
    const Eigen::Index n = r.size();
    int used = 0;
    for (int round = 0; round < (bins_ > 0 ? 4 : 1); ++round) {
        Eigen::Vector3d moment = Eigen::Vector3d::Zero();
        for (Eigen::Index k = 0; k < n; ++k) moment += r[k] * Eigen::Vector3d(1.0, x_[k], x_[k] * x_[k]);
        const Eigen::Vector3d c = trend_.solve(moment);
        for (Eigen::Index k = 0; k < n; ++k) r[k] -= c[0] + x_[k] * (c[1] + x_[k] * c[2]);
        if (bins_ == 0) continue;
        std::fill(bin_sum_.begin(), bin_sum_.end(), 0.0);
        std::fill(bin_rows_.begin(), bin_rows_.end(), 0);
        for (Eigen::Index k = 0; k < n; ++k) {
            bin_sum_[static_cast<std::size_t>(bin_[static_cast<std::size_t>(k)])] += r[k];
            ++bin_rows_[static_cast<std::size_t>(bin_[static_cast<std::size_t>(k)])];
        }
        for (Eigen::Index k = 0; k < n; ++k) {
            const auto b = static_cast<std::size_t>(bin_[static_cast<std::size_t>(k)]);
            r[k] -= bin_sum_[b] / bin_rows_[b];
        }
        used = static_cast<int>(std::count_if(bin_rows_.begin(), bin_rows_.end(), [](int m) { return m > 0; }));
    }
    return 3 + used;
}

namespace {

struct WindowVariance {
    double variance = 0.0, correlation = 0.0, dof = 0.0;
};

// The median of `field` over `windows`, each weighted by its degrees of freedom (sorts them): a
// window whose structure the bins could not resolve (a short one at speed, a few bins across a
// large ripple) is an outlier among windows that agree, not a share of a pooled sum.
double weighted_median(std::vector<WindowVariance>& windows, double WindowVariance::*field) {
    std::sort(windows.begin(), windows.end(), [&](const auto& a, const auto& b) { return a.*field < b.*field; });
    double total = 0.0;
    for (const auto& w : windows) total += w.dof;
    double below = 0.0;
    for (const auto& w : windows) {
        below += w.dof;
        if (below >= 0.5 * total) return w.*field;
    }
    return windows.back().*field;
}

}  // namespace

WindowNoise window_noise(const Measurement& data, const ModelFit& fit) {
    Eigen::VectorXd storage;
    return window_noise(data, residual_of(data, fit, storage));
}

WindowNoise window_noise(const Measurement& data, const Eigen::VectorXd& residual) {
    const Eigen::Index n = data.size();
    WindowNoise noise;
    const WindowAngles angles(data);
    Eigen::VectorXd r;
    // Per window and axis: variance, lag-one correlation, degrees of freedom.
    std::array<std::vector<WindowVariance>, 2> windows;
    for (const auto& segment : segment_ranges(data)) {
        // A longer segment is measured on its middle rows only (noise.hpp): a fixed cost a segment.
        const Eigen::Index m = std::min(segment.rows, window_noise_max_rows);
        WindowProjection projection(data, angles, segment.first + (segment.rows - m) / 2, m);
        if (!projection.leaves_noise()) continue;
        for (int axis = 0; axis < 2; ++axis) {
            r = residual.segment(axis * n + projection.first(), m);
            const double dof = static_cast<double>(m - projection.remove(r));
            const double square = r.squaredNorm();
            windows[axis].push_back({square / dof, square > 0.0 ? r.head(m - 1).dot(r.tail(m - 1)) / square : 0.0, dof});
        }
    }
    noise.angle = angles.text();
    if (windows[0].empty()) return noise;
    for (int axis = 0; axis < 2; ++axis) {
        auto& w = windows[axis];
        noise.sigma[axis] = std::sqrt(weighted_median(w, &WindowVariance::variance));
        noise.correlation[axis] = std::clamp(weighted_median(w, &WindowVariance::correlation), 0.0, 0.9);
    }
    for (const auto& w : windows[0]) noise.dof += w.dof;
    return noise;
}

std::string window_noise_method(const WindowNoise& noise) {
    return "the residual of the model diagnosed or of the best fit, the lower, within segments less each segment's quadratic trend in time" +
           (noise.angle.empty() ? std::string(", no angle (neither theta_e nor t is logged); the median over segments")
                                : fmt::format(" and its means in up to {} bins of the electrical angle, from {}; the median over segments",
                                              window_noise_bins, noise.angle));
}

double likelihood_ratio(const ModelFit& model, const ModelFit& candidate, const NoiseEstimate& noise) {
    double lr = 0.0;
    for (int a = 0; a < 2; ++a) lr += (model.rss_axis(a) - candidate.rss_axis(a)) / (noise.long_run[a] * noise.long_run[a]);
    return lr / noise.dispersion;
}

NoiseEstimate noise_of_best(const Measurement& data, const std::vector<const ModelFit*>& fits, const WindowNoise& window) {
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
    // The lower of the two on each axis: what a model leaves that is neither slow nor locked to the
    // angle can only add to the noise.
    noise.window = window;
    const WindowNoise on_best = window_noise(data, residual);
    for (int a = 0; a < 2; ++a)
        if (on_best.dof > 0.0 && (!(window.dof > 0.0) || on_best.sigma[a] < window.sigma[a])) {
            noise.window.sigma[a] = on_best.sigma[a];
            noise.window.correlation[a] = on_best.correlation[a];
        }
    // A residual well above the data's own noise holds structure (transients, a misfit within
    // segments) that would set the floor too high and hide effects: the evidence is then measured
    // in the noise of the data, first-order correlated as measured.
    noise.effective_samples = 0.0;
    for (int a = 0; a < 2; ++a) {
        const double s = noise.window.sigma[a], rho = noise.window.correlation[a];
        if (s > 0.0 && noise.sigma[a] > residual_structure_ratio * s) {
            noise.from_windows[a] = true;
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
