#include "optimizers/snake/tent_quasi_opposition.hpp"

#include <algorithm>
#include <numeric>

#include "framework/input_error.hpp"

namespace mhb {

TentMap::TentMap(double epsilon) : epsilon_(epsilon) {
    if (!(epsilon > 0.0 && epsilon < 1.0)) throw ParameterError("tent_epsilon", "must lie in (0, 1)");
}

void TentMap::remember(double z) {
    recent_[static_cast<std::size_t>(recent_next_)] = z;
    recent_next_ = (recent_next_ + 1) % kMemory;
    recent_count_ = std::min(recent_count_ + 1, kMemory);
}

bool TentMap::seen(double z) const {
    for (int k = 0; k < recent_count_; ++k)
        if (recent_[static_cast<std::size_t>(k)] == z) return true;
    return false;
}

void TentMap::reseed(Rng& rng) {
    ++reseeds_;
    recent_count_ = 0;
    recent_next_ = 0;
    z_ = rng.uniform_open();
    remember(z_);
}

void TentMap::start(double z, Rng& rng) {
    if (!(z > 0.0 && z < 1.0)) {
        reseed(rng);
        return;
    }
    recent_count_ = 0;
    recent_next_ = 0;
    z_ = z;
    remember(z_);
}

double TentMap::next(Rng& rng) {
    const double z = step(z_, epsilon_);
    if (!(z > 0.0 && z < 1.0) || seen(z)) {
        reseed(rng);
        return z_;
    }
    z_ = z;
    remember(z_);
    return z_;
}

void quasi_opposite(const Eigen::Ref<const Vector>& x, const Bounds& bounds, Rng& rng, Eigen::Ref<Vector> out) {
    for (Eigen::Index j = 0; j < x.size(); ++j) {
        const double centre = 0.5 * (bounds.lower[j] + bounds.upper[j]);
        out[j] = centre + (centre - x[j]) * rng.uniform();
    }
}

TentQuasiOppositionInit::TentQuasiOppositionInit(TentQuasiOppositionSettings settings)
    : settings_(settings), tent_(settings.epsilon) {
    if (!(settings.jumping_rate >= 0.0 && settings.jumping_rate <= 1.0))
        throw ParameterError("jumping_rate", "must lie in [0, 1]");
}

void TentQuasiOppositionInit::resize(Eigen::Index dimension, Eigen::Index size) {
    union_.resize(dimension, 2 * size);
    union_fitness_.resize(2 * size);
    source_.resize(static_cast<std::size_t>(size));
    order_.resize(static_cast<std::size_t>(2 * size));
}

void TentQuasiOppositionInit::tent_population(const Bounds& bounds, Rng& rng, Eigen::Ref<Matrix> out) {
    for (Eigen::Index j = 0; j < out.rows(); ++j) {
        const double lower = bounds.lower[j];
        const double width = bounds.upper[j] - lower;
        tent_.start(rng.uniform_open(), rng);
        for (Eigen::Index i = 0; i < out.cols(); ++i) {
            const double z = i == 0 ? tent_.value() : tent_.next(rng);
            out(j, i) = lower + z * width;
        }
    }
}

Eigen::Index TentQuasiOppositionInit::quasi_opposite_points(const Eigen::Ref<const Matrix>& population,
                                                            const Bounds& bounds, Rng& rng, Eigen::Ref<Matrix> out,
                                                            std::vector<Eigen::Index>& source) {
    Eigen::Index count = 0;
    for (Eigen::Index i = 0; i < population.cols(); ++i) {
        if (!(rng.uniform() < settings_.jumping_rate)) continue;
        quasi_opposite(population.col(i), bounds, rng, out.col(count));
        source[static_cast<std::size_t>(count)] = i;
        ++count;
    }
    return count;
}

std::int64_t TentQuasiOppositionInit::initialize(Evaluator& evaluator, Rng& rng, Eigen::Ref<Matrix> population,
                                                 Eigen::Ref<Vector> fitness) {
    const Eigen::Index n = population.cols();
    const Bounds& bounds = evaluator.bounds();
    tent_population(bounds, rng, union_.leftCols(n));
    const Eigen::Index m = quasi_opposite_points(union_.leftCols(n), bounds, rng, union_.middleCols(n, n), source_);
    const Eigen::Index total = n + m;
    // The centre plus a fraction of a half-width can round one ulp past a bound.
    clamp_to_bounds(union_.leftCols(total), bounds);
    evaluator.evaluate(union_.leftCols(total), union_fitness_.head(total));

    // Best n of the union, kept in union order so that neither sex receives all the best points.
    const auto first = order_.begin();
    const auto last = first + total;
    std::iota(first, last, Eigen::Index{0});
    std::nth_element(first, first + (n - 1), last, [&](Eigen::Index p, Eigen::Index q) {
        return union_fitness_[p] != union_fitness_[q] ? union_fitness_[p] < union_fitness_[q] : p < q;
    });
    std::sort(first, first + n);
    for (Eigen::Index k = 0; k < n; ++k) {
        const Eigen::Index i = order_[static_cast<std::size_t>(k)];
        population.col(k) = union_.col(i);
        fitness[k] = union_fitness_[i];
    }
    return total;
}

}  // namespace mhb
