#include "problems/pmsm/diagnosis/model_checks.hpp"

#include <algorithm>
#include <cmath>
#include <functional>

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "problems/pmsm/diagnosis/lack_of_fit.hpp"
#include "problems/pmsm/diagnosis/segments.hpp"
#include "problems/pmsm/diagnosis/verdict.hpp"

namespace mhb::pmsm {

// The refit for held-out prediction is one Gauss-Newton step from the fit on all rows, computed from
// per-segment normal equations: one pass over the rows instead of a refit per segment, exact for the
// base parameters (the prediction is linear in them) and first order in the effect parameters, which
// the fit on all rows has already placed. Effect parameters at an end of their range stay there, as
// they would in a bounded refit.
namespace {

// `kept`: the fit's own per-segment sums when they are of these data, these segments, these values
// and every column asked for (the same numbers a pass would give); null to make them.
std::vector<double> leave_one_segment_out(const Measurement& data, const ModelSpec& spec, const Eigen::VectorXd& values,
                                          const SegmentSums* kept) {
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
    std::vector<Eigen::Index> positions;
    if (kept != nullptr && kept->data == &data && kept->samples == data.size() && kept->starts == starts &&
        kept->values.size() == values.size() && (kept->values.array() == values.array()).all())
        for (const auto j : columns)
            if (const auto at = std::find(kept->columns.begin(), kept->columns.end(), j); at != kept->columns.end())
                positions.push_back(static_cast<Eigen::Index>(at - kept->columns.begin()));
    const auto sums = positions.size() == columns.size() && !columns.empty() ? select_columns(kept->sums, positions)
                                                                             : range_normal_equations(*model, values, columns, starts);
    const Eigen::MatrixXd steps = leave_one_range_out_steps(sums);
    for (std::size_t s = 0; s < ranges.size(); ++s) {
        const Eigen::VectorXd step = steps.col(static_cast<Eigen::Index>(s));
        sse.push_back(std::max(sums.total[s] - 2.0 * step.dot(sums.moment[s]) + step.dot(sums.gram[s] * step), 0.0));
    }
    return sse;
}

}  // namespace

std::vector<double> leave_one_segment_out(const Measurement& data, const ModelSpec& spec, const Eigen::VectorXd& values) {
    return leave_one_segment_out(data, spec, values, nullptr);
}

std::vector<double> leave_one_segment_out(const Measurement& data, const ModelFit& fit) {
    return leave_one_segment_out(data, fit.spec, fit.values, fit.segment_sums.get());
}

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

StatedAccuracy stated_law_accuracy(const ModelSpec& spec) {
    StatedAccuracy out;
    // The accuracy is the law's, not the fit's: an effect made from its name says it, without the
    // pass over the rows that a model of the data would make for its operating scale.
    for (const auto& term : spec.effects)
        if (const auto effect = make_effect(term.name); effect->law_accuracy() > out.accuracy) out = {effect->name(), effect->law_accuracy()};
    return out;
}

LawAllowance law_allowance(const Measurement& data, const ModelFit& fit, const NoiseEstimate& noise) {
    LawAllowance out;
    const StatedAccuracy stated = stated_law_accuracy(fit.spec);
    const double accuracy = stated.accuracy;
    if (!stated.effect.empty()) out.source = fmt::format("{} ({:g} % of the flux linkage)", stated.effect, 100.0 * accuracy);
    const double noise_power = static_cast<double>(data.size()) * noise.sigma.squaredNorm();
    if (!(accuracy > 0.0) || !(noise_power > 0.0)) return out;
    // omega psi = u - Rs i in the steady state, whatever else the model holds.
    const double rs = fit.values[0];
    out.power = accuracy * accuracy * ((data.u_d - rs * data.i_d).squaredNorm() + (data.u_q - rs * data.i_q).squaredNorm()) / noise_power;
    return out;
}

std::vector<LawStandIn> law_stand_ins(const Measurement& data, const Diagnosis& d) {
    std::vector<LawStandIn> out;
    const std::size_t last = d.recommended_step;
    if (last >= d.path.size() || d.path[last].fit.spec.text() != d.recommended.text()) return out;
    const double rows = static_cast<double>(data.size());
    const double noise_power = rows * d.noise.sigma.squaredNorm();
    Eigen::VectorXd before_storage, after_storage;
    for (std::size_t k = 1; k <= last; ++k) {
        const PathStep& before = d.path[k - 1];
        const PathStep& step = d.path[k];
        if (step.kind != StepKind::Added || !(before.allowance.power > 0.0) || !d.recommended.contains(step.effect)) continue;
        const double change = (residual_of(data, before.fit, before_storage) - residual_of(data, step.fit, after_storage)).squaredNorm();
        const double allowance = before.allowance.power * noise_power;
        if (change > allowance) continue;
        out.push_back({step.effect, before.allowance.source, std::sqrt(change / (2.0 * rows)), std::sqrt(allowance / (2.0 * rows))});
    }
    return out;
}

bool at_noise_floor(const LackOfFit& left, double floor_tolerance, const LawAllowance& allowance) {
    return !left.significant || left.structure < floor_tolerance + allowance.power;
}

namespace {

// Whether parameter j of `fit`, real parameter k of `effect`, lies at or beyond an end of its
// plausible range that makes the fit implausible.
bool implausible_at_range_end(const ModelFit& fit, Eigen::Index j, const Effect& effect, std::size_t k) {
    const bool beyond = fit.beyond_range(j);
    if (!(beyond || fit.at_bound(j)) || !effect.range_end_implausible(k)) return false;
    const bool at_lower = fit.values[j] <= fit.range_lower[j] + 1e-9 * (fit.range_upper[j] - fit.range_lower[j]);
    // Zero is a magnitude's natural floor (no band, no harmonic, no delay), not an implausible value.
    return !(at_lower && !beyond && fit.range_lower[j] == 0.0);
}

}  // namespace

std::map<std::string, std::map<std::string, double>> material_values_at_range_ends(const ModelFit& fit, const Measurement& data) {
    std::map<std::string, std::map<std::string, double>> held;
    if (fit.spec.effects.empty()) return held;
    const auto model = make_model(fit.spec, data);
    Eigen::Index j = 4;
    for (const auto& effect : model->effects())
        for (std::size_t k = 0; k < effect->parameter_names().size(); ++k, ++j) {
            if (!implausible_at_range_end(fit, j, *effect, k)) continue;
            const auto value = effect->material_value(k);
            if (!value) return {};
            held[effect->name()][effect->parameter_names()[k]] = *value;
        }
    return held;
}

void check_effects(const ModelFit& fit, const Measurement& data, std::vector<std::string>& problems) {
    if (fit.spec.effects.empty()) return;
    // The model's effects know the data's scale, and with it their ranges and what their ends mean.
    const auto model = make_model(fit.spec, data);
    // The logged currents the machine must be physical at: every row of a short log, an even spread
    // of 4096 of a long one (a saturation curve does not change between neighbouring rows).
    const Eigen::Index stride = std::max<Eigen::Index>(1, data.size() / 4096);
    const Eigen::Index count = (data.size() + stride - 1) / stride;
    const Eigen::ArrayXd i_d = Eigen::Map<const Eigen::ArrayXd, 0, Eigen::InnerStride<>>(data.i_d.data(), count, Eigen::InnerStride<>(stride));
    const Eigen::ArrayXd i_q = Eigen::Map<const Eigen::ArrayXd, 0, Eigen::InnerStride<>>(data.i_q.data(), count, Eigen::InnerStride<>(stride));
    Eigen::Index j = 4;
    for (const auto& effect : model->effects()) {
        const Eigen::Index first = j;
        for (std::size_t k = 0; k < effect->parameter_names().size(); ++k, ++j) {
            if (!implausible_at_range_end(fit, j, *effect, k)) continue;
            const bool beyond = fit.beyond_range(j);
            const bool at_lower = fit.values[j] <= fit.range_lower[j] + 1e-9 * (fit.range_upper[j] - fit.range_lower[j]);
            const std::string meaning = effect->range_end_meaning(k, !at_lower);
            problems.push_back(fmt::format("{} = {:.4g} {} {} {} end of its plausible range{} [{:g}, {:g}]{}{}",
                                           fit.names[static_cast<std::size_t>(j)], fit.values[j], fit.units[static_cast<std::size_t>(j)],
                                           beyond ? "lies beyond the" : "sits at the", at_lower ? "lower" : "upper", beyond ? " for this log" : "",
                                           fit.range_lower[j], fit.range_upper[j], meaning.empty() ? "" : ": ", meaning));
        }
        const std::string reason = effect->implausible_reason(fit.values.data() + first, fit.values.data(), i_d, i_q);
        if (!reason.empty()) problems.push_back(fmt::format("{}: {}", effect->name(), reason));
    }
}

std::string deciding_count(const HeldOutVote& vote) {
    if (vote.deciding == 0 || vote.deciding >= vote.segments) return {};
    return fmt::format(" ({} of the {} it changes by {:g} % or more)", vote.better_deciding, vote.deciding, 100.0 * evidence::deciding_change);
}

HeldOutComparison compare_held_out(const Measurement& data, const ModelFit& candidate, const std::vector<double>& model_folds) {
    HeldOutComparison c;
    c.folds = leave_one_segment_out(data, candidate);
    HeldOutVote& v = c.vote;
    v.segments = static_cast<int>(c.folds.size());
    for (std::size_t k = 0; k < c.folds.size(); ++k) {
        const bool better = c.folds[k] < model_folds[k];
        v.better += better ? 1 : 0;
        if (std::abs(c.folds[k] - model_folds[k]) >= evidence::deciding_change * model_folds[k]) {
            ++v.deciding;
            v.better_deciding += better ? 1 : 0;
        }
    }
    return c;
}

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
        if (chi_squared_survival(spread, static_cast<double>(v.size() - 1)) > evidence::significance) continue;
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

}  // namespace mhb::pmsm
