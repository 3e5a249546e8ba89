#include "problems/pmsm/diagnosis/findings.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "problems/pmsm/diagnosis/model_checks.hpp"
#include "problems/pmsm/diagnosis/verdict.hpp"

namespace mhb::pmsm {
namespace {

// What became of the other effect that a partial candidate says is missing. The sentence may say the
// search added it only when the recommended model holds an effect besides this one that the model
// diagnosed lacked: on a tie the search stops before adding anything, and the recommendation is then
// the model itself, so "added it" would contradict the recommended path.
std::string other_missing_effect(const Diagnosis& d, const std::string& partial) {
    for (const auto& e : d.recommended.effects)
        if (e.name != partial && !d.model.spec.contains(e.name)) return ", and the search over sets of effects added it";
    if (!d.tie.empty()) return "; which one, the data cannot yet say (the near tie below)";
    return "";
}

std::string percent(double relative) { return fmt::format("{:+.1f} %", 100.0 * relative); }

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

const char* unit_of(const std::string& variable) {
    if (variable.rfind("temp", 0) == 0) return "K";
    if (variable.find("omega") != std::string::npos) return "rad/s";
    return "A";
}

// The fitted effect parameters from index `from` on; the held ones are in the model's name.
std::string effect_values(const ModelFit& fit, Eigen::Index from) {
    std::string values;
    for (Eigen::Index j = from; j < fit.values.size(); ++j)
        if (fit.free[static_cast<std::size_t>(j)])
            values += fmt::format("{}{} = {:.4g}{}{}", values.empty() ? "" : ", ", fit.names[static_cast<std::size_t>(j)], fit.values[j],
                              fit.units[static_cast<std::size_t>(j)].empty() ? "" : " ", fit.units[static_cast<std::size_t>(j)]);
    return values;
}

bool has_column(const Diagnosis& d, const char* column) { return std::find(d.columns.begin(), d.columns.end(), column) != d.columns.end(); }

const Candidate* candidate_of(const Diagnosis& d, const std::string& effect) {
    const Candidate* found = nullptr;
    for (const auto& c : d.candidates)
        if (c.effect == effect) found = &c;
    return found;
}

// "harmonic 2 of the electrical angle (110 mV on u_d, 422 mV on u_q, noise 31 mV)", and so on.
std::string outside_harmonics_text(const Diagnosis& d) {
    std::vector<std::string> parts;
    for (const auto& h : d.outside_harmonics)
        parts.push_back(fmt::format("harmonic {} of the electrical angle ({:.3g} mV on u_d, {:.3g} mV on u_q, noise {:.2g} mV{})", h.order,
                                    1e3 * h.amplitude[0], 1e3 * h.amplitude[1], 1e3 * h.standard_error,
                                    // In the rotor frame a stator-frame negative sequence at the fundamental turns at 2 theta.
                                    h.order == 2 ? "; a negative-sequence fundamental: phase current sensors of unequal gain, or phases of "
                                                   "unequal impedance"
                                                 : ""));
    return join(parts);
}

// The model's residual against the noise, and what the design can determine at all.
void model_findings(const Diagnosis& d, std::vector<std::string>& f) {
    const auto& m = d.model;
    f.push_back(fmt::format("{} fits with a residual of {:.4g} V rms (u_d {:.4g} V, u_q {:.4g} V); the noise alone is {:.3g} V on u_d "
                            "and {:.3g} V on u_q (measured on {}).",
                            m.spec.text(), m.rms.total, m.rms.d, m.rms.q, d.noise.sigma[0], d.noise.sigma[1], d.noise.model));
    if (d.build_up.size() > 1)
        f.push_back(fmt::format("Before the effects (base model) the residual was {:.4g} V rms; with them it is {:.4g} V ({}).",
                                d.build_up.front().rms.total, m.rms.total, percent(m.rms.total / d.build_up.front().rms.total - 1.0)));
    const int unknowns = static_cast<int>(m.free_count());
    if (!has_column(d, "segment"))
        f.push_back("The data have no segment column, so the operating points are unknown: leave-one-segment-out prediction and the "
                    "segment-mean test are not available, and identifiability is judged on the raw samples, where noise can make an effect "
                    "look identifiable. Add a segment column (docs/data-format.md).");
    else if (d.mean_equations <= unknowns)
        f.push_back(fmt::format(
            "The {} operating points give {} segment-mean equations for the {} free parameters of {}: any effect without an angle or "
            "temperature signature is absorbed into these parameters without leaving a residual, and cannot be checked on this data.",
            d.mean_equations / 2, d.mean_equations, unknowns, m.spec.text()));
    for (const auto& p : d.base_problems) f.push_back("The fitted model is physically impossible: " + p + ". Something is missing or the design cannot determine it.");
}

// What a step at the noise floor still leaves, when the segment-mean or harmonic tests see it: the
// law's own error within its stated accuracy, or the steady-state model's own error below the
// tolerance. Empty when nothing significant is left.
std::string structure_at_floor(const PathStep& last, double floor_tolerance) {
    if (last.signature.empty()) return {};
    if (last.structure >= floor_tolerance)
        return fmt::format("Some structure remains ({}), with {:.2f} of the noise power: more than the tolerance of {:.2f}, within what "
                           "the stated accuracy of the law of {} allows on this log ({:.2f}). It is that law's own error; a larger one "
                           "would mean another effect. The intervals count only the noise, not that error: they are not valid.",
                           last.signature, last.structure, floor_tolerance, last.allowance.source, floor_tolerance + last.allowance.power);
    return fmt::format("Some structure remains ({}), with {:.2f} of the noise power: below the tolerance of {:.2f}. It is the size of "
                       "the steady-state model's own error on effects that make the currents ripple; a larger one would mean "
                       "another effect.",
                       last.signature, last.structure, floor_tolerance);
}

// The effects the search added: one, or a set step by step; what structure they leave.
void found_findings(const Diagnosis& d, double floor_tolerance, std::vector<std::string>& f) {
    const auto& m = d.model;
    const PathStep& last = d.path[d.recommended_step];
    std::vector<std::string> added;
    for (const auto& e : last.fit.spec.effects)
        if (!m.spec.contains(e.name)) added.push_back(e.name);
    const double floor = std::sqrt(d.noise.sigma.squaredNorm() / 2.0);
    if (added.size() == 1) {
        const Candidate* w = candidate_of(d, added.front());
        const Candidate* next = nullptr;
        for (const auto& c : d.candidates)
            if (&c != w && !next) next = &c;
        // The table of single additions divides its evidence by the overdispersion of the segment
        // means; the search does not, and its evidence is what added the effect: quoting only the
        // table's would give a positive dBIC as the reason for an effect the search found.
        const std::string evidence =
            w && d.noise.dispersion > 1.0
                ? fmt::format("{:.1f} in the search over sets ({:.1f} in the table above, which divides the evidence by the overdispersion "
                              "of the segment means, {:.3g}){}",
                              last.delta_bic, w->delta_bic, d.noise.dispersion,
                              next ? fmt::format("; the next best there ({}) {:.1f}", next->effect, next->delta_bic) : std::string())
                : fmt::format("{:.1f}{}", w ? w->delta_bic : last.delta_bic,
                              next ? fmt::format(", the next best ({}) {:.1f}", next->effect, next->delta_bic) : std::string());
        f.push_back(fmt::format("Missing effect: {} (its fit: {}). Adding it lowers the residual to {:.4g} V rms; evidence dBIC = {}.",
                                added.front(), effect_values(last.fit, m.values.size()), last.fit.rms.total, evidence));
    } else {
        std::string steps;
        for (std::size_t k = 1; k <= d.recommended_step; ++k)
            steps += fmt::format("{} {} {:.4g} V (dBIC {:.1f})", k == 1 ? "" : ",", d.path[k].change(), d.path[k].fit.rms.total, d.path[k].delta_bic);
        f.push_back(fmt::format("Missing effects: {} together (recommended model {}; their fit: {}). The residual falls from {:.4g} V rms "
                                "step by step:{}, {} the noise floor of {:.3g} V.",
                                join(added), last.fit.spec.text(), effect_values(last.fit, m.values.size()), m.rms.total, steps,
                                d.incomplete ? "towards" : "to", floor));
    }
    for (std::size_t k = 1; k <= d.recommended_step; ++k)
        if (!d.path[k].held_at_material.empty()) f.push_back("Held at its material value: " + d.path[k].held_at_material + ".");
    for (std::size_t k = 1; k <= d.recommended_step; ++k)
        if (!d.path[k].reduced_law.empty())
            f.push_back("Only the terms of its law this log pins: " + d.path[k].reduced_law +
                        ". More operating points (other currents and speeds) would show whether the other terms are there.");
    if (d.incomplete && last.at_noise_floor && !d.outside_harmonics.empty())
        f.push_back(fmt::format("Something else is missing too: what {} leaves is within the noise floor's tolerance, but it holds {}, an order "
                                "that no library law makes at any size. Model incomplete: its intervals are not valid (they take that structure "
                                "for noise), and its values hold only as far as the structure does not bias them.",
                                last.fit.spec.text(), outside_harmonics_text(d)));
    else if (d.incomplete)
        f.push_back(fmt::format("Something else is missing too: {} explains {:.0f} % of the excess residual, and what it leaves is above the "
                                "noise floor of {:.3g} V ({}). No library effect added to it explains that. Model incomplete: its intervals "
                                "are not valid (they take that structure for noise), and its values hold only as far as the structure does not bias them.",
                                last.fit.spec.text(), 100.0 * last.explained, floor,
                                last.signature.empty() ? std::string("structure beyond the noise") : last.signature));
    else if (const std::string rest = structure_at_floor(last, floor_tolerance); !rest.empty())
        f.push_back(rest);
    // What the search added after the recommended set and why it is not recommended with it.
    for (std::size_t k = d.recommended_step + 1; k < d.path.size(); ++k)
        f.push_back(fmt::format("The search then added {} ({:.4g} V rms, dBIC {:.1f}), but it takes implausible values ({}): it is not "
                                "recommended{}.",
                                d.path[k].effect, d.path[k].fit.rms.total, d.path[k].delta_bic, d.path[k].implausible.empty() ? "" : d.path[k].implausible.front(),
                                last.at_noise_floor ? fmt::format(", and {} reaches the noise floor without it", last.fit.spec.text()) : std::string()));
    if (d.winner) {
        const Candidate* w = candidate_of(d, *d.winner);
        if (w && w->identifiability == Identifiability::MostlyAbsorbed)
            f.push_back(fmt::format("Only {:.0f} % of {}'s signature is its own on this design; the rest shifts the base parameters (Rs {}, Ld {}, "
                                    "Lq {}, psi_f {} when it is added).",
                                    100.0 * w->unique_fraction, w->effect, percent(w->base_shift[0]), percent(w->base_shift[1]),
                                    percent(w->base_shift[2]), percent(w->base_shift[3])));
    }
}

// The answer when the search did not end on a plausible set at the noise floor.
void unresolved_findings(const Diagnosis& d, const LackOfFit& remaining, double floor_tolerance, std::vector<std::string>& f) {
    const PathStep& last = d.path.back();
    if (!d.tie.empty()) {
        const std::string after = d.path.size() > 1 ? "After " + last.fit.spec.text() + ", " : std::string();
        f.push_back(fmt::format("{}Near tie: {} explain the {}residual about equally well (dBIC within {:g}) or cannot be told apart on this "
                                "design; the data cannot say which is missing.",
                                after, join(d.tie), d.path.size() > 1 ? "remaining " : "", evidence::tie_margin));
        f.push_back(d.tie_experiments.empty() ? std::string("No single extra operating point separates them.")
                                              : "An experiment that would separate them: " + experiment_list(d.tie_experiments) + ".");
    } else if (d.not_in_library) {
        const bool named = d.not_in_library_by_harmonics();
        std::string text = named
                               ? fmt::format("What {} leaves is within the noise floor's tolerance, but it holds {}, an order that no library "
                                             "law makes at any size: the missing effect is not in the library.",
                                             d.model.spec.text(), outside_harmonics_text(d))
                               : std::string("No set of library effects reaches the noise floor with plausible values: the missing effect is "
                                             "not in the library.");
        if (d.path.size() > 1)
            text += fmt::format(" The best set the library offers, {}, explains {:.0f} % of the excess residual{}; its effects may be real or may "
                                "absorb part of the unknown one, so it is not recommended.",
                                last.fit.spec.text(), 100.0 * last.explained,
                                last.plausible ? std::string() : " but takes implausible values (" + last.implausible.front() + ")");
        // The harmonics named above are not named again.
        std::vector<int> orders;
        if (named)
            for (const auto& h : d.outside_harmonics) orders.push_back(h.order);
        const std::string rest = (remaining.significant ? remaining : d.lack_of_fit).signature_without(orders);
        if (!rest.empty())
            text += std::string(named ? " Besides it" : " The signature") + (d.path.size() > 1 && remaining.significant ? " of what it leaves" : "") +
                    ": " + rest + ".";
        f.push_back(text);
    } else if (!d.missing_effect_found) {
        const std::string none = d.unpredictive.empty()
                                     ? "No missing effect: the residual is at the noise floor and no library effect earns its parameters."
                                     : "No missing effect is recommended: the residual is at the noise floor, and the library effects with strong "
                                       "evidence do not carry over to operating points they were not fitted to (below).";
        f.push_back(d.lack_of_fit.means_available || has_column(d, "theta_e")
                        ? none + (d.detection_limits.empty() ? "" : " An effect smaller than this log's detection limit (listed) may still be present.")
                        : std::string("No missing effect can be seen on this data."));
        if (const std::string rest = structure_at_floor(d.path.front(), floor_tolerance); !rest.empty()) f.push_back(rest);
    }
}

// Harmonics at mechanical orders that the last set leaves: named with their order, size and phase,
// and what turns with the shaft to make them. No library effect has this signature. Below the noise
// floor's tolerance, where the verdict says the residual is at the floor (not "not in the
// library"), they are named as small.
void mechanical_findings(const Diagnosis& d, double floor_tolerance, std::vector<std::string>& f) {
    const bool at_floor = !d.not_in_library && !d.path.empty() && d.path[d.recommended_step].at_noise_floor;
    for (const auto& h : d.mechanical_left) {
        if (!h.significant) continue;
        const int axis = h.amplitude[1] >= h.amplitude[0] ? 1 : 0;
        const char* names[] = {"u_d", "u_q"};
        const std::string per_turn = h.order == 1 ? "once per turn" : fmt::format("{} times per turn", h.order);
        const std::string phase =
            h.phase ? fmt::format(", phase {:.2f} ± {:.2f} rad against the logged mechanical angle ({} = A cos({}theta_m + phase) turning forwards, of the other sign backwards)", (*h.phase)[axis],
                                  h.phase_standard_error[axis], names[axis], h.order == 1 ? "" : std::to_string(h.order) + " ")
                    : std::string("; its phase is per segment, since the mechanical angle is integrated from the speed and its zero in each "
                                  "segment is unknown (log theta_m for a phase)");
        const std::string causes = h.order == 1 ? "rotor eccentricity, a bent shaft or a load with a once-per-turn torque"
                                                : fmt::format("an eccentric or bent shaft's harmonics, or a coupling, gear or load with {} events "
                                                              "per turn", h.order);
        const std::string named = fmt::format(
            "harmonic at mechanical order {} ({}, {}/{} of the electrical frequency) {}: amplitude {:.3g} V on {} and {:.3g} V on {} "
            "(± {:.2g} V), on the {} segment(s) that turn the shaft through a whole period of it{}",
            h.order, per_turn, h.order, h.pole_pairs, at_floor ? "is significant in the residual" : "is left in the residual",
            h.amplitude[axis], names[axis], h.amplitude[1 - axis], names[1 - axis], h.amplitude_standard_error[axis], h.segments, phase);
        f.push_back(at_floor
                        ? fmt::format("A small {}. With the rest of the structure it holds less than {:.2f} of the noise power, so the verdict "
                                      "stands; if it grows, something turns with the shaft: {}.",
                                      named, floor_tolerance, causes)
                        : fmt::format("A {}. Something turns with the shaft: {}. No library effect has this signature.", named, causes));
    }
}

// What an unidentifiable candidate would need, and what it does to the base parameters meanwhile.
std::string hidden_effect_finding(const Candidate& c) {
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
                            largest->typical, moved.empty() ? std::string("the base parameters by less than 0.5 %") : moved, largest->rss_change);
        for (const auto& [name, value] : largest->impossible_from)
            text += fmt::format("; at {} = {:.3g} {} would reach zero", largest->parameter, value, name);
        text += ".";
    }
    return text;
}

