#include "problems/pmsm/diagnosis/lack_of_fit.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

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

// cos and sin of harmonics 1..orders of theta, in pairs from out[0], by turning e^{j theta}.
void write_angle_harmonics(double theta, double* out) {
    const Complex rotor = std::polar(1.0, theta);
    Complex turn = rotor;
    for (int h = 0; h < orders; ++h) {
        out[2 * h] = turn.real();
        out[2 * h + 1] = turn.imag();
        turn *= rotor;
    }
}

struct HarmonicEquations {
    // Columns: one indicator per segment, then one linear trend per segment, then cos and sin of each order.
    Eigen::MatrixXd gram;
    Eigen::MatrixXd moment;  // the same rows, one column per axis
};

// Segment k's trend at row t: -1 at its first row, +1 at its last, 0 at its centre (so it is
// orthogonal to the segment's mean); 0 for a segment of one row.
double segment_trend(const RowRange& r, Eigen::Index t) {
    return r.rows > 1 ? (2.0 * static_cast<double>(t - r.first) - static_cast<double>(r.rows - 1)) / static_cast<double>(r.rows - 1) : 0.0;
}

// The regressors are never stored: each block of rows adds its share of X'X and X'r, the harmonics
// by turning e^{j theta}.
HarmonicEquations harmonic_normal_equations(const Measurement& data, const std::vector<RowRange>& ranges, const Eigen::VectorXd& residual) {
    const Eigen::Index n = data.size();
    const auto s = static_cast<Eigen::Index>(ranges.size());
    using Harmonics = Eigen::Matrix<double, 2 * orders, 1>;
    struct Share {
        Eigen::Matrix<double, 2 * orders, 2 * orders> harmonic_gram;
        // s x 2 orders, row-major: each row adds to one segment's row.
        Eigen::Matrix<double, Eigen::Dynamic, 2 * orders, Eigen::RowMajor> segment_harmonic, trend_harmonic;
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
        share.segment_harmonic.setZero(s, 2 * orders);
        share.trend_harmonic.setZero(s, 2 * orders);
        share.harmonic_residual.setZero();
        Harmonics x;
        for (Eigen::Index t = b * block_rows; t < std::min(n, (b + 1) * block_rows); ++t) {
            write_angle_harmonics((*data.theta_e)[t], x.data());
            const Eigen::Index k = segment_of_row[static_cast<std::size_t>(t)];
            share.harmonic_gram.selfadjointView<Eigen::Lower>().rankUpdate(x);
            share.segment_harmonic.row(k) += x.transpose();
            share.trend_harmonic.row(k) += segment_trend(ranges[static_cast<std::size_t>(k)], t) * x.transpose();
            share.harmonic_residual.col(0) += residual[t] * x;
            share.harmonic_residual.col(1) += residual[n + t] * x;
        }
    });
    const Eigen::Index columns = 2 * s + 2 * orders;
    HarmonicEquations e{Eigen::MatrixXd::Zero(columns, columns), Eigen::MatrixXd::Zero(columns, 2)};
    for (Eigen::Index k = 0; k < s; ++k) {
        const auto& r = ranges[static_cast<std::size_t>(k)];
        e.gram(k, k) = static_cast<double>(r.rows);
        double trend_sum = 0.0, trend_squares = 0.0;
        for (Eigen::Index t = r.first; t < r.first + r.rows; ++t) {
            const double tau = segment_trend(r, t);
            trend_sum += tau;
            trend_squares += tau * tau;
            for (int a = 0; a < 2; ++a) e.moment(s + k, a) += tau * residual[a * n + t];
        }
        e.gram(k, s + k) = e.gram(s + k, k) = trend_sum;
        e.gram(s + k, s + k) = trend_squares;
        for (int a = 0; a < 2; ++a) e.moment(k, a) = residual.segment(a * n + r.first, r.rows).sum();
    }
    for (const auto& share : shares) {
        e.gram.bottomRightCorner(2 * orders, 2 * orders) += share.harmonic_gram.selfadjointView<Eigen::Lower>().toDenseMatrix();
        e.gram.block(0, 2 * s, s, 2 * orders) += share.segment_harmonic;
        e.gram.block(s, 2 * s, s, 2 * orders) += share.trend_harmonic;
        e.moment.bottomRows(2 * orders) += share.harmonic_residual;
    }
    e.gram.bottomLeftCorner(2 * orders, 2 * s) = e.gram.topRightCorner(2 * s, 2 * orders).transpose();
    return e;
}

