#pragma once
// Result tables (Markdown for people, CSV for programs) from an experiment's trial records.
#include <filesystem>
#include <string>
#include <vector>

#include "framework/report_document.hpp"
#include "framework/results_store.hpp"

namespace mhb {

// Trials grouped per (problem, optimiser), in the experiment's declaration order.
struct TrialGroups {
    // groups[p][o] holds the successful trials; failed[p][o] counts the failed ones.
    std::vector<std::vector<std::vector<const TrialRecord*>>> ok;
    std::vector<std::vector<std::size_t>> failed;
};
TrialGroups group_trials(const ExperimentInfo& info, const std::vector<TrialRecord>& records);

// The value tables and plots use for a fitness f: f minus the known optimum when there is one, and 0
// when that error is below the experiment's error threshold (analysis.error_threshold).
double reported_error(const ExperimentInfo& info, const ProblemInfo& problem, double f);
// reported_error of a trial's final best fitness.
double final_error(const ExperimentInfo& info, const ProblemInfo& problem, const TrialRecord& record);

// What table.md says: per problem the final errors and identified parameters, the Friedman ranks and
// the anytime section.
Document tables_document(const ExperimentInfo& info, const std::vector<TrialRecord>& records);
// table.csv: a row per (problem, optimiser) with every statistic at full precision.
Table results_table(const ExperimentInfo& info, const std::vector<TrialRecord>& records);
std::string markdown_report(const ExperimentInfo& info, const std::vector<TrialRecord>& records);
std::string csv_table(const ExperimentInfo& info, const std::vector<TrialRecord>& records);

// Writes table.md and table.csv into `directory`; returns what table.md says.
Document write_tables(const std::filesystem::path& directory, const ExperimentInfo& info, const std::vector<TrialRecord>& records);

}  // namespace mhb
