#include <catch2/catch.hpp>

#include <Eigen/Dense>

#include "framework/random.hpp"
#include "problems/pmsm/linear_fit.hpp"

using namespace mhb;
using namespace mhb::pmsm;

namespace {

Eigen::MatrixXd random_matrix(Eigen::Index rows, Eigen::Index cols, Rng& rng) {
    Eigen::MatrixXd m(rows, cols);
    for (Eigen::Index j = 0; j < cols; ++j)
        for (Eigen::Index i = 0; i < rows; ++i) m(i, j) = rng.normal();
    return m;
}

// Minimiser of |y - Phi x|^2 on a box by projected gradient descent with a fixed step 1/L (L the
// largest eigenvalue of the Gram matrix): slow but obviously correct, to check the enumeration.
Eigen::VectorXd projected_gradient(const Eigen::MatrixXd& phi, const Eigen::VectorXd& y, const Bounds& box) {
    const Eigen::MatrixXd g = phi.transpose() * phi;
    const Eigen::VectorXd b = phi.transpose() * y;
    const double step = 1.0 / Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(g).eigenvalues().maxCoeff();
    Eigen::VectorXd x = (box.lower + box.upper) / 2;
    for (int k = 0; k < 200000; ++k) x = (x - step * (g * x - b)).cwiseMax(box.lower).cwiseMin(box.upper);
    return x;
}

// Base-model regressors (Rs, Ld, Lq, psi_f) at a few steady operating points of the Table 1 motor:
// d rows [i_d, 0, -w i_q, 0], q rows [i_q, w i_d, 0, w]. Returns the layout with one block per point.
Eigen::MatrixXd operating_point_regressors(Eigen::Index per_point, RowLayout& layout) {
    struct Point {
        double w, i_d, i_q;
    };
    const std::vector<Point> points{{16.76, 0.0, 0.095}, {16.76, -0.1, 0.095}, {27.98, -0.2, 0.14},
                                    {-16.76, 0.0, -0.08}, {-27.98, -0.15, -0.11}, {16.76, -0.2, 0.05}};
    const Eigen::Index n = per_point * static_cast<Eigen::Index>(points.size());
    Eigen::MatrixXd phi = Eigen::MatrixXd::Zero(2 * n, 4);
    layout.samples = n;
    layout.axes = 2;
    layout.block.resize(n);
    for (Eigen::Index k = 0; k < n; ++k) {
        const auto& p = points[static_cast<std::size_t>(k / per_point)];
        layout.block[k] = static_cast<int>(k / per_point);
        phi.row(k) << p.i_d, 0.0, -p.w * p.i_q, 0.0;
        phi.row(n + k) << p.i_q, p.w * p.i_d, 0.0, p.w;
    }
    return phi;
}

struct Coverage {
    double white = 0.0, newey_west = 0.0;  // fraction of parameter intervals holding the truth
};

// Repeated noisy fits: noise per axis with standard deviations sigma_d, sigma_q and AR(1) coefficient
// rho within each block.
Coverage coverage(double rho, int repetitions, std::uint64_t seed) {
    RowLayout layout;
    const Eigen::MatrixXd phi = operating_point_regressors(150, layout);
    const Eigen::Vector4d truth(46.0, 0.02025, 0.02025, 0.04375);
    const Eigen::VectorXd clean = phi * truth;
    const double sigma[2] = {0.01, 0.03};
    Rng rng(seed);
    Coverage c;
    const Eigen::Index n = layout.samples;
    for (int r = 0; r < repetitions; ++r) {
        Eigen::VectorXd y = clean;
        for (int a = 0; a < 2; ++a) {
            double e = 0.0;
            for (Eigen::Index k = 0; k < n; ++k) {
                const double innovation = sigma[a] * std::sqrt(1 - rho * rho) * rng.normal();
                e = (k == 0 || layout.block[k] != layout.block[k - 1]) ? sigma[a] * rng.normal() : rho * e + innovation;
                y[a * n + k] += e;
            }
        }
        const auto ls = solve_least_squares(phi, y);
        for (auto method : {CovarianceMethod::White, CovarianceMethod::NeweyWest}) {
            const auto u = parameter_uncertainty(phi, y, ls.solution, layout, method);
            const double covered = ((truth.array() >= u.lower.array()) && (truth.array() <= u.upper.array())).cast<double>().mean();
            (method == CovarianceMethod::White ? c.white : c.newey_west) += covered / repetitions;
        }
    }
    return c;
}

}  // namespace

