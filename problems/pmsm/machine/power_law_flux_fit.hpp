#pragma once
// Fits the power-law magnetic model (power_law_flux.hpp) to measured flux linkages by least squares.
#include <vector>

#include "problems/pmsm/machine/flux_models.hpp"
#include "problems/pmsm/machine/power_law_flux.hpp"

namespace mhb::pmsm {

// Measured points: the flux linkage psi[k] carried by the currents i[k].
struct FluxPoints {
    std::vector<Complex> current;  // A
    std::vector<Complex> flux;     // Wb
};

// Every grid point of a measured map, at the map's own magnet flux.
FluxPoints flux_points(const FluxMap& map);

struct FluxFitOptions {
    double base_current = 0.0;  // A; 0: the largest |i_d| or |i_q| of the points
    double base_flux = 0.0;     // Wb; 0: the largest |psi_d| or |psi_q| of the points
    int iterations = 400;       // Levenberg-Marquardt iterations per stage
};

struct FluxModelFit {
    PowerLawSaturation parameters;
    // Misfit of the model's psi(i) at the measured currents: rms and largest error per axis, and the
    // map's span of each flux linkage (max - min), which the relative figures divide by.
    double rms_d = 0.0, rms_q = 0.0, max_error_d = 0.0, max_error_q = 0.0;  // Wb
    double span_d = 0.0, span_q = 0.0;                                       // Wb
    double relative_rms_d() const { return rms_d / span_d; }
    double relative_rms_q() const { return rms_q / span_q; }
    int iterations = 0;  // of both stages
};

// Two stages of Levenberg-Marquardt over the 14 dimensionless parameters (coefficients and exponents
// through their logarithms, so they stay positive): first on the currents i(psi) at the measured flux
// linkages, which is explicit and cheap and finds the basin; then on the flux linkages psi(i) at the
// measured currents, each point inverted by Newton, which is the misfit that matters to a plant. A
// step that makes the energy non-convex at a measured point is refused. The flux residuals are
// divided by each axis's span, so both axes weigh the same relative to their range. Throws
// std::invalid_argument for fewer points than parameters.
FluxModelFit fit_flux_model(const FluxPoints& points, const FluxFitOptions& options = {});
FluxModelFit fit_flux_model(const FluxMap& map, const FluxFitOptions& options = {});

}  // namespace mhb::pmsm
