#pragma once
// Runs every (optimiser variant, problem variant, trial) of an experiment on TBB. Each trial's seed
// derives from (master seed, optimiser label, problem label, trial index), so results are bitwise
// identical whatever the thread count or order; each finished trial is appended to results.jsonl at
// once.
#include <filesystem>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "framework/experiment_config.hpp"
#include "framework/problem.hpp"
#include "framework/results_store.hpp"
#include "framework/shared_problem_data.hpp"

namespace mhb {

struct RunOptions {
    int threads = 0;                               // 0 = all cores
    bool resume = false;                           // skip trials already in results.jsonl
    std::optional<std::filesystem::path> output;   // overrides the config's output
    bool progress = true;                          // draw the progress line (when stderr is a terminal)
    // Run only this share of the trials; the output then defaults to <output>/shard-K-of-N.
    std::optional<Shard> shard;
    // Keep the records in RunSummary::records when the results file holds this run's only.
    bool keep_records = false;
};

struct RunSummary {
    std::filesystem::path output;
    ExperimentInfo info;
    std::size_t total = 0, ran = 0, skipped = 0, failed = 0;
    std::vector<std::string> failures;  // the first few, "optimizer on problem, trial k: reason"
    std::vector<std::string> notes;
    double seconds = 0;
    // With RunOptions::keep_records, when the results file held nothing before this run: the records
    // as written there, in its order, so that the tables need not read them back (trial_from_json
    // gives back to_json's record bit for bit).
    std::optional<std::vector<TrialRecord>> records;
};

// Resolves problem information (dimension, truth) by creating each problem once; InputError for
// problems that cannot be created from the config (e.g. a missing data file).
// `shared`: the experiment's shared problem data, so that the trials reuse what this builds.
ExperimentInfo describe_experiment(const ExperimentSpec& spec, std::shared_ptr<SharedProblemData> shared = nullptr);

RunSummary run_experiment(const ExperimentSpec& spec, const RunOptions& options);

// Keeps only the problems of this dimension (`mhbench run --dimension D`) and records the choice in
// the spec, so the results say which part of the config they hold; InputError when none has it.
void select_dimension(ExperimentSpec& spec, int dimension);

// run_experiment in two steps, for runs spread over processes (framework/mpi/distributed_run.cpp):
// one process prepares the output, then every process runs its share of the trials into a results
// file of its own, and the first joins those files.
using TrialKey = std::tuple<std::string, std::string, std::int64_t>;  // optimizer label, problem label, trial
struct PreparedRun {
    std::filesystem::path output;
    ExperimentInfo info;
    std::set<TrialKey> done;  // trials already in results.jsonl (kept on --resume)
    std::vector<std::string> notes;
    std::shared_ptr<SharedProblemData> shared;
};
// Folds leftover rank files into results.jsonl, keeps an earlier run aside or checks it can be
// resumed, and writes experiment.json (its provenance saying `ranks`).
PreparedRun prepare_run(const ExperimentSpec& spec, const RunOptions& options, int ranks = 1);
// What another process needs of a run that the first has prepared: the done trials, read back.
PreparedRun attach_to_run(const ExperimentSpec& spec, const RunOptions& options);
// Runs the trials of `share` (all when empty) not yet done, appending each record to `results`.
RunSummary run_prepared(const ExperimentSpec& spec, const RunOptions& options, const PreparedRun& prepared,
                        const std::optional<Shard>& share, const std::filesystem::path& results);
// "results.rank-3.jsonl": where rank 3 of a distributed run writes its records.
std::string rank_results_name(int rank);
// Appends the records of every results.rank-*.jsonl in `output` that results.jsonl does not hold yet
// (a record twice is kept once; a record cut short by a kill is dropped, to be rerun), then removes
// those files. Returns notes on what it found.
std::vector<std::string> fold_rank_results(const std::filesystem::path& output);

// "shard-2-of-8": the directory a shard writes into under the experiment's output by default.
std::string shard_directory_name(const Shard& shard);

}  // namespace mhb
