#include "problems/pmsm/report/diagnosis_report.hpp"

#include "problems/pmsm/diagnosis/noise.hpp"
#include "problems/pmsm/report/fit_report.hpp"

namespace mhb::pmsm {
namespace {

using json = nlohmann::ordered_json;

json experiments_json(const std::vector<Experiment>& experiments) {
    json out = json::array();
    for (const auto& e : experiments)
        out.push_back({{"experiment", e.name}, {"operating_point", e.description}, {"unique_fraction_after", e.unique_after}});
    return out;
}

json harmonic_json(const Harmonic& x) {
    return {{"order", x.order}, {"amplitude", {{"u_d", x.amplitude[0]}, {"u_q", x.amplitude[1]}}}, {"standard_error", x.standard_error},
            {"p_value", x.p_value}};
}

json lack_of_fit_json(const LackOfFit& l) {
    json out{{"significant", l.significant}, {"signature", l.signature}};
    if (l.means_available) out["segment_means"] = {{"statistic", l.statistic}, {"dof", l.dof}, {"p_value", l.p_value}};
    else out["segment_means"] = nullptr;
    json h = json::array();
    for (const auto& x : l.harmonics) h.push_back(harmonic_json(x));
    out["harmonics"] = h;
    if (!l.mechanical_angle.empty()) {
        out["mechanical_angle"] = l.mechanical_angle;
        json m = json::array();
        for (const auto& x : l.mechanical_harmonics) {
            auto axes = [](const Eigen::Vector2d& v) { return json{{"u_d", v[0]}, {"u_q", v[1]}}; };
            m.push_back({{"order", x.order},
                         {"electrical_order", static_cast<double>(x.order) / x.pole_pairs},
                         {"amplitude", axes(x.amplitude)},
                         {"amplitude_standard_error", axes(x.amplitude_standard_error)},
                         {"phase", x.phase ? axes(*x.phase) : json(nullptr)},
                         {"phase_standard_error", x.phase ? axes(x.phase_standard_error) : json(nullptr)},
                         {"standard_error", x.standard_error},
                         {"p_value", x.p_value},
                         {"significant", x.significant},
                         {"segments", x.segments}});
        }
        out["mechanical_harmonics"] = m;
    }
    return out;
}

}  // namespace

json diagnosis_json(const Diagnosis& d) {
    json out = fit_json(d.model);
    out["data"] = d.source;
    if (d.current_loop_bandwidth > 0.0) out["current_loop"] = {{"bandwidth", d.current_loop_bandwidth}, {"delay", d.current_loop_delay}};
    out["columns"] = d.columns;
    out["missing_effect_found"] = d.missing_effect_found;
    out["winner"] = d.winner ? json(*d.winner) : json(nullptr);
    out["tie"] = d.tie;
    out["tie_experiments"] = experiments_json(d.tie_experiments);
    out["not_in_library"] = d.not_in_library;
    json outside = json::array();
    for (const auto& x : d.outside_harmonics) outside.push_back(harmonic_json(x));
    out["outside_harmonics"] = outside;
    out["incomplete"] = d.incomplete;
    out["recommended_model"] = d.recommended.text();
    out["intervals_valid"] = d.model_intervals_valid();
    out["recommended_intervals_valid"] = d.recommended_intervals_valid();
    json caveats = json::array();
    for (const auto& c : d.interval_caveats) {
        json parameters = json::array();
        for (std::size_t j = 0; j < 4; ++j)
            if (c.base[j]) parameters.push_back(d.model.names[j]);
        caveats.push_back({{"reason", c.reason}, {"parameters", parameters}});
    }
    out["recommended_interval_caveats"] = caveats;
    if (d.sample_and_hold) out["sample_and_hold"] = sample_and_hold_json(d.recommended_fit(), *d.sample_and_hold);
    if (d.shared_noise)
        out["shared_noise"] = shared_noise_json(d.recommended_fit(), *d.shared_noise, d.sample_and_hold ? &*d.sample_and_hold : nullptr);
    json path = json::array();
    for (const auto& step : d.path) {
        path.push_back({{"model", step.fit.spec.text()},
                        {"added", step.change().empty() ? json(nullptr) : json(step.change())},
                        {"rms", step.fit.rms.total},
                        {"rms_axes", rms_json(step.fit.rms)},
                        {"dbic", step.delta_bic},
                        {"explained", step.explained},
                        {"plausible", step.plausible},
                        {"implausible", step.implausible},
                        {"at_noise_floor", step.at_noise_floor}});
        // Only where a law states an error: the structure it may leave, relative to the noise power.
        if (!step.allowance.source.empty()) path.back()["law_allowance"] = {{"law", step.allowance.source}, {"power", step.allowance.power}};
        if (!step.reduced_law.empty()) path.back()["reduced_law"] = step.reduced_law;
    }
    out["path"] = path;
    out["recommended_step"] = d.recommended_step;
    out["pruned"] = d.pruned;
    auto unpredictive = nlohmann::ordered_json::array();
    for (const auto& u : d.unpredictive)
        unpredictive.push_back({{"effect", u.effect}, {"dbic", u.delta_bic}, {"explained", u.explained}, {"added_parameters", u.added_parameters},
                                {"held_out_better", u.held_out.better}, {"held_out_segments", u.held_out.segments},
                                {"held_out_better_deciding", u.held_out.better_deciding}, {"held_out_deciding", u.held_out.deciding},
                                {"fewer_terms_withheld", u.fewer_terms_withheld}});
    out["unpredictive_additions"] = unpredictive;
    out["findings"] = d.findings;
    json limits = json::array();
    for (const auto& l : d.detection_limits)
        limits.push_back({{"effect", l.effect},
                          {"parameter", l.parameter},
                          {"limit", finite_or_null(l.limit)},
                          {"unit", l.unit},
                          {"typical", l.typical},
                          {"set_by", l.set_by() ? json(l.set_by()) : json(nullptr)}});
    out["detection_limits"] = limits;
    json stand_ins = json::array();
    for (const auto& s : d.law_stand_ins)
        stand_ins.push_back({{"effect", s.effect}, {"law", s.law}, {"change_rms", s.change_rms}, {"allowance_rms", s.allowance_rms}});
    out["law_stand_ins"] = stand_ins;
    json candidates = json::array();
    for (const auto& c : d.candidates) {
        json e;
        e["effect"] = c.effect;
        e["verdict"] = to_string(c.verdict);
        e["rms_after"] = rms_json(c.fit.rms);
        e["parameters"] = parameters_json(c.fit);
        e["plausible"] = c.plausible;
        e["implausible"] = c.implausible;
        e["added_parameters"] = c.added_parameters;
        e["likelihood_ratio"] = c.likelihood_ratio;
        e["delta_bic"] = c.delta_bic;
        e["explained"] = c.explained;
        e["loso_rms"] = c.loso_rms ? json(*c.loso_rms) : json(nullptr);
        e["loso_better_segments"] = c.held_out.segments > 0 ? json::array({c.held_out.better, c.held_out.segments}) : json(nullptr);
        e["loso_better_deciding"] = c.held_out.segments > 0 ? json::array({c.held_out.better_deciding, c.held_out.deciding}) : json(nullptr);
        e["predicts_held_out"] = c.predicts_held_out;
        e["identifiability"] = to_string(c.identifiability);
        e["unique_fraction"] = finite_or_null(c.unique_fraction);
        e["experiments"] = experiments_json(c.experiments);
        json absorption = json::array();
        for (const auto& a : c.absorption) {
            json shift, zero = json::object();
            for (int j = 0; j < 4; ++j) shift[base_parameter_names[static_cast<std::size_t>(j)]] = a.base_shift[j];
            for (const auto& [name, value] : a.impossible_from) zero[name] = value;
            absorption.push_back({{"parameter", a.parameter}, {"typical", a.typical}, {"base_shift", shift}, {"rss_change", a.rss_change},
                                  {"zero_at", zero}});
        }
        e["absorption"] = absorption;
        json shift;
        for (int j = 0; j < 4; ++j) shift[base_parameter_names[static_cast<std::size_t>(j)]] = c.base_shift[j];
        e["base_shift"] = shift;
        candidates.push_back(e);
    }
    out["candidates"] = candidates;
    json not_tried = json::array();
    for (const auto& n : d.not_tried) not_tried.push_back({{"effect", n.effect}, {"needs", n.column}});
    out["not_tried"] = not_tried;
    out["noise"] = {{"measured_on", d.noise.model},
                    {"sigma", {{"u_d", d.noise.sigma[0]}, {"u_q", d.noise.sigma[1]}}},
                    {"long_run_sigma", {{"u_d", d.noise.long_run[0]}, {"u_q", d.noise.long_run[1]}}},
                    {"effective_samples", d.noise.effective_samples},
                    {"dispersion", d.noise.dispersion},
                    {"from_data", {{"method", window_noise_method(d.noise.window)},
                                   {"sigma", {{"u_d", d.noise.window.sigma[0]}, {"u_q", d.noise.window.sigma[1]}}},
                                   {"correlation", {{"u_d", d.noise.window.correlation[0]}, {"u_q", d.noise.window.correlation[1]}}},
                                   {"degrees_of_freedom", d.noise.window.dof},
                                   {"used_for_evidence", {{"u_d", d.noise.from_windows[0]}, {"u_q", d.noise.from_windows[1]}}}}}};
    out["lack_of_fit"] = lack_of_fit_json(d.lack_of_fit);
    if (d.after_winner) out["lack_of_fit_after_winner"] = lack_of_fit_json(*d.after_winner);
    out["loso_rms"] = d.model_loso_rms ? json(*d.model_loso_rms) : json(nullptr);
    out["base_plausible"] = d.base_plausible;
    out["base_problems"] = d.base_problems;
    json steps = json::array();
    for (const auto& s : d.build_up) steps.push_back({{"model", s.spec.text()}, {"rms", rms_json(s.rms)}});
    out["steps"] = steps;
    json segments = json::array();
    for (const auto& s : d.segments) {
        json e{{"label", s.label}, {"rows", s.rows}, {"omega_e", s.omega}, {"i_d", s.i_d}, {"i_q", s.i_q}};
        if (s.temp_winding) e["temp_winding"] = *s.temp_winding;
        if (s.temp_magnet) e["temp_magnet"] = *s.temp_magnet;
        e["rms"] = rms_json(s.model.rms);
        e["rms_before"] = rms_json(s.before.rms);
        e["mean_residual"] = {{"u_d", s.model.mean[0]}, {"u_q", s.model.mean[1]}};
        e["mean_standard_error"] = {{"u_d", s.mean_standard_error[0]}, {"u_q", s.mean_standard_error[1]}};
        json apparent;
        for (std::size_t p = 0; p < d.apparent_names.size(); ++p) {
            const auto& a = s.apparent[p];
            apparent[d.apparent_names[p]] = a.determined ? json{{"value", a.value}, {"standard_error", a.standard_error}} : json(nullptr);
        }
        e["apparent"] = apparent;
        segments.push_back(e);
    }
    out["segments"] = segments;
    json drifts = json::array();
    for (const auto& x : d.drifts)
        drifts.push_back({{"parameter", x.parameter}, {"with", x.variable.empty() ? json(nullptr) : json(x.variable)}, {"correlation", x.correlation}, {"slope", x.slope}});
    out["drifts"] = drifts;
    return out;
}

}  // namespace mhb::pmsm
