#include "problems/pmsm/diagnosis/diagnosis.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>

#include <Eigen/Dense>
#include <boost/math/distributions/chi_squared.hpp>
#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "framework/input_error.hpp"
#include "framework/registry.hpp"

namespace mhb::pmsm {
namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();

// Evidence thresholds (docs/effects.md, "How diagnose decides").
constexpr double supported_bic = -10.0;   // "very strong" on Kass and Raftery's scale of 2 ln B
constexpr double weak_bic = -2.0;
constexpr double tie_margin = 6.0;        // below "strong" preference between two candidates
constexpr double absorbed_below = 1e-6;   // unique fraction: in the span of the model's columns
constexpr double clear_above = 0.1;       // unique fraction: at least a tenth of the signature is its own
constexpr double significance = 1e-3;

struct Range {
    Eigen::Index first = 0, rows = 0;
};

std::vector<Range> segment_ranges(const Measurement& m) {
    std::vector<Range> out;
    Eigen::Index begin = 0;
    for (Eigen::Index k = 1; k <= m.size(); ++k)
        if (k == m.size() || (m.has_segments() && m.segment[k] != m.segment[k - 1])) {
            out.push_back({begin, k - begin});
            begin = k;
        }
    return out;
}

double chi_squared_survival(double statistic, double dof) {
    if (dof <= 0.0) return 1.0;
    return boost::math::cdf(boost::math::complement(boost::math::chi_squared(dof), std::max(statistic, 0.0)));
}

std::string percent(double relative) { return fmt::format("{:+.1f} %", 100.0 * relative); }

// ---- noise ----

// Takes its own copy of the fit's residual, or moves the one it recomputes: on a long log this
// holds one row-sized array, not two.
NoiseEstimate estimate_noise(const Measurement& data, const ModelFit& fit) {
    const Eigen::Index n = data.size();
    const auto ranges = segment_ranges(data);
    Eigen::VectorXd storage;
    const Eigen::VectorXd& residual = residual_of(data, fit, storage);
    Eigen::VectorXd within = &residual == &storage ? std::move(storage) : residual;
    for (int a = 0; a < 2; ++a)
        for (const auto& r : ranges) {
            auto block = within.segment(a * n + r.first, r.rows);
            block.array() -= block.mean();
        }
    // The long-run variance of each axis' mean: the regression on one indicator per axis.
    RegressorBlocks indicators;
    indicators.columns = 2;
    indicators.fill = [](Eigen::Index, Eigen::Ref<Eigen::MatrixXd> rows) {
        const Eigen::Index size = rows.rows() / 2;
        rows.topRows(size).col(0).setOnes();
        rows.topRows(size).col(1).setZero();
        rows.bottomRows(size).col(0).setZero();
        rows.bottomRows(size).col(1).setOnes();
    };
    RowLayout layout;
    layout.samples = n;
    layout.axes = 2;
    if (data.has_segments()) layout.block = data.segment;
    const auto u = residual_uncertainty(indicators, within, Eigen::Vector2d::Zero(), layout, CovarianceMethod::NeweyWest);
    NoiseEstimate noise;
    noise.model = fit.spec.text();
    for (int a = 0; a < 2; ++a) {
        noise.sigma[a] = std::sqrt(within.segment(a * n, n).squaredNorm() / static_cast<double>(n));
        noise.long_run[a] = std::sqrt(std::max(u.covariance(a, a), 0.0) * static_cast<double>(n));
        // Correlation can only cost information here; a negative one is taken as none.
        noise.long_run[a] = std::max(noise.long_run[a], noise.sigma[a]);
        noise.effective_samples += static_cast<double>(n) * std::pow(noise.sigma[a] / noise.long_run[a], 2);
    }
    return noise;
}

double likelihood_ratio(const ModelFit& model, const ModelFit& candidate, const NoiseEstimate& noise) {
    double lr = 0.0;
    for (int a = 0; a < 2; ++a) lr += (model.rss_axis(a) - candidate.rss_axis(a)) / (noise.long_run[a] * noise.long_run[a]);
    return lr / noise.dispersion;
}

// ---- the design: what the operating points, the angle and the temperature trend can tell ----

// The data with each segment's currents and speed at their means and its temperatures on a straight
// line through time, so that the noise cannot make an effect look identifiable.
Measurement design_of(const Measurement& data) {
    Measurement d = data;
    // Without segments the operating points are unknown: the samples themselves are the design.
    if (!data.has_segments()) return d;
    for (const auto& r : segment_ranges(data)) {
        for (auto* column : {&d.i_d, &d.i_q, &d.omega_e}) column->segment(r.first, r.rows).setConstant(column->segment(r.first, r.rows).mean());
        for (auto* column : {&d.temp_winding, &d.temp_magnet}) {
            if (!*column || r.rows < 2) continue;
            auto block = (*column)->segment(r.first, r.rows);
            const Eigen::ArrayXd x = Eigen::ArrayXd::LinSpaced(r.rows, 0.0, static_cast<double>(r.rows - 1));
            const double xm = x.mean(), ym = block.mean();
            const double slope = ((x - xm) * (block.array() - ym)).sum() / (x - xm).square().sum();
            block = (ym + slope * (x - xm)).matrix();
        }
    }
    return d;
}

struct OperatingPoint {
    double omega = 0.0, i_d = 0.0, i_q = 0.0, temp_winding = 0.0, temp_magnet = 0.0;
};

// Appends a hypothetical held operating point: one electrical period of the angle when the data log
// it (so angle signatures show), two rows otherwise.
Measurement with_point(const Measurement& design, const OperatingPoint& p) {
    Measurement d = design;
    const Eigen::Index n = design.size(), m = design.theta_e ? 72 : 2;
    auto grow = [&](Eigen::VectorXd& v, double value) {
        v.conservativeResize(n + m);
        v.tail(m).setConstant(value);
    };
    grow(d.i_d, p.i_d);
    grow(d.i_q, p.i_q);
    grow(d.omega_e, p.omega);
    grow(d.u_d, 0.0);
    grow(d.u_q, 0.0);
    if (d.t) grow(*d.t, 0.0);
    if (d.temp_winding) grow(*d.temp_winding, p.temp_winding);
    if (d.temp_magnet) grow(*d.temp_magnet, p.temp_magnet);
    if (d.theta_e) {
        grow(*d.theta_e, 0.0);
        for (Eigen::Index k = 0; k < m; ++k)
            (*d.theta_e)[n + k] = wrap_angle(2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(m));
    }
    if (d.has_segments()) {
        d.segment.conservativeResize(n + m);
        d.segment.tail(m).setConstant(static_cast<int>(d.segment_labels.size()));
        d.segment_labels.push_back("hypothetical");
    }
    return d;
}

// The design with a logged angle: one electrical period swept through each segment.
Measurement with_angle(const Measurement& design) {
    Measurement d = design;
    d.theta_e = Eigen::VectorXd(d.size());
    for (const auto& r : segment_ranges(d))
        for (Eigen::Index k = 0; k < r.rows; ++k)
            (*d.theta_e)[r.first + k] = wrap_angle(2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(r.rows));
    return d;
}

// Fraction of `column` outside the span of `others` (columns scaled first; rank-revealing QR).
double unique_fraction(const Eigen::MatrixXd& others, const Eigen::VectorXd& column) {
    const double norm = column.norm();
    if (!(norm > 0.0)) return nan;
    if (others.cols() == 0) return 1.0;
    Eigen::MatrixXd scaled = others;
    for (Eigen::Index j = 0; j < scaled.cols(); ++j) {
        const double s = scaled.col(j).norm();
        if (s > 0.0) scaled.col(j) /= s;
    }
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(scaled);
    qr.setThreshold(1e-10);
    const Eigen::Index rank = qr.rank();
    Eigen::VectorXd coefficients = qr.householderQ().adjoint() * column;
    coefficients.tail(coefficients.size() - rank).setZero();
    const Eigen::VectorXd projected = qr.householderQ() * coefficients;
    return (column - projected).norm() / norm;
}

// Unique fraction of each free parameter of `effect` in the model `spec`+`effect`(+`rival`) on
// `design`, against the model's own free parameters (and the rival's). Effect parameters are taken
// at their declared typical (default) values, the model's at `model_values`.
std::vector<double> design_unique_fractions(const Measurement& design, const ModelSpec& spec, const Eigen::VectorXd& model_values,
                                            const std::string& effect, const std::string& rival = {}) {
    ModelSpec full = spec.with(effect);
    if (!rival.empty()) full = full.with(rival);
    const auto model = make_model(full, design);
    Eigen::VectorXd values = model->parameters_of(MotorParameters{});
    values.head(model_values.size()) = model_values;
    const auto free = free_parameters(full);
    const auto base_count = static_cast<Eigen::Index>(free_parameters(spec).size());
    const auto effect_count = static_cast<Eigen::Index>(free_parameters(spec.with(effect)).size()) - base_count;
    std::vector<Eigen::Index> columns, own;
    for (Eigen::Index j = 0; j < static_cast<Eigen::Index>(free.size()); ++j) {
        if (!free[static_cast<std::size_t>(j)]) continue;
        columns.push_back(j);
        const bool is_effect = j >= base_count && j < base_count + effect_count;
        if (is_effect) own.push_back(static_cast<Eigen::Index>(columns.size()) - 1);
    }
    const Eigen::MatrixXd jacobian = prediction_jacobian(*model, values, columns);
    std::vector<Eigen::Index> others;
    for (Eigen::Index c = 0; c < jacobian.cols(); ++c)
        if (std::find(own.begin(), own.end(), c) == own.end()) others.push_back(c);
    Eigen::MatrixXd other_columns(jacobian.rows(), static_cast<Eigen::Index>(others.size()));
    for (std::size_t c = 0; c < others.size(); ++c) other_columns.col(static_cast<Eigen::Index>(c)) = jacobian.col(others[c]);
    std::vector<double> out;
    for (const auto c : own) out.push_back(unique_fraction(other_columns, jacobian.col(c)));
    return out;
}

double most_distinct(const std::vector<double>& fractions) {
    double best = nan;
    for (double f : fractions)
        if (std::isfinite(f) && !(f <= best)) best = f;
    return best;
}

struct Proposal {
    Experiment experiment;
    std::function<Measurement(const Measurement&)> apply;
};

std::vector<Proposal> experiment_proposals(const Measurement& data, const std::vector<SegmentConditions>& segments) {
    std::vector<Proposal> out;
    if (segments.empty()) return out;
    const auto fastest = *std::max_element(segments.begin(), segments.end(),
                                           [](const auto& a, const auto& b) { return std::abs(a.omega) < std::abs(b.omega); });
    double largest_current = 0.0, lowest_i_d = 0.0;
    for (const auto& s : segments) {
        largest_current = std::max(largest_current, std::hypot(s.i_d, s.i_q));
        lowest_i_d = std::min(lowest_i_d, s.i_d);
    }
    if (!(largest_current > 0.0)) largest_current = 1.0;
    const OperatingPoint base{fastest.omega, fastest.i_d, fastest.i_q, fastest.temp_winding.value_or(reference_temperature),
                              fastest.temp_magnet.value_or(reference_temperature)};
    auto add = [&](std::string name, OperatingPoint p) {
        // Currents that are zero up to the noise of the segment means read as zero.
        for (double* i : {&p.i_d, &p.i_q})
            if (std::abs(*i) < 1e-3 * largest_current) *i = 0.0;
        const std::string where = fmt::format("omega_e = {:.3g} rad/s, i_d = {:.3g} A, i_q = {:.3g} A", p.omega, p.i_d, p.i_q);
        out.push_back({{std::move(name), where, 0.0}, [p](const Measurement& d) { return with_point(d, p); }});
    };
    OperatingPoint p = base;
    p.omega = base.omega / 2.0;
    add("another speed", p);
    p = base;
    p.omega = -base.omega;
    p.i_q = -base.i_q;
    add("the other direction", p);
    p = base;
    p.i_d = lowest_i_d - 0.5 * largest_current;
    add("another d-axis current", p);
    p = base;
    p.i_q = base.i_q + (base.i_q < 0.0 ? -0.5 : 0.5) * largest_current;
    add("another load", p);
    if (data.temp_winding || data.temp_magnet) {
        p = base;
        p.temp_winding += 30.0;
        p.temp_magnet += 30.0;
        out.push_back({{"a temperature change", fmt::format("the fastest point again 30 K warmer (omega_e = {:.3g} rad/s)", p.omega), 0.0},
                       [p](const Measurement& d) { return with_point(d, p); }});
    }
    if (!data.theta_e)
        out.push_back({{"logging theta_e", "the controller's electrical angle with every sample", 0.0},
                       [](const Measurement& d) { return with_angle(d); }});
    return out;
}

// Experiments after which `effect` (against `rival` too, when given, and the rival against it) has
// at least a tenth of its signature to itself.
std::vector<Experiment> revealing_experiments(const Measurement& design, const std::vector<Proposal>& proposals, const ModelSpec& spec,
                                              const Eigen::VectorXd& model_values, const std::string& effect,
                                              const std::string& rival = {}) {
    auto clarity = [&](const Measurement& d) {
        double u = most_distinct(design_unique_fractions(d, spec, model_values, effect, rival));
        if (!rival.empty()) u = std::min(u, most_distinct(design_unique_fractions(d, spec, model_values, rival, effect)));
        return u;
    };
    std::vector<Experiment> out;
    for (const auto& p : proposals) {
        Experiment e = p.experiment;
        e.unique_after = clarity(p.apply(design));
        if (e.unique_after >= clear_above) out.push_back(e);
    }
    if (out.empty() && proposals.size() > 1) {
        Measurement all = design;
        std::string names;
        for (const auto& p : proposals) {
            all = p.apply(all);
            names += (names.empty() ? "" : ", ") + p.experiment.name;
        }
        const double u = clarity(all);
        if (u >= clear_above) out.push_back({"all of these together", names, u});
    }
    std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.unique_after > b.unique_after; });
    return out;
}

