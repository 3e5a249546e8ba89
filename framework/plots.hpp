#pragma once
// Plots of an experiment, drawn by gnuplot (PNG and SVG): convergence curves (median and
// inter-quartile band over trials, log scale), parameter convergence for problems with named
// parameters, and final-fitness box plots. The data behind each plot is kept in plot-data/.
#include <filesystem>
#include <string>
#include <vector>

#include "framework/results_store.hpp"

namespace mhb {

struct PlotOutcome {
    std::vector<std::filesystem::path> images;  // PNG files written (an SVG sits beside each)
    std::vector<std::string> notes;             // e.g. gnuplot missing: plots skipped
};

PlotOutcome write_plots(const std::filesystem::path& directory, const ExperimentInfo& info,
                        const std::vector<TrialRecord>& records);

// The colour of the i-th optimiser, the same in every plot.
std::string plot_line_style(std::size_t i);

// File-name form of a label: letters, digits, '-', '.' and '_' only.
std::string slug(const std::string& label);

// Runs a gnuplot script twice, once per terminal (pngcairo and svg), writing base.png and base.svg.
// Returns false (with the reason in `error`) when gnuplot is missing or fails.
bool render_gnuplot(const std::filesystem::path& base, const std::string& script_body, int width, int height,
                    std::string& error);

// A gnuplot string literal for a script: single-quoted, so gnuplot runs no backquoted command
// in it; control characters become blanks so the literal cannot end the command.
std::string gnuplot_quote(const std::string& text);

// A string column of a gnuplot data file (double-quoted, control characters as blanks).
std::string gnuplot_data_string(const std::string& text);

}  // namespace mhb
