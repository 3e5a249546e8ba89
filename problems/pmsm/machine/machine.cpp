#include "problems/pmsm/machine/machine.hpp"

#include <stdexcept>

namespace mhb::pmsm {

Complex FluxModel::current(Complex psi, double psi_f, Complex guess) const {
    Complex i = guess;
    Complex residual = flux(i, psi_f) - psi;
    const double tolerance = 1e-14 * (std::abs(psi) + 1e-3);
    for (int iteration = 0; iteration < 60; ++iteration) {
        if (std::abs(residual) <= tolerance) return i;
        const auto l = incremental_inductance(i);
        const double det = l[0] * l[3] - l[1] * l[2];
        if (!(std::abs(det) > 0.0)) break;
        const Complex step{(l[3] * residual.real() - l[1] * residual.imag()) / det,
                           (-l[2] * residual.real() + l[0] * residual.imag()) / det};
        // Halve the step until the residual falls: a flux map is only piecewise smooth.
        double scale = 1.0;
        for (int halving = 0; halving < 30; ++halving, scale *= 0.5) {
            const Complex candidate = i - scale * step;
            const Complex r = flux(candidate, psi_f) - psi;
            if (std::abs(r) < std::abs(residual) || halving == 29) {
                i = candidate;
                residual = r;
                break;
            }
        }
    }
    if (std::abs(residual) <= 1e-9 * (std::abs(psi) + 1e-3)) return i;
    throw std::runtime_error("flux model: no current produces the flux linkage (" + std::to_string(psi.real()) + ", " +
                             std::to_string(psi.imag()) + ") Wb");
}

}  // namespace mhb::pmsm
