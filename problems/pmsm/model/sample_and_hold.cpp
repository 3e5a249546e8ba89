#include "problems/pmsm/model/sample_and_hold.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <unsupported/Eigen/MatrixFunctions>

#include "problems/pmsm/machine/machine.hpp"

namespace mhb::pmsm {
namespace {

using Matrix5 = Eigen::Matrix<double, 5, 5>;
using Vector5 = Eigen::Matrix<double, 5, 1>;

// State (psi_d, psi_q, v_d, v_q, 1): the rotor-frame flux under
// psi' = v - Rs L^-1 (psi - psi_f e_d) - omega J psi, and a stator-frame voltage held constant, seen
// from the rotor, v' = -omega J v (J turns by +90 degrees).
Matrix5 circuit(const Eigen::Vector4d& base, double omega) {
    const double rs = base[0], ld = base[1], lq = base[2], psi_f = base[3];
    Matrix5 a = Matrix5::Zero();
    a(0, 0) = -rs / ld;
    a(0, 1) = omega;
    a(0, 2) = 1.0;
    a(0, 4) = rs / ld * psi_f;
    a(1, 0) = -omega;
    a(1, 1) = -rs / lq;
    a(1, 3) = 1.0;
    a(2, 3) = omega;
    a(3, 2) = -omega;
    return a;
}

Eigen::Vector2d flux_of(const Eigen::Vector4d& base, std::complex<double> current) {
    return {base[1] * current.real() + base[3], base[2] * current.imag()};
}

// The controller computed the reference one period before the one it is applied over and turned it
// by 1.5 omega T: its stator-frame angle lies omega T / 2 ahead of the rotor's at the period's start.
std::complex<double> applied_turn(double omega, double period) { return std::polar(1.0, 0.5 * omega * period); }

// The carrier's switching pattern for the reference `u` (rotor frame at the period's start): the
// instants of one carrier period at which the legs switch, and the stator-frame voltage between them.
struct Pattern {
    std::vector<double> lengths;                // s
    std::vector<std::complex<double>> voltage;  // V, stator frame
};

Pattern pattern_of(std::complex<double> u, double omega, double angle, const DriveTiming& timing) {
    const double carrier = 1.0 / timing.carrier_frequency;
    const auto phase = inverse_clarke(u * applied_turn(omega, timing.control_period) * std::polar(1.0, angle));
    const double zero_sequence = -0.5 * (std::max({phase[0], phase[1], phase[2]}) + std::min({phase[0], phase[1], phase[2]}));
    std::array<double, 3> duty{};
    std::vector<double> instants{0.0, carrier};
    for (std::size_t x = 0; x < 3; ++x) {
        duty[x] = std::clamp(0.5 + (phase[x] + zero_sequence) / timing.dc_voltage, 0.0, 1.0);
        // A leg is high while the centred carrier (1 at the period's ends, 0 in its middle) is below its duty.
        if (duty[x] > 0.0 && duty[x] < 1.0)
            for (const double t : {0.5 * (1.0 - duty[x]) * carrier, 0.5 * (1.0 + duty[x]) * carrier}) instants.push_back(t);
    }
    std::sort(instants.begin(), instants.end());
    Pattern p;
    for (std::size_t k = 0; k + 1 < instants.size(); ++k) {
        const double length = instants[k + 1] - instants[k];
        if (!(length > 1e-12 * carrier)) continue;
        const double middle = instants[k] + 0.5 * length;
        std::array<double, 3> high{};
        for (std::size_t x = 0; x < 3; ++x)
            high[x] = std::abs(middle - 0.5 * carrier) < 0.5 * duty[x] * carrier ? timing.dc_voltage : 0.0;
        p.lengths.push_back(length);
        p.voltage.push_back(clarke(high[0], high[1], high[2]));
    }
    return p;
}

// The flux at the control period's end (rotor frame then) from `psi` at its start under the switched
// reference `u`, the rotor at electrical `angle` when the period starts.
Eigen::Vector2d switched_end_flux(const Matrix5& a, const Eigen::Vector2d& psi, std::complex<double> u, double omega, double angle,
                                  const DriveTiming& timing) {
    const Pattern p = pattern_of(u, omega, angle, timing);
    std::vector<Matrix5> step(p.lengths.size());
    for (std::size_t k = 0; k < step.size(); ++k) step[k] = (a * p.lengths[k]).exp();
    const auto carriers = static_cast<int>(std::lround(timing.control_period * timing.carrier_frequency));
    Vector5 z;
    z << psi, 0.0, 0.0, 1.0;
    double t = 0.0;
    for (int n = 0; n < carriers; ++n)
        for (std::size_t k = 0; k < step.size(); ++k) {
            const std::complex<double> seen = p.voltage[k] * std::polar(1.0, -(angle + omega * t));
            z[2] = seen.real();
            z[3] = seen.imag();
            z = step[k] * z;
            t += p.lengths[k];
        }
    return z.head<2>();
}

}  // namespace

void state_current_loop(Measurement& data, const DriveTiming& timing) {
    if (!(timing.current_bandwidth > 0.0)) return;
    data.current_loop_bandwidth = timing.current_bandwidth;
    data.current_loop_delay = 1.5 * timing.control_period;
}

double current_loop_period(const Measurement& data) { return data.current_loop_delay / 1.5; }

std::string current_loop_text(double bandwidth, double delay) {
    if (!(bandwidth > 0.0)) return {};
    return fmt::format("current loop: {:g} Hz, its delay {:g} µs (dead time's and flux harmonics' voltages reach the logged one "
                       "through it; docs/diagnosis.md, section 8)\n",
                       bandwidth, 1e6 * delay);
}

std::string timing_problem(const DriveTiming& timing) {
    if (!(timing.control_period > 0.0)) {
        if (timing.current_bandwidth > 0.0) return "current bandwidth: needs the control period as well";
        if (timing.carrier()) return "carrier frequency: needs the control period as well";
        return timing.dc_voltage > 0.0 ? "dc voltage: needs the control period as well" : "";
    }
    if (!timing.carrier()) return timing.dc_voltage > 0.0 ? "dc voltage: given without the carrier frequency" : "";
    if (!(timing.dc_voltage > 0.0)) return "carrier frequency: needs the DC voltage as well";
    const double carriers = timing.control_period * timing.carrier_frequency;
    if (!(carriers >= 0.999) || std::abs(carriers - std::round(carriers)) > 1e-6 * carriers)
        return fmt::format("carrier frequency: {:g} Hz is not a whole number of carrier periods per control period ({:g} s)",
                           timing.carrier_frequency, timing.control_period);
    return "";
}

std::string timing_text(const DriveTiming& timing) {
    std::string t = fmt::format("{:g} µs", 1e6 * timing.control_period);
    if (timing.carrier()) t += fmt::format(", carrier {:g} kHz from {:g} V", 1e-3 * timing.carrier_frequency, timing.dc_voltage);
    return t;
}

std::vector<std::string> shift_texts(const SampleAndHold& held, const std::vector<std::string>& names, const Eigen::VectorXd& fitted) {
    std::vector<std::string> out;
    for (Eigen::Index j = 0; j < 4; ++j)
        out.push_back(fmt::format("{} {:+.3g} %", names[static_cast<std::size_t>(j)], 100.0 * held.bias[j] / (fitted[j] - held.bias[j])));
    return out;
}

std::complex<double> held_voltage(const Eigen::Vector4d& base, double omega, std::complex<double> current, double period) {
    const Matrix5 e = (circuit(base, omega) * period).exp();
    // Steady state: the flux at the period's end, in the rotor frame, is the one at its start.
    const Eigen::Vector2d psi = flux_of(base, current);
    const Eigen::Vector2d rhs = psi - e.block<2, 2>(0, 0) * psi - e.block<2, 1>(0, 4);
    const Eigen::Vector2d v = e.block<2, 2>(0, 2).partialPivLu().solve(rhs);
    // v is the held voltage in the rotor frame at the period's start; the reference's own frame lies behind it.
    return std::complex<double>(v[0], v[1]) / applied_turn(omega, period);
}

std::complex<double> switched_voltage(const Eigen::Vector4d& base, double omega, std::complex<double> current, double angle, const DriveTiming& timing) {
    // The reference computed at the sample is applied from the next one, a period later.
    angle += omega * timing.control_period;
    const Matrix5 a = circuit(base, omega);
    const Eigen::Vector2d psi = flux_of(base, current);
    // Newton's method on the reference: the pattern moves its edges continuously with it.
    std::complex<double> u = held_voltage(base, omega, current, timing.control_period);
    const double scale = std::max(std::abs(u), 1e-3 * timing.dc_voltage);
    for (int iteration = 0; iteration < 8; ++iteration) {
        const Eigen::Vector2d r = switched_end_flux(a, psi, u, omega, angle, timing) - psi;
        const double h = 1e-7 * scale;
        Eigen::Matrix2d jacobian;
        jacobian.col(0) = (switched_end_flux(a, psi, u + h, omega, angle, timing) - psi - r) / h;
        jacobian.col(1) = (switched_end_flux(a, psi, u + std::complex<double>(0.0, h), omega, angle, timing) - psi - r) / h;
        const Eigen::Vector2d du = jacobian.partialPivLu().solve(-r);
        // Legs clamped at a duty of 0 or 1 stop moving with the reference; where none moves, the held
        // solution is as near as this gets.
        if (!du.allFinite()) return held_voltage(base, omega, current, timing.control_period);
        u += std::complex<double>(du[0], du[1]);
        if (std::hypot(du[0], du[1]) < 1e-12 * scale) break;
    }
    return u;
}

namespace {

// How far the base model's least-squares fit moves from `base` when the voltages of every `step`-th
// row of `data` are the drive's instead of the continuous model's at `base`: the fit of the
// differences (the model is linear in the base parameters). Parameters the rows do not determine
// (psi_f without speed) do not move.
Eigen::Vector4d refit_shift(const Measurement& data, const Eigen::Vector4d& base, const DriveTiming& timing, Eigen::Index step) {
    Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
    Eigen::Vector4d projected = Eigen::Vector4d::Zero();
    for (Eigen::Index k = 0; k < data.size(); k += step) {
        const double w = data.omega_e[k];
        const std::complex<double> i{data.i_d[k], data.i_q[k]};
        // The base model's columns (Rs, Ld, Lq, psi_f) on each axis.
        const Eigen::Vector4d on_d{i.real(), 0.0, -w * i.imag(), 0.0}, on_q{i.imag(), w * i.real(), 0.0, w};
        // Where the log has no angle, the rows take angles spread over a sixth of a turn, the carrier
        // pattern's period in the angle, so that the fit sees its average.
        const double angle = data.theta_e ? (*data.theta_e)[k] : std::numbers::pi / 3.0 * static_cast<double>((k / step) % 12) / 12.0;
        const std::complex<double> logged = timing.carrier() ? switched_voltage(base, w, i, angle, timing) : held_voltage(base, w, i, timing.control_period);
        const std::complex<double> difference = logged - std::complex<double>(on_d.dot(base), on_q.dot(base));
        normal += on_d * on_d.transpose() + on_q * on_q.transpose();
        projected += on_d * difference.real() + on_q * difference.imag();
    }
    return normal.completeOrthogonalDecomposition().solve(projected);
}

}  // namespace

Eigen::Vector4d sample_and_hold_bias(const Measurement& data, const Eigen::Vector4d& base, const DriveTiming& timing) {
    if (!(timing.control_period > 0.0) || !timing_problem(timing).empty() || data.size() == 0) return Eigen::Vector4d::Zero();
    // The circuit needs a positive resistance and inductances; an implausible fit gets no correction.
    if (!(base[0] > 0.0 && base[1] > 0.0 && base[2] > 0.0) || !base.allFinite()) return Eigen::Vector4d::Constant(std::nan(""));
    const Eigen::Index max_rows = timing.carrier() ? 500 : 20000;
    const Eigen::Index step = std::max<Eigen::Index>(1, (data.size() + max_rows - 1) / max_rows);
    // The fitted values are the machine's plus the bias; the bias is evaluated at the machine's.
    const Eigen::Vector4d first = refit_shift(data, base, timing, step);
    return refit_shift(data, base - first, timing, step);
}

}  // namespace mhb::pmsm
