#pragma once
// Drives an optimiser by hand, one iteration at a time, so that tests can look at its state
// between iterations (run_trial only reports the end).
#include "framework/optimizer.hpp"

namespace mhb::testing {

struct ManualRun {
    Evaluator evaluator;
    Rng rng;
    Progress progress;

    ManualRun(const Problem& problem, Budget budget, std::uint64_t seed) : evaluator(problem, budget), rng(seed) {
        progress.budget = budget;
    }
    void initialize(Optimizer& optimizer) {
        optimizer.initialize(evaluator, rng);
        progress.last_step_evaluations = evaluator.evaluations();
    }
    // Runs the next iteration, numbered and counted as run_trial numbers and counts it.
    void iterate(Optimizer& optimizer) {
        progress.evaluations = evaluator.evaluations();
        optimizer.iterate(progress, evaluator, rng);
        progress.last_step_evaluations = evaluator.evaluations() - progress.evaluations;
        ++progress.iteration;
    }
};

}  // namespace mhb::testing
