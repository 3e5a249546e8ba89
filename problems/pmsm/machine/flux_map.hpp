#pragma once
// A measured flux map psi_d(i_d, i_q), psi_q(i_d, i_q) on a rectangular current grid, used as a
// saturated plant: bilinear interpolation inside the grid, linear extension from the edge cells
// outside it (continuous, so the Newton inversion for the currents stays well behaved).
#include <filesystem>
#include <string>
#include <vector>

#include "problems/pmsm/machine/machine.hpp"

namespace mhb::pmsm {

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
