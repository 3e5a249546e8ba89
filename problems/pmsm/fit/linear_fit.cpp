#include "problems/pmsm/fit/linear_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Dense>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
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

// Gram^{-1} through its equilibrated form; +inf everywhere when it is singular (some parameter
// combination is not determined by the data at all).
Eigen::MatrixXd gram_inverse(const Eigen::MatrixXd& gram) {
    Eigen::VectorXd s = gram.diagonal().cwiseMax(0.0).cwiseSqrt();
    for (Eigen::Index j = 0; j < s.size(); ++j)
        if (!(s[j] > 0.0)) s[j] = 1.0;
    const Eigen::MatrixXd g = s.cwiseInverse().asDiagonal() * gram * s.cwiseInverse().asDiagonal();
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(g);
    const double largest = eig.eigenvalues().maxCoeff();
    if (!(eig.eigenvalues().minCoeff() > 1e-14 * largest)) return Eigen::MatrixXd::Constant(gram.rows(), gram.cols(), inf);
    const Eigen::MatrixXd inverse =
        eig.eigenvectors() * eig.eigenvalues().cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
    return s.cwiseInverse().asDiagonal() * inverse * s.cwiseInverse().asDiagonal();
}

// Andrews (1991) automatic bandwidth for the Bartlett kernel from AR(1) fits to each score component:
// S = 1.1447 (alpha(1) n)^(1/3), alpha(1) = sum 4 rho^2 s^4 / ((1-rho)^6 (1+rho)^2) / sum s^4 / (1-rho)^4.
// From the sums over consecutive pairs within blocks: x the earlier score, y the later.
double andrews_bandwidth(const Eigen::ArrayXd& sxy, const Eigen::ArrayXd& sxx, const Eigen::ArrayXd& syy, Eigen::Index pairs,
                         Eigen::Index samples) {
    if (pairs == 0) return 0.0;
    double numerator = 0.0, denominator = 0.0;
    for (Eigen::Index j = 0; j < sxy.size(); ++j) {
        if (!(sxx[j] > 0.0)) continue;
        const double rho = std::clamp(sxy[j] / sxx[j], -0.97, 0.97);
        // sum (y - rho x)^2, expanded.
        const double innovation = std::max(syy[j] - 2.0 * rho * sxy[j] + rho * rho * sxx[j], 0.0);
        const double s4 = std::pow(innovation / static_cast<double>(pairs), 2);
        numerator += 4.0 * rho * rho * s4 / (std::pow(1.0 - rho, 6) * std::pow(1.0 + rho, 2));
        denominator += s4 / std::pow(1.0 - rho, 4);
    }
    if (!(denominator > 0.0)) return 0.0;
    return 1.1447 * std::cbrt(numerator / denominator * static_cast<double>(samples));
}

// The regression's residual and regressor rows a block of samples at a time, and the scores made
// from them. Prewhitening (after Andrews & Monahan 1992), on each axis' residual series: an AR(1)
// fitted within blocks takes out most of the autocorrelation of closed-loop errors, and dividing the
// innovations by (1 - rho) recolours their sums. The whitened scores, all axes together so their
// correlation is kept, then get Newey-West weights. This assumes the regressors change slowly
// against the errors' correlation time, as at held operating points; plain Bartlett weights on
// strongly persistent errors underestimate the variance badly.
struct ScoreStream {
    ScoreStream(const RegressorBlocks& regressors, const Eigen::VectorXd& residual, const RowLayout& layout)
        : regressors(regressors), residual(residual), layout(layout), n(layout.samples), p(regressors.columns),
          width(regressors.block_samples), axes(layout.axes), blocks((n + width - 1) / width) {}

    Eigen::Index block_size(Eigen::Index b) const { return std::min(width, n - b * width); }
    // Whether sample t continues the block (segment) of sample t - 1.
    bool continues(Eigen::Index t) const { return t > 0 && (layout.block.size() == 0 || layout.block[t] == layout.block[t - 1]); }
    // Block b's regressor rows, every axis (phi is resized).
    void fill(Eigen::Index b, Eigen::MatrixXd& phi) const {
        phi.resize(axes * block_size(b), p);
        regressors.fill(b, phi);
    }
    // The whitened scores of block b's samples (p x size), from its rows `phi`.
    void scores(Eigen::Index b, const Eigen::MatrixXd& phi, const Eigen::VectorXd& rho, Eigen::MatrixXd& out) const {
        const Eigen::Index first = b * width, size = block_size(b);
        out.setZero(p, size);
        for (int a = 0; a < axes; ++a) {
            const double* r = residual.data() + a * n;
            for (Eigen::Index k = 0; k < size; ++k) {
                const Eigen::Index t = first + k;
                // Prais-Winsten first term, so a block's first innovation has the same variance.
                const double innovation = continues(t) ? r[t] - rho[a] * r[t - 1] : std::sqrt(1.0 - rho[a] * rho[a]) * r[t];
                out.col(k) += phi.row(a * size + k).transpose() * (innovation / (1.0 - rho[a]));
            }
        }
    }

