#include "problems/pmsm/diagnosis/diagnosis.hpp"

#include "problems/pmsm/diagnosis/detection_limits.hpp"
#include "problems/pmsm/diagnosis/diagnosis_stages.hpp"
#include "problems/pmsm/diagnosis/findings.hpp"
#include "problems/pmsm/diagnosis/interval_caveats.hpp"
#include "problems/pmsm/diagnosis/library_orders.hpp"
#include "problems/pmsm/diagnosis/model_checks.hpp"
#include "problems/pmsm/diagnosis/segments.hpp"

namespace mhb::pmsm {

Diagnosis diagnose(const Measurement& data, const ModelSpec& spec, const DiagnosisOptions& options) {
    Diagnosis out;
    out.source = data.source;
    out.samples = data.size();
    out.current_loop_bandwidth = data.current_loop_bandwidth;
    out.current_loop_delay = data.current_loop_delay;
    if (data.t) out.columns.push_back("t");
    if (data.has_segments()) out.columns.push_back("segment");
    if (data.theta_e) out.columns.push_back("theta_e");
    if (data.temp_winding) out.columns.push_back("temp_winding");
    if (data.temp_magnet) out.columns.push_back("temp_magnet");
    if (data.theta_m) out.columns.push_back("theta_m");

    // The log's operating scale and angle table, made once for the tens of models made of it.
    const auto shared_tables = SteadyStateModel::hold_shared_tables(data);

    // No fit keeps its residual: each is recomputed where it is needed (residual_of), so that a long
    // log's diagnosis holds no row-sized array but the data while it searches.
    FitOptions without_residual = options.fit;
    without_residual.keep_residual = false;
    Baseline baseline = fit_baseline(data, spec, without_residual);
    LibraryScreen screen = screen_library(data, spec);
    out.not_tried = std::move(screen.not_tried);
    out.candidates = fit_candidates(data, spec, baseline.model, screen.library, without_residual);

    const Measurement design = search_design(data, options.fit);
    const SetSearch search = search_effect_sets(data, design, spec, baseline.model, screen.library, out.candidates, options);
    out.pruned = search.pruned;
    out.unpredictive = search.unpredictive;
    out.noise = measure_noise(data, search, out.candidates);

    // Held for the whole diagnosis: one double a row, against the 800 bytes a row the rest takes.
    const ShaftAngle shaft = shaft_angle(data, options.pole_pairs);
    ModelCheck check = check_model(data, spec, baseline, out.noise, options, shaft);
    const auto proposals = experiment_proposals(data, check.segments);
    score_candidates(out.candidates, data, design, proposals, baseline.model, out.noise, check.folds, check.lack_of_fit);
    PathTrace trace = trace_path(data, search, baseline.model, check.lack_of_fit, out.noise, options.floor_tolerance, shaft);
    Recommendation r = recommend(spec, search, trace, check.lack_of_fit, design, proposals);
    // A harmonic that no law of the library makes, at any size, is missing physics however small
    // against the floor's tolerance, which only excuses the laws' own errors (docs/diagnosis.md, section 3).
    {
        const std::size_t judged = r.missing_effect_found && r.tie.empty() ? r.step : 0;
        out.outside_harmonics = harmonics_outside_library(trace.left[judged], trace.path[judged].fit.spec, out.noise);
        if (!out.outside_harmonics.empty() && r.tie.empty()) {
            if (r.missing_effect_found) r.incomplete = true;
            else r.not_in_library = true;
        }
    }

    out.model = std::move(baseline.model);
    out.build_up = std::move(baseline.build_up);
    out.mean_equations = 2 * static_cast<int>(segment_ranges(data).size());
    out.lack_of_fit = std::move(check.lack_of_fit);
    out.model_loso_rms = check.loso_rms;
    out.base_problems = std::move(check.base_problems);
    out.base_plausible = out.base_problems.empty();
    out.segments = std::move(check.segments);
    out.apparent_names = std::move(check.apparent_names);
    out.drifts = std::move(check.drifts);
    out.path = std::move(trace.path);
    out.recommended = std::move(r.recommended);
    out.missing_effect_found = r.missing_effect_found;
    out.winner = std::move(r.winner);
    out.after_winner = std::move(r.after_winner);
    out.tie = std::move(r.tie);
    out.tie_experiments = std::move(r.tie_experiments);
    out.not_in_library = r.not_in_library;
    out.incomplete = r.incomplete;
    out.recommended_step = r.step;
    const PathStep& last = out.path[r.step];
    const ModelFit& recommended = out.recommended_fit();
    out.law_error_beyond_noise = &recommended == &last.fit && last.at_noise_floor && last.structure >= options.floor_tolerance;
    out.detection_limits = detection_limits(design, data.size(), recommended, screen.library, out.noise);
    for (const auto& h : trace.left[r.step].mechanical_harmonics)
        if (h.significant) out.mechanical_left.push_back(h);
    out.interval_caveats = interval_caveats(data, out, options.fit);
    out.law_stand_ins = law_stand_ins(data, out);
    if (options.timing.control_period > 0.0)
        out.sample_and_hold = SampleAndHold{options.timing, sample_and_hold_bias(data, out.recommended_fit().values.head<4>(), options.timing)};
    out.shared_noise = shared_noise_bias(data, out.recommended_fit());
    out.findings = findings_of(out, trace.left[r.step], options.floor_tolerance);
    return out;
}

}  // namespace mhb::pmsm
