#pragma once
// Checks every stochastic optimiser's tests repeat: a seed fixes a trial, and the median best of a
// few seeded trials (single runs of a metaheuristic are too erratic to test one by one).
#include <catch2/catch.hpp>

#include <algorithm>
#include <functional>
#include <memory>
#include <vector>

#include "framework/trial.hpp"

namespace mhb::testing {

using OptimizerFactory = std::function<std::unique_ptr<Optimizer>()>;

// Two trials with one seed agree in every recorded value; a third with another seed does not.
inline void require_seed_fixes_trial(const OptimizerFactory& make, const Problem& problem) {
    const auto a = run_trial(*make(), problem, {Budget{30, 0}, 42, true});
    const auto b = run_trial(*make(), problem, {Budget{30, 0}, 42, true});
    const auto c = run_trial(*make(), problem, {Budget{30, 0}, 43, true});
    REQUIRE(a.trace_best == b.trace_best);
    REQUIRE(a.trace_position == b.trace_position);
    REQUIRE(a.trace_best != c.trace_best);
}

// Median of the best fitness over trials with seeds 1..seeds (seeds odd).
inline double median_best(const OptimizerFactory& make, const Problem& problem, Budget budget, int seeds) {
    std::vector<double> best;
    for (int seed = 1; seed <= seeds; ++seed)
        best.push_back(run_trial(*make(), problem, {budget, static_cast<std::uint64_t>(seed), false}).best_fitness);
    const auto middle = best.begin() + seeds / 2;
    std::nth_element(best.begin(), middle, best.end());
    return *middle;
}

}  // namespace mhb::testing
