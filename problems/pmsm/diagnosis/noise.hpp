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

// Sum over axes of (RSS_model - RSS_candidate) / long-run variance, divided by the dispersion.
double likelihood_ratio(const ModelFit& model, const ModelFit& candidate, const NoiseEstimate& noise);

// The noise measured on the best-fitting of `fits` whose base parameters are all positive (the first
// of equals; the first fit when none is), with the overdispersion
// of its segment means: when even the best model tried leaves segment means that the noise cannot
// explain, every likelihood ratio is divided by that excess (Q / dof), as a quasi-likelihood does.
NoiseEstimate noise_of_best(const Measurement& data, const std::vector<const ModelFit*>& fits);

}  // namespace mhb::pmsm