// ---- prediction, plausibility ----

}  // namespace

// The refit for held-out prediction is one Gauss-Newton step from the fit on all rows, computed from
// per-segment normal equations: one pass over the rows instead of a refit per segment, exact for the
// base parameters (the prediction is linear in them) and first order in the effect parameters, which
// the fit on all rows has already placed. Effect parameters at an end of their range stay there, as
// they would in a bounded refit.
std::vector<double> leave_one_segment_out(const Measurement& data, const ModelSpec& spec, const Eigen::VectorXd& values) {
    const auto ranges = segment_ranges(data);
    std::vector<double> sse;
    if (ranges.size() < 3) return sse;
    const auto model = make_model(spec, data);
    const auto free = free_parameters(spec);
    const auto& lo = model->bounds().lower;
    const auto& hi = model->bounds().upper;
    const auto periodic = periodic_parameters(*model);
    std::vector<Eigen::Index> columns;
    for (Eigen::Index j = 0; j < values.size(); ++j)
        if (free[static_cast<std::size_t>(j)] && (j < 4 || !at_range_end(values[j], lo[j], hi[j], periodic[static_cast<std::size_t>(j)])))
            columns.push_back(j);
    std::vector<Eigen::Index> starts;
    for (const auto& r : ranges) starts.push_back(r.first);
    const auto sums = range_normal_equations(*model, values, columns, starts);
    const auto p = static_cast<Eigen::Index>(columns.size());
    Eigen::MatrixXd all_gram = Eigen::MatrixXd::Zero(p, p);
    Eigen::VectorXd all_moment = Eigen::VectorXd::Zero(p);
    for (std::size_t s = 0; s < ranges.size(); ++s) {
        all_gram += sums.gram[s];
        all_moment += sums.moment[s];
    }
    for (std::size_t s = 0; s < ranges.size(); ++s) {
        // The step on the other segments; a parameter they do not determine does not move.
        const Eigen::VectorXd step = scaled_pseudo_inverse(all_gram - sums.gram[s]) * (all_moment - sums.moment[s]);
        sse.push_back(std::max(sums.total[s] - 2.0 * step.dot(sums.moment[s]) + step.dot(sums.gram[s] * step), 0.0));
    }
    return sse;
}

