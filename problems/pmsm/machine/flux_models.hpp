#pragma once
// Every flux model of the machine in one place, the way the plants use them: the linear machine of
// the base model, iron saturating with stored magnetic energy (the device plant), the saturation
// effect's polynomial co-energy, and a measured flux map.
#include <array>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "problems/pmsm/machine/machine.hpp"

namespace mhb::pmsm {

// psi_d = Ld i_d + psi_f, psi_q = Lq i_q: the machine of the base model.
class LinearFlux final : public FluxModel {
public:
    LinearFlux(double ld, double lq) : ld_(ld), lq_(lq) {}
    Complex flux(Complex i, double psi_f) const override { return {ld_ * i.real() + psi_f, lq_ * i.imag()}; }
    Inductance incremental_inductance(Complex) const override { return {ld_, 0.0, 0.0, lq_}; }
    Complex current(Complex psi, double psi_f, Complex) const override {
        return {(psi.real() - psi_f) / ld_, psi.imag() / lq_};
    }

private:
    double ld_, lq_;
};

// Iron whose permeability falls with the armature's stored magnetic energy. The co-energy
// W = psi_f i_d + Q (sqrt(1 + q/Q) - 1), q = L_d i_d^2 + L_q i_q^2, Q = L_q I_sat^2 gives
// psi_d = psi_f + k L_d i_d, psi_q = k L_q i_q with k = (1 + q/Q)^(-1/2): linear for small currents,
// the q flux tending to L_q I_sat, the d current saturating the q axis and back (reciprocal, since
// both come from one co-energy).
class SaturatingIron final : public FluxModel {
public:
    SaturatingIron(double ld, double lq, double saturation_current)
        : ld_(ld), lq_(lq), q_sat_(lq * saturation_current * saturation_current) {}

    Complex flux(Complex i, double psi_f) const override {
        const double k = permeability_factor(i);
        return {psi_f + k * ld_ * i.real(), k * lq_ * i.imag()};
    }

    Inductance incremental_inductance(Complex i) const override {
        const double k = permeability_factor(i);
        const double k3 = k * k * k / q_sat_;  // -2 dk/dq
        const double ld_id = ld_ * i.real(), lq_iq = lq_ * i.imag();
        const double cross = -k3 * ld_id * lq_iq;
        return {k * ld_ - k3 * ld_id * ld_id, cross, cross, k * lq_ - k3 * lq_iq * lq_iq};
    }

private:
    double permeability_factor(Complex i) const {
        const double q = ld_ * i.real() * i.real() + lq_ * i.imag() * i.imag();
        return 1.0 / std::sqrt(1.0 + q / q_sat_);
    }

    double ld_, lq_, q_sat_;
};

// The saturation effect's law (effects/saturation.cpp gives it; docs/effects.md, "The saturation
// effect"): the change of the flux linkages from the linear machine's, as the gradient of a magnetic
// co-energy in per-unit currents x = i_d / I_b, y = i_q / I_b. The q axis saturates through a knee:
// its incremental inductance falls by q (per unit of Psi_b / I_b) from its small-current value,
// smoothly around the knee current k (per unit of I_b),
//   Delta psi_q = -Psi_b q (y - k g(y / k)),   g(z) = z / sqrt(1 + z^2);
// the d flux changes with |i_q| (cross-saturation: it may first rise, where the q flux saturates a
// rotor bridge that short-circuits magnet flux, then fall as the iron saturates), and the d axis's
// inductance changes linearly with i_d, the magnet-side asymmetry (e):
//   w(x, y) = -q (y^2/2 - k^2 (sqrt(1 + (y/k)^2) - 1)) - a x y^2/2 - c x |y|^(V+2)/(V+2) + e x^3/3.
// Nothing more on the d axis: a steady-state log holds a few d currents (often three), and a knee or
// a cubic among them trades against L_d and psi_f (docs/effects.md).
// Reciprocal (d psi_d/d i_q = d psi_q/d i_d) by construction; neither value nor slope at zero current,
// so L_d, L_q and psi_f keep their meaning as the small-current inductances and the magnet flux.
struct CoenergySaturation {
    static constexpr int count = 6;
    // In the effect's declaration order: q, k, c, V, e, a.
    double q = 0.0, knee = 1.0, c = 0.0, v = 2.0, e = 0.0, a = 0.0;
    double base_current = 1.0, base_flux = 1.0;

