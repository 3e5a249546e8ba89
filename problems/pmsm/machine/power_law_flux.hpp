#pragma once
// A saturating machine whose currents derive from one magnetic energy W(psi_d, psi_q): the algebraic
// power-law model of Hinkkanen et al. (IEEE Trans. Ind. Appl. 53(3), 2017) for the iron of both axes,
// plus the saturating rotor bridge in parallel with a Norton-equivalent magnet of Lelli, Hinkkanen and
// Giulii Capponi (ICEM 2024) for a PM machine. docs/effects.md ("A physical saturation model") gives the
// equations and the reasons.
//
// Everything is per unit of the machine's own base current and base flux, so the same parameters give
// the same shape on a 0.3 A servo and a 400 A traction machine: x = psi_d / base_flux,
// y = psi_q / base_flux, i = base_current * grad w(x, y).
#include <array>
#include <string>

#include "problems/pmsm/machine/machine.hpp"

namespace mhb::pmsm {

struct PowerLawSaturation {
    static constexpr int count = 14;  // dimensionless parameters (the two bases aside)

    double base_current = 1.0;  // A: the current range the parameters are stated for
    double base_flux = 1.0;     // Wb
    // Iron (Hinkkanen 2017): inverse inductances per unit and exponents.
    double d0 = 1.0, dd = 0.0, s = 2.0;   // d axis: a_d0 + a_dd |x|^S
    double q0 = 1.0, qq = 0.0, t = 2.0;   // q axis: a_q0 + a_qq |y|^T
    double dq = 0.0, u = 1.0, v = 0.0;    // cross saturation a_dq |x|^U |y|^V
    // Bridge and magnet (Lelli 2024): the magnet's Norton flux per unit and the bridge's inverse
    // inductance a_b r^W / (1 + a_bp r^W), r = sqrt((x - magnet)^2 + k_q y^2).
    double magnet = 0.0, bridge = 0.0, bridge_saturation = 0.0, w = 2.0, bridge_q = 0.0;

    // The dimensionless parameters in a fixed order (the names are in parameter_names()).
    std::array<double, count> values() const;
    static PowerLawSaturation from_values(const std::array<double, count>& values, double base_current, double base_flux);
    static const std::array<const char*, count>& parameter_names();
    // Empty when the parameters are admissible (coefficients and exponents >= 0), else why not.
    std::string inadmissible_reason() const;
};

// The model as a plant's flux model. Built from the parameters, it finds its own magnet flux
// psi_d(0, 0); flux(i, psi_f) with a psi_f different from that shifts psi_d by the difference, as the
// measured FluxMap does, so flux() and incremental_inductance() agree for every psi_f.
class PowerLawFlux final : public FluxModel {
public:
    explicit PowerLawFlux(const PowerLawSaturation& parameters);

    Complex flux(Complex i, double psi_f) const override;
    Inductance incremental_inductance(Complex i) const override;
    // Explicit in this model: no iteration.
    Complex current(Complex psi, double psi_f, Complex guess) const override;

    // The currents that carry the flux linkage `psi` (the model's own magnet, no shift).
    Complex current_of_flux(Complex psi) const;
    // d(i_d, i_q)/d(psi_d, psi_q) at `psi`, in A/Wb: symmetric, and positive definite where the
    // magnetic energy is convex.
    Inductance inverse_inductance(Complex psi) const;
    // The flux linkage that carries the currents `i` (the model's own magnet): Newton on grad W = i,
    // each step halved until |grad W - i| falls (the Newton step always descends on that norm, since
    // the Hessian is symmetric). Throws std::runtime_error when it does not converge.
    Complex flux_of_current(Complex i) const;

    double magnet_flux() const { return magnet_flux_; }
    const PowerLawSaturation& parameters() const { return p_; }

private:
    // The per-unit energy's gradient and Hessian {xx, xy, yy} at (x, y).
    void energy_derivatives(double x, double y, double gradient[2], double hessian[3]) const;

    PowerLawSaturation p_;
    double magnet_flux_ = 0.0;
};

}  // namespace mhb::pmsm