TEST_CASE("least squares: solution, sum of squares and rank", "[pmsm][linear_fit]") {
    Rng rng(1);
    const Eigen::MatrixXd phi = random_matrix(50, 4, rng) * Eigen::Vector4d(1e-3, 1.0, 1e3, 10.0).asDiagonal();
    const Eigen::VectorXd y = random_matrix(50, 1, rng);
    const auto ls = solve_least_squares(phi, y);
    const Eigen::VectorXd reference = phi.jacobiSvd(Eigen::ComputeThinU | Eigen::ComputeThinV).solve(y);
    CHECK((ls.solution - reference).cwiseQuotient(reference).cwiseAbs().maxCoeff() < 1e-10);
    CHECK(ls.rank == 4);
    const Eigen::Vector4d theta(0.3, -2.0, 1e-3, 0.5);
    const double direct = (y - phi * theta).squaredNorm();
    CHECK(ls.sum_of_squares(theta) == Approx(direct).epsilon(1e-12));
    CHECK(theta.dot(ls.gram * theta) - 2 * ls.moment.dot(theta) + ls.total == Approx(direct).epsilon(1e-9));

    // A rank-deficient design still has an exact optimum.
    Eigen::MatrixXd deficient = phi;
    deficient.col(3) = 2.0 * deficient.col(1);
    const auto d = solve_least_squares(deficient, y);
    CHECK(d.rank == 3);
    CHECK(d.rss == Approx(solve_least_squares(deficient.leftCols(3), y).rss).epsilon(1e-10));
}

TEST_CASE("the box least-squares optimum matches projected gradient descent", "[pmsm][linear_fit]") {
    Rng rng(7);
    for (int trial = 0; trial < 20; ++trial) {
        const Eigen::MatrixXd phi = random_matrix(30, 3, rng);
        const Eigen::VectorXd y = random_matrix(30, 1, rng) * 3.0;
        Bounds box{Eigen::Vector3d(-0.2, -0.3, 0.0), Eigen::Vector3d(0.4, 0.1, 0.5)};
        const auto ls = solve_least_squares(phi, y);
        const auto inside = box_least_squares(ls, box);
        const Eigen::VectorXd reference = projected_gradient(phi, y, box);
        CHECK((inside.solution - reference).cwiseAbs().maxCoeff() < 1e-8);
        CHECK(inside.rss == Approx((y - phi * reference).squaredNorm()).epsilon(1e-10));
        for (int j = 0; j < 3; ++j) {
            if (inside.at_bound[static_cast<std::size_t>(j)] < 0) CHECK(inside.solution[j] == box.lower[j]);
            if (inside.at_bound[static_cast<std::size_t>(j)] > 0) CHECK(inside.solution[j] == box.upper[j]);
        }
        const bool unconstrained_inside = ((ls.solution.array() >= box.lower.array()) && (ls.solution.array() <= box.upper.array())).all();
        CHECK(inside.any_bound_active() != unconstrained_inside);
    }
}

TEST_CASE("white intervals cover the truth at 95 % when the errors are independent", "[pmsm][linear_fit]") {
    // 200 repetitions x 4 parameters: the coverage's standard error is about 0.8 %.
    const auto c = coverage(0.0, 200, 11);
    CHECK(c.white > 0.925);
    CHECK(c.white < 0.975);
    CHECK(c.newey_west > 0.91);
    CHECK(c.newey_west < 0.975);
}

TEST_CASE("with serially correlated errors only Newey-West intervals keep their coverage", "[pmsm][linear_fit]") {
    // AR(1) with rho = 0.8 inflates the variance of a block mean about (1 + rho) / (1 - rho) = 9 times.
    const auto c = coverage(0.8, 200, 12);
    INFO("white " << c.white << ", newey-west " << c.newey_west);
    CHECK(c.white < 0.75);
    CHECK(c.newey_west > 0.91);
    CHECK(c.newey_west < 0.98);
}

TEST_CASE("parameter uncertainty refuses mismatched layouts and flags unidentifiable designs", "[pmsm][linear_fit]") {
    RowLayout layout;
    const Eigen::MatrixXd phi = operating_point_regressors(10, layout);
    const Eigen::VectorXd y = phi * Eigen::Vector4d(46.0, 0.02, 0.02, 0.04);
    RowLayout wrong = layout;
    wrong.samples += 1;
    CHECK_THROWS_AS(parameter_uncertainty(phi, y, Eigen::Vector4d::Zero(), wrong, CovarianceMethod::White), std::invalid_argument);
    // Only i_d = 0 points: L_d multiplies a zero column and is not determined at all.
    Eigen::MatrixXd no_injection = phi;
    no_injection.col(1).setZero();
    const auto u = parameter_uncertainty(no_injection, y, Eigen::Vector4d(46.0, 0.0, 0.02, 0.04), layout, CovarianceMethod::White);
    CHECK(std::isinf(u.standard_error[1]));
}
