#pragma once
// report.html of a results directory, for people: where the results came from, the tables (from the
// document table.md is written from, so the two never say different things), the plots inline and the configuration
// the run read. One file that opens offline in any browser.
#include <filesystem>
#include <string>
#include <vector>

#include "framework/report_document.hpp"
#include "framework/results_store.hpp"

namespace mhb {

struct ExperimentPlots {
    std::vector<std::filesystem::path> images;  // PNG files written by write_plots; the SVG beside each is shown
    std::string absent_because;                 // what the report says instead when there are none
};

// Writes `directory`/report.html and returns its path; InputError when a plot cannot be read or the
// file cannot be written.
std::filesystem::path write_experiment_report(const std::filesystem::path& directory, const ExperimentInfo& info,
                                              const Document& tables, const ExperimentPlots& plots);

}  // namespace mhb