// The harmonics, and what each explains of the residual's sum of squares (both axes) beyond every
// other column: c' V^-1 c per axis, V its coefficients' covariance per unit noise variance. On rows
// spread evenly over the angle that is n |amplitude|^2 / 2; where a segment turns through less than
// a period, the part a trend could make as well is not counted.
struct AngleHarmonicFit {
    std::vector<Harmonic> harmonics;
    std::vector<double> explained;
};

AngleHarmonicFit fit_angle_harmonics(const Measurement& data, const Eigen::VectorXd& residual, const NoiseEstimate& noise) {
    const auto ranges = segment_ranges(data);
    const auto s = static_cast<Eigen::Index>(ranges.size());
    const HarmonicEquations e = harmonic_normal_equations(data, ranges, residual);
    const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(e.gram);
    const Eigen::MatrixXd inverse = cod.pseudoInverse();
    const Eigen::MatrixXd coefficients = inverse * e.moment;
    AngleHarmonicFit out;
    for (int h = 1; h <= orders; ++h) {
        const Eigen::Index c = 2 * s + 2 * (h - 1);
        Harmonic harmonic;
        harmonic.order = h;
        const Eigen::Matrix2d block = inverse.block(c, c, 2, 2);
        harmonic.standard_error = std::sqrt(0.5 * block.trace()) * 0.5 * (noise.long_run[0] + noise.long_run[1]);
        const bool determined = block.determinant() > 0.0;
        double p_min = 1.0, explained = 0.0;
        for (int a = 0; a < 2; ++a) {
            const Eigen::Vector2d ab = coefficients.block(c, a, 2, 1);
            harmonic.amplitude[a] = ab.norm();
            const double sum_of_squares = determined ? ab.dot(block.ldlt().solve(ab)) : 0.0;
            explained += sum_of_squares;
            p_min = std::min(p_min, determined ? chi_squared_survival(sum_of_squares / (noise.long_run[a] * noise.long_run[a]), 2.0) : 1.0);
        }
        harmonic.p_value = p_min;
        out.harmonics.push_back(harmonic);
        out.explained.push_back(explained);
    }
    return out;
}

}  // namespace

std::vector<Harmonic> angle_harmonics(const Measurement& data, const Eigen::VectorXd& residual, const NoiseEstimate& noise) {
    return fit_angle_harmonics(data, residual, noise).harmonics;
}

namespace {

// One mechanical order tested: the segments that carry it, and where its cos and sin coefficients
// sit. With the logged angle they are two global columns; with the integrated one two local columns
// of each carrying segment.
struct OrderColumns {
    int order = 0;
    std::vector<std::size_t> carriers;  // segments that carry the order
    Eigen::Index global = -1;           // first of its two global columns (logged angle)
    std::vector<Eigen::Index> local;    // first of its two local columns in each carrier (integrated angle)
    Eigen::Index rows = 0;              // rows of the carriers
};

// The joint fit's normal equations in blocks: per segment its local columns (its mean, and with the
// integrated angle the pairs of the orders it carries), and the global columns every row has (the
// electrical harmonics, and with the logged angle the mechanical pairs).
struct SegmentEquations {
    Eigen::MatrixXd local, cross, moment;  // local x local, local x global, local x 2 axes
};
struct JointEquations {
    std::vector<SegmentEquations> segments;
    Eigen::MatrixXd global, moment;  // global x global, global x 2 axes
};

// P(chi^2 > c' V^-1 c / variance) for coefficients c whose covariance per unit noise variance is V =
// D + U S^-1 U' (D block diagonal with 2 x 2 blocks, S the global columns' Schur complement), by
// Woodbury's identity, V^-1 = D^-1 - D^-1 U (S + U' D^-1 U)^-1 U' D^-1, so that a pair per segment
// over many segments costs no dense matrix of their number; 1 when V is not positive definite (the
// columns are not determined).
double wald_p_value(const std::vector<Eigen::Matrix2d>& d, const Eigen::MatrixXd& u, const Eigen::MatrixXd& schur, const Eigen::VectorXd& c,
                    double variance) {
    Eigen::VectorXd d_inverse_c(c.size());
    Eigen::MatrixXd d_inverse_u(u.rows(), u.cols());
    for (std::size_t k = 0; k < d.size(); ++k) {
        const Eigen::LDLT<Eigen::Matrix2d> ldlt(d[k]);
        if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) return 1.0;
        const auto i = 2 * static_cast<Eigen::Index>(k);
        d_inverse_c.segment<2>(i) = ldlt.solve(c.segment<2>(i));
        if (u.cols() > 0) d_inverse_u.middleRows<2>(i) = ldlt.solve(u.middleRows<2>(i));
    }
    double statistic = c.dot(d_inverse_c);
    if (u.cols() > 0) {
        const Eigen::MatrixXd inner = schur + u.transpose() * d_inverse_u;
        const Eigen::LDLT<Eigen::MatrixXd> ldlt(inner);
        if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) return 1.0;
        const Eigen::VectorXd projected = u.transpose() * d_inverse_c;
        statistic -= projected.dot(ldlt.solve(projected));
    }
    return chi_squared_survival(statistic / variance, static_cast<double>(c.size()));
}

}  // namespace