namespace {

double pooled_rms(const std::vector<double>& sse, Eigen::Index samples) {
    double total = 0.0;
    for (double v : sse) total += v;
    return std::sqrt(total / (2.0 * static_cast<double>(samples)));
}

void check_base(const ModelFit& fit, std::vector<std::string>& problems) {
    const Bounds box = base_parameter_bounds();
    for (int j = 0; j < 4; ++j) {
        const double v = fit.values[j];
        if (!(v > 0.0))
            problems.push_back(fmt::format("{} = {:.4g} {} is physically impossible (not positive)", fit.names[static_cast<std::size_t>(j)], v,
                                           fit.units[static_cast<std::size_t>(j)]));
        else if (v < box.lower[j] || v > box.upper[j])
            problems.push_back(fmt::format("{} = {:.4g} {} is outside Table 2's box [{:g}, {:g}]", fit.names[static_cast<std::size_t>(j)], v,
                                           fit.units[static_cast<std::size_t>(j)], box.lower[j], box.upper[j]));
    }
}

void check_effects(const ModelFit& fit, std::vector<std::string>& problems) {
    for (Eigen::Index j = 4; j < fit.values.size(); ++j) {
        if (!fit.at_bound(j)) continue;
        const bool at_lower = fit.values[j] <= fit.range_lower[j] + 1e-9 * (fit.range_upper[j] - fit.range_lower[j]);
        // Zero is a magnitude's natural floor (no band, no harmonic, no delay), not an implausible value.
        if (at_lower && fit.range_lower[j] == 0.0) continue;
        problems.push_back(fmt::format("{} = {:.4g} {} sits at the {} end of its plausible range [{:g}, {:g}]",
                                       fit.names[static_cast<std::size_t>(j)], fit.values[j], fit.units[static_cast<std::size_t>(j)],
                                       at_lower ? "lower" : "upper", fit.range_lower[j], fit.range_upper[j]));
    }
}

// ---- where the model fails ----

std::vector<SegmentConditions> segment_conditions(const Measurement& data, const ModelFit& model, const ModelFit* before) {
    std::vector<SegmentConditions> out;
    for (std::size_t s = 0; s < model.segments.size(); ++s) {
        const auto& seg = model.segments[s];
        SegmentConditions c;
        c.label = seg.label;
        c.first = seg.first;
        c.rows = seg.rows;
        auto mean = [&](const Eigen::VectorXd& v) { return v.segment(seg.first, seg.rows).mean(); };
        c.omega = mean(data.omega_e);
        c.i_d = mean(data.i_d);
        c.i_q = mean(data.i_q);
        if (data.temp_winding) c.temp_winding = mean(*data.temp_winding);
        if (data.temp_magnet) c.temp_magnet = mean(*data.temp_magnet);
        if (data.t) c.time = mean(*data.t);
        c.model = seg;
        c.before = before ? before->segments[s] : seg;
        out.push_back(c);
    }
    return out;
}

// Each free parameter refitted alone on each segment, the others held at the global fit: the value
// that segment asks for. A drift of these with temperature, current or speed shows what is missing.
// `residual` is the fit's (residual_of).
void apparent_values(const SteadyStateModel& model, const ModelFit& fit, const Eigen::VectorXd& residual, const NoiseEstimate& noise,
                     std::vector<SegmentConditions>& segments,
                     std::vector<std::string>& names) {
    std::vector<Eigen::Index> columns;
    for (Eigen::Index j = 0; j < fit.values.size(); ++j)
        if (fit.free[static_cast<std::size_t>(j)]) {
            columns.push_back(j);
            names.push_back(fit.names[static_cast<std::size_t>(j)]);
        }
    const Eigen::Index n = fit.samples, p = static_cast<Eigen::Index>(columns.size());
    // Per segment and parameter, of its Jacobian column: the squared norm on u_d and on u_q and the
    // product with the residual (both axes), a block of rows at a time, summed in block order.
    std::vector<Eigen::Index> starts;
    for (const auto& s : segments) starts.push_back(s.first);
    struct Share {
        std::size_t segment = 0;
        Eigen::ArrayXd dd, qq, dr;
    };
    std::vector<std::vector<Share>> shares(static_cast<std::size_t>(model.blocks()));
    tbb::enumerable_thread_specific<Eigen::VectorXd> at(fit.values);
    tbb::parallel_for(Eigen::Index{0}, model.blocks(), [&](Eigen::Index b) {
        const Eigen::Index first = model.block_first(b), size = model.block_size(b);
        Eigen::MatrixXd d(size, p), q(size, p);
        block_jacobian(model, fit.values, columns, b, at.local(), d, q);
        auto segment = static_cast<std::size_t>(std::upper_bound(starts.begin(), starts.end(), first) - starts.begin() - 1);
        for (Eigen::Index k = 0; k < size; ++segment) {
            const Eigen::Index end = segment + 1 < starts.size() ? std::min(size, starts[segment + 1] - first) : size;
            const auto jd = d.middleRows(k, end - k), jq = q.middleRows(k, end - k);
            Share share{segment, jd.colwise().squaredNorm().transpose().array(), jq.colwise().squaredNorm().transpose().array(),
                        (jd.transpose() * residual.segment(first + k, end - k) + jq.transpose() * residual.segment(n + first + k, end - k)).array()};
            shares[static_cast<std::size_t>(b)].push_back(std::move(share));
            k = end;
        }
    });
    const auto count = segments.size();
    std::vector<Eigen::ArrayXd> dd(count, Eigen::ArrayXd::Zero(p)), qq(count, Eigen::ArrayXd::Zero(p)), dr(count, Eigen::ArrayXd::Zero(p));
    for (const auto& block : shares)
        for (const auto& share : block) {
            dd[share.segment] += share.dd;
            qq[share.segment] += share.qq;
            dr[share.segment] += share.dr;
        }
    for (Eigen::Index c = 0; c < p; ++c) {
        std::vector<double> strength;
        for (std::size_t k = 0; k < count; ++k) strength.push_back(std::sqrt((dd[k][c] + qq[k][c]) / static_cast<double>(segments[k].rows)));
        const double strongest = *std::max_element(strength.begin(), strength.end());
        for (std::size_t k = 0; k < count; ++k) {
            const double norm2 = dd[k][c] + qq[k][c];
            ApparentValue a;
            a.determined = strength[k] > 0.05 * strongest && norm2 > 0.0;
            if (a.determined) {
                a.value = fit.values[columns[static_cast<std::size_t>(c)]] + dr[k][c] / norm2;
                a.standard_error = std::sqrt(std::pow(noise.long_run[0], 2) * dd[k][c] + std::pow(noise.long_run[1], 2) * qq[k][c]) / norm2;
            }
            segments[k].apparent.push_back(a);
        }
    }
}

std::vector<Drift> drifts_of(const std::vector<SegmentConditions>& segments, const std::vector<std::string>& names) {
    std::vector<Drift> out;
    struct Variable {
        const char* name;
        std::function<std::optional<double>(const SegmentConditions&)> of;
    };
    const std::vector<Variable> variables{
        {"temp_winding", [](const SegmentConditions& s) { return s.temp_winding; }},
        {"temp_magnet", [](const SegmentConditions& s) { return s.temp_magnet; }},
        {"|i|", [](const SegmentConditions& s) { return std::optional<double>(std::hypot(s.i_d, s.i_q)); }},
        {"i_d", [](const SegmentConditions& s) { return std::optional<double>(s.i_d); }},
        {"i_q", [](const SegmentConditions& s) { return std::optional<double>(s.i_q); }},
        {"omega_e", [](const SegmentConditions& s) { return std::optional<double>(s.omega); }},
        {"|omega_e|", [](const SegmentConditions& s) { return std::optional<double>(std::abs(s.omega)); }},
    };
    for (std::size_t p = 0; p < names.size(); ++p) {
        std::vector<double> v, se;
        std::vector<std::size_t> which;
        for (std::size_t k = 0; k < segments.size(); ++k)
            if (segments[k].apparent[p].determined) {
                v.push_back(segments[k].apparent[p].value);
                se.push_back(segments[k].apparent[p].standard_error);
                which.push_back(k);
            }
        if (v.size() < 4) continue;
        // Is the spread more than the noise allows?
        double wsum = 0.0, wmean = 0.0;
        for (std::size_t k = 0; k < v.size(); ++k) {
            wsum += 1.0 / (se[k] * se[k]);
            wmean += v[k] / (se[k] * se[k]);
        }
        wmean /= wsum;
        double spread = 0.0;
        for (std::size_t k = 0; k < v.size(); ++k) spread += std::pow((v[k] - wmean) / se[k], 2);
        if (chi_squared_survival(spread, static_cast<double>(v.size() - 1)) > significance) continue;
        Drift best;
        for (const auto& var : variables) {
            std::vector<double> x;
            for (auto k : which)
                if (auto value = var.of(segments[k])) x.push_back(*value);
            if (x.size() != v.size()) continue;
            const Eigen::Map<const Eigen::ArrayXd> xa(x.data(), static_cast<Eigen::Index>(x.size())), ya(v.data(), static_cast<Eigen::Index>(v.size()));
            const double sxx = (xa - xa.mean()).square().sum(), syy = (ya - ya.mean()).square().sum();
            if (!(sxx > 0.0) || !(syy > 0.0)) continue;
            const double sxy = ((xa - xa.mean()) * (ya - ya.mean())).sum();
            const double r = sxy / std::sqrt(sxx * syy);
            if (std::abs(r) > std::abs(best.correlation)) best = {names[p], var.name, r, sxy / sxx};
        }
        // Varies beyond the noise: say with what, when one operating condition explains it.
        if (std::abs(best.correlation) < 0.8) best = {names[p], "", 0.0, 0.0};
        out.push_back(best);
    }
    return out;
}

// `residual` is the fit's (residual_of).
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
    bool significant = l.means_available && l.p_value < significance;
    // Structure counts once it is significant: the means when they are, each significant harmonic.
    double structure_energy = significant ? means_energy : 0.0;

