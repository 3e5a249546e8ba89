#pragma once
// The seed's identification model, eq. (6): the base steady-state model
//   u_d = R_s i_d - omega L_q i_q,   u_q = R_s i_q + omega L_d i_d + omega psi_f
// is linear in theta = (R_s, L_d, L_q, psi_f), so each fitness below is a quadratic in theta whose
// exact optimum and uncertainty follow from linear least squares (docs/pmsm.md, "Fitness").
#include <Eigen/Core>

#include "problems/pmsm/fit/linear_fit.hpp"
#include "problems/pmsm/data/measurement.hpp"

namespace mhb::pmsm {

enum class Fitness {
    MeanSquared,    // f = (1/n) sum_k (e_d,k^2 + e_q,k^2)
    NoiseWeighted,  // f = (1/n) sum_k (e_d,k^2 / s_d^2 + e_q,k^2 / s_q^2), s_a from the LS residual of axis a
};
Fitness parse_fitness(const std::string& name);  // "mse" or "noise_weighted"
const char* to_string(Fitness fitness);

// Stacked regression: rows 0..n-1 the d axis, rows n..2n-1 the q axis; columns Rs, Ld, Lq, psi_f.
void base_regression(const Measurement& m, Eigen::MatrixXd& phi, Eigen::VectorXd& y);

struct BaseModelFit {
    Fitness fitness = Fitness::MeanSquared;
    Eigen::Index samples = 0;
    Eigen::Vector2d axis_noise{0.0, 0.0};   // rms residual of each axis at the unweighted LS optimum (V)
    Eigen::Vector2d axis_weight{1.0, 1.0};  // weight of each axis' squared error in the fitness
    LeastSquares least_squares;             // of the weighted regression; fitness = sum_of_squares / samples
    BoxLeastSquares in_bounds;              // exact optimum inside Table 2's box
    ParameterUncertainty uncertainty;       // of the unconstrained optimum

    double fitness_at(const Eigen::Ref<const Eigen::VectorXd>& theta) const {
        return least_squares.sum_of_squares(theta) / static_cast<double>(samples);
    }
};

// Fits eq. (6) to all rows of `m`; serial correlation is taken within segments when m has them.
BaseModelFit fit_base_model(const Measurement& m, Fitness fitness, CovarianceMethod method);

}  // namespace mhb::pmsm
