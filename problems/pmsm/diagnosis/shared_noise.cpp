#include "problems/pmsm/diagnosis/shared_noise.hpp"

#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Cholesky>
#include <fmt/format.h>

#include "problems/pmsm/diagnosis/noise.hpp"
#include "problems/pmsm/diagnosis/segments.hpp"
#include "problems/pmsm/model/steady_state_model.hpp"

namespace mhb::pmsm {

bool SharedNoise::relevant() const {
    for (Eigen::Index j = 0; j < 4; ++j)
        if (windows >= 3 && bias[j] != 0.0 && std::abs(bias[j]) >= 0.25 * fit_standard_error[j] && std::abs(bias[j]) >= 2.0 * standard_error[j])
            return true;
    return false;
}

std::pair<double, double> SharedNoise::corrected_interval(const ModelFit& fit, Eigen::Index j, double other) const {
    const double half = 0.5 * (fit.upper[j] - fit.lower[j]), mid = 0.5 * (fit.upper[j] + fit.lower[j]) - bias[j] - other;
    const double widened = std::hypot(half, 1.959963984540054 * (std::isfinite(standard_error[j]) ? standard_error[j] : 0.0));
    return {mid - widened, mid + widened};
}

std::vector<std::string> SharedNoise::shift_texts(const ModelFit& fit) const {
    std::vector<std::string> out;
    for (Eigen::Index j = 0; j < 4; ++j) {
        const double machine = fit.values[j] - bias[j];
        out.push_back(fmt::format("{} {:+.3g} % (standard error {:.2g} %)", fit.names[static_cast<std::size_t>(j)], 100.0 * bias[j] / machine,
                                  100.0 * standard_error[j] / machine));
    }
    return out;
}

std::optional<SharedNoise> shared_noise_bias(const Measurement& data, const ModelFit& fit) {
    const WindowAngles angles(data);
    if (!angles.available()) return std::nullopt;
    const Eigen::Index n = data.size();
    // One model serves the residual (unless the fit kept it) and the Jacobian.
    const auto model = make_model(fit.spec, data);
    Eigen::VectorXd projected = fit.residual.size() == 2 * n ? fit.residual : residual_stacked(*model, fit.values);
    std::vector<Eigen::Index> starts, sizes;
    std::vector<bool> measured;
    // The projection takes its parameters' share of the noise with it: of m rows' noise, m - spent
    // rows' worth is left in the product, which is scaled back to m.
    std::vector<double> kept;
    // A window too short to leave the noise most of its rows gives nothing: its residual is zeroed,
    // and its rows count in J'J alone, as in the fit.
    for (const auto& segment : segment_ranges(data)) {
        starts.push_back(segment.first);
        sizes.push_back(segment.rows);
        WindowProjection projection(data, angles, segment.first, segment.rows);
        measured.push_back(projection.leaves_noise());
        int spent = 0;
        for (int axis = 0; axis < 2; ++axis) {
            auto rows = projected.segment(axis * n + segment.first, segment.rows);
            if (measured.back()) spent = projection.remove(rows);
            else rows.setZero();
        }
        kept.push_back(measured.back() ? static_cast<double>(segment.rows - spent) / static_cast<double>(segment.rows) : 1.0);
    }
    std::vector<Eigen::Index> columns;
    for (Eigen::Index j = 0; j < fit.values.size(); ++j)
        if (fit.free[static_cast<std::size_t>(j)]) columns.push_back(j);
    const auto p = static_cast<Eigen::Index>(columns.size());
    if (p == 0) return std::nullopt;
    const RangeNormalEquations sums = range_normal_equations(*model, fit.values, columns, starts, &projected);
    Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(p, p);
    Eigen::VectorXd moment = Eigen::VectorXd::Zero(p);
    Eigen::Index rows = 0;
    double square = 0.0;
    SharedNoise out;
    std::vector<Eigen::VectorXd> window_moment(starts.size());
    for (std::size_t w = 0; w < starts.size(); ++w) {
        window_moment[w] = sums.moment[w] / kept[w];
        gram += sums.gram[w];
        moment += window_moment[w];
        if (measured[w]) {
            square += sums.total[w] / kept[w];
            rows += sizes[w];
            ++out.windows;
        }
    }
    if (out.windows == 0) return std::nullopt;
    // The parameters' scales differ by orders (ohms, millihenries, an angle): solved scaled to a unit diagonal.
    const Eigen::VectorXd scale = gram.diagonal().cwiseSqrt().cwiseInverse();
    if (!scale.allFinite()) return std::nullopt;
    const Eigen::LDLT<Eigen::MatrixXd> solve(scale.asDiagonal() * gram * scale.asDiagonal());
    if (solve.info() != Eigen::Success || !(solve.vectorD().array() > 1e-12).all()) return std::nullopt;
    const auto inverse_times = [&](const Eigen::MatrixXd& m) -> Eigen::MatrixXd {
        return scale.asDiagonal() * solve.solve(scale.asDiagonal() * m);
    };
    const Eigen::VectorXd step = inverse_times(moment);
    // The estimate's spread: each window's share of J'r against its share of the rows, as clusters.
    Eigen::MatrixXd spread = Eigen::MatrixXd::Zero(p, p);
    for (std::size_t w = 0; w < starts.size(); ++w) {
        if (!measured[w]) continue;
        const double share = static_cast<double>(sizes[w]) / static_cast<double>(rows);
        const Eigen::VectorXd d = window_moment[w] - share * moment;
        spread += d * d.transpose();
    }
    const double windows = static_cast<double>(out.windows);
    const Eigen::VectorXd white = inverse_times(Eigen::MatrixXd::Identity(p, p)).diagonal() * (square / static_cast<double>(2 * rows));
    Eigen::MatrixXd covariance = Eigen::MatrixXd::Constant(p, p, std::numeric_limits<double>::quiet_NaN());
    if (out.windows > 1) {
        const Eigen::MatrixXd left = inverse_times(spread * windows / (windows - 1.0));
        covariance = inverse_times(left.transpose());
    }
    for (Eigen::Index k = 0; k < p; ++k)
        if (columns[static_cast<std::size_t>(k)] < 4) {
            const Eigen::Index j = columns[static_cast<std::size_t>(k)];
            out.bias[j] = step[k];
            out.standard_error[j] = std::sqrt(covariance(k, k));
            out.fit_standard_error[j] = std::sqrt(white[k]);
        }
    return out;
}

}  // namespace mhb::pmsm
