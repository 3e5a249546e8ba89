#include "framework/optimizer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <fmt/format.h>

#include "framework/anytime.hpp"
#include "framework/input_error.hpp"

namespace mhb {

namespace {

// True when every coordinate of the first n columns of x is finite and inside the box. It runs on
// every evaluation, so it has no branch per coordinate and takes two coordinates at a time with SSE2
// (GCC 12 does not vectorise this reduction by itself); the coordinate that fails, if one does, is
// looked for afterwards. Comparisons written as "not inside" so that a NaN counts as outside.
bool all_inside(const Eigen::Ref<const Matrix>& x, Eigen::Index n, const Bounds& b) {
    const Eigen::Index d = x.rows();
    const double* lower = b.lower.data();
    const double* upper = b.upper.data();
    constexpr double largest = std::numeric_limits<double>::max();
    bool outside = false;
#if defined(__SSE2__)
    const __m128d magnitude = _mm_castsi128_pd(_mm_set1_epi64x(0x7FFFFFFFFFFFFFFF));
    const __m128d finite_limit = _mm_set1_pd(largest);
    __m128d any = _mm_setzero_pd();
#endif
    for (Eigen::Index i = 0; i < n; ++i) {
        const double* column = x.data() + i * x.outerStride();
        Eigen::Index j = 0;
#if defined(__SSE2__)
        for (; j + 2 <= d; j += 2) {
            const __m128d v = _mm_loadu_pd(column + j);
            any = _mm_or_pd(any, _mm_cmpnge_pd(v, _mm_loadu_pd(lower + j)));
            any = _mm_or_pd(any, _mm_cmpnle_pd(v, _mm_loadu_pd(upper + j)));
            // An infinity inside an infinite box is still not finite.
            any = _mm_or_pd(any, _mm_cmpnle_pd(_mm_and_pd(v, magnitude), finite_limit));
        }
#endif
        for (; j < d; ++j) {
            const double v = column[j];
            outside |= !(v >= lower[j]) || !(v <= upper[j]) || !(std::abs(v) <= largest);
        }
    }
#if defined(__SSE2__)
    outside |= _mm_movemask_pd(any) != 0;
#endif
    return !outside;
}

// The first coordinate (column by column) that is not finite or leaves the box, as a PluginFault.
[[noreturn]] void report_first_outside(const Eigen::Ref<const Matrix>& x, Eigen::Index n, const Bounds& b) {
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
    throw std::logic_error("report_first_outside: every coordinate is inside");
}

}  // namespace

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
    if (!all_inside(x, n, b)) report_first_outside(x, n, b);
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
    // std::max then std::min is what Eigen's cwiseMax(lower).cwiseMin(upper) computes, NaN included
    // (a NaN coordinate stays NaN), without building an expression per column.
    const double* lower = bounds.lower.data();
    const double* upper = bounds.upper.data();
    const Eigen::Index d = x.rows();
    for (Eigen::Index i = 0; i < x.cols(); ++i) {
        double* column = x.data() + i * x.outerStride();
        for (Eigen::Index j = 0; j < d; ++j) column[j] = std::min(std::max(column[j], lower[j]), upper[j]);
    }
}

void fill_uniform(Eigen::Ref<Matrix> x, const Bounds& bounds, Rng& rng) {
    for (Eigen::Index i = 0; i < x.cols(); ++i)
        for (Eigen::Index j = 0; j < x.rows(); ++j)
            x(j, i) = bounds.lower[j] + rng.uniform() * (bounds.upper[j] - bounds.lower[j]);
}

}  // namespace mhb