    std::vector<std::string> parts;
    if (data.theta_e) {
        // Harmonics of the electrical angle, fitted jointly with the segment means.
        constexpr int orders = 12;
        const auto s = static_cast<Eigen::Index>(ranges.size());
        // The regressors (one indicator per segment, cos and sin of each order) are never stored:
        // each block of rows adds its share of X'X and X'r, the harmonics by turning e^{j theta}.
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
        Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(columns, columns);
        Eigen::MatrixXd moment = Eigen::MatrixXd::Zero(columns, 2);
        for (Eigen::Index k = 0; k < s; ++k) {
            const auto& r = ranges[static_cast<std::size_t>(k)];
            gram(k, k) = static_cast<double>(r.rows);
            for (int a = 0; a < 2; ++a) moment(k, a) = residual.segment(a * n + r.first, r.rows).sum();
        }
        for (const auto& share : shares) {
            gram.bottomRightCorner(2 * orders, 2 * orders) += share.harmonic_gram.selfadjointView<Eigen::Lower>().toDenseMatrix();
            gram.topRightCorner(s, 2 * orders) += share.segment_harmonic;
            moment.bottomRows(2 * orders) += share.harmonic_residual;
        }
        gram.bottomLeftCorner(2 * orders, s) = gram.topRightCorner(s, 2 * orders).transpose();
        const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(gram);
        const Eigen::MatrixXd inverse = cod.pseudoInverse();
        const Eigen::MatrixXd coefficients = inverse * moment;
        const double tests = 2.0 * orders;
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
            l.harmonics.push_back(harmonic);
            if (p_min < significance / tests) {
                significant = true;
                structure_energy += 0.5 * static_cast<double>(n) * harmonic.amplitude.squaredNorm();
                parts.push_back(fmt::format("harmonic {} of the electrical angle ({:.3g} mV on u_d, {:.3g} mV on u_q, noise {:.2g} mV)", h,
                                            1e3 * harmonic.amplitude[0], 1e3 * harmonic.amplitude[1], 1e3 * harmonic.standard_error));
            }
        }
    }
    l.significant = significant;
    const double noise_energy = static_cast<double>(n) * noise.sigma.squaredNorm();
    l.structure = noise_energy > 0.0 ? structure_energy / noise_energy : 0.0;
    if (l.means_available && l.p_value < significance) {
        // Which operating condition the segment means follow most closely, per axis.
        const auto& segments = fit.segments;
        for (int a = 0; a < 2; ++a) {
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
            parts.insert(parts.begin() + a, text);
        }
    }
    for (const auto& p : parts) l.signature += (l.signature.empty() ? "" : "; ") + p;
    return l;
}

// Each parameter of an unidentifiable candidate pinned at a typical value (the others at their
// defaults), the model refitted around it: how far the base parameters move for no change in residual.
std::vector<Absorption> absorption_of(const Measurement& data, const ModelSpec& spec, const ModelFit& model, const Candidate& c,
                                      const NoiseEstimate& noise) {
    std::vector<Absorption> out;
    const auto effect = make_effect(c.effect);
    const Eigen::Index n = data.size();
    const auto first = model.values.size();
    for (Eigen::Index j = first; j < c.fit.values.size(); ++j) {
        Absorption a;
        a.parameter = c.fit.names[static_cast<std::size_t>(j)];
        const double declared = effect->values()[j - first];
        a.typical = declared != 0.0 ? declared : 0.01 * (c.fit.range_upper[j] - c.fit.range_lower[j]);
        ModelSpec pinned = spec.with(c.effect);
        for (std::size_t k = 0; k < effect->parameter_names().size(); ++k)
            pinned.effects.back().fixed[effect->parameter_names()[k]] =
                static_cast<Eigen::Index>(k) == j - first ? a.typical : effect->values()[static_cast<Eigen::Index>(k)];
        const auto pinned_model = make_model(pinned, data);
        Eigen::VectorXd start = pinned_model->parameters_of(MotorParameters{});
        start.head(first) = model.values;
        const Eigen::VectorXd v = refine_parameters(*pinned_model, pinned, start);
        const Eigen::VectorXd r = residual_stacked(*pinned_model, v);
        for (int axis = 0; axis < 2; ++axis)
            a.rss_change += (r.segment(axis * n, n).squaredNorm() - model.rss_axis(axis)) / std::pow(noise.long_run[axis], 2);
        for (int b = 0; b < 4; ++b) {
            a.base_shift[b] = v[b] / model.values[b] - 1.0;
            const double slope = (v[b] - model.values[b]) / a.typical;
            if (slope == 0.0) continue;
            const double zero = -model.values[b] / slope;
            if (zero >= c.fit.range_lower[j] && zero <= c.fit.range_upper[j])
                a.impossible_from.emplace_back(base_parameter_names[static_cast<std::size_t>(b)], zero);
        }
        out.push_back(a);
    }
    return out;
}

