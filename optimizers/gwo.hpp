#pragma once
// Grey Wolf Optimizer (Mirjalili, Mirjalili & Lewis 2014) as the authors' GWO.m does it, and the
// variants other widely used codes run under the same name, as one optimiser with a `variant`
// choice (docs/algorithms.md, "GWO").
#include <array>
#include <string>
#include <vector>

#include "framework/optimizer.hpp"

namespace mhb {

enum class GwoVariant {
    Original,       // GWO.m: best-so-far archive, strict rules, no demotion, synchronous, unconditional
    GreedyTop3,     // mealpy OriginalGWO: leaders = best 3 of the population, greedy selection
    AsyncDemotion,  // asynchronous, archive with cascading demotion
    Pagmo2,         // pagmo2 2.18 gwo::evolve: asynchronous, GWO.m's rules, descending initial sort
};

// Parses "original" | "greedy_top3" | "async_demotion" | "pagmo2" (ParameterError otherwise).
GwoVariant parse_gwo_variant(const std::string& name);

// The three leaders: columns 0, 1, 2 of `position` are alpha, beta, delta.
struct WolfLeaders {
    Matrix position;
    std::array<double, 3> score{};

    // GWO.m's start: every leader at the origin with score +inf.
    void reset(Eigen::Index dimension);
    // GWO.m's update: f < alpha -> alpha; alpha < f < beta -> beta; alpha, beta < f < delta -> delta.
    // The three tests run in sequence, a new alpha does not push the old one down.
    void offer_without_demotion(double f, const Eigen::Ref<const Vector>& x);
    // Ranking archive: a new alpha moves alpha to beta and beta to delta; a new beta moves beta to delta.
    void offer_with_demotion(double f, const Eigen::Ref<const Vector>& x);
};

class GreyWolfOptimizer final : public Optimizer {
public:
    GreyWolfOptimizer(Eigen::Index population, GwoVariant variant);

    void initialize(Evaluator& evaluator, Rng& rng) override;
    void iterate(const Progress& progress, Evaluator& evaluator, Rng& rng) override;

    const WolfLeaders& leaders() const { return leaders_; }
    // The coefficient a of the last move (2 before the first one).
    double a() const { return a_; }
    const Matrix& positions() const { return positions_; }
    const Vector& fitness() const { return fitness_; }

private:
    // Eq. (3.3)-(3.7) of the GWO paper for wolf `i` against the current leaders, into `out`.
    void hunt(Eigen::Index i, Rng& rng, Eigen::Ref<Vector> out) const;
    void offer(double f, const Eigen::Ref<const Vector>& x);
    // Leaders = the best (ascending) or, for pagmo2's sort, the worst three of the population.
    void rank_leaders(bool ascending);
    void iterate_synchronous(Evaluator& evaluator, Rng& rng);
    void iterate_asynchronous(Evaluator& evaluator, Rng& rng);

    Eigen::Index population_;
    GwoVariant variant_;
    Matrix positions_;
    Vector fitness_;
    Matrix candidates_;          // greedy_top3 only
    Vector candidate_fitness_;
    std::vector<Eigen::Index> order_;
    WolfLeaders leaders_;
    double a_ = 2.0;
};

}  // namespace mhb
