#include "problems/pmsm/machine/power_law_flux.hpp"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace mhb::pmsm {

std::array<double, PowerLawSaturation::count> PowerLawSaturation::values() const {
    return {d0, dd, s, q0, qq, t, dq, u, v, magnet, bridge, bridge_saturation, w, bridge_q};
}

PowerLawSaturation PowerLawSaturation::from_values(const std::array<double, count>& x, double base_current,
                                                   double base_flux) {
    return {base_current, base_flux, x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8], x[9], x[10], x[11], x[12], x[13]};
}

const std::array<const char*, PowerLawSaturation::count>& PowerLawSaturation::parameter_names() {
    static const std::array<const char*, count> names{"a_d0", "a_dd", "S", "a_q0", "a_qq", "T", "a_dq", "U", "V",
                                                      "psi_n", "a_b", "a_bp", "W", "k_q"};
    return names;
}

std::string PowerLawSaturation::inadmissible_reason() const {
    if (!(base_current > 0.0) || !(base_flux > 0.0)) return "the base current and base flux must be positive";
    const auto x = values();
    for (int k = 0; k < count; ++k) {
        if (!std::isfinite(x[k])) return fmt::format("{} is not finite", parameter_names()[k]);
        // The magnet's flux may have either sign; every other coefficient and exponent is >= 0, which
        // keeps each term of the energy convex but the cross-saturation one.
        if (k != 9 && x[k] < 0.0) return fmt::format("{} = {} is negative", parameter_names()[k], x[k]);
    }
    if (!(d0 > 0.0) || !(q0 > 0.0)) return "a_d0 and a_q0 must be positive (finite unsaturated inductances)";
    return {};
}

PowerLawFlux::PowerLawFlux(const PowerLawSaturation& parameters) : p_(parameters) {
    if (const auto reason = p_.inadmissible_reason(); !reason.empty())
        throw std::invalid_argument("power-law flux model: " + reason);
    magnet_flux_ = flux_of_current(Complex{0.0, 0.0}).real();
}

void PowerLawFlux::energy_derivatives(double x, double y, double g[2], double h[3]) const {
    const double ax = std::abs(x), ay = std::abs(y);
    // Iron of each axis: a_0 z^2 / 2 + a_zz |z|^(E+2) / (E+2).
    const double xs = std::pow(ax, p_.s), yt = std::pow(ay, p_.t);
    g[0] = (p_.d0 + p_.dd * xs) * x;
    g[1] = (p_.q0 + p_.qq * yt) * y;
    h[0] = p_.d0 + (p_.s + 1.0) * p_.dd * xs;
    h[2] = p_.q0 + (p_.t + 1.0) * p_.qq * yt;
    h[1] = 0.0;
    // Cross saturation a_dq |x|^(U+2) |y|^(V+2) / ((U+2)(V+2)).
    if (p_.dq > 0.0) {
        const double xu = std::pow(ax, p_.u), yv = std::pow(ay, p_.v);
        g[0] += p_.dq / (p_.v + 2.0) * xu * x * yv * ay * ay;
        g[1] += p_.dq / (p_.u + 2.0) * xu * ax * ax * yv * y;
        h[0] += p_.dq * (p_.u + 1.0) / (p_.v + 2.0) * xu * yv * ay * ay;
        h[2] += p_.dq * (p_.v + 1.0) / (p_.u + 2.0) * xu * ax * ax * yv;
        h[1] += p_.dq * xu * x * yv * y;
    }
    // Bridge in parallel with the magnet: energy e(r) with e'(r) = g_b(r) r, r the weighted distance
    // from the magnet's own flux; convex because e' grows with r and r is a norm.
    if (p_.bridge > 0.0) {
        const double bx = x - p_.magnet, k = p_.bridge_q;
        const double r = std::sqrt(bx * bx + k * y * y);
        if (r > 0.0) {
            const double rw = std::pow(r, p_.w), den = 1.0 + p_.bridge_saturation * rw;
            const double gb = p_.bridge * rw / den;
            const double gb_r = p_.bridge * p_.w * rw / (den * den);  // g_b'(r) r, finite at r -> 0
            const double cx = bx / r, cy = k * y / r;
            g[0] += gb * bx;
            g[1] += k * gb * y;
            h[0] += gb + gb_r * cx * cx;
            h[1] += gb_r * cx * cy;
            h[2] += k * gb + gb_r * cy * cy;
        } else if (p_.w == 0.0) {  // a constant inverse inductance, whose Hessian is defined at r = 0 too
            const double gb = p_.bridge / (1.0 + p_.bridge_saturation);
            h[0] += gb;
            h[2] += k * gb;
        }
    }
}