    const RegressorBlocks& regressors;
    const Eigen::VectorXd& residual;
    const RowLayout& layout;
    Eigen::Index n, p, width;
    int axes;
    Eigen::Index blocks;
};

// Each axis' residual standard deviation and lag-1 autocorrelation within blocks.
void axis_noise(const ScoreStream& stream, Eigen::VectorXd& sigma, Eigen::VectorXd& rho) {
    const Eigen::Index n = stream.n;
    sigma.resize(stream.axes);
    rho = Eigen::VectorXd::Zero(stream.axes);
    for (int a = 0; a < stream.axes; ++a) {
        const auto r = stream.residual.segment(a * n, n);
        sigma[a] = std::sqrt(r.squaredNorm() / static_cast<double>(n));
        double sxy = 0.0, sxx = 0.0;
        for (Eigen::Index t = 1; t < n; ++t)
            if (stream.continues(t)) {
                sxy += r[t] * r[t - 1];
                sxx += r[t - 1] * r[t - 1];
            }
        rho[a] = sxx > 0.0 ? std::clamp(sxy / sxx, -0.97, 0.97) : 0.0;
    }
}

struct GramAndLagSums {
    std::vector<Eigen::MatrixXd> gram;  // per axis
    Eigen::ArrayXd sxy, sxx, syy;       // lag-1 sums of the scores (Newey-West only)
    Eigen::Index pairs = 0;
};

// Pass 1: the Gram matrix of each axis and, with `lag_sums`, the lag-1 sums of the scores that choose
// the bandwidth. Each block's share, summed in block order.
GramAndLagSums gram_and_lag_sums(const ScoreStream& stream, const Eigen::VectorXd& rho, bool lag_sums) {
    const Eigen::Index p = stream.p, width = stream.width;
    struct Share {
        std::vector<Eigen::MatrixXd> gram;
        Eigen::ArrayXd sxy, sxx, syy;
        Eigen::Index pairs = 0;
        Eigen::VectorXd first, last;  // the block's first and last score, for the pairs across blocks
    };
    std::vector<Share> shares(static_cast<std::size_t>(stream.blocks));
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, stream.blocks), [&](const tbb::blocked_range<Eigen::Index>& range) {
        Eigen::MatrixXd phi, scores;
        for (Eigen::Index b = range.begin(); b != range.end(); ++b) {
            const Eigen::Index size = stream.block_size(b);
            stream.fill(b, phi);
            Share& share = shares[static_cast<std::size_t>(b)];
            for (int a = 0; a < stream.axes; ++a) {
                const auto block = phi.middleRows(a * size, size);
                share.gram.push_back(block.transpose() * block);
            }
            if (!lag_sums) continue;
            stream.scores(b, phi, rho, scores);
            share.sxy = share.sxx = share.syy = Eigen::ArrayXd::Zero(p);
            for (Eigen::Index k = 1; k < size; ++k)
                if (stream.continues(b * width + k)) {
                    share.sxy += scores.col(k).array() * scores.col(k - 1).array();
                    share.sxx += scores.col(k - 1).array().square();
                    share.syy += scores.col(k).array().square();
                    ++share.pairs;
                }
            share.first = scores.col(0);
            share.last = scores.col(size - 1);
        }
    });
    GramAndLagSums out;
    out.gram.assign(static_cast<std::size_t>(stream.axes), Eigen::MatrixXd::Zero(p, p));
    out.sxy = out.sxx = out.syy = Eigen::ArrayXd::Zero(p);
    for (Eigen::Index b = 0; b < stream.blocks; ++b) {
        const Share& share = shares[static_cast<std::size_t>(b)];
        for (int a = 0; a < stream.axes; ++a) out.gram[static_cast<std::size_t>(a)] += share.gram[static_cast<std::size_t>(a)];
        if (!lag_sums) continue;
        out.sxy += share.sxy;
        out.sxx += share.sxx;
        out.syy += share.syy;
        out.pairs += share.pairs;
        if (b > 0 && stream.continues(b * width)) {
            const Share& before = shares[static_cast<std::size_t>(b - 1)];
            out.sxy += share.first.array() * before.last.array();
            out.sxx += before.last.array().square();
            out.syy += share.first.array().square();
            ++out.pairs;
        }
    }
    return out;
}

