#pragma once
// A digital drive's sample and hold against the steady-state model (docs/diagnosis.md, "The control
// period's sample and hold"). The controller samples the currents once per control period T and
// holds the voltage it then computes, fixed in the stator frame, over the next period, at the angle
// its 1.5 T compensation aims at. Within a period the current decays toward its end value, so the
// sampled current and the logged voltage do not satisfy the continuous steady state the model writes,
// and a fit's inductances read high by about (T R_s / L)^2 / 12. The model cannot hold the voltage
// itself: that would make its prediction depend on R_s / L, and a fit splits every prediction
// affinely in the base parameters. So the bias is computed after the fit, from the base values, for a
// control period the user states.
#include <complex>

#include <Eigen/Core>

#include "problems/pmsm/data/measurement.hpp"

namespace mhb::pmsm {

// The voltage a drive with control period `period` logs at a steady operating point of the machine
// `base` (Rs, Ld, Lq, psi_f, linear iron): electrical speed `omega`, sampled current `current`
// (d + j q, rotor frame). The exact periodic solution of the rotor-frame circuit under a voltage held
// in the stator frame; the continuous model's (Rs + j omega L) i + j omega psi_f as the period goes to 0.
std::complex<double> held_voltage(const Eigen::Vector4d& base, double omega, std::complex<double> current, double period);

// What a stated control period does to a fit's base parameters.
struct SampleAndHold {
    double period = 0.0;                           // s, as the user stated it
    Eigen::Vector4d bias = Eigen::Vector4d::Zero();  // fitted - machine's, in the parameters' units
};

// How much a least-squares fit of the base model reads each base parameter above the machine's
// (fitted - true, in the parameters' units) on the operating points of `data` when its voltages are
// held over `period`, for a machine near `base`. One fixed-point step from the fitted values (the
// bias at the corrected values), on at most `max_rows` rows evenly spaced through the log.
Eigen::Vector4d sample_and_hold_bias(const Measurement& data, const Eigen::Vector4d& base, double period, Eigen::Index max_rows = 20000);

}  // namespace mhb::pmsm
