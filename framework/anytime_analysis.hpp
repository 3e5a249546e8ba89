#pragma once
// Runtime-to-target analysis of an experiment with [anytime], as COCO reports it: the expected
// running time (ERT) to each target, pooled over a function's instances, and the empirical
// cumulative distribution (ECDF) of runtimes over all (run, target) pairs, averaged over the
// functions of one dimension. Confidence intervals by bootstrap over runs.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "framework/report_document.hpp"
#include "framework/results_store.hpp"

namespace mhb {

// A function of the analysis: a problem name with its settings other than `instance` and
// `dimension` (a box given in the config included), at one dimension. Its problem variants are its instances; their runs are pooled.
struct AnytimeFunction {
    std::string label;                 // e.g. "bbob_f3", or "F1(scale=2)"
    int dimension = 0;
    std::vector<std::size_t> problems;  // indices into ExperimentInfo::problems
};
std::vector<AnytimeFunction> anytime_functions(const ExperimentInfo& info);

// One run's outcome for one target: the evaluation that reached it (0: never) and the evaluations
// the run used in all.
struct RunToTarget {
    std::int64_t hit = 0;
    std::int64_t evaluations = 0;
};

// ERT = (evaluations of all runs until they reached the target, or in all when they did not) /
// (runs that reached it); +inf when none did. The interval: 2.5 and 97.5 percentiles of the ERT
// of `bootstrap` resamples of the runs with replacement (nearest rank; +inf when a resample has no
// success); equal to the estimate when bootstrap is 0.
struct Ert {
    double value = 0.0, low = 0.0, high = 0.0;
    std::size_t successes = 0, runs = 0;
};
Ert expected_running_time(const std::vector<RunToTarget>& runs, int bootstrap, std::uint64_t seed);

// The fraction of (run, target) pairs reached within each budget (evaluations / dimension), per
// function, averaged over functions; with pointwise 2.5/97.5 bootstrap percentiles over runs
// (resampled within each function).
struct Ecdf {
    std::vector<double> budgets;  // evaluations / dimension
    std::vector<double> value, low, high;
};
// `runs[f]`: the runs of function f, each with its hits (one per target, 0 = never).
Ecdf runtime_ecdf(const std::vector<std::vector<std::vector<std::int64_t>>>& runs, int dimension,
                  const std::vector<double>& budgets, int bootstrap, std::uint64_t seed);

// The ERT tables and the ECDF at the end of the budget, as a section of table.md (no blocks without
// [anytime]).
Document anytime_section(const ExperimentInfo& info, const std::vector<TrialRecord>& records);

// ecdf_D<d>.png/.svg per dimension, drawn by `render(base, gnuplot body, width, height)`; the data
// beside the other plots' in `data_dir`.
void write_ecdf_plots(const std::filesystem::path& directory, const std::filesystem::path& data_dir, const ExperimentInfo& info,
                      const std::vector<TrialRecord>& records,
                      const std::function<bool(const std::filesystem::path&, const std::string&, int, int)>& render);

}  // namespace mhb