// Effects this data cannot carry: unidentifiable, or not tried for a missing column; and drifts.
void data_findings(const Diagnosis& d, std::vector<std::string>& f) {
    std::vector<std::string> hidden;
    for (const auto& c : d.candidates)
        if (c.verdict == Verdict::NotIdentifiable) hidden.push_back(c.effect);
    if (!hidden.empty()) {
        f.push_back(fmt::format("Not identifiable from this data (absorbed by the model's parameters without trace): {}.", join(hidden)));
        for (const auto& c : d.candidates)
            if (c.verdict == Verdict::NotIdentifiable) f.push_back(hidden_effect_finding(c));
    }
    for (const auto& n : d.not_tried)
        f.push_back(fmt::format("{} was not tried: it needs the column {}, which the data lack (log it to check this effect).", n.effect, n.column));
    for (const auto& drift : d.drifts)
        if (!drift.variable.empty())
            f.push_back(fmt::format("The apparent {} drifts with {} across segments (r = {:.2f}, {:.3g} {} per {}).", drift.parameter, drift.variable,
                                    drift.correlation, drift.slope, d.model.units[static_cast<std::size_t>(d.model.index_of(drift.parameter))],
                                    unit_of(drift.variable)));
}

// The stated control period's sample and hold on the recommended model's base parameters.
std::string sample_and_hold_finding(const Diagnosis& d) {
    const ModelFit& recommended = d.recommended_fit();
    const SampleAndHold& held = *d.sample_and_hold;
    if (!held.bias.allFinite())
        return fmt::format("The stated control period ({}) is not corrected for: the recommended model's Rs, Ld or Lq is not positive.",
                           timing_text(held.timing));
    std::vector<std::string> corrected;
    for (Eigen::Index j = 0; j < 4; ++j)
        corrected.push_back(fmt::format("{} {:.6g}", recommended.names[static_cast<std::size_t>(j)], recommended.values[j] - held.bias[j]));
    return fmt::format("The stated control period ({}) samples the currents once a period and holds the voltage computed from them over "
                       "the next{}: it reads the continuous model's base parameters {} off the machine's; corrected for it they are {} "
                       "(`mhbench fit --control-period` gives the corrected intervals; docs/diagnosis.md).",
                       timing_text(held.timing), held.timing.carrier() ? ", switched by the carrier" : "",
                       fmt::join(shift_texts(held, recommended.names, recommended.values), ", "), fmt::join(corrected, ", "));
}

