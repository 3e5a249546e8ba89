#pragma once
// Trial results as JSON Lines: one finished trial per line, appended and flushed as soon as it
// finishes, so an interrupted run keeps everything that finished. An experiment.json beside it
// describes the experiment, so tables can be remade from the directory alone.
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "framework/experiment_config.hpp"
#include "framework/problem.hpp"
#include "framework/provenance.hpp"
#include "framework/trial.hpp"

namespace mhb {

// What the tables need to know about a problem beyond its trials.
struct ProblemInfo {
    std::string label;
    std::string name;
    int dimension = 0;
    std::vector<std::string> parameter_names;
    bool named_parameters = false;
    KnownTruth truth;
    std::string description;
    // The settings as the config gave them (the variant's values and box), so that `--resume` can
    // refuse to mix trials of two settings under one label. Empty in files from before they were
    // recorded: `settings_recorded` tells the two apart.
    std::map<std::string, ParameterValue> parameters;
    std::vector<double> lower, upper;
    bool settings_recorded = true;
};

// One of `count` deterministic shares of an experiment's trials (`mhbench run --shard K/N`): the trials
// whose place in the fixed order (problem, optimizer, trial) is K-1 modulo N. Consecutive trials go to
// different shards, so each share holds a slice of every problem and optimiser and the shares cost
// about the same.
struct Shard {
    std::int64_t index = 1;  // 1-based
    std::int64_t count = 1;
    bool operator==(const Shard&) const = default;
    bool holds(std::int64_t position) const { return position % count == index - 1; }
};

struct ExperimentInfo {
    std::string name;
    std::string description;
    std::string config_file;
    std::int64_t trials = 0;
    std::uint64_t seed = 0;
    Budget budget;
    std::int64_t evaluations_per_dimension = 0;  // see ExperimentSpec
    std::map<int, std::int64_t> evaluations_by_dimension;  // see ExperimentSpec
    double error_threshold = 0;                  // see ExperimentSpec
    int selected_dimension = 0;                  // see ExperimentSpec
    std::vector<PluginVariant> optimizers;
    std::vector<ProblemInfo> problems;
    std::string baseline;
    std::vector<std::string> references;
    bool plots = true;
    bool per_problem = true;  // see ExperimentSpec
    std::vector<PublishedResult> published;
    // The config file's text as the run read it, so the results show what made them even after the
    // file has changed. Empty in files from before it was recorded.
    std::string config_text;
    // One entry per `mhbench run` that wrote trials here (a `--resume` adds one). Empty in files from
    // before provenance was recorded.
    std::vector<Provenance> runs;
    // Set when the directory holds one shard of the experiment; `mhbench merge` joins them.
    std::optional<Shard> shard;
    // `[anytime]` of the config: the records then carry anytime data, the tables ERT and ECDFs.
    std::optional<AnytimeSpec> anytime;
};

nlohmann::json to_json(const TrialRecord& record);
TrialRecord trial_from_json(const nlohmann::json& j);
nlohmann::json to_json(const ExperimentInfo& info);
ExperimentInfo experiment_from_json(const nlohmann::json& j);

class ResultsWriter {
public:
    // Opens `path` for appending; InputError when the directory is not writable.
    explicit ResultsWriter(const std::filesystem::path& path);
    // Thread-safe; flushed before it returns. A failed write (a full disk) is an InputError naming the
    // file; the records written before it stay readable (at worst the last line is cut short, which
    // read_results reports and `--resume` reruns). When `kept` is given the record is also added to
    // it, in the file's order.
    void append(const TrialRecord& record, std::vector<TrialRecord>* kept = nullptr);

private:
    std::filesystem::path path_;
    std::ofstream out_;
    std::mutex mutex_;
    // Why the first write failed: every later append says the same, so that whichever thread's
    // exception a parallel run reports, it names the cause and the way out.
    std::string failure_;
};

struct LoadedResults {
    std::vector<TrialRecord> records;
    std::vector<std::string> notes;  // e.g. a truncated last line from an interrupted run
};
// Reads a results file; an unreadable line other than a truncated last one is an InputError.
LoadedResults read_results(const std::filesystem::path& path);

ExperimentInfo read_experiment_info(const std::filesystem::path& directory);
// Replaces experiment.json whole (temporary file and rename): a kill never leaves it half written.
void write_experiment_info(const std::filesystem::path& directory, const ExperimentInfo& info);

}  // namespace mhb