    static CoenergySaturation from(const double* p, double base_current, double base_flux) {
        return {p[0], p[1], p[2], p[3], p[4], p[5], base_current, base_flux};
    }
    // The same law stated per unit of other scales (a plant's and a log's differ).
    CoenergySaturation rescaled(double current, double flux) const {
        const double ci = base_current / current, cf = base_flux / flux;
        return {q * cf / ci, knee * ci, c * cf * std::pow(ci, -(v + 2.0)), v, e * cf / (ci * ci), a * cf / (ci * ci), current, flux};
    }
    std::array<double, count> values() const { return {q, knee, c, v, e, a}; }
    // The flux the axis loses to its knee, per unit (u - k g(u/k)), and its slope 1 - g'(u/k).
    static double knee_loss(double u, double k) { return u - u / std::sqrt(1.0 + (u / k) * (u / k)); }
    static double knee_slope(double u, double k) {
        const double r = 1.0 + (u / k) * (u / k);
        return 1.0 - 1.0 / (r * std::sqrt(r));
    }
    Complex flux_change(double id, double iq) const {
        return flux_change(id, iq, std::pow(cross_base(iq), v), knee_loss(iq / base_current, knee));
    }
    // |y|, whose V-th power the cross-saturation takes.
    double cross_base(double iq) const { return std::abs(iq / base_current); }
    // The same given yv = pow(cross_base(iq), v) and loss = knee_loss(y, knee), for a caller that has
    // them already (the model side remembers them between the predictions of a Jacobian,
    // effects/saturation.cpp); without a square root or pow, a loop over rows of it vectorises.
    Complex flux_change(double id, double iq, double yv, double loss) const {
        const double x = id / base_current, y = iq / base_current, ay = std::abs(y);
        return {base_flux * (-0.5 * a * y * y - c * yv * ay * ay / (v + 2.0) + e * x * x),
                base_flux * (-q * loss - (a + c * yv) * x * y)};
    }
    // d(Delta psi_d, Delta psi_q)/d(i_d, i_q), {dd, dq, qd, qq}: symmetric, the Hessian of the co-energy change.
    Inductance inductance_change(double id, double iq) const {
        const double x = id / base_current, y = iq / base_current, ay = std::abs(y);
        const double per_ampere = base_flux / base_current, yv = std::pow(ay, v);
        const double cross = per_ampere * (-(a + c * yv) * y);
        return {per_ampere * 2.0 * e * x, cross, cross, per_ampere * (-q * knee_slope(y, knee) - (a + c * (v + 1.0) * yv) * x)};
    }
};

// The linear machine with the saturation effect's change (the plant side of the effect).
class CoenergySaturatedFlux final : public FluxModel {
public:
    CoenergySaturatedFlux(double ld, double lq, const CoenergySaturation& law) : ld_(ld), lq_(lq), law_(law) {}
    Complex flux(Complex i, double psi_f) const override {
        return Complex{ld_ * i.real() + psi_f, lq_ * i.imag()} + law_.flux_change(i.real(), i.imag());
    }
    Inductance incremental_inductance(Complex i) const override {
        Inductance l = law_.inductance_change(i.real(), i.imag());  // {dd, dq, qd, qq}
        l[0] += ld_;
        l[3] += lq_;
        return l;
    }

private:
    double ld_, lq_;
    CoenergySaturation law_;
};

// A measured flux map psi_d(i_d, i_q), psi_q(i_d, i_q) on a rectangular current grid, used as a
// saturated plant: bilinear interpolation inside the grid, linear extension from the edge cells
// outside it (continuous, so the Newton inversion for the currents stays well behaved).
class FluxMap final : public FluxModel {
public:
    // Reads a CSV with the columns i_d_A, i_q_A, psi_d_Vs, psi_q_Vs (any order, one row per grid point,
    // every grid point exactly once). Throws mhb::InputError naming file, line and column.
    // `nominal_psi_f` is the magnet flux the caller will pass at the reference temperature: a different
    // psi_f scales the map's own magnet flux psi_d(0, 0) by psi_f / nominal_psi_f.
    static FluxMap read(const std::filesystem::path& path, double nominal_psi_f);
    // The same from CSV text already read; `source` names it in messages.
    static FluxMap parse(const std::string& text, const std::string& source, double nominal_psi_f);
    FluxMap(std::vector<double> i_d, std::vector<double> i_q, std::vector<double> psi_d, std::vector<double> psi_q,
            double nominal_psi_f);

    Complex flux(Complex i, double psi_f) const override;
    Inductance incremental_inductance(Complex i) const override;

    // The map's own permanent-magnet flux, psi_d at zero current.
    double magnet_flux() const { return magnet_flux_; }
    // The psi_f at which flux() returns the map's own values.
    double nominal_psi_f() const { return nominal_psi_f_; }
    const std::vector<double>& i_d_grid() const { return i_d_; }
    const std::vector<double>& i_q_grid() const { return i_q_; }

private:
    struct Cell {
        std::size_t a, b;  // lower-left grid indices
        double u, v;       // position inside the cell (outside [0, 1] beyond the grid)
    };
    Cell locate(Complex i) const;
    double at(const std::vector<double>& table, std::size_t a, std::size_t b) const { return table[a * i_q_.size() + b]; }

    std::vector<double> i_d_, i_q_;        // ascending grid coordinates
    std::vector<double> psi_d_, psi_q_;    // row-major: index a * i_q_.size() + b
    double nominal_psi_f_;
    double magnet_flux_;
};

}  // namespace mhb::pmsm
