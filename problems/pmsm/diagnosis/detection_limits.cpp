#include "problems/pmsm/diagnosis/detection_limits.hpp"

#include <cmath>
#include <limits>

#include <Eigen/QR>

#include "problems/pmsm/diagnosis/design.hpp"
#include "problems/pmsm/diagnosis/verdict.hpp"

namespace mhb::pmsm {

namespace {

// Enough rows for every signature the design holds (operating points, an electrical period of the
// angle, the temperature trend), few enough that a Jacobian per effect stays small on any log.
constexpr Eigen::Index most_rows = 8192;

Measurement strided(const Measurement& design) {
    if (design.size() <= most_rows) return design;
    std::vector<Eigen::Index> rows;
    rows.reserve(static_cast<std::size_t>(most_rows));
    for (Eigen::Index k = 0; k < most_rows; ++k) rows.push_back(k * design.size() / most_rows);
    return select_rows(design, rows);
}

}  // namespace

std::vector<DetectionLimit> detection_limits(const Measurement& design, Eigen::Index rows, const ModelFit& model,
                                             const std::vector<std::string>& library, const NoiseEstimate& noise) {
    std::vector<DetectionLimit> out;
    const Measurement sample = strided(design);
    const Eigen::Index m = sample.size();
    if (m == 0 || rows == 0) return out;
    // Each sampled row stands for this many logged ones.
    const double weight = static_cast<double>(rows) / static_cast<double>(m);
    const double log_n = std::log(std::max(noise.effective_samples, 2.0));
    const double resolution = std::sqrt(noise.sigma.squaredNorm() / 2.0);
    for (const auto& effect : library) {
        if (model.spec.contains(effect)) continue;
        const ModelSpec full = model.spec.with(effect);
        const auto extended = make_model(full, sample);
        Eigen::VectorXd values = extended->parameters_of(MotorParameters{});
        values.head(model.values.size()) = model.values;
        const auto free = free_parameters(full);
        const auto own_first = model.values.size();
        std::vector<Eigen::Index> columns;
        std::vector<Eigen::Index> sizes;  // positions in `columns` of the effect's size parameters
        int added = 0;
        for (Eigen::Index j = 0; j < values.size(); ++j) {
            if (!free[static_cast<std::size_t>(j)]) continue;
            const bool own = j >= own_first;
            if (own) {
                ++added;
                const auto k = static_cast<std::size_t>(j - own_first);
                if (!extended->effects().back()->is_size(k)) continue;
                sizes.push_back(static_cast<Eigen::Index>(columns.size()));
            }
            columns.push_back(j);
        }
        if (sizes.empty()) continue;
        Eigen::MatrixXd jacobian = prediction_jacobian(*extended, values, columns);
        // In units of each axis' long-run noise: the likelihood ratio's metric.
        jacobian.topRows(m) /= noise.long_run[0];
        jacobian.bottomRows(m) /= noise.long_run[1];
        std::vector<Eigen::Index> base;
        for (Eigen::Index c = 0; c < jacobian.cols(); ++c)
            if (columns[static_cast<std::size_t>(c)] < own_first) base.push_back(c);
        Eigen::MatrixXd others(jacobian.rows(), static_cast<Eigen::Index>(base.size()));
        for (std::size_t c = 0; c < base.size(); ++c) others.col(static_cast<Eigen::Index>(c)) = jacobian.col(base[c]);
        const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(others);
        const double needed = added * log_n - evidence::supported_bic;
        const auto& names = extended->parameter_names();
        std::vector<std::string> units;
        for (const auto& spec : extended->effects().back()->parameter_specs())
            if (spec.type == ParameterType::Real) units.push_back(spec.unit);
        for (const auto c : sizes) {
            const Eigen::VectorXd column = jacobian.col(c);
            const Eigen::VectorXd unique = base.empty() ? column : Eigen::VectorXd(column - others * qr.solve(column));
            // Per unit of the size, squared: the likelihood ratio and the voltage it adds.
            const double information = weight * unique.squaredNorm();
            Eigen::VectorXd volts = unique;
            volts.head(m) *= noise.long_run[0];
            volts.tail(m) *= noise.long_run[1];
            const double power = volts.squaredNorm() / (2.0 * static_cast<double>(m));
            const auto j = static_cast<std::size_t>(columns[static_cast<std::size_t>(c)]);
            DetectionLimit limit;
            limit.effect = effect;
            limit.parameter = names[j];
            limit.unit = units[j - static_cast<std::size_t>(own_first)];
            limit.typical = values[static_cast<Eigen::Index>(j)];
            // A signature the model's own parameters take whole (as identifiability_of judges it) shows at no size.
            const bool absorbed = !(unique_fraction(others, column) >= evidence::absorbed_below);
            if (!absorbed && information > 0.0 && power > 0.0) {
                const double by_evidence = std::sqrt(needed / information);
                const double by_relevant_size = evidence::relevant_voltage * resolution / std::sqrt(power);
                limit.limit = std::max(by_evidence, by_relevant_size);
                limit.set_by_relevant_size = by_relevant_size > by_evidence;
            } else {
                limit.limit = std::numeric_limits<double>::infinity();
            }
            out.push_back(std::move(limit));
        }
    }
    return out;
}

}  // namespace mhb::pmsm
