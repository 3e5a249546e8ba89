#pragma once
// Default strategy parameters of the (mu/mu_w, lambda)-CMA-ES (Hansen, "The CMA Evolution Strategy:
// A Tutorial", arXiv:1604.00772, 2016: eqs. (48)-(56) and the c_1, c_mu defaults, positive weights
// only) and the reflection the plugin can evaluate through; separate from the plugin so that tests
// can check them.
#include "framework/problem.hpp"

namespace mhb::cmaes {

struct StrategyParameters {
    int lambda = 0;     // offspring per generation
    int mu = 0;         // parents: the best mu offspring are recombined
    Vector weights;     // recombination weights w_1 >= ... >= w_mu > 0, summing to 1
    double mu_eff = 0;  // variance effective selection mass (sum w)^2 / sum w^2
    double c_sigma = 0; // learning rate of the step-size path
    double d_sigma = 0; // damping of the step-size update
    double c_c = 0;     // learning rate of the rank-one path
    double c_1 = 0;     // rank-one learning rate
    double c_mu = 0;    // rank-mu learning rate
    double chi_n = 0;   // E||N(0, I)||, approximated as in the tutorial
};

// The tutorial's defaults for dimension n >= 1; lambda = 0 selects 4 + floor(3 ln n), any other
// lambda must be at least 2 (ParameterError), so that mu >= 1.
StrategyParameters default_strategy(int n, int lambda = 0);

// Reflects x into [lo, hi] at both bounds, periodically (period 2 (hi - lo)): the identity inside
// the box, continuous everywhere.
double reflect_into(double x, double lo, double hi);

}  // namespace mhb::cmaes
