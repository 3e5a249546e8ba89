#pragma once
// Every flux model of the machine in one place, the way the plants use them: the linear machine of
// the base model, iron saturating with stored magnetic energy (the device plant), the saturation
// effect's polynomial co-energy, and a measured flux map.
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

// The saturation effect's polynomial co-energy (effects/saturation.cpp gives it): the change of the
// flux linkages from the linear machine's. Coefficient order: k_d2, k_d3, k_q3, k_q5, k_dq1, k_dq2, k_dq3.
inline Complex polynomial_flux_change(const double* k, double id, double iq) {
    const double iq2 = iq * iq;
    return {k[0] * id * id + k[1] * id * id * id + 0.5 * k[4] * iq2 + k[5] * id * iq2 + 0.25 * k[6] * iq2 * iq2,
            k[2] * iq2 * iq + k[3] * iq2 * iq2 * iq + k[4] * id * iq + k[5] * id * id * iq + k[6] * id * iq2 * iq};
}

class PolynomialFlux final : public FluxModel {
public:
    PolynomialFlux(double ld, double lq, const Eigen::VectorXd& k) : ld_(ld), lq_(lq) {
        for (int j = 0; j < 7; ++j) k_[j] = k[j];
    }
    Complex flux(Complex i, double psi_f) const override {
        return Complex{ld_ * i.real() + psi_f, lq_ * i.imag()} + polynomial_flux_change(k_, i.real(), i.imag());
    }
    Inductance incremental_inductance(Complex i) const override {
        const double id = i.real(), iq = i.imag(), iq2 = iq * iq;
        const double cross = k_[4] * iq + 2.0 * k_[5] * id * iq + k_[6] * iq2 * iq;
        return {ld_ + 2.0 * k_[0] * id + 3.0 * k_[1] * id * id + k_[5] * iq2, cross, cross,
                lq_ + 3.0 * k_[2] * iq2 + 5.0 * k_[3] * iq2 * iq2 + k_[4] * id + k_[5] * id * id + 3.0 * k_[6] * id * iq2};
    }

private:
    double ld_, lq_;
    double k_[7];
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