// The noise the current and the voltage share, on the recommended model's base parameters.
std::string shared_noise_finding(const Diagnosis& d) {
    const ModelFit& recommended = d.recommended_fit();
    const SharedNoise& shared = *d.shared_noise;
    const bool held = d.sample_and_hold && d.sample_and_hold->bias.allFinite();
    const std::vector<std::string> shifts = shared.shift_texts(recommended);
    std::vector<std::string> corrected;
    for (Eigen::Index j = 0; j < 4; ++j) {
        const double value = recommended.values[j] - shared.bias[j] - (held ? d.sample_and_hold->bias[j] : 0.0);
        corrected.push_back(fmt::format("{} {:.6g}", recommended.names[static_cast<std::size_t>(j)], value));
    }
    return fmt::format("The logged current and voltage share noise (a current loop answers the current sensors' noise within its control "
                       "period, and a noisy current enters R i, omega L i and the effects' laws): measured in {} steady window{}, it reads "
                       "the base parameters {} off the machine's; corrected for it{} they are {} (`mhbench fit` gives the corrected "
                       "intervals; docs/diagnosis.md).",
                       shared.windows, shared.windows == 1 ? "" : "s", fmt::join(shifts, ", "), held ? " and for the sample and hold" : "",
                       fmt::join(corrected, ", "));
}

}  // namespace

