#pragma once
// The diagnosis report's plots (gnuplot): residual against time and angle, segment means against
// speed, current and temperature, residual per segment, apparent parameters, the candidates and the
// search's path; for a log without a segment column, the log itself with the steady windows found in
// it. Each is a PNG with an SVG beside it and its script and data in plot-data/.
#include <filesystem>
#include <string>

#include "problems/pmsm/report/diagnosis_report.hpp"

namespace mhb::pmsm {

// The PNG file names; empty for a plot that does not apply to the data or that gnuplot could not draw
// (the reason then in the outcome's notes).
struct DiagnosisPlots {
    std::string time, angle, speed, current, temperature, rms, apparent, candidates, path, operating_points;
};

// The recommended model's fit, which the residual plots and the table of segments show beside the
// model diagnosed, when it is neither that model nor the base model they already show and its
// segment summaries line up with the diagnosis' segments; else null.
const ModelFit* recommended_to_show(const Diagnosis& d);

DiagnosisPlots draw_diagnosis_plots(const std::filesystem::path& directory, const Measurement& data, const Diagnosis& d,
                                    ReportOutcome& outcome, const FoundOperatingPoints* found = nullptr);

}  // namespace mhb::pmsm
