// Grey Wolf Optimizer. The variants differ in four decisions only (table below); the hunt itself,
// eq. (3.3)-(3.7) of the GWO paper with fresh r1, r2 per wolf, coordinate and leader, is shared.
#include "optimizers/gwo.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "framework/input_error.hpp"
#include "framework/registry.hpp"
#include "optimizers/greedy_selection.hpp"

namespace mhb {
namespace {

struct VariantRules {
    const char* name;
    bool asynchronous;     // each wolf is evaluated and offered to the leaders right after its move
    bool greedy;           // a move is kept only if it improves the wolf
    bool demotion;         // archive with cascading demotion (else GWO.m's rules)
    int schedule_offset;   // a = 2 - 2 * fraction(offset): GWO.m's l = 0..T-1 is -1, gen = 1..G is 0
};

constexpr VariantRules kRules[] = {
    {"original", false, false, false, -1},
    {"greedy_top3", false, true, false, 0},
    {"async_demotion", true, false, true, 0},
    {"pagmo2", true, false, false, 0},
};

const VariantRules& rules(GwoVariant v) { return kRules[static_cast<int>(v)]; }

}  // namespace

GwoVariant parse_gwo_variant(const std::string& name) {
    for (int k = 0; k < 4; ++k)
        if (name == kRules[k].name) return static_cast<GwoVariant>(k);
    throw ParameterError("variant", "unknown GWO variant '" + name + "'");
}

void WolfLeaders::reset(Eigen::Index dimension) {
    position = Matrix::Zero(dimension, 3);
    score.fill(std::numeric_limits<double>::infinity());
}

void WolfLeaders::offer_without_demotion(double f, const Eigen::Ref<const Vector>& x) {
    if (f < score[0]) {
        score[0] = f;
        position.col(0) = x;
    }
    if (f > score[0] && f < score[1]) {
        score[1] = f;
        position.col(1) = x;
    }
    if (f > score[0] && f > score[1] && f < score[2]) {
        score[2] = f;
        position.col(2) = x;
    }
}

void WolfLeaders::offer_with_demotion(double f, const Eigen::Ref<const Vector>& x) {
    int rank = 3;
    while (rank > 0 && f < score[static_cast<std::size_t>(rank - 1)]) --rank;
    if (rank == 3) return;
    for (int k = 2; k > rank; --k) {
        score[static_cast<std::size_t>(k)] = score[static_cast<std::size_t>(k - 1)];
        position.col(k) = position.col(k - 1);
    }
    score[static_cast<std::size_t>(rank)] = f;
    position.col(rank) = x;
}

GreyWolfOptimizer::GreyWolfOptimizer(Eigen::Index population, GwoVariant variant)
    : population_(population), variant_(variant) {
    if (population < 3) throw ParameterError("population", "GWO needs at least 3 wolves (alpha, beta, delta)");
}

void GreyWolfOptimizer::initialize(Evaluator& evaluator, Rng& rng) {
    const Eigen::Index d = evaluator.dimension();
    positions_.resize(d, population_);
    fitness_.resize(population_);
    order_.resize(static_cast<std::size_t>(population_));
    leaders_.reset(d);
    if (rules(variant_).greedy) {
        candidates_.resize(d, population_);
        candidate_fitness_.resize(population_);
    }
    a_ = 2.0;
    fill_uniform(positions_, evaluator.bounds(), rng);
    evaluator.evaluate(positions_, fitness_);
    switch (variant_) {
        case GwoVariant::Original:
            for (Eigen::Index i = 0; i < population_; ++i) offer(fitness_[i], positions_.col(i));
            break;
        case GwoVariant::GreedyTop3:
        case GwoVariant::AsyncDemotion: rank_leaders(true); break;
        // pagmo2 2.18 sorts the initial population with greater_than_f, so its first "alpha" is
        // the worst wolf; reproduced because this variant stands for what that library runs.
        case GwoVariant::Pagmo2: rank_leaders(false); break;
    }
}

void GreyWolfOptimizer::iterate(const Progress& progress, Evaluator& evaluator, Rng& rng) {
    a_ = 2.0 - 2.0 * progress.fraction(rules(variant_).schedule_offset);
    if (rules(variant_).asynchronous) iterate_asynchronous(evaluator, rng);
    else iterate_synchronous(evaluator, rng);
}

void GreyWolfOptimizer::hunt(Eigen::Index i, Rng& rng, Eigen::Ref<Vector> out) const {
    // A = 2a r1 - a and C = 2 r2 with r = m 2^-53, m the generator's 53-bit integer (Rng::uniform).
    // Scaling by a power of two is exact, so (2a 2^-53) m and 2^-52 m round exactly as 2a r1 and
    // 2 r2 do: the same doubles with one multiplication fewer per draw. (2a 2^-53 stays a normal
    // number: a is 0 or at least 2^-52.)
    const double a = a_;
    const double two_a_scaled = 2.0 * a * 0x1.0p-53;
    constexpr double two_scaled = 0x1.0p-52;
    const Eigen::Index d = positions_.rows();
    const double* x = positions_.data() + i * d;
    const double* alpha = leaders_.position.data();
    const double* beta = alpha + d;
    const double* delta = beta + d;
    for (Eigen::Index j = 0; j < d; ++j) {
        const double xj = x[j];
        double sum = 0.0;
        for (const double leader : {alpha[j], beta[j], delta[j]}) {
            const double m1 = static_cast<double>(rng() >> 11);
            const double m2 = static_cast<double>(rng() >> 11);
            const double big_a = two_a_scaled * m1 - a;
            const double big_c = two_scaled * m2;
            sum += leader - big_a * std::abs(big_c * leader - xj);
        }
        out[j] = sum / 3.0;
    }
}

void GreyWolfOptimizer::offer(double f, const Eigen::Ref<const Vector>& x) {
    if (rules(variant_).demotion) leaders_.offer_with_demotion(f, x);
    else leaders_.offer_without_demotion(f, x);
}

void GreyWolfOptimizer::rank_leaders(bool ascending) {
    std::iota(order_.begin(), order_.end(), Eigen::Index{0});
    std::partial_sort(order_.begin(), order_.begin() + 3, order_.end(), [&](Eigen::Index p, Eigen::Index q) {
        if (fitness_[p] != fitness_[q]) return ascending ? fitness_[p] < fitness_[q] : fitness_[p] > fitness_[q];
        return p < q;
    });
    for (int k = 0; k < 3; ++k) {
        const Eigen::Index i = order_[static_cast<std::size_t>(k)];
        leaders_.position.col(k) = positions_.col(i);
        leaders_.score[static_cast<std::size_t>(k)] = fitness_[i];
    }
}

void GreyWolfOptimizer::iterate_synchronous(Evaluator& evaluator, Rng& rng) {
    const Bounds& bounds = evaluator.bounds();
    if (rules(variant_).greedy) {
        for (Eigen::Index i = 0; i < population_; ++i) hunt(i, rng, candidates_.col(i));
        clamp_to_bounds(candidates_, bounds);
        evaluator.evaluate(candidates_, candidate_fitness_);
        greedy_replace(positions_, fitness_, candidates_, candidate_fitness_);
        rank_leaders(true);
        return;
    }
    // A wolf's move reads only its own coordinates and the frozen leaders, so it can be in place.
    for (Eigen::Index i = 0; i < population_; ++i) hunt(i, rng, positions_.col(i));
    clamp_to_bounds(positions_, bounds);
    evaluator.evaluate(positions_, fitness_);
    for (Eigen::Index i = 0; i < population_; ++i) offer(fitness_[i], positions_.col(i));
}

void GreyWolfOptimizer::iterate_asynchronous(Evaluator& evaluator, Rng& rng) {
    const Bounds& bounds = evaluator.bounds();
    for (Eigen::Index i = 0; i < population_; ++i) {
        hunt(i, rng, positions_.col(i));
        clamp_to_bounds(positions_.middleCols(i, 1), bounds);
        evaluator.evaluate(positions_.middleCols(i, 1), fitness_.segment(i, 1));
        offer(fitness_[i], positions_.col(i));
    }
}

namespace {

const bool registered = register_optimizer({
    "gwo",
    "Grey wolf optimizer (Mirjalili et al. 2014): GWO.m and the variants other codes run under the name",
    {
        ParameterSpec::integer("population", 30, 3, 1'000'000, "number of wolves N (evaluations per iteration)"),
        ParameterSpec::choice("variant", "original", {"original", "greedy_top3", "async_demotion", "pagmo2"},
                              "original = GWO.m; greedy_top3 = mealpy (leaders = best 3, greedy selection); "
                              "async_demotion = asynchronous with cascading demotion; pagmo2 = pagmo2 2.18"),
    },
    [](const ParameterSet& p) -> std::unique_ptr<Optimizer> {
        return std::make_unique<GreyWolfOptimizer>(static_cast<Eigen::Index>(p.integer("population")),
                                                   parse_gwo_variant(p.text("variant")));
    },
});

}  // namespace
}  // namespace mhb
