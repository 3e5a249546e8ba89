#pragma once
// `mhbench export --format iohprofiler`: a results directory as IOHprofiler data (the .info/.dat
// layout of IOHexperimenter's Analyzer logger), so that IOHanalyzer can load a campaign and draw its
// fixed-target and fixed-budget views. docs/campaigns.md, "Export to IOHanalyzer", describes the layout.
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace mhb {

struct ExportSummary {
    std::filesystem::path output;  // the folder to load into IOHanalyzer
    std::size_t algorithms = 0;    // folders written, one per optimiser with a successful trial
    std::size_t functions = 0;     // distinct functions with at least one run
    std::size_t runs = 0;          // run blocks written (successful trials)
    std::vector<std::string> notes;  // skipped trials, a truncated results line
};

// Reads `results_dir` (experiment.json and results.jsonl) and writes the IOHprofiler files under `out`.
// InputError, naming the file, when `results_dir` is not a results directory or holds no successful
// trial, and when `out` exists and is not an empty directory (an earlier export is never overwritten);
// nothing is written then.
ExportSummary export_iohprofiler(const std::filesystem::path& results_dir, const std::filesystem::path& out);

}  // namespace mhb