// Pass 2: sum_t s_t s_t' + s_t g_t' + g_t s_t', g_t = sum_{1 <= l < lag} (1 - l / lag) s_{t-l} within
// the block. g_t = A_t - B_t / lag with A_t the plain and B_t the lag-weighted sum of the window, both
// updated in O(1) per sample. Chunks of a fixed number of blocks run in parallel; each first replays
// the window before its first sample.
Eigen::MatrixXd newey_west_sum(const ScoreStream& stream, const Eigen::VectorXd& rho, double lag) {
    const Eigen::Index n = stream.n, p = stream.p, width = stream.width;
    const Eigen::Index window = lag > 1.0 ? static_cast<Eigen::Index>(std::ceil(lag)) - 1 : 0;
    std::vector<Eigen::Index> run_starts;
    for (Eigen::Index t = 0; t < n; ++t)
        if (!stream.continues(t)) run_starts.push_back(t);
    constexpr Eigen::Index chunk_blocks = 64;
    const Eigen::Index chunks = (stream.blocks + chunk_blocks - 1) / chunk_blocks;
    std::vector<Eigen::MatrixXd> parts(static_cast<std::size_t>(chunks));
    tbb::parallel_for(Eigen::Index{0}, chunks, [&](Eigen::Index c) {
        const Eigen::Index begin = c * chunk_blocks * width, end = std::min(n, (c + 1) * chunk_blocks * width);
        const Eigen::Index run_start = *(std::upper_bound(run_starts.begin(), run_starts.end(), begin) - 1);
        const Eigen::Index replay = std::max(run_start, begin - window);
        Eigen::MatrixXd phi, scores, lagged, ring(p, std::max<Eigen::Index>(window, 1));
        Eigen::VectorXd plain = Eigen::VectorXd::Zero(p), weighted = Eigen::VectorXd::Zero(p);
        Eigen::Index filled = 0;
        Eigen::MatrixXd part = Eigen::MatrixXd::Zero(p, p);
        for (Eigen::Index b = replay / width; b * width < end; ++b) {
            const Eigen::Index first = b * width, size = stream.block_size(b);
            stream.fill(b, phi);
            stream.scores(b, phi, rho, scores);
            lagged.setZero(p, size);
            for (Eigen::Index k = std::max<Eigen::Index>(0, replay - first); k < size; ++k) {
                const Eigen::Index t = first + k;
                if (!stream.continues(t) || t == replay) {
                    plain.setZero();
                    weighted.setZero();
                    filled = 0;
                }
                if (window == 0) continue;
                lagged.col(k) = plain - weighted / lag;
                auto slot = ring.col(t % window);
                if (filled == window) {
                    weighted += plain + scores.col(k) - static_cast<double>(window + 1) * slot;
                    plain += scores.col(k) - slot;
                } else {
                    weighted += plain + scores.col(k);
                    plain += scores.col(k);
                    ++filled;
                }
                slot = scores.col(k);
            }
            const Eigen::Index from = std::max<Eigen::Index>(0, begin - first);
            if (from >= size) continue;
            const auto s = scores.rightCols(size - from);
            const auto g = lagged.rightCols(size - from);
            part.noalias() += s * s.transpose();
            part.noalias() += s * g.transpose();
            part.noalias() += g * s.transpose();
        }
        parts[static_cast<std::size_t>(c)] = std::move(part);
    });
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(p, p);
    for (const auto& part : parts) sum += part;
    return sum;
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
    if (phi.rows() != layout.samples * layout.axes)
        throw std::invalid_argument("parameter uncertainty: the row layout does not match the regression");
    RegressorBlocks blocks;
    blocks.columns = phi.cols();
    blocks.fill = [&](Eigen::Index b, Eigen::Ref<Eigen::MatrixXd> rows) {
        const Eigen::Index first = b * blocks.block_samples, size = rows.rows() / layout.axes;
        for (int a = 0; a < layout.axes; ++a) rows.middleRows(a * size, size) = phi.middleRows(a * layout.samples + first, size);
    };
    return residual_uncertainty(blocks, residual, estimate, layout, method);
}

ParameterUncertainty residual_uncertainty(const RegressorBlocks& regressors, const Eigen::VectorXd& residual,
                                          const Eigen::VectorXd& estimate, const RowLayout& layout,
                                          CovarianceMethod method) {
    const Eigen::Index p = regressors.columns, rows = layout.samples * layout.axes;
    if (residual.size() != rows || estimate.size() != p || regressors.block_samples < 1 || layout.axes < 1 ||
        (layout.block.size() != 0 && layout.block.size() != layout.samples))
        throw std::invalid_argument("parameter uncertainty: the row layout does not match the regression");
    if (rows <= p) throw std::invalid_argument("parameter uncertainty: needs more rows than parameters");
    const double dof_correction = static_cast<double>(rows) / static_cast<double>(rows - p);

    ParameterUncertainty u;
    u.method = method;
    const ScoreStream stream(regressors, residual, layout);
    axis_noise(stream, u.axis_sigma, u.axis_rho);
    const bool serial = method == CovarianceMethod::NeweyWest;
    const GramAndLagSums sums = gram_and_lag_sums(stream, u.axis_rho, serial);
    Eigen::MatrixXd total_gram = Eigen::MatrixXd::Zero(p, p);
    for (const auto& g : sums.gram) total_gram += g;
    const Eigen::MatrixXd bread = gram_inverse(total_gram);

    Eigen::MatrixXd meat = Eigen::MatrixXd::Zero(p, p);
    if (!serial) {
        for (int a = 0; a < layout.axes; ++a)
            meat += u.axis_sigma[a] * u.axis_sigma[a] * dof_correction * sums.gram[static_cast<std::size_t>(a)];
        u.critical_value = boost::math::quantile(boost::math::students_t(static_cast<double>(rows - p)), 0.975);
    } else {
        u.lag = andrews_bandwidth(sums.sxy, sums.sxx, sums.syy, sums.pairs, layout.samples);
        meat = newey_west_sum(stream, u.axis_rho, u.lag);
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
