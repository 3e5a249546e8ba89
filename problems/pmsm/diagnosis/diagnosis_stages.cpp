#include "problems/pmsm/diagnosis/diagnosis_stages.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>

#include <boost/math/distributions/chi_squared.hpp>
#include <fmt/format.h>

#include "framework/input_error.hpp"
#include "framework/registry.hpp"
#include "problems/pmsm/diagnosis/lack_of_fit.hpp"
#include "problems/pmsm/diagnosis/library_orders.hpp"
#include "problems/pmsm/diagnosis/model_checks.hpp"
#include "problems/pmsm/diagnosis/noise.hpp"
#include "problems/pmsm/diagnosis/segments.hpp"
#include "problems/pmsm/diagnosis/verdict.hpp"

namespace mhb::pmsm {

Baseline fit_baseline(const Measurement& data, const ModelSpec& spec, const FitOptions& options) {
    Baseline b;
    b.model = fit_model(data, spec, options);
    for (std::size_t k = 0; k < spec.effects.size(); ++k) b.build_up.push_back(fit_model(data, spec.prefix(k), options));
    b.build_up.push_back(b.model);
    return b;
}

LibraryScreen screen_library(const Measurement& data, const ModelSpec& spec) {
    LibraryScreen s;
    for (const auto* entry : EffectRegistry::instance().entries()) {
        if (spec.contains(entry->name)) continue;
        try {
            require_columns(*make_effect(entry->name), data);
        } catch (const InputError& e) {
            s.not_tried.push_back({entry->name, e.field()});
            continue;
        }
        s.library.push_back(entry->name);
    }
    return s;
}

std::vector<Candidate> fit_candidates(const Measurement& data, const ModelSpec& spec, const ModelFit& model,
                                      const std::vector<std::string>& library, const FitOptions& options) {
    std::vector<Candidate> out;
    for (auto& a : fit_additions(data, spec, model, library, options)) {
        Candidate c;
        c.effect = a.effect;
        c.added_parameters = a.added_parameters;
        c.fit = std::move(a.fit);
        for (int j = 0; j < 4; ++j) c.base_shift[j] = c.fit.values[j] / model.values[j] - 1.0;
        out.push_back(std::move(c));
    }
    return out;
}

Measurement search_design(const Measurement& data, const FitOptions& options) {
    // Identifiability is a property of the operating points, the angle and the temperature trend, not
    // of the noise; on a long log the search's random subset of rows shows the same, at a fraction of
    // the cost of every design question asked of it.
    const auto rows = search_subsample(data.size(), options);
    return design_of(static_cast<Eigen::Index>(rows.size()) < data.size() ? select_rows(data, rows) : data);
}

NoiseEstimate measure_noise(const Measurement& data, const SetSearch& search, const std::vector<Candidate>& candidates) {
    std::vector<const ModelFit*> fits{&search.steps.back().fit};
    for (const auto& c : candidates) fits.push_back(&c.fit);
    return noise_of_best(data, fits, search.data_noise);
}

ModelCheck check_model(const Measurement& data, const ModelSpec& spec, const Baseline& baseline, const NoiseEstimate& noise,
                       const DiagnosisOptions& options, const ShaftAngle& shaft) {
    ModelCheck check;
    const ModelFit& model = baseline.model;
    check_base(model, check.base_problems);
    if (options.leave_one_out) check.folds = leave_one_segment_out(data, model);
    if (!check.folds.empty()) check.loso_rms = pooled_rms(check.folds, data.size());
    check.segments = segment_conditions(data, model, spec.effects.empty() ? nullptr : &baseline.build_up.front());
    const auto ranges = segment_ranges(data);
    for (auto& s : check.segments) {
        const auto r = ranges[static_cast<std::size_t>(&s - check.segments.data())];
        for (int a = 0; a < 2; ++a) s.mean_standard_error[a] = noise.long_run[a] / std::sqrt(static_cast<double>(r.rows));
    }
    {
        // One residual held at a time.
        Eigen::VectorXd storage;
        const Eigen::VectorXd& residual = residual_of(data, model, storage);
        check.lack_of_fit = lack_of_fit(data, model, residual, noise, shaft);
        apparent_values(*make_model(spec, data), model, residual, noise, check.segments, check.apparent_names);
    }
    check.drifts = drifts_of(check.segments, check.apparent_names);
    return check;
}

double explained_fraction(const ModelFit& model, const ModelFit& fit, double floor_rss) {
    const double excess = model.rss() - floor_rss;
    if (!(excess > 0.0)) return 0.0;
    return std::clamp((model.rss() - fit.rss()) / excess, 0.0, 1.0);
}

namespace {

void score_candidate(Candidate& c, const Measurement& data, const Measurement& design, const std::vector<Proposal>& proposals,
                     const ModelFit& model, const NoiseEstimate& noise, const std::vector<double>& model_folds,
                     const std::function<bool()>& outside_harmonic) {
    const ModelSpec& spec = model.spec;
    const double log_n = std::log(std::max(noise.effective_samples, 2.0));
    c.likelihood_ratio = likelihood_ratio(model, c.fit, noise);
    c.delta_bic = -c.likelihood_ratio + c.added_parameters * log_n;
    c.explained = explained_fraction(model, c.fit, static_cast<double>(data.size()) * noise.sigma.squaredNorm());
    check_base(c.fit, c.implausible);
    check_effects(c.fit, data, c.implausible);
    c.plausible = c.implausible.empty();
    c.unique_fraction = most_distinct(design_unique_fractions(design, spec, model.values, c.effect));
    c.identifiability = identifiability_of(c.unique_fraction);
    if (c.identifiability != Identifiability::Identifiable)
        c.experiments = revealing_experiments(design, proposals, spec, model.values, c.effect);
    if (c.identifiability == Identifiability::NotIdentifiable) c.absorption = absorption_of(data, spec, model, c, noise);
    // Held-out prediction is asked only of candidates with some evidence that the design can identify.
    if (!model_folds.empty() && c.identifiability != Identifiability::NotIdentifiable && c.delta_bic < evidence::weak_bic) {
        const HeldOutComparison held_out = compare_held_out(data, c.fit, model_folds);
        c.loso_rms = pooled_rms(held_out.folds, data.size());
        c.held_out = held_out.vote;
        c.predicts_held_out = held_out.vote.passes(outside_harmonic);
    }
    c.verdict = verdict_of(c);
}

}  // namespace

void score_candidates(std::vector<Candidate>& candidates, const Measurement& data, const Measurement& design,
                      const std::vector<Proposal>& proposals, const ModelFit& model, const NoiseEstimate& noise,
                      const std::vector<double>& model_folds, const LackOfFit& model_left) {
    // Whether the model's residual holds a harmonic no library law makes, asked once and only if a vote needs it.
    std::optional<bool> outside;
    const std::function<bool()> outside_harmonic = [&] {
        if (!outside) outside = !harmonics_outside_library(model_left, model.spec, noise).empty();
        return *outside;
    };
    for (auto& c : candidates) score_candidate(c, data, design, proposals, model, noise, model_folds, outside_harmonic);
    // Supported and partial candidates are ordered by their evidence alone: an effect that explains
    // most of the residual but is biased by another missing one must not fall behind one that
    // explains little.
    std::stable_sort(candidates.begin(), candidates.end(), ranks_before);
}

namespace {

// A set implausible only for parameters left at an end of their range that have a material value
// (winding heating's coefficient at the end of copper's spread, traded against a dead-time band): it
// is refitted with them held there, and the held fit becomes the step's when the data cannot tell
// it from the free one (its loss in noise units within the chi-squared 95 % point of as many
// degrees of freedom) and nothing else is implausible. A range end says the data pull beyond the
// material; a small loss at the material's value says they do not pull hard.
void hold_at_material_values(const Measurement& data, PathStep& step, const NoiseEstimate& noise, int& added_parameters) {
    std::vector<std::string> problems;
    check_base(step.fit, problems);
    if (!problems.empty()) return;
    const auto held = material_values_at_range_ends(step.fit, data);
    if (held.empty()) return;
    // The spec with them fixed has the same parameters in the same order, so the free fit's values
    // start the refit, the held ones replaced.
    ModelSpec spec = step.fit.spec;
    Eigen::VectorXd start = step.fit.values;
    int count = 0;
    std::string what;
    for (auto& term : spec.effects) {
        const auto it = held.find(term.name);
        if (it == held.end()) continue;
        for (const auto& [name, value] : it->second) {
            term.fixed[name] = value;
            ++count;
            const std::string full = term.name + "." + name;
            what += fmt::format("{}{} = {:.4g} (free: {:.4g})", what.empty() ? "" : ", ", full, value, step.fit.values[step.fit.index_of(full)]);
            start[step.fit.index_of(full)] = value;
        }
    }
    FitOptions options;
    options.intervals = false;
    options.keep_residual = false;
    ModelFit refit = polish_model(data, spec, start, options);
    const double loss = likelihood_ratio(refit, step.fit, noise);
    const double limit = boost::math::quantile(boost::math::chi_squared(count), 0.95);
    check_base(refit, problems);
    check_effects(refit, data, problems);
    if (!(loss <= limit) || !problems.empty()) return;
    step.held_at_material = fmt::format("{}: the free fit left it at the end of its plausible range, and held at the material's value "
                                        "it fits as well as far as this log can tell (loss {:.2f} against the chi-squared 95 % point {:.2f})",
                                        what, loss, limit);
    step.fit = std::move(refit);
    step.implausible.clear();
    step.plausible = true;
    added_parameters -= count;
}

}  // namespace

PathTrace trace_path(const Measurement& data, const SetSearch& search, const ModelFit& model, const LackOfFit& model_left,
                     const NoiseEstimate& noise, double floor_tolerance, const ShaftAngle& shaft) {
    PathTrace trace;
    trace.left.push_back(model_left);
    NoiseEstimate path_noise = noise;
    path_noise.dispersion = 1.0;
    const double log_n = std::log(std::max(noise.effective_samples, 2.0));
    const double floor_rss = static_cast<double>(data.size()) * noise.sigma.squaredNorm();
    Eigen::VectorXd storage;
    for (std::size_t k = 0; k < search.steps.size(); ++k) {
        const SearchStep& s = search.steps[k];
        PathStep step;
        step.fit = s.fit;
        check_base(step.fit, step.implausible);
        check_effects(step.fit, data, step.implausible);
        step.plausible = step.implausible.empty();
        int added_parameters = s.added_parameters;
        if (!step.plausible && k > 0) hold_at_material_values(data, step, path_noise, added_parameters);
        step.kind = s.kind;
        step.effect = s.effect;
        step.reduced_law = s.reduced_law;
        step.whole_law_base = s.whole_law_base;
        step.delta_bic = k == 0 ? 0.0 : -likelihood_ratio(search.steps[k - 1].fit, step.fit, path_noise) + added_parameters * log_n;
        step.explained = explained_fraction(model, step.fit, floor_rss);
        if (k > 0) trace.left.push_back(lack_of_fit(data, step.fit, residual_of(data, step.fit, storage), noise, shaft));
        const LackOfFit& left = trace.left[k];
        step.allowance = law_allowance(data, step.fit, noise);
        step.at_noise_floor = at_noise_floor(left, floor_tolerance, step.allowance);
        step.structure = left.significant ? left.structure : 0.0;
        if (left.significant) step.signature = left.signature;
        trace.path.push_back(std::move(step));
    }
    return trace;
}

Recommendation recommend(const ModelSpec& spec, const SetSearch& search, const PathTrace& trace, const LackOfFit& model_left,
                         const Measurement& design, const std::vector<Proposal>& proposals) {
    Recommendation r;
    // An addition that makes the set implausible does not undo the set it was added to: the
    // latest plausible set before a run of implausible additions is judged instead (an effect
    // added at the noise floor to take a sliver, with values no machine has, seen on the 5 kW raw
    // logs' flux harmonics and, while the dead-time band was linear, the 100 kW dead time with
    // winding heating; tests/pmsm_diagnosis_stages_test.cpp). Not across pruning, which already
    // judged the larger sets.
    r.step = trace.path.size() - 1;
    while (r.step > 1 && !trace.path[r.step].plausible && trace.path[r.step].kind == StepKind::Added && search.tie.empty()) --r.step;
    if (!trace.path[r.step].plausible) r.step = trace.path.size() - 1;
    const PathStep& last = trace.path[r.step];
    // A search that stopped on a tie found what it could: the rest is one of the tied effects.
    const bool plausible = trace.path.size() > 1 && last.plausible;
    const bool complete = plausible && (last.at_noise_floor || !search.tie.empty());
    const bool found = complete || (plausible && last.explained >= evidence::most_of_the_excess);
    r.incomplete = found && !complete;
    r.recommended = found ? last.fit.spec : spec;
    r.tie = search.tie;
    r.missing_effect_found = found || !r.tie.empty();
    if (found && r.tie.empty()) {
        r.winner = trace.path[1].effect;
        r.after_winner = trace.left[1];
    }
    if (!r.tie.empty()) r.tie_experiments = revealing_experiments(design, proposals, search.tie_spec, search.tie_values, r.tie[0], r.tie[1]);
    // Structure below the floor's tolerance is at the floor (the search table says so, and the search
    // stops there): no effect is missing, so none can be missing from the library either.
    r.not_in_library = model_left.significant && !trace.path.front().at_noise_floor && !found && r.tie.empty();
    return r;
}

}  // namespace mhb::pmsm
