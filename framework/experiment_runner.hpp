#pragma once
// Runs every (optimiser variant, problem variant, trial) of an experiment on TBB. Each trial's seed
// derives from (master seed, optimiser label, problem label, trial index), so results are bitwise
// identical whatever the thread count or order; each finished trial is appended to results.jsonl at
// once.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "framework/experiment_config.hpp"
#include "framework/problem.hpp"
#include "framework/results_store.hpp"

namespace mhb {

struct RunOptions {
    int threads = 0;                               // 0 = all cores
    bool resume = false;                           // skip trials already in results.jsonl
    std::optional<std::filesystem::path> output;   // overrides the config's output
    bool progress = true;                          // draw the progress line (when stderr is a terminal)
    // Run only this share of the trials; the output then defaults to <output>/shard-K-of-N.
    std::optional<Shard> shard;
};

struct RunSummary {
    std::filesystem::path output;
    ExperimentInfo info;
    std::size_t total = 0, ran = 0, skipped = 0, failed = 0;
    std::vector<std::string> failures;  // the first few, "optimizer on problem, trial k: reason"
    std::vector<std::string> notes;
    double seconds = 0;
};

// Resolves problem information (dimension, truth) by creating each problem once; InputError for
// problems that cannot be created from the config (e.g. a missing data file).
// `shared`: the experiment's shared problem data, so that the trials reuse what this builds.
ExperimentInfo describe_experiment(const ExperimentSpec& spec, std::shared_ptr<SharedProblemData> shared = nullptr);

RunSummary run_experiment(const ExperimentSpec& spec, const RunOptions& options);

// "shard-2-of-8": the directory a shard writes into under the experiment's output by default.
std::string shard_directory_name(const Shard& shard);

}  // namespace mhb
