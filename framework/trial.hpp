#pragma once
// One trial: one optimiser on one problem with one seed, run to its budget, with the framework's own
// record of the best point and its convergence.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "framework/anytime.hpp"
#include "framework/optimizer.hpp"

namespace mhb {

struct TrialRecord {
    std::string optimizer;  // variant label, e.g. "isoa(cuckoo=false)"
    std::string problem;    // problem label, e.g. "F1" or "bbob_f3(dimension=10)"
    std::int64_t trial = 0;
    std::uint64_t seed = 0;
    bool ok = true;
    std::string error;      // why the trial failed, when !ok

    double best_fitness = 0.0;
    Vector best_position;
    std::int64_t evaluations = 0;
    std::int64_t iterations = 0;
    double seconds = 0.0;

    // Entry k is the state after iteration k (entry 0: after initialisation).
    std::vector<std::int64_t> trace_evaluations;
    std::vector<double> trace_best;
    std::vector<Vector> trace_position;  // best-so-far position; filled when record_positions

    // Filled when the experiment has [anytime] (framework/anytime.hpp).
    AnytimeRecord anytime;
};

struct TrialSetup {
    Budget budget;
    std::uint64_t seed = 0;
    bool record_positions = false;
    // false: the trace holds the final state only (see AnytimeSpec::iteration_trace).
    bool record_trace = true;
    // Record anytime data against this optimum (f*); null: none.
    const AnytimeSpec* anytime = nullptr;
    double optimum = 0.0;
    // Asked after initialisation (iterations = 0) and after each iteration; true ends the trial
    // there, as a spent budget would. For callers that stop on a target, a time or a user's callback
    // (the Python module's minimize); null: the budget alone ends the trial.
    std::function<bool(const Evaluator& evaluator, std::int64_t iterations)> stop = nullptr;
};

// Runs the trial. Exceptions thrown by the plugins (including PluginFault from the evaluator) fail
// this trial only: they are caught and recorded in `error`.
TrialRecord run_trial(Optimizer& optimizer, const Problem& problem, const TrialSetup& setup);

}  // namespace mhb
