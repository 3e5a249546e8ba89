#pragma once
// Noise that the logged currents and voltages share, and what it does to a least-squares fit
// (docs/diagnosis.md, "Noise the current and the voltage share"). The steady-state model takes the
// logged current as exact, but it holds the current sensors' noise: that noise enters the model
// through R i, omega L i and an effect's law of the current (dead time's sign near each zero
// crossing), and a closed current loop answers it within the control period, so the logged voltage
// holds it too. Noise in both the regressor and the response, correlated, reads the parameters off
// the machine's (on the 5 kW machine's raw logs with 25 mA of current noise, R_s about 0.26 % low,
// twice its 95 % half-width). Within a steady window the model's regressors and the residual vary
// only by noise once their trend and what is locked to the angle are taken out, so their product
// there measures what the noise adds to the normal equations' right-hand side, and the normal
// matrix turns it into the parameters' bias.
#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "problems/pmsm/data/measurement.hpp"
#include "problems/pmsm/fit/model_fit.hpp"

namespace mhb::pmsm {

struct SharedNoise {
    Eigen::Vector4d bias = Eigen::Vector4d::Zero();            // fitted - machine's, in the parameters' units (0 when fixed)
    Eigen::Vector4d standard_error = Eigen::Vector4d::Zero();  // of that estimate, from its spread over the windows (NaN with one)
    // The fit's own standard errors of the base parameters were the windows' noise white (the
    // projected residual's mean square times (J'J)^-1): the scale a bias is judged on. A fit's
    // interval is at least this wide (its covariance allows for the noise's correlation).
    Eigen::Vector4d fit_standard_error = Eigen::Vector4d::Zero();
    std::size_t windows = 0;  // the windows it was measured in
    // Whether it moves a base parameter by a quarter of that parameter's fit_standard_error or more
    // (below that, a 95 % interval that ignores it still holds the truth 94 % of the time or more)
    // and by two of its own standard errors or more, measured in three windows or more (a smaller
    // shift is not told from the estimate's own spread: a misfit within the windows, a Jacobian the
    // data barely determine).
    bool relevant() const;
    // `fit`'s 95 % interval of base parameter `j` corrected: moved by this bias and `other` (another
    // correction's, such as the sample and hold's), widened by this estimate's standard error in
    // quadrature (it is independent of the fit's noise). NaN ends where the data do not determine it.
    std::pair<double, double> corrected_interval(const ModelFit& fit, Eigen::Index j, double other) const;
    // "Rs -0.275 % (standard error 0.0022 %)" for each base parameter of `fit`, relative to the
    // machine's value (fitted less the bias): what the finding and `fit`'s paragraph both print.
    std::vector<std::string> shift_texts(const ModelFit& fit) const;
};

// The bias of `fit`'s base parameters by noise the logged current and voltage share: with J the
// fit's Jacobian of its free parameters and r its residual less, in each window (segment), its
// quadratic trend in time and its means over the electrical angle's bins (noise.hpp,
// WindowProjection) and each window's J'r scaled by its rows over the rows the projection leaves,
// the Gauss-Newton step (J'J)^-1 J'r. The same cost as one step of the fit's polish. Nothing when the data have no angle (neither theta_e nor t: what is locked to the angle
// would be taken for noise), no window leaves the noise most of its rows, or J'J is singular.
std::optional<SharedNoise> shared_noise_bias(const Measurement& data, const ModelFit& fit);

}  // namespace mhb::pmsm
