#include "framework/optimizer.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "framework/anytime.hpp"
#include "framework/input_error.hpp"

namespace mhb {

Evaluator::Evaluator(const Problem& problem, Budget budget)
    : problem_(problem), budget_(budget), best_position_(Vector::Zero(problem.dimension())) {}

std::int64_t Evaluator::remaining() const {
    if (budget_.max_evaluations <= 0) return std::numeric_limits<std::int64_t>::max();
    return std::max<std::int64_t>(0, budget_.max_evaluations - used_);
}

Eigen::Index Evaluator::evaluate(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    if (x.rows() != dimension() || f.size() != x.cols())
        throw PluginFault(fmt::format("evaluate: population is {}x{} with {} fitness slots; expected {} rows",
                                      x.rows(), x.cols(), f.size(), dimension()));
    const Eigen::Index n = static_cast<Eigen::Index>(std::min<std::int64_t>(x.cols(), remaining()));
    const auto& b = bounds();
    for (Eigen::Index i = 0; i < n; ++i) {
        for (Eigen::Index j = 0; j < x.rows(); ++j) {
            const double v = x(j, i);
            if (!std::isfinite(v))
                throw PluginFault(fmt::format("optimizer produced a non-finite coordinate x{} = {} in candidate {}",
                                              j + 1, v, i));
            if (v < b.lower[j] || v > b.upper[j])
                throw PluginFault(fmt::format("optimizer produced x{} = {:.17g} outside [{:g}, {:g}] in candidate {}",
                                              j + 1, v, b.lower[j], b.upper[j], i));
        }
    }
    if (n > 0) problem_.evaluate(x.leftCols(n), f.head(n));
    const std::int64_t before = used_;
    used_ += n;
    for (Eigen::Index i = 0; i < n; ++i) {
        if (std::isnan(f[i]))
            throw PluginFault(fmt::format("problem returned NaN for candidate {}", i));
        if (f[i] < best_fitness_) {
            best_fitness_ = f[i];
            best_position_ = x.col(i);
        }
        // Column by column: the record knows the very evaluation that reached a target.
        if (recorder_) recorder_->observe(before + i + 1, best_fitness_);
    }
    f.tail(x.cols() - n).setConstant(std::numeric_limits<double>::infinity());
    return n;
}

double Progress::fraction(std::int64_t offset) const {
    double r = 0.0;
    if (budget.max_iterations > 0)
        r = static_cast<double>(iteration + offset) / static_cast<double>(budget.max_iterations);
    if (budget.max_evaluations > 0)
        r = std::max(r, static_cast<double>(evaluations + offset * last_step_evaluations) /
                            static_cast<double>(budget.max_evaluations));
    return std::clamp(r, 0.0, 1.0);
}

void clamp_to_bounds(Eigen::Ref<Matrix> x, const Bounds& bounds) {
    for (Eigen::Index i = 0; i < x.cols(); ++i)
        x.col(i) = x.col(i).cwiseMax(bounds.lower).cwiseMin(bounds.upper);
}

void fill_uniform(Eigen::Ref<Matrix> x, const Bounds& bounds, Rng& rng) {
    for (Eigen::Index i = 0; i < x.cols(); ++i)
        for (Eigen::Index j = 0; j < x.rows(); ++j)
            x(j, i) = bounds.lower[j] + rng.uniform() * (bounds.upper[j] - bounds.lower[j]);
}

}  // namespace mhb