const char* unit_of(const std::string& variable) {
    if (variable.rfind("temp", 0) == 0) return "K";
    if (variable.find("omega") != std::string::npos) return "rad/s";
    return "A";
}

// Supported and partial share a rank: between them the evidence decides.
int rank_of(Verdict v) { return v == Verdict::Partial ? static_cast<int>(Verdict::Supported) : static_cast<int>(v); }

std::string join(const std::vector<std::string>& items) {
    std::string out;
    for (std::size_t k = 0; k < items.size(); ++k) out += (k == 0 ? "" : k + 1 == items.size() ? " and " : ", ") + items[k];
    return out;
}

std::string experiment_list(const std::vector<Experiment>& experiments) {
    std::string out;
    for (std::size_t k = 0; k < experiments.size(); ++k)
        out += fmt::format("{}{} ({})", k == 0 ? "" : k + 1 == experiments.size() ? " or " : ", ", experiments[k].name, experiments[k].description);
    return out;
}

Identifiability identifiability_of(double unique) {
    return !(unique >= absorbed_below) ? Identifiability::NotIdentifiable
           : unique < clear_above      ? Identifiability::MostlyAbsorbed
                                       : Identifiability::Identifiable;
}

// ---- the search over sets of effects ----

struct Addition {
    std::string effect;
    ModelFit fit;
    int added_parameters = 0;
};

// `fit`'s model with each of `effects` added in turn, from `fit`'s values, only the new effect's
// parameters searched. The fits are independent, so they run in parallel with the same result on
// any number of threads.
std::vector<Addition> fit_additions(const Measurement& data, const ModelSpec& spec, const ModelFit& fit,
                                    const std::vector<std::string>& effects, const FitOptions& options) {
    std::vector<Addition> out(effects.size());
    tbb::parallel_for(std::size_t{0}, effects.size(), [&](std::size_t k) {
        // Isolated, so that a thread waiting inside this fit's parallel loops does not start another
        // fit: at most one fit per thread holds its row-sized arrays at a time.
        tbb::this_task_arena::isolate([&] {
            const ModelSpec extended = spec.with(effects[k]);
            const auto extended_model = make_model(extended, data);
            Eigen::VectorXd start = extended_model->parameters_of(MotorParameters{});
            start.head(fit.values.size()) = fit.values;
            std::vector<Eigen::Index> search;
            for (Eigen::Index j = fit.values.size(); j < start.size(); ++j) search.push_back(j);
            out[k] = {effects[k], fit_model(data, extended, options, &start, search), static_cast<int>(search.size())};
        });
    });
    return out;
}

// The noise measured on the best-fitting of `fits`, with the overdispersion of its segment means.
NoiseEstimate noise_of_best(const Measurement& data, const std::vector<const ModelFit*>& fits) {
    const ModelFit* best = fits.front();
    for (const auto* f : fits)
        if (f->rss() < best->rss()) best = f;
    NoiseEstimate noise = estimate_noise(data, *best);
    Eigen::VectorXd storage;
    const LackOfFit l = lack_of_fit(data, *best, residual_of(data, *best, storage), noise);
    if (l.means_available) noise.dispersion = std::max(1.0, l.statistic / l.dof);
    return noise;
}

struct SearchStep {
    ModelFit fit;
    std::string added;         // "+effect", "-effect" when pruned, empty for the start
    int added_parameters = 0;  // negative when pruned
};

struct SetSearch {
    std::vector<SearchStep> steps;  // steps[0]: the model diagnosed
    std::vector<std::string> pruned;
    std::vector<std::string> tie;   // when the search stopped on two or more effects it cannot order
    ModelSpec tie_spec;
    Eigen::VectorXd tie_values;
};

// Whether `candidate` predicts held-out segments at least as well as the model it extends on a
// majority of them (true without leave-one-out).
bool predicts_held_out(const Measurement& data, const ModelFit& candidate, const std::vector<double>& model_folds) {
    if (model_folds.empty()) return true;
    const auto folds = leave_one_segment_out(data, candidate.spec, candidate.values);
    int better = 0;
    for (std::size_t k = 0; k < folds.size(); ++k) better += folds[k] < model_folds[k] ? 1 : 0;
    return 2 * better >= static_cast<int>(folds.size());
}

