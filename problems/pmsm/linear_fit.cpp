#include "problems/pmsm/linear_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Dense>
#include <boost/math/distributions/students_t.hpp>

namespace mhb::pmsm {
namespace {

constexpr double inf = std::numeric_limits<double>::infinity();

// Column norms used to equilibrate the regressor (1 for an all-zero column).
Eigen::VectorXd column_scale(const Eigen::MatrixXd& phi) {
    Eigen::VectorXd s = phi.colwise().norm().transpose();
    for (Eigen::Index j = 0; j < s.size(); ++j)
        if (!(s[j] > 0.0)) s[j] = 1.0;
    return s;
}

// (Phi' Phi)^{-1} through the equilibrated Gram matrix; +inf everywhere when it is singular (some
// parameter combination is not determined by the data at all).
Eigen::MatrixXd gram_inverse(const Eigen::MatrixXd& phi) {
    const Eigen::VectorXd s = column_scale(phi);
    // Scaled after the product, so that no copy as long as the data is made.
    const Eigen::MatrixXd g = s.cwiseInverse().asDiagonal() * (phi.transpose() * phi) * s.cwiseInverse().asDiagonal();
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(g);
    const double largest = eig.eigenvalues().maxCoeff();
    if (!(eig.eigenvalues().minCoeff() > 1e-14 * largest))
        return Eigen::MatrixXd::Constant(phi.cols(), phi.cols(), inf);
    const Eigen::MatrixXd inverse =
        eig.eigenvectors() * eig.eigenvalues().cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
    return s.cwiseInverse().asDiagonal() * inverse * s.cwiseInverse().asDiagonal();
}

// Contiguous runs of equal block ids: [begin, end) sample ranges.
std::vector<std::pair<Eigen::Index, Eigen::Index>> block_runs(const RowLayout& layout) {
    std::vector<std::pair<Eigen::Index, Eigen::Index>> runs;
    Eigen::Index begin = 0;
    for (Eigen::Index k = 1; k <= layout.samples; ++k)
        if (k == layout.samples || (layout.block.size() > 0 && layout.block[k] != layout.block[k - 1])) {
            runs.emplace_back(begin, k);
            begin = k;
        }
    return runs;
}

// Andrews (1991) automatic bandwidth for the Bartlett kernel from AR(1) fits to each score component:
// S = 1.1447 (alpha(1) n)^(1/3), alpha(1) = sum 4 rho^2 s^4 / ((1-rho)^6 (1+rho)^2) / sum s^4 / (1-rho)^4.
double andrews_bandwidth(const Eigen::MatrixXd& scores, const std::vector<std::pair<Eigen::Index, Eigen::Index>>& runs) {
    double numerator = 0.0, denominator = 0.0;
    for (Eigen::Index j = 0; j < scores.rows(); ++j) {
        double sxy = 0.0, sxx = 0.0;
        for (const auto& [b, e] : runs)
            for (Eigen::Index t = b + 1; t < e; ++t) {
                sxy += scores(j, t) * scores(j, t - 1);
                sxx += scores(j, t - 1) * scores(j, t - 1);
            }
        if (!(sxx > 0.0)) continue;
        const double rho = std::clamp(sxy / sxx, -0.97, 0.97);
        double innovation = 0.0;
        Eigen::Index count = 0;
        for (const auto& [b, e] : runs)
            for (Eigen::Index t = b + 1; t < e; ++t, ++count) {
                const double u = scores(j, t) - rho * scores(j, t - 1);
                innovation += u * u;
            }
        if (count == 0) continue;
        const double s4 = std::pow(innovation / static_cast<double>(count), 2);
        numerator += 4.0 * rho * rho * s4 / (std::pow(1.0 - rho, 6) * std::pow(1.0 + rho, 2));
        denominator += s4 / std::pow(1.0 - rho, 4);
    }
    if (!(denominator > 0.0)) return 0.0;
    return 1.1447 * std::cbrt(numerator / denominator * static_cast<double>(scores.cols()));
}

}  // namespace

double LeastSquares::sum_of_squares(const Eigen::Ref<const Eigen::VectorXd>& theta) const {
    const Eigen::VectorXd d = theta - solution;
    return rss + d.dot(gram * d);
}

LeastSquares solve_least_squares(const Eigen::MatrixXd& phi, const Eigen::VectorXd& y) {
    if (phi.rows() != y.size()) throw std::invalid_argument("least squares: phi and y differ in rows");
    LeastSquares ls;
    const Eigen::VectorXd s = column_scale(phi);
    const Eigen::MatrixXd scaled = phi * s.cwiseInverse().asDiagonal();
    Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(scaled);
    ls.rank = static_cast<int>(cod.rank());
    ls.solution = cod.solve(y).cwiseQuotient(s);
    ls.gram = phi.transpose() * phi;
    ls.moment = phi.transpose() * y;
    ls.total = y.squaredNorm();
    ls.rss = (y - phi * ls.solution).squaredNorm();
    return ls;
}

bool BoxLeastSquares::any_bound_active() const {
    return std::any_of(at_bound.begin(), at_bound.end(), [](int b) { return b != 0; });
}

BoxLeastSquares box_least_squares(const LeastSquares& ls, const Bounds& box) {
    const auto p = static_cast<int>(ls.solution.size());
    if (p > 10) throw std::invalid_argument("box least squares: enumeration is limited to 10 parameters");
    BoxLeastSquares best;
    best.rss = inf;
    // A point inside the box whose free coordinates minimise the quadratic on their face: the box
    // optimum is one of these, so the smallest feasible one is it.
    std::vector<int> state(static_cast<std::size_t>(p), -1);
    Eigen::VectorXd x(p);
    for (bool more = true; more;) {
        std::vector<Eigen::Index> free;
        for (int j = 0; j < p; ++j) {
            if (state[static_cast<std::size_t>(j)] == 0) free.push_back(j);
            else x[j] = state[static_cast<std::size_t>(j)] < 0 ? box.lower[j] : box.upper[j];
        }
        bool feasible = true;
        if (!free.empty()) {
            const auto f = static_cast<Eigen::Index>(free.size());
            Eigen::MatrixXd g(f, f);
            Eigen::VectorXd rhs(f);
            for (Eigen::Index a = 0; a < f; ++a) {
                rhs[a] = ls.moment[free[static_cast<std::size_t>(a)]];
                for (int j = 0; j < p; ++j)
                    if (state[static_cast<std::size_t>(j)] != 0) rhs[a] -= ls.gram(free[static_cast<std::size_t>(a)], j) * x[j];
                for (Eigen::Index b = 0; b < f; ++b) g(a, b) = ls.gram(free[static_cast<std::size_t>(a)], free[static_cast<std::size_t>(b)]);
            }
            const Eigen::VectorXd scale = g.diagonal().cwiseSqrt().cwiseMax(1e-300);
            const Eigen::MatrixXd scaled = scale.cwiseInverse().asDiagonal() * g * scale.cwiseInverse().asDiagonal();
            const Eigen::VectorXd xf =
                Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(scaled).solve(rhs.cwiseQuotient(scale)).cwiseQuotient(scale);
            for (Eigen::Index a = 0; a < f && feasible; ++a) {
                const Eigen::Index j = free[static_cast<std::size_t>(a)];
                const double slack = 1e-12 * (box.upper[j] - box.lower[j]);
                if (!std::isfinite(xf[a]) || xf[a] < box.lower[j] - slack || xf[a] > box.upper[j] + slack) feasible = false;
                else x[j] = std::clamp(xf[a], box.lower[j], box.upper[j]);
            }
        }
        if (feasible) {
            const double rss = ls.sum_of_squares(x);
            if (rss < best.rss) {
                best.rss = rss;
                best.solution = x;
                best.at_bound = state;
            }
        }
        more = false;
        for (int j = 0; j < p && !more; ++j) {
            if (++state[static_cast<std::size_t>(j)] <= 1) more = true;
            else state[static_cast<std::size_t>(j)] = -1;
        }
    }
    return best;
}

ParameterUncertainty parameter_uncertainty(const Eigen::MatrixXd& phi, const Eigen::VectorXd& y,
                                           const Eigen::VectorXd& estimate, const RowLayout& layout,
                                           CovarianceMethod method) {
    if (y.size() != phi.rows() || estimate.size() != phi.cols())
        throw std::invalid_argument("parameter uncertainty: the row layout does not match the regression");
    return residual_uncertainty(phi, y - phi * estimate, estimate, layout, method);
}

ParameterUncertainty residual_uncertainty(const Eigen::MatrixXd& phi, const Eigen::VectorXd& residual,
                                          const Eigen::VectorXd& estimate, const RowLayout& layout,
                                          CovarianceMethod method) {
    const Eigen::Index n = layout.samples, p = phi.cols(), rows = phi.rows();
    if (n * layout.axes != rows || residual.size() != rows || estimate.size() != p ||
        (layout.block.size() != 0 && layout.block.size() != n))
        throw std::invalid_argument("parameter uncertainty: the row layout does not match the regression");
    if (rows <= p) throw std::invalid_argument("parameter uncertainty: needs more rows than parameters");
    const double dof_correction = static_cast<double>(rows) / static_cast<double>(rows - p);
    const Eigen::MatrixXd bread = gram_inverse(phi);

    ParameterUncertainty u;
    u.method = method;
    u.axis_sigma.resize(layout.axes);
    u.axis_rho = Eigen::VectorXd::Zero(layout.axes);
    const auto runs = block_runs(layout);
    for (int a = 0; a < layout.axes; ++a) {
        const auto r = residual.segment(a * n, n);
        u.axis_sigma[a] = std::sqrt(r.squaredNorm() / static_cast<double>(n));
        double sxy = 0.0, sxx = 0.0;
        for (const auto& [b, e] : runs)
            for (Eigen::Index t = b + 1; t < e; ++t) {
                sxy += r[t] * r[t - 1];
                sxx += r[t - 1] * r[t - 1];
            }
        u.axis_rho[a] = sxx > 0.0 ? std::clamp(sxy / sxx, -0.97, 0.97) : 0.0;
    }

    Eigen::MatrixXd meat = Eigen::MatrixXd::Zero(p, p);
    if (method == CovarianceMethod::White) {
        for (int a = 0; a < layout.axes; ++a) {
            const auto block = phi.middleRows(a * n, n);
            meat += u.axis_sigma[a] * u.axis_sigma[a] * dof_correction * (block.transpose() * block);
        }
        u.critical_value = boost::math::quantile(boost::math::students_t(static_cast<double>(rows - p)), 0.975);
    } else {
        // Prewhitening (after Andrews & Monahan 1992), on each axis' residual series: an AR(1) fitted
        // within blocks takes out most of the autocorrelation of closed-loop errors, and dividing the
        // innovations by (1 - rho) recolours their sums. The whitened scores, all axes together so
        // their correlation is kept, then get Newey-West weights. This assumes the regressors change
        // slowly against the errors' correlation time, as at held operating points; plain Bartlett
        // weights on strongly persistent errors underestimate the variance badly.
        Eigen::MatrixXd scores = Eigen::MatrixXd::Zero(p, n);
        for (int a = 0; a < layout.axes; ++a) {
            const auto r = residual.segment(a * n, n);
            const double rho = u.axis_rho[a];
            for (const auto& [b, e] : runs)
                for (Eigen::Index t = b; t < e; ++t) {
                    // Prais-Winsten first term, so the block's first innovation has the same variance.
                    const double innovation = t == b ? std::sqrt(1.0 - rho * rho) * r[t] : r[t] - rho * r[t - 1];
                    scores.col(t) += phi.row(a * n + t).transpose() * (innovation / (1.0 - rho));
                }
        }
        u.lag = andrews_bandwidth(scores, runs);
        for (const auto& [b, e] : runs) {
            const auto s = scores.middleCols(b, e - b);
            meat += s * s.transpose();
            for (Eigen::Index l = 1; l < e - b && static_cast<double>(l) < u.lag; ++l) {
                const double w = 1.0 - static_cast<double>(l) / u.lag;
                const Eigen::MatrixXd cross = s.rightCols(e - b - l) * s.leftCols(e - b - l).transpose();
                meat += w * (cross + cross.transpose());
            }
        }
        meat *= dof_correction;
        u.critical_value = 1.959963984540054;
    }
    u.covariance = bread * meat * bread.transpose();
    if (!bread.allFinite()) u.covariance.setConstant(inf);
    u.standard_error = u.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
    u.lower = estimate - u.critical_value * u.standard_error;
    u.upper = estimate + u.critical_value * u.standard_error;
    return u;
}

const char* to_string(CovarianceMethod method) {
    return method == CovarianceMethod::White ? "white" : "newey-west";
}

// The pseudo-inverse of a symmetric positive semi-definite matrix through its column-scaled form:
// directions the data do not determine (eigenvalues below 1e-13 of the largest) get no weight.
Eigen::MatrixXd scaled_pseudo_inverse(const Eigen::MatrixXd& gram) {
    const Eigen::Index p = gram.rows();
    Eigen::VectorXd scale = gram.diagonal().cwiseMax(0.0).cwiseSqrt();
    for (Eigen::Index j = 0; j < p; ++j)
        if (!(scale[j] > 0.0)) scale[j] = 1.0;
    const Eigen::MatrixXd scaled = scale.cwiseInverse().asDiagonal() * gram * scale.cwiseInverse().asDiagonal();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(scaled);
    const double largest = eig.eigenvalues().maxCoeff();
    Eigen::VectorXd inverse(p);
    for (Eigen::Index j = 0; j < p; ++j) inverse[j] = eig.eigenvalues()[j] > 1e-13 * largest ? 1.0 / eig.eigenvalues()[j] : 0.0;
    return scale.cwiseInverse().asDiagonal() * eig.eigenvectors() * inverse.asDiagonal() * eig.eigenvectors().transpose() *
           scale.cwiseInverse().asDiagonal();
}

}  // namespace mhb::pmsm
