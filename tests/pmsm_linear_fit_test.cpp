#include <catch2/catch.hpp>

#include <Eigen/Dense>
#include <tbb/task_arena.h>

#include "framework/random.hpp"
#include "problems/pmsm/fit/linear_fit.hpp"

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

namespace {

// The prewhitened Newey-West covariance written out as its definition (docs/pmsm.md, "Uncertainty"):
// the scores as a matrix, the Andrews bandwidth from direct sums, the Bartlett double sum over lags.
Eigen::MatrixXd direct_newey_west(const Eigen::MatrixXd& phi, const Eigen::VectorXd& r, const RowLayout& layout, double& lag) {
    const Eigen::Index n = layout.samples, p = phi.cols();
    auto starts = [&](Eigen::Index t) { return t == 0 || layout.block[t] != layout.block[t - 1]; };
    Eigen::MatrixXd scores = Eigen::MatrixXd::Zero(p, n);
    for (int a = 0; a < 2; ++a) {
        double sxy = 0.0, sxx = 0.0;
        for (Eigen::Index t = 0; t < n; ++t)
            if (!starts(t)) {
                sxy += r[a * n + t] * r[a * n + t - 1];
                sxx += r[a * n + t - 1] * r[a * n + t - 1];
            }
        const double rho = std::clamp(sxy / sxx, -0.97, 0.97);
        for (Eigen::Index t = 0; t < n; ++t) {
            const double e = starts(t) ? std::sqrt(1 - rho * rho) * r[a * n + t] : r[a * n + t] - rho * r[a * n + t - 1];
            scores.col(t) += phi.row(a * n + t).transpose() * e / (1 - rho);
        }
    }
    double numerator = 0.0, denominator = 0.0;
    for (Eigen::Index j = 0; j < p; ++j) {
        double sxy = 0.0, sxx = 0.0;
        Eigen::Index count = 0;
        for (Eigen::Index t = 1; t < n; ++t)
            if (!starts(t)) {
                sxy += scores(j, t) * scores(j, t - 1);
                sxx += scores(j, t - 1) * scores(j, t - 1);
                ++count;
            }
        const double rho = std::clamp(sxy / sxx, -0.97, 0.97);
        double innovation = 0.0;
        for (Eigen::Index t = 1; t < n; ++t)
            if (!starts(t)) innovation += std::pow(scores(j, t) - rho * scores(j, t - 1), 2);
        const double s4 = std::pow(innovation / static_cast<double>(count), 2);
        numerator += 4 * rho * rho * s4 / (std::pow(1 - rho, 6) * std::pow(1 + rho, 2));
        denominator += s4 / std::pow(1 - rho, 4);
    }
    lag = 1.1447 * std::cbrt(numerator / denominator * static_cast<double>(n));
    Eigen::MatrixXd meat = Eigen::MatrixXd::Zero(p, p);
    for (Eigen::Index t = 0; t < n; ++t) {
        meat += scores.col(t) * scores.col(t).transpose();
        Eigen::Index start = t;
        while (!starts(start)) --start;
        for (Eigen::Index l = 1; l < lag && t - l >= start; ++l)
            meat += (1 - static_cast<double>(l) / lag) *
                    (scores.col(t) * scores.col(t - l).transpose() + scores.col(t - l) * scores.col(t).transpose());
    }
    meat *= static_cast<double>(2 * n) / static_cast<double>(2 * n - p);
    const Eigen::MatrixXd bread = (phi.transpose() * phi).inverse();
    return bread * meat * bread;
}

}  // namespace

TEST_CASE("the Newey-West covariance from regressor blocks equals its direct double sum over lags", "[pmsm][linear_fit]") {
    // Errors of a slow AR(1) (0.998) at twice the white noise: one AR(1) prewhitening leaves the slow part
    // correlated, so the bandwidth spans many of the 5-sample blocks and crosses the 320-sample chunks
    // that run in parallel.
    RowLayout layout;
    const Eigen::Index per_point = 700;
    const Eigen::MatrixXd phi = operating_point_regressors(per_point, layout);
    const Eigen::Index n = layout.samples;
    Rng rng(21);
    Eigen::VectorXd residual(2 * n);
    double slow = 0.0;
    for (Eigen::Index k = 0; k < 2 * n; ++k) {
        slow = 0.998 * slow + std::sqrt(1 - 0.998 * 0.998) * rng.normal();
        residual[k] = 0.01 * (2 * slow + rng.normal());
    }
    double lag = 0.0;
    const Eigen::MatrixXd expected = direct_newey_west(phi, residual, layout, lag);

    RegressorBlocks blocks;
    blocks.columns = 4;
    blocks.block_samples = 5;
    blocks.fill = [&](Eigen::Index b, Eigen::Ref<Eigen::MatrixXd> rows) {
        const Eigen::Index size = rows.rows() / 2;
        rows.topRows(size) = phi.middleRows(b * 5, size);
        rows.bottomRows(size) = phi.middleRows(n + b * 5, size);
    };
    const auto streamed = residual_uncertainty(blocks, residual, Eigen::Vector4d::Zero(), layout, CovarianceMethod::NeweyWest);
    INFO("bandwidth " << lag);
    CHECK(lag > 3.0 * 5);
    CHECK(streamed.lag == Approx(lag).epsilon(1e-9));
    for (Eigen::Index i = 0; i < 4; ++i)
        for (Eigen::Index j = 0; j < 4; ++j) {
            INFO("covariance (" << i << ", " << j << ")");
            CHECK(streamed.covariance(i, j) == Approx(expected(i, j)).epsilon(1e-8).margin(1e-12 * std::abs(expected(i, i))));
        }
    // One thread gives the same numbers, bit for bit.
    tbb::task_arena one(1);
    const auto serial = one.execute([&] { return residual_uncertainty(blocks, residual, Eigen::Vector4d::Zero(), layout, CovarianceMethod::NeweyWest); });
    CHECK(serial.covariance == streamed.covariance);
}
