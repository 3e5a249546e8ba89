#pragma once
// Operating points found in a raw log, one without a segment column: the steady windows between the
// steps, ramps and settling of a bench run, found as the stretches where no level change of the
// measured currents and speed can be told from their noise (a moving-sum change-point test,
// docs/diagnosis.md, "Operating points found in a raw log").
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "problems/pmsm/data/measurement.hpp"

namespace mhb::pmsm {

struct OperatingPointOptions {
    // G: rows in each of the two windows whose means the test compares. A level shift of about
    // 4.5 sqrt(2 / G) long-run standard deviations is found; 10 rows find two, and still resolve
    // windows of 30 rows.
    Eigen::Index bandwidth = 10;
    // Steady stretches shorter than this are dropped with the transients (0: three bandwidths).
    Eigen::Index min_rows = 0;
    // Probability that a log without any change gets a false one (over all its rows and channels).
    double false_alarm = 0.01;
};

struct SteadyWindow {
    Eigen::Index first = 0, rows = 0;
};

struct OperatingPoints {
    std::vector<SteadyWindow> windows;     // in order, disjoint
    Eigen::Index rows = 0;                 // the log's rows
    Eigen::Index transient_rows = 0;       // rows in no window
    Eigen::Index bandwidth = 0, min_rows = 0;
    double false_alarm = 0.0;
    double threshold = 0.0;                // of the standardised moving-sum statistic
    std::vector<double> scale;             // long-run standard deviation of each channel
    std::vector<std::string> channels;     // the channels tested
};

// The test on any channels (one column each, rows in time order). Throws std::invalid_argument on
// a bandwidth below 2 or a false-alarm probability outside (0, 1).
OperatingPoints find_steady_windows(const Eigen::MatrixXd& channels, const OperatingPointOptions& options = {});
// The same, with the windows' edges also held to the levels of the channels in `held` (same rows):
// a window ends where any of them leaves its level, though only `tested` is tested for changes.
OperatingPoints find_steady_windows(const Eigen::MatrixXd& tested, const Eigen::MatrixXd& held,
                                    const OperatingPointOptions& options = {});

// The test on a measurement's i_d, i_q and omega_e, with u_d and u_q held.
OperatingPoints find_operating_points(const Measurement& m, const OperatingPointOptions& options = {});

// The rows of the windows, each window a segment labelled "steady1", "steady2", ... InputError
// naming the file when no window was found.
Measurement select_operating_points(Measurement&& m, const OperatingPoints& points);

// What fit and diagnose (command line and Python) do with a log: without a segment column its steady
// windows are found and become its segments, the rows between them dropped; a given column wins
// (nothing found, nullopt).
std::optional<OperatingPoints> segment_at_operating_points(Measurement& m, const OperatingPointOptions& options = {});

// One line for fit's and diagnose's output: how many windows, how many rows dropped, the method.
std::string operating_points_summary(const OperatingPoints& points);

}  // namespace mhb::pmsm