Complex PowerLawFlux::current_of_flux(Complex psi) const {
    double g[2], h[3];
    energy_derivatives(psi.real() / p_.base_flux, psi.imag() / p_.base_flux, g, h);
    return {p_.base_current * g[0], p_.base_current * g[1]};
}

Inductance PowerLawFlux::inverse_inductance(Complex psi) const {
    double g[2], h[3];
    energy_derivatives(psi.real() / p_.base_flux, psi.imag() / p_.base_flux, g, h);
    const double scale = p_.base_current / p_.base_flux;
    return {scale * h[0], scale * h[1], scale * h[1], scale * h[2]};
}

Complex PowerLawFlux::flux_of_current(Complex i) const {
    const double jd = i.real() / p_.base_current, jq = i.imag() / p_.base_current;
    const double tolerance = 1e-13 * (1.0 + std::hypot(jd, jq));
    // From the magnet's own point, where the energy's curvature is that of the unloaded machine.
    double x = magnet_flux_ / p_.base_flux, y = 0.0;
    double g[2], h[3];
    energy_derivatives(x, y, g, h);
    double rd = g[0] - jd, rq = g[1] - jq;
    for (int iteration = 0; iteration < 200; ++iteration) {
        const double norm = std::hypot(rd, rq);
        if (norm <= tolerance) return {p_.base_flux * x, p_.base_flux * y};
        const double det = h[0] * h[2] - h[1] * h[1];
        if (!(std::abs(det) > 0.0)) break;
        const double sx = (h[2] * rd - h[1] * rq) / det, sy = (-h[1] * rd + h[0] * rq) / det;
        // Power laws overshoot from far away: halve until the residual falls.
        double scale = 1.0;
        for (int halving = 0; halving < 60; ++halving, scale *= 0.5) {
            double gc[2], hc[3];
            energy_derivatives(x - scale * sx, y - scale * sy, gc, hc);
            const double cd = gc[0] - jd, cq = gc[1] - jq;
            if (std::hypot(cd, cq) < norm) {
                x -= scale * sx;
                y -= scale * sy;
                rd = cd;
                rq = cq;
                std::copy(hc, hc + 3, h);
                break;
            }
        }
        if (scale < 1e-17) break;
    }
    if (std::hypot(rd, rq) <= 1e-9 * (1.0 + std::hypot(jd, jq))) return {p_.base_flux * x, p_.base_flux * y};
    throw std::runtime_error(fmt::format("power-law flux model: no flux linkage found for the currents ({}, {}) A",
                                         i.real(), i.imag()));
}

Complex PowerLawFlux::flux(Complex i, double psi_f) const {
    return flux_of_current(i) + Complex{psi_f - magnet_flux_, 0.0};
}

Inductance PowerLawFlux::incremental_inductance(Complex i) const {
    const auto m = inverse_inductance(flux_of_current(i));
    const double det = m[0] * m[3] - m[1] * m[2];
    return {m[3] / det, -m[1] / det, -m[2] / det, m[0] / det};
}

Complex PowerLawFlux::current(Complex psi, double psi_f, Complex) const {
    return current_of_flux(psi - Complex{psi_f - magnet_flux_, 0.0});
}

}  // namespace mhb::pmsm
