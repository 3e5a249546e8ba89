#pragma once
// The diagnosis report's plots (gnuplot): residual against time and angle, segment means against
// speed, current and temperature, residual per segment, apparent parameters, the candidates and the
// search's path. Each is a PNG with an SVG beside it and its script and data in plot-data/.
#include <filesystem>
#include <string>

#include "problems/pmsm/report/diagnosis_report.hpp"

namespace mhb::pmsm {

// The PNG file names; empty for a plot that does not apply to the data or that gnuplot could not draw
// (the reason then in the outcome's notes).
struct DiagnosisPlots {
    std::string time, angle, speed, current, temperature, rms, apparent, candidates, path;
};

DiagnosisPlots draw_diagnosis_plots(const std::filesystem::path& directory, const Measurement& data, const Diagnosis& d,
                                    ReportOutcome& outcome);

}  // namespace mhb::pmsm
