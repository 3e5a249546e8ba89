#pragma once
// The noise a diagnosis measures its evidence in: the long-run variance of each axis' residual
// within segments, and the likelihood ratio in units of it.
#include <vector>

#include "problems/pmsm/diagnosis/diagnosis.hpp"

namespace mhb::pmsm {

// The residual of `fit` with each segment's mean removed: its standard deviation per axis, and the
// long-run standard deviation of its mean (AR(1)-prewhitened Newey-West, at least sigma). The
// dispersion is left at 1.
NoiseEstimate estimate_noise(const Measurement& data, const ModelFit& fit);

// The noise measured from sample-to-sample differences, not from the residual's level: within each
// segment (the whole log without one), per axis, the mean square of the first differences of the
// residual of `fit` (2n rows, u_d then u_q), g0, and the lag-one correlation r of consecutive
// differences. The residual, not the voltage alone: the current sensors' noise enters the model
// through R i and omega L i as it enters the residual (on the seed's servo, R = 46 ohm times 1 mA is
// more than the voltage's own noise). Noise filtered to first order (a logging filter) has lag-one correlation
// rho = 1 + 2 r, and its variance is g0 / (2 (1 - rho)) (white noise: r = -1/2, g0 / 2); rho is taken
// in [0, 0.9]. Slow structure (a model's misfit, a drift, a settling) hardly moves a difference.
// Fills difference_sigma, difference_correlation and difference_pairs.
void difference_noise(const Measurement& data, const Eigen::VectorXd& residual, NoiseEstimate& noise);

// When the residual's standard deviation exceeds the difference-based one by more than this, the
// residual holds structure within segments and the evidence is measured in the difference-based
// noise. Below it, what the residual holds beyond the voltage's own noise (the current sensors'
// noise through the model, R and omega L times it) and the first-order assumption's error (about
// 10 % on noise that is part white, part filtered) can explain the gap.
inline constexpr double residual_structure_ratio = 1.5;

// Sum over axes of (RSS_model - RSS_candidate) / long-run variance, divided by the dispersion.
double likelihood_ratio(const ModelFit& model, const ModelFit& candidate, const NoiseEstimate& noise);

// The noise measured on the best-fitting of `fits` whose base parameters are all positive (the first
// of equals; the first fit when none is), with the overdispersion
// of its segment means: when even the best model tried leaves segment means that the noise cannot
// explain, every likelihood ratio is divided by that excess (Q / dof), as a quasi-likelihood does.
NoiseEstimate noise_of_best(const Measurement& data, const std::vector<const ModelFit*>& fits);

}  // namespace mhb::pmsm
