#pragma once
// The synchronous machine in its rotor (dq) frame: parameters, amplitude-invariant transforms and the
// flux-linkage models the simulated plant can use.
#include <array>
#include <cmath>
#include <complex>
#include <numbers>

namespace mhb::pmsm {

using Complex = std::complex<double>;  // a space vector: real part d (or alpha), imaginary part q (or beta)

// Electrical parameters of the base model (seed eq. 1) plus the pole-pair number. Defaults: the seed's
// Table 1 motor. rs and psi_f are at the reference temperature (20 °C) when thermal effects are used.
struct MotorParameters {
    double rs = 46.0;         // stator resistance, Ω
    double ld = 0.02025;      // d-axis inductance, H
    double lq = 0.02025;      // q-axis inductance, H
    double psi_f = 0.04375;   // permanent-magnet flux linkage, Wb
    int pole_pairs = 16;
};

inline constexpr double reference_temperature = 20.0;  // °C at which rs and psi_f are stated

// Amplitude-invariant Clarke transform of three phase quantities to the alpha-beta space vector.
inline Complex clarke(double a, double b, double c) {
    return {(2.0 * a - b - c) / 3.0, (b - c) / std::numbers::sqrt3};
}
// Phase quantities of an alpha-beta space vector (no zero sequence).
inline std::array<double, 3> inverse_clarke(Complex v) {
    const double half_beta = 0.5 * std::numbers::sqrt3 * v.imag();
    return {v.real(), -0.5 * v.real() + half_beta, -0.5 * v.real() - half_beta};
}
// Stationary frame -> frame at electrical angle theta, and back.
inline Complex park(Complex alpha_beta, double theta) { return alpha_beta * std::polar(1.0, -theta); }
inline Complex inverse_park(Complex dq, double theta) { return dq * std::polar(1.0, theta); }

// Wraps an angle to [-pi, pi).
inline double wrap_angle(double a) {
    a = std::fmod(a + std::numbers::pi, 2.0 * std::numbers::pi);
    if (a < 0) a += 2.0 * std::numbers::pi;
    return a - std::numbers::pi;
}

// Jacobian of the flux linkage with respect to the currents (incremental inductances):
// {dpsi_d/di_d, dpsi_d/di_q, dpsi_q/di_d, dpsi_q/di_q}.
using Inductance = std::array<double, 4>;

// The plant's flux linkage as a function of the currents (rotor frame), with the permanent-magnet
// flux psi_f passed in so thermal effects can change it. The models mhbench brings are in
// flux_models.hpp.
class FluxModel {
public:
    virtual ~FluxModel() = default;
    virtual Complex flux(Complex i, double psi_f) const = 0;
    virtual Inductance incremental_inductance(Complex i) const = 0;
    // Inverts flux(): the currents that produce `psi`. Damped Newton from `guess` (the simulator passes
    // the previous step's current, so one or two iterations suffice).
    virtual Complex current(Complex psi, double psi_f, Complex guess) const;
};

// Electromagnetic torque of a dq machine, 1.5 p (psi_d i_q - psi_q i_d), in N m.
inline double electromagnetic_torque(int pole_pairs, Complex psi, Complex i) {
    return 1.5 * pole_pairs * (psi.real() * i.imag() - psi.imag() * i.real());
}

}  // namespace mhb::pmsm
