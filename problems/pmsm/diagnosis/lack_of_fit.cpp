#include "problems/pmsm/diagnosis/lack_of_fit.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>
#include <boost/math/distributions/chi_squared.hpp>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "problems/pmsm/diagnosis/segments.hpp"
#include "problems/pmsm/diagnosis/verdict.hpp"

namespace mhb::pmsm {

using evidence::significance;

double chi_squared_survival(double statistic, double dof) {
    if (dof <= 0.0) return 1.0;
    return boost::math::cdf(boost::math::complement(boost::math::chi_squared(dof), std::max(statistic, 0.0)));
}

namespace {

constexpr int orders = harmonic_orders;

struct HarmonicEquations {
    Eigen::MatrixXd gram;    // segments + 2 orders columns: one indicator per segment, cos and sin of each order
    Eigen::MatrixXd moment;  // the same rows, one column per axis
};

// The regressors are never stored: each block of rows adds its share of X'X and X'r, the harmonics
// by turning e^{j theta}.
HarmonicEquations harmonic_normal_equations(const Measurement& data, const std::vector<RowRange>& ranges, const Eigen::VectorXd& residual) {
    const Eigen::Index n = data.size();
    const auto s = static_cast<Eigen::Index>(ranges.size());
    using Harmonics = Eigen::Matrix<double, 2 * orders, 1>;
    struct Share {
        Eigen::Matrix<double, 2 * orders, 2 * orders> harmonic_gram;
        Eigen::MatrixXd segment_harmonic;  // s x 2 orders
        Eigen::Matrix<double, 2 * orders, 2> harmonic_residual;
    };
    constexpr Eigen::Index block_rows = 4096;
    const Eigen::Index blocks = (n + block_rows - 1) / block_rows;
    std::vector<Share> shares(static_cast<std::size_t>(blocks));
    std::vector<Eigen::Index> segment_of_row(static_cast<std::size_t>(n));
    for (Eigen::Index k = 0; k < s; ++k)
        std::fill_n(segment_of_row.begin() + ranges[static_cast<std::size_t>(k)].first, ranges[static_cast<std::size_t>(k)].rows, k);
    tbb::parallel_for(Eigen::Index{0}, blocks, [&](Eigen::Index b) {
        Share& share = shares[static_cast<std::size_t>(b)];
        share.harmonic_gram.setZero();
        share.segment_harmonic = Eigen::MatrixXd::Zero(s, 2 * orders);
        share.harmonic_residual.setZero();
        Harmonics x;
        for (Eigen::Index t = b * block_rows; t < std::min(n, (b + 1) * block_rows); ++t) {
            const Complex rotor = std::polar(1.0, (*data.theta_e)[t]);
            Complex turn = rotor;
            for (int h = 0; h < orders; ++h) {
                x[2 * h] = turn.real();
                x[2 * h + 1] = turn.imag();
                turn *= rotor;
            }
            share.harmonic_gram.selfadjointView<Eigen::Lower>().rankUpdate(x);
            share.segment_harmonic.row(segment_of_row[static_cast<std::size_t>(t)]) += x.transpose();
            share.harmonic_residual.col(0) += residual[t] * x;
            share.harmonic_residual.col(1) += residual[n + t] * x;
        }
    });
    const Eigen::Index columns = s + 2 * orders;
    HarmonicEquations e{Eigen::MatrixXd::Zero(columns, columns), Eigen::MatrixXd::Zero(columns, 2)};
    for (Eigen::Index k = 0; k < s; ++k) {
        const auto& r = ranges[static_cast<std::size_t>(k)];
        e.gram(k, k) = static_cast<double>(r.rows);
        for (int a = 0; a < 2; ++a) e.moment(k, a) = residual.segment(a * n + r.first, r.rows).sum();
    }
    for (const auto& share : shares) {
        e.gram.bottomRightCorner(2 * orders, 2 * orders) += share.harmonic_gram.selfadjointView<Eigen::Lower>().toDenseMatrix();
        e.gram.topRightCorner(s, 2 * orders) += share.segment_harmonic;
        e.moment.bottomRows(2 * orders) += share.harmonic_residual;
    }
    e.gram.bottomLeftCorner(2 * orders, s) = e.gram.topRightCorner(s, 2 * orders).transpose();
    return e;
}

}  // namespace

std::vector<Harmonic> angle_harmonics(const Measurement& data, const Eigen::VectorXd& residual, const NoiseEstimate& noise) {
    const auto ranges = segment_ranges(data);
    const auto s = static_cast<Eigen::Index>(ranges.size());
    const HarmonicEquations e = harmonic_normal_equations(data, ranges, residual);
    const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(e.gram);
    const Eigen::MatrixXd inverse = cod.pseudoInverse();
    const Eigen::MatrixXd coefficients = inverse * e.moment;
    std::vector<Harmonic> out;
    for (int h = 1; h <= orders; ++h) {
        const Eigen::Index c = s + 2 * (h - 1);
        Harmonic harmonic;
        harmonic.order = h;
        const Eigen::Matrix2d block = inverse.block(c, c, 2, 2);
        harmonic.standard_error = std::sqrt(0.5 * block.trace()) * 0.5 * (noise.long_run[0] + noise.long_run[1]);
        double p_min = 1.0;
        for (int a = 0; a < 2; ++a) {
            const Eigen::Vector2d ab = coefficients.block(c, a, 2, 1);
            harmonic.amplitude[a] = ab.norm();
            const double statistic = ab.dot(block.ldlt().solve(ab)) / (noise.long_run[a] * noise.long_run[a]);
            p_min = std::min(p_min, block.determinant() > 0.0 ? chi_squared_survival(statistic, 2.0) : 1.0);
        }
        harmonic.p_value = p_min;
        out.push_back(harmonic);
    }
    return out;
}

std::string segment_means_signature(const Measurement& data, const ModelFit& fit, int a) {
    const auto& segments = fit.segments;
    std::vector<double> y;
    for (const auto& seg : segments) y.push_back(seg.mean[a]);
    auto mean_of = [&](const Eigen::VectorXd& v, std::size_t k) { return v.segment(segments[k].first, segments[k].rows).mean(); };
    std::vector<std::pair<std::string, std::vector<double>>> shapes;
    std::vector<double> omega, abs_omega, omega2, id, iq, mag, tw, tm, sign;
    for (std::size_t k = 0; k < segments.size(); ++k) {
        const double w = mean_of(data.omega_e, k), d = mean_of(data.i_d, k), q = mean_of(data.i_q, k);
        omega.push_back(w);
        abs_omega.push_back(std::abs(w));
        omega2.push_back(w * std::abs(w));
        id.push_back(d);
        iq.push_back(q);
        mag.push_back(std::hypot(d, q));
        sign.push_back(w >= 0 ? 1.0 : -1.0);
        if (data.temp_winding) tw.push_back(mean_of(*data.temp_winding, k));
        if (data.temp_magnet) tm.push_back(mean_of(*data.temp_magnet, k));
    }
    shapes = {{"omega_e", omega}, {"|omega_e|", abs_omega}, {"omega_e |omega_e|", omega2}, {"i_d", id},
              {"i_q", iq},        {"|i|", mag},              {"the direction", sign}};
    if (!tw.empty()) shapes.emplace_back("temp_winding", tw);
    if (!tm.empty()) shapes.emplace_back("temp_magnet", tm);
    const Eigen::Map<const Eigen::ArrayXd> ya(y.data(), static_cast<Eigen::Index>(y.size()));
    std::string best_name;
    double best_r = 0.0;
    for (const auto& [name, x] : shapes) {
        const Eigen::Map<const Eigen::ArrayXd> xa(x.data(), static_cast<Eigen::Index>(x.size()));
        const double sxx = (xa - xa.mean()).square().sum(), syy = (ya - ya.mean()).square().sum();
        if (!(sxx > 0.0) || !(syy > 0.0)) continue;
        const double r = ((xa - xa.mean()) * (ya - ya.mean())).sum() / std::sqrt(sxx * syy);
        if (std::abs(r) > std::abs(best_r)) {
            best_r = r;
            best_name = name;
        }
    }
    const double largest = ya.abs().maxCoeff();
    std::string text = fmt::format("segment means of the {} residual up to {:.3g} mV", a == 0 ? "u_d" : "u_q", 1e3 * largest);
    if (std::abs(best_r) >= 0.7) text += fmt::format(", following {} (r = {:.2f})", best_name, best_r);
    return text;
}

LackOfFit lack_of_fit(const Measurement& data, const ModelFit& fit, const Eigen::VectorXd& residual, const NoiseEstimate& noise) {
    LackOfFit l;
    const Eigen::Index n = data.size();
    const auto ranges = segment_ranges(data);
    // Segment means: each has variance long_run^2 / n_s under noise alone.
    l.dof = 2 * static_cast<int>(ranges.size()) - static_cast<int>(fit.free_count());
    l.means_available = l.dof > 0;
    double means_energy = 0.0;
    for (const auto& r : ranges)
        for (int a = 0; a < 2; ++a) {
            const double mean = residual.segment(a * n + r.first, r.rows).mean();
            l.statistic += static_cast<double>(r.rows) * std::pow(mean / noise.long_run[a], 2);
            means_energy += static_cast<double>(r.rows) * mean * mean;
        }
    l.p_value = l.means_available ? chi_squared_survival(l.statistic, l.dof) : 1.0;
    const bool means_significant = l.means_available && l.p_value < significance;
    bool significant = means_significant;
    // Structure counts once it is significant: the means when they are, each significant harmonic.
    double structure_energy = significant ? means_energy : 0.0;
    std::vector<std::string> parts;
    if (means_significant)
        for (int a = 0; a < 2; ++a) parts.push_back(segment_means_signature(data, fit, a));
    if (data.theta_e) {
        l.harmonics = angle_harmonics(data, residual, noise);
        const double tests = 2.0 * orders;
        for (const auto& harmonic : l.harmonics)
            if (harmonic.p_value < significance / tests) {
                significant = true;
                structure_energy += 0.5 * static_cast<double>(n) * harmonic.amplitude.squaredNorm();
                parts.push_back(fmt::format("harmonic {} of the electrical angle ({:.3g} mV on u_d, {:.3g} mV on u_q, noise {:.2g} mV)",
                                            harmonic.order, 1e3 * harmonic.amplitude[0], 1e3 * harmonic.amplitude[1],
                                            1e3 * harmonic.standard_error));
            }
    }
    l.significant = significant;
    const double noise_energy = static_cast<double>(n) * noise.sigma.squaredNorm();
    l.structure = noise_energy > 0.0 ? structure_energy / noise_energy : 0.0;
    for (const auto& p : parts) l.signature += (l.signature.empty() ? "" : "; ") + p;
    return l;
}

}  // namespace mhb::pmsm
