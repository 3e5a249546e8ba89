#pragma once
// The shaft's mechanical angle at each row, against which lack_of_fit tests harmonics at mechanical
// orders (docs/diagnosis.md, "Harmonics at mechanical orders"): the logged theta_m when there is
// one, else the speed integrated over time within each segment.
#include <string>

#include <Eigen/Core>

#include "problems/pmsm/data/measurement.hpp"

namespace mhb::pmsm {

struct ShaftAngle {
    Eigen::VectorXd angle;  // rad, one per row; empty when the log gives no mechanical angle
    // The logged theta_m: one zero, a mark on the shaft, for every segment, so a harmonic's phase
    // means the same in each. Otherwise integrated, from zero at each segment's first row: where the
    // shaft stood then is unknown, so each segment has a phase of its own.
    bool logged = false;
    int pole_pairs = 0;   // 0: not known
    std::string source;   // how the angle was had, or why there is none, in words

    bool available() const { return angle.size() > 0; }
};

// The mechanical angle of `data`, with `pole_pairs` from the user (0: not known). Without a known
// count, one is taken from the logged theta_e and theta_m when both are logged (their steps' ratio
// within 0.05 of a whole number); a mechanical order can only be told from an electrical one with it.
ShaftAngle shaft_angle(const Measurement& data, int pole_pairs);

// Within each segment, from zero at its first row: the trapezoidal integral of omega_e / pole_pairs
// over t. With theta_e logged, each step is instead the electrical angle's own step divided by the
// pole pairs, unwrapped to the turn nearest the integrated speed's (exact while the speed's step is
// off by less than pi electrical). Needs t.
Eigen::VectorXd integrated_shaft_angle(const Measurement& data, int pole_pairs);

}  // namespace mhb::pmsm