// Forward selection with backward pruning (docs/effects.md, "Several effects at once"). Each round
// adds the library effect with the strongest evidence (dBIC with the effective sample count, the
// noise measured on the round's best fit) among those the design can identify and that predict
// held-out segments; plausibility is not asked of a single step, only of the set the search ends
// with, because one missing effect biases the values that another takes alone. It stops when no
// effect is supported, or on a tie. Then each added effect that the others now explain (its
// removal costs less than strong evidence) is pruned, the weakest first.
SetSearch search_effect_sets(const Measurement& data, const Measurement& design, const ModelSpec& spec, const ModelFit& model,
                             const std::vector<std::string>& library, const std::vector<Candidate>& first_round,
                             const DiagnosisOptions& options) {
    SetSearch s;
    s.steps.push_back({model, "", 0});
    // Fits after the first round are compared by their residuals and shown on the path without
    // intervals, so they are made without them. Each addition is polished jointly with the effects
    // already there: screening it with their values held (tried in 2026-11) lost the second effect of
    // 37 of 60 triples, because one missing effect biases the values the others take.
    FitOptions compared = options.fit;
    compared.intervals = false;
    compared.keep_residual = false;
    std::vector<Addition> round;
    for (const auto& c : first_round) round.push_back({c.effect, c.fit, c.added_parameters});
    while (!round.empty() && static_cast<int>(s.steps.size()) - 1 < options.max_effects) {
        const ModelFit current = s.steps.back().fit;
        std::vector<const ModelFit*> fits{&current};
        for (const auto& a : round) fits.push_back(&a.fit);
        // No overdispersion here: while two effects are missing, no single addition removes the
        // structure of the other, and dividing by it would hide both. Structure that no library set
        // explains is caught at the end, where the set must reach the noise floor.
        NoiseEstimate noise = noise_of_best(data, fits);
        noise.dispersion = 1.0;
        const double log_n = std::log(std::max(noise.effective_samples, 2.0));
        std::vector<std::pair<double, const Addition*>> supported;
        for (const auto& a : round) {
            const double dbic = -likelihood_ratio(current, a.fit, noise) + a.added_parameters * log_n;
            if (dbic > supported_bic) continue;
            if (identifiability_of(most_distinct(design_unique_fractions(design, current.spec, current.values, a.effect))) ==
                Identifiability::NotIdentifiable)
                continue;
            supported.emplace_back(dbic, &a);
        }
        std::stable_sort(supported.begin(), supported.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
        const std::vector<double> current_folds =
            options.leave_one_out ? leave_one_segment_out(data, current.spec, current.values) : std::vector<double>{};
        std::size_t chosen = supported.size();
        for (std::size_t k = 0; k < supported.size() && chosen == supported.size(); ++k)
            if (predicts_held_out(data, supported[k].second->fit, current_folds)) chosen = k;
        if (chosen == supported.size()) break;
        const Addition& best = *supported[chosen].second;
        // A tie: another supported effect that the evidence does not separate from the best, or that
        // the design cannot tell apart from it at all.
        std::vector<std::string> tie{best.effect};
        for (std::size_t k = chosen + 1; k < supported.size(); ++k) {
            const auto& other = *supported[k].second;
            const bool close = supported[k].first - supported[chosen].first < tie_margin;
            const bool confounded =
                !close && std::max(most_distinct(design_unique_fractions(design, current.spec, current.values, other.effect, best.effect)),
                                   most_distinct(design_unique_fractions(design, current.spec, current.values, best.effect, other.effect))) <
                              clear_above;
            if ((close || confounded) && predicts_held_out(data, other.fit, current_folds)) tie.push_back(other.effect);
        }
        if (tie.size() > 1) {
            s.tie = tie;
            s.tie_spec = current.spec;
            s.tie_values = current.values;
            break;
        }
        s.steps.push_back({best.fit, "+" + best.effect, best.added_parameters});
        std::vector<std::string> rest;
        for (const auto& e : library)
            if (!best.fit.spec.contains(e)) rest.push_back(e);
        round = fit_additions(data, best.fit.spec, best.fit, rest, compared);
    }

    // Backward pruning, only of what the search added and only once two effects are there.
    while (s.steps.back().fit.spec.effects.size() >= spec.effects.size() + 2) {
        const ModelFit current = s.steps.back().fit;
        // The criterion that added the effects, no overdispersion: the same evidence decides both ways.
        NoiseEstimate noise = noise_of_best(data, {&current});
        noise.dispersion = 1.0;
        const double log_n = std::log(std::max(noise.effective_samples, 2.0));
        std::optional<SearchStep> weakest;
        double weakest_bic = supported_bic;
        for (const auto& term : current.spec.effects) {
            if (spec.contains(term.name)) continue;
            const ModelSpec reduced = current.spec.without(term.name);
            const auto reduced_model = make_model(reduced, data);
            const auto& names = reduced_model->parameter_names();
            Eigen::VectorXd start(static_cast<Eigen::Index>(names.size()));
            for (std::size_t j = 0; j < names.size(); ++j) start[static_cast<Eigen::Index>(j)] = current.values[current.index_of(names[j])];
            ModelFit reduced_fit = polish_model(data, reduced, start, compared);
            const int removed = static_cast<int>(current.free_count() - reduced_fit.free_count());
            // Evidence for keeping the effect, given all the others.
            const double keep_bic = -likelihood_ratio(reduced_fit, current, noise) + removed * log_n;
            if (keep_bic > weakest_bic) {
                weakest_bic = keep_bic;
                weakest = SearchStep{std::move(reduced_fit), "-" + term.name, -removed};
            }
        }
        if (!weakest) break;
        s.pruned.push_back(weakest->added.substr(1));
        s.steps.push_back(std::move(*weakest));
    }
    return s;
}

}  // namespace

const char* to_string(Identifiability level) {
    switch (level) {
        case Identifiability::Identifiable: return "identifiable";
        case Identifiability::MostlyAbsorbed: return "mostly absorbed";
        case Identifiability::NotIdentifiable: return "not identifiable";
    }
    return "?";
}

const char* to_string(Verdict verdict) {
    switch (verdict) {
        case Verdict::Supported: return "supported";
        case Verdict::Partial: return "partial";
        case Verdict::Weak: return "weak";
        case Verdict::NotSupported: return "not supported";
        case Verdict::Implausible: return "implausible";
        case Verdict::NotIdentifiable: return "not identifiable";
    }
    return "?";
}

