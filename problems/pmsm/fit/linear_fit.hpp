#pragma once
// Linear least squares for models linear in their parameters, y ~ Phi theta, as the base PMSM model
// is: the exact optimum (unconstrained, and inside a box by active-set enumeration), an O(p^2)
// evaluation of the objective for any candidate, and parameter uncertainty that can respect the
// serial correlation of closed-loop data (docs/pmsm.md, "Uncertainty").
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "framework/problem.hpp"

namespace mhb::pmsm {

// The sufficient statistics of a least-squares problem and its unconstrained optimum.
struct LeastSquares {
    Eigen::MatrixXd gram;      // Phi' Phi
    Eigen::VectorXd moment;    // Phi' y
    double total = 0.0;        // y' y
    Eigen::VectorXd solution;  // a minimiser (minimum norm when Phi is rank deficient)
    double rss = 0.0;          // residual sum of squares at `solution`, summed directly
    int rank = 0;

    // Sum of squares at theta, as rss + (theta - solution)' gram (theta - solution): the same
    // quadratic as theta' gram theta - 2 moment' theta + total, without its cancellation.
    double sum_of_squares(const Eigen::Ref<const Eigen::VectorXd>& theta) const;
};

// Solves by column-pivoting QR on the column-scaled regressor (the PMSM columns differ by orders of
// magnitude), so the solution is accurate even when the Gram matrix is ill conditioned.
LeastSquares solve_least_squares(const Eigen::MatrixXd& phi, const Eigen::VectorXd& y);

// The pseudo-inverse of a symmetric positive semi-definite matrix (a Gram matrix) through its
// column-scaled form, so that columns of very different magnitude do not decide the rank: directions
// the data do not determine (scaled eigenvalues below 1e-13 of the largest) get no weight.
Eigen::MatrixXd scaled_pseudo_inverse(const Eigen::MatrixXd& gram);

// The exact minimiser of the sum of squares inside a box: every combination of free coordinates and
// coordinates at a bound is tried (3^p of them, p <= 10), and the best point satisfying the KKT
// conditions is returned. `at_bound[j]` is -1 (lower), +1 (upper) or 0 (free).
struct BoxLeastSquares {
    Eigen::VectorXd solution;
    double rss = 0.0;
    std::vector<int> at_bound;
    bool any_bound_active() const;
};
BoxLeastSquares box_least_squares(const LeastSquares& ls, const Bounds& box);

// How rows are arranged: `axes` stacked blocks of `samples` rows each (row a * samples + k is axis a at
// sample k), and the block (segment) of each sample. Serial correlation is taken within a block.
struct RowLayout {
    Eigen::Index samples = 0;
    int axes = 1;
    Eigen::VectorXi block;  // size samples; empty: one block
};

enum class CovarianceMethod {
    White,      // independent errors with one variance per axis: the Jacobian-and-residual formula
    NeweyWest,  // autocorrelation consistent: AR(1) prewhitening of each axis' residuals within blocks,
                // then Newey-West (Bartlett kernel, Andrews bandwidth) on the whitened scores
};

struct ParameterUncertainty {
    CovarianceMethod method = CovarianceMethod::White;
    Eigen::MatrixXd covariance;
    Eigen::VectorXd standard_error;
    Eigen::VectorXd lower, upper;  // 95 % confidence interval
    double critical_value = 0.0;   // the t or z quantile used for the interval
    double lag = 0.0;              // Newey-West bandwidth in samples after prewhitening (0 for White)
    Eigen::VectorXd axis_sigma;    // residual standard deviation of each axis
    Eigen::VectorXd axis_rho;      // lag-1 autocorrelation of each axis' residuals within blocks
};

// Uncertainty of `estimate` for the regression (phi, y). Throws std::invalid_argument when the
// layout does not match phi or phi has fewer rows than columns.
ParameterUncertainty parameter_uncertainty(const Eigen::MatrixXd& phi, const Eigen::VectorXd& y,
                                           const Eigen::VectorXd& estimate, const RowLayout& layout,
                                           CovarianceMethod method);

// The same from the residual y - phi estimate, for a caller that has it (no second copy of y).
ParameterUncertainty residual_uncertainty(const Eigen::MatrixXd& phi, const Eigen::VectorXd& residual,
                                          const Eigen::VectorXd& estimate, const RowLayout& layout,
                                          CovarianceMethod method);

// A regressor made a block of samples at a time and never held whole, for logs too long to store a
// Jacobian: block b covers samples [b * block_samples, min(samples, (b + 1) * block_samples)) and
// fill(b, rows) writes their rows on every axis, axis a's at rows.middleRows(a * size, size). fill is
// called from several threads at once, and up to three times per block.
struct RegressorBlocks {
    Eigen::Index columns = 0;
    Eigen::Index block_samples = 512;
    std::function<void(Eigen::Index block, Eigen::Ref<Eigen::MatrixXd> rows)> fill;
};

// The same uncertainty from a regressor made in blocks: memory independent of the row count, the
// same numbers on any number of threads. The Newey-West sum over lags is taken as one running
// Bartlett-weighted sum per sample (two recursive sums), so its cost does not grow with the bandwidth.
ParameterUncertainty residual_uncertainty(const RegressorBlocks& phi, const Eigen::VectorXd& residual,
                                          const Eigen::VectorXd& estimate, const RowLayout& layout,
                                          CovarianceMethod method);

const char* to_string(CovarianceMethod method);

}  // namespace mhb::pmsm