std::vector<std::string> findings_of(const Diagnosis& d, const LackOfFit& left_by_last_step, double floor_tolerance) {
    std::vector<std::string> f;
    model_findings(d, f);
    if (d.missing_effect_found && d.path.size() > 1) found_findings(d, floor_tolerance, f);
    for (const auto& c : d.candidates)
        if (c.verdict == Verdict::Partial)
            f.push_back(fmt::format("Alone, {} explains {:.0f} % of the excess residual (dBIC {:.1f}) but takes implausible values ({}): another effect "
                                    "is still missing{}.",
                                    c.effect, 100.0 * c.explained, c.delta_bic, c.implausible.front(), other_missing_effect(d, c.effect)));
    for (const auto& p : d.pruned) f.push_back(p + " was added on the way and pruned again: the other effects of the set explain it.");
    for (const auto& s : d.law_stand_ins)
        f.push_back(fmt::format("{} may stand in for the misfit of a law rather than be in the machine: adding it changed the modelled voltage by {:.4g} V "
                                "rms, no more than the stated accuracy of {} lets that law's own error change it ({:.4g} V rms). They differ where "
                                "the law's flux error is small against the effect's own voltage (at standstill or low speed for a turn of the "
                                "frame such as an encoder offset); docs/effects.md, \"The Baldor study\".",
                                s.effect, s.change_rms, s.law, s.allowance_rms));
    unresolved_findings(d, left_by_last_step, floor_tolerance, f);
    // Strong evidence that a leave-one-segment-out check turned down: the log's operating points do
    // not pin the effect's shape, which more of them would.
    const std::string after = d.path.empty() ? d.model.spec.text() : d.path.back().fit.spec.text();
    for (const auto& u : d.unpredictive)
        f.push_back(fmt::format("{} would explain {:.0f} % of what {} leaves (dBIC {:.1f} in the search over sets), but fitted without one operating "
                                "point it predicts that point better than {} in only {} of {}{}: the {} operating points do not pin its {} "
                                "parameters, so it is not added. More operating points (other currents and speeds) would decide.{}",
                                u.effect, 100.0 * u.explained, after, u.delta_bic, after,
                                u.held_out.better, u.held_out.segments, deciding_count(u.held_out), u.held_out.segments, u.added_parameters,
                                u.fewer_terms_withheld ? " Its law with fewer terms is not tried while a harmonic that no library law makes is "
                                                         "left: the best of its subsets could take that effect's segment means."
                                                       : ""));
    mechanical_findings(d, floor_tolerance, f);
    if (!d.model_intervals_valid())
        f.push_back(fmt::format("Model incomplete: the 95 % intervals of {} are not valid (they take what it misses for noise){}.",
                                d.model.spec.text(),
                                d.recommended_intervals_valid() && d.recommended.text() != d.model.spec.text()
                                    ? "; those of " + d.recommended.text() + " hold as far as this log can tell"
                                    : std::string()));
    for (const auto& caveat : d.interval_caveats) f.push_back("Beyond the intervals of " + d.recommended.text() + ": " + caveat.reason + ".");
    if (d.sample_and_hold) f.push_back(sample_and_hold_finding(d));
    if (d.shared_noise && d.shared_noise->relevant()) f.push_back(shared_noise_finding(d));
    data_findings(d, f);
    return f;
}

}  // namespace mhb::pmsm
