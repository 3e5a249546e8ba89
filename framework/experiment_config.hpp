#pragma once
// Experiments are TOML files (see docs/config-reference.md). Loading one resolves and validates
// everything before a trial runs: every name is registered, every parameter value fits its
// declaration, and lists of values expand into a grid of variants.
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "framework/anytime.hpp"
#include "framework/optimizer.hpp"
#include "framework/parameters.hpp"

namespace mhb {

// One optimiser or problem as it will run: a registered name plus parameter values.
struct PluginVariant {
    std::string label;  // unique within the experiment; used in tables, plots and seeds
    std::string name;   // registry name
    std::map<std::string, ParameterValue> values;
    long line = 0;      // where it was declared in the config
    // Problems only: a box that replaces the problem's own (`lower`/`upper` keys; one value for
    // all coordinates or one per coordinate).
    std::vector<double> lower, upper;
    long bounds_line = 0;
};

// Numbers a paper published for the same experiment, shown beside ours (never used in a test of
// our results): `[[published]]` tables in the config.
struct PublishedResult {
    std::string label;    // e.g. "GWO (paper)"
    std::string problem;  // the problem label it belongs to
    std::string source;   // e.g. "He et al. 2024, Table 3"
    std::map<std::string, double> mean, sd;  // per parameter name
    std::optional<double> fitness_mean, fitness_sd, time_total;
    long line = 0;
};

struct ExperimentSpec {
    std::filesystem::path file;       // the TOML file
    std::string text;                 // its content, recorded with the results
    std::string name;
    std::string description;
    std::int64_t trials = 0;
    std::uint64_t seed = 0;
    Budget budget;
    // `budget.evaluations_per_dimension`: each problem's evaluation budget is this times its
    // dimension (as COCO budgets scale), in place of one `evaluations` for all; 0 when not given.
    std::int64_t evaluations_per_dimension = 0;
    // `budget.evaluations_by_dimension`: each problem's evaluation budget by its dimension (the CEC
    // 2022 protocol's 200 000 at D = 10 and 1 000 000 at D = 20), in place of `evaluations`.
    std::map<int, std::int64_t> evaluations_by_dimension;
    long evaluations_by_dimension_line = 0;
    std::filesystem::path output;     // resolved: relative paths are relative to the config file
    std::vector<PluginVariant> optimizers;
    std::vector<PluginVariant> problems;
    std::string baseline;             // optimiser label the others are tested against
    std::vector<std::string> references;  // labels for pairwise columns (default: the baseline)
    // `analysis.error_threshold`: errors f - f* below it are reported as 0 (the CEC rule, 1e-8); 0: none.
    double error_threshold = 0;
    long error_threshold_line = 0;
    // `mhbench run --dimension D`: only the problems of this dimension run (0: all); recorded with
    // the results, so that a directory says which part of the config it holds.
    int selected_dimension = 0;
    bool plots = true;
    // `analysis.per_problem = false`: no table and no plot per problem variant (a campaign has
    // thousands); the CSV keeps every row, and the summaries across problems stay.
    bool per_problem = true;
    std::vector<PublishedResult> published;
    std::vector<std::filesystem::path> plugins;  // `plugins`, relative paths resolved against the config
    std::optional<AnytimeSpec> anytime;          // `[anytime]`: record runtimes to targets (ERT, ECDF)
};

// Whether reading a config loads the plugin libraries its `plugins` list names. Loading runs their
// code, so whatever only checks a config's text (the fuzzers) records the paths and loads nothing.
enum class PluginLoading { load, record_only };

// Upper limits of what a config may ask for, checked before any trial runs (the messages give them).
inline constexpr std::int64_t max_trials = 100'000;
inline constexpr std::int64_t max_budget_iterations = 10'000'000;
inline constexpr std::int64_t max_budget_evaluations = 1'000'000'000;
// Variants one [[optimizer]] or [[problem]] entry's lists may expand into: a few short lists
// multiply into billions, which would exhaust memory while the config is still being read.
inline constexpr std::int64_t max_grid_variants = 10'000;

// Throws InputError (file, line, field) for anything malformed, unknown or out of range.
ExperimentSpec load_experiment(const std::filesystem::path& file, PluginLoading plugins = PluginLoading::load);
// The same from text already read; `file` names it in messages and anchors a relative `output`.
ExperimentSpec parse_experiment(const std::string& text, const std::filesystem::path& file,
                                PluginLoading plugins = PluginLoading::load);

// The evaluation budget of a problem of this dimension: `evaluations_by_dimension` when given (0 for a
// dimension it does not list), else `evaluations_per_dimension` times the dimension, else `evaluations`.
std::int64_t evaluation_budget(const Budget& budget, std::int64_t evaluations_per_dimension,
                               const std::map<int, std::int64_t>& evaluations_by_dimension, int dimension);

// Expands list-valued entries into the cartesian product, in declaration order.
std::vector<std::map<std::string, ParameterValue>> expand_grid(
    const std::vector<std::pair<std::string, std::vector<ParameterValue>>>& axes);

}  // namespace mhb
