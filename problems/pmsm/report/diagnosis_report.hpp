#pragma once
// What `mhbench diagnose` prints and writes: console text, JSON for programs (the contract in
// docs/effects.md), and the diagnosis report for people: one directory with
// report.md and PNG plots (SVG beside each, the gnuplot scripts and data in plot-data/), and the same
// report as one self-contained page, report.html, with the plots inline.
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "problems/pmsm/data/operating_points.hpp"
#include "problems/pmsm/diagnosis/diagnosis.hpp"

namespace mhb::pmsm {

// fit_json of the model plus "candidates" (ranked, each with "rms_after" and "parameters"),
// "missing_effect_found", "winner", "tie", "not_in_library", the noise, lack of fit, segments,
// drifts, steps and findings.
nlohmann::ordered_json diagnosis_json(const Diagnosis& diagnosis);

std::string diagnosis_text(const Diagnosis& diagnosis);

struct ReportOutcome {
    std::filesystem::path markdown;
    std::filesystem::path html;
    std::vector<std::filesystem::path> images;  // PNG files written
    std::vector<std::string> notes;             // e.g. gnuplot missing
};

// The operating points found in a log without a segment column, as JSON (fit's and diagnose's
// `operating_points`, on the command line and in Python).
nlohmann::ordered_json operating_points_json(const OperatingPoints& points);

// A log without a segment column as it was read, and the steady windows found in it, which became the
// segments of the measurement diagnosed.
struct FoundOperatingPoints {
    const Measurement& log;
    const OperatingPoints& points;
};

// Writes report.md, report.html and the plots into `directory` (created). `data` is the measurement diagnosed;
// `data_options` (e.g. " --columns i_d=Id") follow `data_path` in the commands the report suggests,
// so that they read the file as the diagnosis did. With `found`, the report shows the raw log with its
// steady windows shaded.
ReportOutcome write_diagnosis_report(const std::filesystem::path& directory, const Measurement& data, const Diagnosis& diagnosis,
                                     const std::string& data_path, const std::string& data_options = "",
                                     const FoundOperatingPoints* found = nullptr);

}  // namespace mhb::pmsm
