#pragma once
// Lack of fit: structure in a residual beyond the noise. The segment means (each one's variance
// under noise alone is the long-run variance over its rows) and, when the angle is logged, the
// harmonics of the electrical angle fitted jointly with them.
#include <string>
#include <vector>

#include "problems/pmsm/diagnosis/diagnosis.hpp"

namespace mhb::pmsm {

inline constexpr int harmonic_orders = 12;  // of the electrical angle, tested in lack_of_fit

// P(chi^2_dof > statistic); 1 without degrees of freedom.
double chi_squared_survival(double statistic, double dof);

// Harmonics 1 to harmonic_orders of the electrical angle in `residual` (both axes stacked), fitted
// jointly with one mean per segment; each with its amplitude per axis, the standard error of an
// amplitude component under noise alone and the p-value of the more significant axis. Needs theta_e.
std::vector<Harmonic> angle_harmonics(const Measurement& data, const Eigen::VectorXd& residual, const NoiseEstimate& noise);

// The segment means of `fit`'s residual on `axis` (0: u_d, 1: u_q) in words: how large, and the
// operating condition they follow when one does (|r| >= 0.7).
std::string segment_means_signature(const Measurement& data, const ModelFit& fit, int axis);

// `residual` is the fit's (residual_of). Structure is significant at p < evidence::significance, for
// the harmonics after Bonferroni over their 2 x harmonic_orders tests.
LackOfFit lack_of_fit(const Measurement& data, const ModelFit& fit, const Eigen::VectorXd& residual, const NoiseEstimate& noise);

}  // namespace mhb::pmsm