Diagnosis diagnose(const Measurement& data, const ModelSpec& spec, const DiagnosisOptions& options) {
    Diagnosis out;
    out.source = data.source;
    out.samples = data.size();
    if (data.t) out.columns.push_back("t");
    if (data.has_segments()) out.columns.push_back("segment");
    if (data.theta_e) out.columns.push_back("theta_e");
    if (data.temp_winding) out.columns.push_back("temp_winding");
    if (data.temp_magnet) out.columns.push_back("temp_magnet");

    // No fit keeps its residual: each is recomputed where it is needed (residual_of), so that a long
    // log's diagnosis holds no row-sized array but the data while it searches.
    FitOptions without_residual = options.fit;
    without_residual.keep_residual = false;
    out.model = fit_model(data, spec, without_residual);
    for (std::size_t k = 0; k < spec.effects.size(); ++k) out.steps.push_back(fit_model(data, spec.prefix(k), without_residual));
    out.steps.push_back(out.model);
    const auto model = make_model(spec, data);
    const auto ranges = segment_ranges(data);
    out.mean_equations = 2 * static_cast<int>(ranges.size());

    // Candidates: every library effect not in the model whose columns the data have.
    std::vector<std::string> library;
    for (const auto* entry : EffectRegistry::instance().entries()) {
        if (spec.contains(entry->name)) continue;
        try {
            require_columns(*make_effect(entry->name), data);
        } catch (const InputError& e) {
            out.not_tried.push_back({entry->name, e.field()});
            continue;
        }
        library.push_back(entry->name);
    }
    for (auto& a : fit_additions(data, spec, out.model, library, without_residual)) {
        Candidate c;
        c.effect = a.effect;
        c.added_parameters = a.added_parameters;
        c.fit = std::move(a.fit);
        for (int j = 0; j < 4; ++j) c.base_shift[j] = c.fit.values[j] / out.model.values[j] - 1.0;
        out.candidates.push_back(std::move(c));
    }

    // Identifiability is a property of the operating points, the angle and the temperature trend, not
    // of the noise; on a long log the search's random subset of rows shows the same, at a fraction of
    // the cost of every design question asked below.
    const auto design_rows = search_subsample(data.size(), options.fit);
    const Measurement design =
        design_of(static_cast<Eigen::Index>(design_rows.size()) < data.size() ? select_rows(data, design_rows) : data);
    const SetSearch search = search_effect_sets(data, design, spec, out.model, library, out.candidates, options);
    out.pruned = search.pruned;

    // The noise, measured where the residual is smallest: on the last set of the search or on a
    // single addition, whichever fits best.
    const ModelFit* reference = &search.steps.back().fit;
    for (const auto& c : out.candidates)
        if (c.fit.rss() < reference->rss()) reference = &c.fit;
    {
        out.noise = estimate_noise(data, *reference);
        Eigen::VectorXd storage;
        const Eigen::VectorXd& residual = residual_of(data, *reference, storage);
        // Overdispersion: when even the best model tried leaves segment means that the noise cannot
        // explain, every likelihood ratio is divided by that excess (Q / dof), as a quasi-likelihood does.
        const LackOfFit reference_fit = lack_of_fit(data, *reference, residual, out.noise);
        if (reference_fit.means_available) out.noise.dispersion = std::max(1.0, reference_fit.statistic / reference_fit.dof);
    }
    const double log_n = std::log(std::max(out.noise.effective_samples, 2.0));
    // The excess residual: what the model leaves above the within-segment noise.
    const double floor_rss = static_cast<double>(data.size()) * out.noise.sigma.squaredNorm();
    auto explained = [&](const ModelFit& fit) {
        const double excess = out.model.rss() - floor_rss;
        if (!(excess > 0.0)) return 0.0;
        return std::clamp((out.model.rss() - fit.rss()) / excess, 0.0, 1.0);
    };

    check_base(out.model, out.base_problems);
    out.base_plausible = out.base_problems.empty();
    std::vector<double> model_folds;
    if (options.leave_one_out) model_folds = leave_one_segment_out(data, spec, out.model.values);
    if (!model_folds.empty()) out.model_loso_rms = pooled_rms(model_folds, data.size());

    out.segments = segment_conditions(data, out.model, spec.effects.empty() ? nullptr : &out.steps.front());
    for (auto& s : out.segments) {
        const auto r = ranges[static_cast<std::size_t>(&s - out.segments.data())];
        for (int a = 0; a < 2; ++a) s.mean_standard_error[a] = out.noise.long_run[a] / std::sqrt(static_cast<double>(r.rows));
    }
    const auto proposals = experiment_proposals(data, out.segments);

    for (auto& c : out.candidates) {
        c.likelihood_ratio = likelihood_ratio(out.model, c.fit, out.noise);
        c.delta_bic = -c.likelihood_ratio + c.added_parameters * log_n;
        c.explained = explained(c.fit);
        check_base(c.fit, c.implausible);
        check_effects(c.fit, c.implausible);
        c.plausible = c.implausible.empty();
        c.unique_fraction = most_distinct(design_unique_fractions(design, spec, out.model.values, c.effect));
        c.identifiability = identifiability_of(c.unique_fraction);
        if (c.identifiability != Identifiability::Identifiable)
            c.experiments = revealing_experiments(design, proposals, spec, out.model.values, c.effect);
        if (c.identifiability == Identifiability::NotIdentifiable) c.absorption = absorption_of(data, spec, out.model, c, out.noise);
        bool predicts = true;
        if (!model_folds.empty() && c.identifiability != Identifiability::NotIdentifiable && c.delta_bic < weak_bic) {
            const auto folds = leave_one_segment_out(data, spec.with(c.effect), c.fit.values);
            c.loso_rms = pooled_rms(folds, data.size());
            c.loso_segments = static_cast<int>(folds.size());
            for (std::size_t k = 0; k < folds.size(); ++k) c.loso_better += folds[k] < model_folds[k] ? 1 : 0;
            // A majority of held-out segments, not the pooled error: one operating point at the edge of
            // the range, where a polynomial extrapolates, must not outvote all the others.
            predicts = 2 * c.loso_better >= c.loso_segments;
        }
        const bool strong = c.delta_bic <= supported_bic && predicts;
        if (c.identifiability == Identifiability::NotIdentifiable) c.verdict = Verdict::NotIdentifiable;
        else if (!c.plausible) c.verdict = strong ? Verdict::Partial : Verdict::Implausible;
        else if (strong) c.verdict = Verdict::Supported;
        else if (c.delta_bic <= weak_bic) c.verdict = Verdict::Weak;
        else c.verdict = Verdict::NotSupported;
    }
    // Supported and partial candidates are ordered by their evidence alone: an effect that explains
    // most of the residual but is biased by another missing one must not fall behind one that
    // explains little.
    std::stable_sort(out.candidates.begin(), out.candidates.end(), [](const Candidate& a, const Candidate& b) {
        if (rank_of(a.verdict) != rank_of(b.verdict)) return rank_of(a.verdict) < rank_of(b.verdict);
        return a.delta_bic < b.delta_bic;
    });

    // The path, scored with the final noise estimate so that its steps compare with each other, and
    // as the search decided (without overdispersion: the noise floor at the end is the safeguard).
    {
        // One residual held at a time.
        Eigen::VectorXd storage;
        const Eigen::VectorXd& model_residual = residual_of(data, out.model, storage);
        out.lack_of_fit = lack_of_fit(data, out.model, model_residual, out.noise);
        apparent_values(*model, out.model, model_residual, out.noise, out.segments, out.apparent_names);
    }
    // Each step's structure left, kept for the findings below (step 0 is the model).
    std::vector<LackOfFit> path_left{out.lack_of_fit};
    NoiseEstimate path_noise = out.noise;
    Eigen::VectorXd step_storage;
    path_noise.dispersion = 1.0;
    for (std::size_t k = 0; k < search.steps.size(); ++k) {
        PathStep step;
        step.fit = search.steps[k].fit;
        step.added = search.steps[k].added;
        step.delta_bic = k == 0 ? 0.0
                                : -likelihood_ratio(search.steps[k - 1].fit, step.fit, path_noise) +
                                      search.steps[k].added_parameters * log_n;
        step.explained = explained(step.fit);
        check_base(step.fit, step.implausible);
        check_effects(step.fit, step.implausible);
        step.plausible = step.implausible.empty();
        if (k > 0) path_left.push_back(lack_of_fit(data, step.fit, residual_of(data, step.fit, step_storage), out.noise));
        const LackOfFit& left = path_left[k];
        step.at_noise_floor = !left.significant || left.structure < options.floor_tolerance;
        step.structure = left.significant ? left.structure : 0.0;
        if (left.significant) step.signature = left.signature;
        out.path.push_back(std::move(step));
    }
    const PathStep& last = out.path.back();
    // A search that stopped on a tie found what it could: the rest is one of the tied effects.
    const bool found = out.path.size() > 1 && last.plausible && (last.at_noise_floor || !search.tie.empty());
    out.recommended = found ? last.fit.spec : spec;
    out.tie = search.tie;
    out.missing_effect_found = found || !out.tie.empty();
    if (found && out.tie.empty()) {
        out.winner = out.path[1].added.substr(1);
        out.after_winner = path_left[1];
    }
    if (!out.tie.empty()) out.tie_experiments = revealing_experiments(design, proposals, search.tie_spec, search.tie_values, out.tie[0], out.tie[1]);
    // "Not in the library" only when no set of library effects reaches the noise floor with
    // plausible values while the model does not.
    out.not_in_library = out.lack_of_fit.significant && !found && out.tie.empty();

    out.drifts = drifts_of(out.segments, out.apparent_names);

    // ---- findings, in words ----
    auto& f = out.findings;
    const auto& m = out.model;
    f.push_back(fmt::format("{} fits with a residual of {:.4g} V rms (u_d {:.4g} V, u_q {:.4g} V); the noise alone is {:.3g} V on u_d "
                            "and {:.3g} V on u_q (measured on {}).",
                            m.spec.text(), m.rms.total, m.rms.d, m.rms.q, out.noise.sigma[0], out.noise.sigma[1], out.noise.model));
    if (out.steps.size() > 1)
        f.push_back(fmt::format("Before the effects (base model) the residual was {:.4g} V rms; with them it is {:.4g} V ({}).", out.steps.front().rms.total,
                                m.rms.total, percent(m.rms.total / out.steps.front().rms.total - 1.0)));
    const int unknowns = static_cast<int>(m.free_count());
    if (!data.has_segments())
        f.push_back("The data have no segment column, so the operating points are unknown: leave-one-segment-out prediction and the "
                    "segment-mean test are not available, and identifiability is judged on the raw samples, where noise can make an effect "
                    "look identifiable. Add a segment column (docs/data-format.md).");
    else if (out.mean_equations <= unknowns)
        f.push_back(fmt::format(
            "The {} operating points give {} segment-mean equations for the {} free parameters of {}: any effect without an angle or "
            "temperature signature is absorbed into these parameters without leaving a residual, and cannot be checked on this data.",
            ranges.size(), out.mean_equations, unknowns, m.spec.text()));
    for (const auto& p : out.base_problems) f.push_back("The fitted model is physically impossible: " + p + ". Something is missing or the design cannot determine it.");
    const PathStep& end = out.path.back();
    auto effect_values = [](const ModelFit& fit, Eigen::Index from) {
        std::string values;
        for (Eigen::Index j = from; j < fit.values.size(); ++j)
            values += fmt::format("{}{} = {:.4g} {}", values.empty() ? "" : ", ", fit.names[static_cast<std::size_t>(j)], fit.values[j],
                                  fit.units[static_cast<std::size_t>(j)]);
        return values;
    };
    if (out.missing_effect_found && out.path.size() > 1) {
        std::vector<std::string> added;
        for (const auto& e : end.fit.spec.effects)
            if (!spec.contains(e.name)) added.push_back(e.name);
        const double floor = std::sqrt(out.noise.sigma.squaredNorm() / 2.0);
        if (added.size() == 1) {
            const Candidate* w = nullptr;
            for (const auto& c : out.candidates)
                if (c.effect == added.front()) w = &c;
            const Candidate* next = nullptr;
            for (const auto& c : out.candidates)
                if (&c != w && !next) next = &c;
            f.push_back(fmt::format("Missing effect: {} (its fit: {}). Adding it lowers the residual to {:.4g} V rms; evidence dBIC = {:.1f}{}.",
                                    added.front(), effect_values(end.fit, m.values.size()), end.fit.rms.total, w ? w->delta_bic : end.delta_bic,
                                    next ? fmt::format(", the next best ({}) {:.1f}", next->effect, next->delta_bic) : std::string()));
        } else {
            std::string steps;
            for (std::size_t k = 1; k < out.path.size(); ++k)
                steps += fmt::format("{} {} {:.4g} V (dBIC {:.1f})", k == 1 ? "" : ",", out.path[k].added, out.path[k].fit.rms.total, out.path[k].delta_bic);
            f.push_back(fmt::format("Missing effects: {} together (recommended model {}; their fit: {}). The residual falls from {:.4g} V rms "
                                    "step by step:{}, to the noise floor of {:.3g} V.",
                                    join(added), end.fit.spec.text(), effect_values(end.fit, m.values.size()), m.rms.total, steps, floor));
        }
        if (!end.signature.empty())
            f.push_back(fmt::format("Some structure remains ({}), with {:.2f} of the noise power: below the tolerance of {:.2f}. It is the size of "
                                    "the steady-state model's own error on effects that make the currents ripple; a larger one would mean "
                                    "another effect.",
                                    end.signature, end.structure, options.floor_tolerance));
        if (out.winner) {
            const Candidate* w = nullptr;
            for (const auto& c : out.candidates)
                if (c.effect == *out.winner) w = &c;
            if (w && w->identifiability == Identifiability::MostlyAbsorbed)
                f.push_back(fmt::format("Only {:.0f} % of {}'s signature is its own on this design; the rest shifts the base parameters (Rs {}, Ld {}, "
                                        "Lq {}, psi_f {} when it is added).",
                                        100.0 * w->unique_fraction, w->effect, percent(w->base_shift[0]), percent(w->base_shift[1]),
                                        percent(w->base_shift[2]), percent(w->base_shift[3])));
        }
    }
    for (const auto& c : out.candidates)
        if (c.verdict == Verdict::Partial)
            f.push_back(fmt::format("Alone, {} explains {:.0f} % of the excess residual (dBIC {:.1f}) but takes implausible values ({}): another effect "
                                    "is still missing{}.",
                                    c.effect, 100.0 * c.explained, c.delta_bic, c.implausible.front(),
                                    out.missing_effect_found ? ", and the search over sets of effects added it" : ""));
    for (const auto& p : out.pruned) f.push_back(p + " was added on the way and pruned again: the other effects of the set explain it.");
    if (!out.tie.empty()) {
        const std::string after = out.path.size() > 1 ? "After " + end.fit.spec.text() + ", " : std::string();
        f.push_back(fmt::format("{}Near tie: {} explain the {}residual about equally well (dBIC within {:g}) or cannot be told apart on this "
                                "design; the data cannot say which is missing.",
                                after, join(out.tie), out.path.size() > 1 ? "remaining " : "", tie_margin));
        f.push_back(out.tie_experiments.empty() ? std::string("No single extra operating point separates them.")
                                                : "An experiment that would separate them: " + experiment_list(out.tie_experiments) + ".");
    } else if (out.not_in_library) {
        const LackOfFit& remaining = path_left.back();
        std::string text = "No set of library effects reaches the noise floor with plausible values: the missing effect is not in the library.";
        if (out.path.size() > 1)
            text += fmt::format(" The best set the library offers, {}, explains {:.0f} % of the excess residual{}; its effects may be real or may "
                                "absorb part of the unknown one, so it is not recommended.",
                                end.fit.spec.text(), 100.0 * end.explained,
                                end.plausible ? std::string() : " but takes implausible values (" + end.implausible.front() + ")");
        text += " The signature" + std::string(out.path.size() > 1 && remaining.significant ? " of what it leaves" : "") + ": " +
                (remaining.significant ? remaining.signature : out.lack_of_fit.signature) + ".";
        f.push_back(text);
    } else if (!out.missing_effect_found) {
        f.push_back(out.lack_of_fit.means_available || data.theta_e
                        ? "No missing effect: the residual is at the noise floor and no library effect earns its parameters."
                        : "No missing effect can be seen on this data.");
    }
    std::vector<std::string> hidden;
    for (const auto& c : out.candidates)
        if (c.verdict == Verdict::NotIdentifiable) hidden.push_back(c.effect);
    if (!hidden.empty()) {
        f.push_back(fmt::format("Not identifiable from this data (absorbed by the model's parameters without trace): {}.", join(hidden)));
        for (const auto& c : out.candidates) {
            if (c.verdict != Verdict::NotIdentifiable) continue;
            std::string text = c.effect + ": ";
            text += c.experiments.empty() ? std::string("none of the extra operating points tried, alone or together, would make a tenth of its "
                                                        "signature its own.")
                                          : "would show with " + experiment_list(c.experiments) + ".";
            // The parameter that moves the base parameters most says the most about what is at stake.
            const Absorption* largest = nullptr;
            for (const auto& a : c.absorption)
                if (!largest || a.base_shift.cwiseAbs().maxCoeff() > largest->base_shift.cwiseAbs().maxCoeff()) largest = &a;
            if (largest) {
                std::string moved;
                for (int j = 0; j < 4; ++j)
                    if (std::abs(largest->base_shift[j]) >= 0.005)
                        moved += fmt::format("{}{} {}", moved.empty() ? "" : ", ", base_parameter_names[static_cast<std::size_t>(j)],
                                             percent(largest->base_shift[j]));
                text += fmt::format(" A typical {} = {:.4g} moves {} while the residual changes by {:.2g} noise variances", largest->parameter,
                                    largest->typical, moved.empty() ? std::string("the base parameters by less than 0.5 %") : moved,
                                    largest->rss_change);
                for (const auto& [name, value] : largest->impossible_from)
                    text += fmt::format("; at {} = {:.3g} {} would reach zero", largest->parameter, value, name);
                text += ".";
            }
            f.push_back(text);
        }
    }
    for (const auto& n : out.not_tried)
        f.push_back(fmt::format("{} was not tried: it needs the column {}, which the data lack (log it to check this effect).", n.effect, n.column));
    for (const auto& d : out.drifts)
        if (!d.variable.empty())
            f.push_back(fmt::format("The apparent {} drifts with {} across segments (r = {:.2f}, {:.3g} {} per {}).", d.parameter, d.variable,
                                    d.correlation, d.slope, out.model.units[static_cast<std::size_t>(out.model.index_of(d.parameter))],
                                    unit_of(d.variable)));
    return out;
}

}  // namespace mhb::pmsm