MechanicalTest mechanical_harmonics(const Measurement& data, const Eigen::VectorXd& residual, const NoiseEstimate& noise, const ShaftAngle& shaft) {
    MechanicalTest out;
    if (!shaft.available()) {
        out.note = "not tested: " + shaft.source;
        return out;
    }
    const Eigen::Index n = data.size();
    const auto ranges = segment_ranges(data);
    const Eigen::VectorXd& angle = shaft.angle;
    // How far the shaft turns in each segment (steps of less than half a turn a row), and which way.
    std::vector<double> travel, direction;
    for (const auto& r : ranges) {
        double sum = 0.0;
        for (Eigen::Index k = r.first + 1; k < r.first + r.rows; ++k) sum += wrap_angle(angle[k] - angle[k - 1]);
        travel.push_back(std::abs(sum));
        direction.push_back(sum < 0.0 ? -1.0 : 1.0);
    }
    const Eigen::Index electrical = data.theta_e ? 2 * orders : 0;
    Eigen::Index globals = electrical;
    std::vector<Eigen::Index> locals(ranges.size(), 1);  // each segment's mean first
    std::vector<OrderColumns> tested;
    std::vector<int> coinciding;
    for (int k = 1; k <= mechanical_orders; ++k) {
        if (k % shaft.pole_pairs == 0) {
            coinciding.push_back(k);
            continue;
        }
        OrderColumns o;
        o.order = k;
        for (std::size_t g = 0; g < ranges.size(); ++g)
            if (k * travel[g] >= 2.0 * std::numbers::pi) {
                o.carriers.push_back(g);
                o.rows += ranges[g].rows;
            }
        if (o.carriers.empty()) continue;
        if (shaft.logged) {
            o.global = globals;
            globals += 2;
        } else {
            for (const auto g : o.carriers) {
                o.local.push_back(locals[g]);
                locals[g] += 2;
            }
        }
        tested.push_back(std::move(o));
    }
    const double longest = travel.empty() ? 0.0 : *std::max_element(travel.begin(), travel.end()) / (2.0 * std::numbers::pi);
    if (tested.empty()) {
        out.note = coinciding.size() == static_cast<std::size_t>(mechanical_orders)
                       ? fmt::format("not tested: with {} pole pair(s) every mechanical order up to {} is an electrical one", shaft.pole_pairs,
                                     mechanical_orders)
                       : fmt::format("not tested: no segment spans a whole period of a mechanical order (the longest turns the shaft "
                                     "{:.2g} turn); segments of a whole turn or more would show them (shaft angle: {})",
                                     longest, shaft.source);
        return out;
    }
    // The orders each segment's rows carry: (order, its first column: global or local).
    std::vector<std::vector<std::pair<int, Eigen::Index>>> active(ranges.size());
    for (const auto& o : tested)
        for (std::size_t c = 0; c < o.carriers.size(); ++c)
            active[o.carriers[c]].emplace_back(o.order, shaft.logged ? o.global : o.local[c]);

    // A block of rows at a time, in parallel; each block's share of the segments it touches, added in
    // block order, so the sums do not depend on the thread count.
    struct Share {
        JointEquations equations;
        std::size_t first_segment = 0;
    };
    constexpr Eigen::Index block_rows = 4096;
    const Eigen::Index blocks = (n + block_rows - 1) / block_rows;
    std::vector<Share> shares(static_cast<std::size_t>(blocks));
    std::vector<std::size_t> segment_of_row(static_cast<std::size_t>(n));
    for (std::size_t g = 0; g < ranges.size(); ++g)
        std::fill_n(segment_of_row.begin() + ranges[g].first, ranges[g].rows, g);
    tbb::parallel_for(Eigen::Index{0}, blocks, [&](Eigen::Index b) {
        const Eigen::Index begin = b * block_rows, end = std::min(n, (b + 1) * block_rows);
        Share& share = shares[static_cast<std::size_t>(b)];
        share.first_segment = segment_of_row[static_cast<std::size_t>(begin)];
        auto& e = share.equations;
        e.global = Eigen::MatrixXd::Zero(globals, globals);
        e.moment = Eigen::MatrixXd::Zero(globals, 2);
        for (std::size_t g = share.first_segment; g <= segment_of_row[static_cast<std::size_t>(end - 1)]; ++g)
            e.segments.push_back({Eigen::MatrixXd::Zero(locals[g], locals[g]), Eigen::MatrixXd::Zero(locals[g], globals),
                                  Eigen::MatrixXd::Zero(locals[g], 2)});
        Eigen::VectorXd x_global(globals), x_local;
        for (Eigen::Index t = begin; t < end; ++t) {
            const std::size_t g = segment_of_row[static_cast<std::size_t>(t)];
            SegmentEquations& own = e.segments[g - share.first_segment];
            x_global.setZero();
            x_local.setZero(locals[g]);
            x_local[0] = 1.0;
            if (electrical > 0) write_angle_harmonics((*data.theta_e)[t], x_global.data());
            // With the logged angle one pair serves both directions, turned with the direction: what the
            // voltage shows of something turning with the shaft is an EMF or an angle error, both
            // proportional to the speed, so it changes sign with it and would cancel otherwise.
            const double sign = shaft.logged ? direction[g] : 1.0;
            for (const auto& [order, first] : active[g]) {
                Eigen::VectorXd& x = shaft.logged ? x_global : x_local;
                x[first] = sign * std::cos(order * angle[t]);
                x[first + 1] = sign * std::sin(order * angle[t]);
            }
            const Eigen::Vector2d r(residual[t], residual[n + t]);
            e.global.selfadjointView<Eigen::Lower>().rankUpdate(x_global);
            e.moment.noalias() += x_global * r.transpose();
            own.local.selfadjointView<Eigen::Lower>().rankUpdate(x_local);
            own.cross.noalias() += x_local * x_global.transpose();
            own.moment.noalias() += x_local * r.transpose();
        }
    });
    JointEquations joint;
    joint.global = Eigen::MatrixXd::Zero(globals, globals);
    joint.moment = Eigen::MatrixXd::Zero(globals, 2);
    for (std::size_t g = 0; g < ranges.size(); ++g)
        joint.segments.push_back({Eigen::MatrixXd::Zero(locals[g], locals[g]), Eigen::MatrixXd::Zero(locals[g], globals),
                                  Eigen::MatrixXd::Zero(locals[g], 2)});
    for (const auto& share : shares) {
        joint.global += share.equations.global;
        joint.moment += share.equations.moment;
        for (std::size_t k = 0; k < share.equations.segments.size(); ++k) {
            auto& to = joint.segments[share.first_segment + k];
            const auto& from = share.equations.segments[k];
            to.local += from.local;
            to.cross += from.cross;
            to.moment += from.moment;
        }
    }
    joint.global = Eigen::MatrixXd(joint.global.selfadjointView<Eigen::Lower>());

    // Eliminate each segment's local columns: U = A^-1 B and w = A^-1 m per segment, the global
    // columns' Schur complement S = C - sum B' U, their coefficients, then the locals' (each with
    // covariance A^-1 + U S^-1 U' per unit noise variance).
    std::vector<Eigen::MatrixXd> local_inverse(ranges.size()), eliminated(ranges.size()), local_coefficients(ranges.size());
    Eigen::MatrixXd schur = joint.global, reduced = joint.moment;
    for (std::size_t g = 0; g < ranges.size(); ++g) {
        const auto& seg = joint.segments[g];
        local_inverse[g] = Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(Eigen::MatrixXd(seg.local.selfadjointView<Eigen::Lower>()))
                               .pseudoInverse();
        eliminated[g] = local_inverse[g] * seg.cross;
        schur -= seg.cross.transpose() * eliminated[g];
        reduced -= seg.cross.transpose() * (local_inverse[g] * seg.moment);
    }
    const Eigen::MatrixXd global_covariance =
        globals > 0 ? Eigen::MatrixXd(Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(schur).pseudoInverse()) : Eigen::MatrixXd();
    const Eigen::MatrixXd global_coefficients = global_covariance * reduced;
    for (std::size_t g = 0; g < ranges.size(); ++g)
        local_coefficients[g] = local_inverse[g] * (joint.segments[g].moment - joint.segments[g].cross * global_coefficients);

    const double mean_long_run = 0.5 * (noise.long_run[0] + noise.long_run[1]);
    std::vector<std::string> names;
    for (const auto& o : tested) {
        MechanicalHarmonic h;
        h.order = o.order;
        h.pole_pairs = shaft.pole_pairs;
        h.segments = static_cast<int>(o.carriers.size());
        h.rows = o.rows;
        // The order's coefficients (per axis), the 2 x 2 blocks of their covariance per unit noise
        // variance that are their own (D), and how they share the global columns' (U).
        const std::size_t pairs = shaft.logged ? 1 : o.carriers.size();
        std::vector<Eigen::Matrix2d> own(pairs);
        Eigen::MatrixXd shared(2 * static_cast<Eigen::Index>(pairs), shaft.logged ? 0 : globals);
        Eigen::MatrixXd c(2 * static_cast<Eigen::Index>(pairs), 2);
        std::vector<Eigen::Matrix2d> covariance(pairs);  // of each pair alone
        for (std::size_t k = 0; k < pairs; ++k) {
            const auto i = 2 * static_cast<Eigen::Index>(k);
            if (shaft.logged) {
                own[k] = global_covariance.block<2, 2>(o.global, o.global);
                c.middleRows<2>(i) = global_coefficients.middleRows<2>(o.global);
                covariance[k] = own[k];
            } else {
                const std::size_t g = o.carriers[k];
                const Eigen::Index at = o.local[k];
                own[k] = local_inverse[g].block<2, 2>(at, at);
                shared.middleRows<2>(i) = eliminated[g].middleRows<2>(at);
                c.middleRows<2>(i) = local_coefficients[g].middleRows<2>(at);
                covariance[k] = own[k] + shared.middleRows<2>(i) * global_covariance * shared.middleRows<2>(i).transpose();
            }
        }
        // Variance of one amplitude component per unit noise variance: the pair's, or with a pair per
        // segment the mean of theirs weighted by the segments' rows.
        double component_variance = 0.0, weights = 0.0;
        for (std::size_t k = 0; k < pairs; ++k) {
            const double weight = shaft.logged ? 1.0 : static_cast<double>(ranges[o.carriers[k]].rows);
            component_variance += weight * 0.5 * covariance[k].trace();
            weights += weight;
        }
        component_variance /= weights;
        h.standard_error = std::sqrt(component_variance) * mean_long_run;
        double p_min = 1.0;
        Eigen::Vector2d phase{0.0, 0.0};
        for (int a = 0; a < 2; ++a) {
            const Eigen::VectorXd ca = c.col(a);
            const double variance = noise.long_run[a] * noise.long_run[a];
            p_min = std::min(p_min, wald_p_value(own, shared, schur, ca, variance));
            const double component_error = std::sqrt(component_variance * variance);
            if (shaft.logged) {
                // a cos(k theta) + b sin(k theta) = A cos(k theta + phase): A cos(phase) = a, A sin(phase) = -b.
                h.amplitude[a] = std::hypot(ca[0], ca[1]);
                phase[a] = std::atan2(-ca[1], ca[0]);
                h.amplitude_standard_error[a] = component_error;
            } else {
                // Each segment's squared amplitude holds the noise's two components' variance besides the
                // harmonic's; the mean over m segments has m times less of the amplitude's error.
                double power = 0.0;
                for (std::size_t k = 0; k < pairs; ++k)
                    power += static_cast<double>(ranges[o.carriers[k]].rows) *
                             (ca.segment<2>(2 * static_cast<Eigen::Index>(k)).squaredNorm() - covariance[k].trace() * variance);
                h.amplitude[a] = std::sqrt(std::max(0.0, power / static_cast<double>(o.rows)));
                h.amplitude_standard_error[a] = component_error / std::sqrt(static_cast<double>(pairs));
            }
            h.phase_standard_error[a] = h.amplitude[a] > 0.0 ? h.amplitude_standard_error[a] / h.amplitude[a] : std::numbers::pi;
        }
        if (shaft.logged) h.phase = phase;
        h.p_value = p_min;
        out.harmonics.push_back(h);
        names.push_back(std::to_string(o.order));
    }
    std::string orders_text;
    for (std::size_t k = 0; k < names.size(); ++k) orders_text += (k == 0 ? "" : k + 1 == names.size() ? " and " : ", ") + names[k];
    out.note = fmt::format("orders {} of the shaft angle tested, each on the segments that turn through a whole period of it (shaft angle: {})",
                           orders_text, shaft.source);
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

LackOfFit lack_of_fit(const Measurement& data, const ModelFit& fit, const Eigen::VectorXd& residual, const NoiseEstimate& noise,
                      const ShaftAngle& shaft) {
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
    auto& parts = l.signature_parts;
    if (means_significant)
        for (int a = 0; a < 2; ++a) parts.emplace_back(0, segment_means_signature(data, fit, a));
    MechanicalTest mechanical;
    if (!shaft.source.empty()) {
        mechanical = mechanical_harmonics(data, residual, noise, shaft);
        l.mechanical_angle = mechanical.note;
    }
    // One family: two tests (the axes) per order of either kind.
    const double tests = 2.0 * static_cast<double>((data.theta_e ? orders : 0) + static_cast<int>(mechanical.harmonics.size()));
    if (data.theta_e) {
        auto fitted = fit_angle_harmonics(data, residual, noise);
        l.harmonics = std::move(fitted.harmonics);
        for (std::size_t k = 0; k < l.harmonics.size(); ++k) {
            auto& harmonic = l.harmonics[k];
            if (harmonic.p_value < significance / tests) {
                harmonic.significant = true;
                significant = true;
                structure_energy += fitted.explained[k];
                parts.emplace_back(harmonic.order, fmt::format("harmonic {} of the electrical angle ({:.3g} mV on u_d, {:.3g} mV on u_q, noise {:.2g} mV)",
                                                               harmonic.order, 1e3 * harmonic.amplitude[0], 1e3 * harmonic.amplitude[1],
                                                               1e3 * harmonic.standard_error));
            }
        }
    }
    for (auto& h : mechanical.harmonics) {
        h.significant = h.p_value < significance / tests;
        if (!h.significant) continue;
        significant = true;
        structure_energy += 0.5 * static_cast<double>(h.rows) * h.amplitude.squaredNorm();
        parts.emplace_back(0, fmt::format("harmonic at mechanical order {} ({}/{} of the electrical frequency; {:.3g} mV on u_d, {:.3g} mV on u_q, "
                                    "noise {:.2g} mV{})",
                                    h.order, h.order, h.pole_pairs, 1e3 * h.amplitude[0], 1e3 * h.amplitude[1], 1e3 * h.standard_error,
                                    h.phase ? fmt::format(", phase {:.2f} rad on u_{} against theta_m", (*h.phase)[h.amplitude[1] >= h.amplitude[0]],
                                                          h.amplitude[1] >= h.amplitude[0] ? 'q' : 'd')
                                            : std::string(", phase per segment")));
    }
    l.mechanical_harmonics = std::move(mechanical.harmonics);
    l.significant = significant;
    const double noise_energy = static_cast<double>(n) * noise.sigma.squaredNorm();
    l.structure = noise_energy > 0.0 ? structure_energy / noise_energy : 0.0;
    l.signature = l.signature_without({});
    return l;
}

std::string LackOfFit::signature_without(const std::vector<int>& orders) const {
    std::string out;
    for (const auto& [order, text] : signature_parts)
        if (order == 0 || std::find(orders.begin(), orders.end(), order) == orders.end()) out += (out.empty() ? "" : "; ") + text;
    return out;
}

}  // namespace mhb::pmsm
