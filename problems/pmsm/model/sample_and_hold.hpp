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
#include <string>
#include <vector>

#include <Eigen/Core>

#include "problems/pmsm/data/measurement.hpp"

namespace mhb::pmsm {

// The voltage a drive with control period `period` logs at a steady operating point of the machine
// `base` (Rs, Ld, Lq, psi_f, linear iron): electrical speed `omega`, sampled current `current`
// (d + j q, rotor frame). The exact periodic solution of the rotor-frame circuit under a voltage held
// in the stator frame; the continuous model's (Rs + j omega L) i + j omega psi_f as the period goes to 0.
std::complex<double> held_voltage(const Eigen::Vector4d& base, double omega, std::complex<double> current, double period);

// What the user states of the drive's timing: the control period alone, or with the carrier too.
struct DriveTiming {
    double control_period = 0.0;     // s: currents sampled and the voltage updated once a period
    double carrier_frequency = 0.0;  // Hz, a whole number of carrier periods per control period (0: not stated)
    double dc_voltage = 0.0;         // V, the DC link (with the carrier)
    double current_bandwidth = 0.0;  // Hz, the current loop's closed-loop bandwidth (0: not stated)
    bool carrier() const { return carrier_frequency > 0.0; }
};

// Tells `data` the drive's current loop when `timing` states its bandwidth: the models of the data
// then pass the voltage of effects with angle harmonics through it (pass_through_current_loop,
// model/steady_state_model.hpp), the loop's delay taken as 1.5 control periods (a period to compute,
// half a period of holding).
void state_current_loop(Measurement& data, const DriveTiming& timing);
// The control period of the loop `data` state (its delay less the half period of holding); 0 without one.
double current_loop_period(const Measurement& data);
// "current loop: 400 Hz, its delay 187.5 µs (...)" and a newline, for a stated loop; empty otherwise.
std::string current_loop_text(double bandwidth, double delay);

// What a stated timing does to a fit's base parameters.
struct SampleAndHold {
    DriveTiming timing;
    Eigen::Vector4d bias = Eigen::Vector4d::Zero();  // fitted - machine's, in the parameters' units
};

// Why `timing` cannot describe a drive, as "<field>: <reason>" with the field "control period",
// "carrier frequency" or "dc voltage"; empty when it can, or when nothing is stated.
std::string timing_problem(const DriveTiming& timing);
// "100 µs" or "100 µs, carrier 10 kHz from 28 V".
std::string timing_text(const DriveTiming& timing);
// "Rs +0.113 %" for each base parameter: how far `fitted` (named `names`) reads off the machine's by
// the sample and hold, in per cent of the machine's value: the sign convention of the shared noise's
// statement (SharedNoise::shift_texts), so that the two read alike side by side.
std::vector<std::string> shift_texts(const SampleAndHold& held, const std::vector<std::string>& names, const Eigen::VectorXd& fitted);

// The same with the inverter's legs switched by a centred carrier of `timing.carrier_frequency` from
// `timing.dc_voltage`, the duties from the phase references with the min-max zero sequence, and the
// currents sampled at the carrier's peak, where every leg is low: besides the hold, the current ripple
// whose mean under the resistance is not its sample. The pattern depends on where the voltage vector
// lies among the inverter's six sectors, so on the rotor's electrical `angle` at the sample (the
// logged theta_e); the rotor is taken as turning by omega T per period at that angle, the operating
// point as steady. Solved for the reference by Newton's method from held_voltage's.
std::complex<double> switched_voltage(const Eigen::Vector4d& base, double omega, std::complex<double> current, double angle,
                                      const DriveTiming& timing);

// How much a least-squares fit of the base model reads each base parameter above the machine's
// (fitted - true, in the parameters' units) on the operating points of `data` when its voltages are
// held over the control period (switched, when the carrier is stated), for a machine near `base`. One
// fixed-point step from the fitted values (the bias at the corrected values), on at most 20 000 rows
// evenly spaced through the log (500 with the carrier, whose solution costs about 65 times more).
// NaN when R_s, L_d or L_q of `base` is not positive (no circuit to solve).
Eigen::Vector4d sample_and_hold_bias(const Measurement& data, const Eigen::Vector4d& base, const DriveTiming& timing);

}  // namespace mhb::pmsm
