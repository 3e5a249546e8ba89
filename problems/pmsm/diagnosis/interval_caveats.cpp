#include "problems/pmsm/diagnosis/interval_caveats.hpp"

#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace mhb::pmsm {
namespace {

constexpr std::array<const char*, 4> base_names{"Rs", "Ld", "Lq", "psi_f"};

// The path step that added `effect` with fewer terms and is still in the recommended set, or null.
const PathStep* reduced_step_of(const Diagnosis& d, const EffectTerm& term) {
    const PathStep* found = nullptr;
    for (std::size_t k = 1; k <= d.recommended_step && k < d.path.size(); ++k) {
        const PathStep& step = d.path[k];
        if (step.effect != term.name) continue;
        found = step.kind == StepKind::Added && step.whole_law_base.size() == 4 ? &step : nullptr;
    }
    return found;
}

}  // namespace

std::vector<IntervalCaveat> interval_caveats(const Measurement& data, const Diagnosis& d, const FitOptions& options) {
    std::vector<IntervalCaveat> out;
    const bool from_path = &d.recommended_fit() != &d.model;
    const ModelFit& recommended = d.recommended_fit();
    for (auto& bias : recommended.unseen_biases()) out.push_back({std::move(bias.text), bias.base});
    if (!from_path) return out;

    std::optional<ModelFit> with_intervals;
    for (const auto& term : recommended.spec.effects) {
        const PathStep* step = reduced_step_of(d, term);
        if (!step) continue;
        if (!with_intervals) {
            FitOptions polish = options;
            polish.intervals = true;
            polish.keep_residual = false;
            with_intervals = polish_model(data, recommended.spec, recommended.values, polish);
        }
        // The held terms' pull on a base parameter, measured as what the whole law gives at the step
        // that reduced it, against the interval the reduced law's parameter gets.
        IntervalCaveat caveat;
        std::vector<std::string> shifts, names;
        for (std::size_t j = 0; j < 4; ++j) {
            const auto k = static_cast<Eigen::Index>(j);
            const double reduced = step->fit.values[k], whole = step->whole_law_base[k];
            const double half_width = 0.5 * (with_intervals->upper[k] - with_intervals->lower[k]);
            if (!std::isfinite(half_width) || !(std::abs(whole - reduced) > half_width)) continue;
            caveat.base[j] = true;
            names.emplace_back(base_names[j]);
            shifts.push_back(fmt::format("{} reads {:.5g} against {:.5g} ({:+.1f} %)", base_names[j], whole, reduced, 100.0 * (whole / reduced - 1.0)));
        }
        if (names.empty()) continue;
        std::vector<std::string> held;
        for (const auto& [name, value] : term.fixed) held.push_back(fmt::format("{} = {:g}", name, value));
        caveat.reason = fmt::format("{} holds {} at their defaults, a choice this log cannot check (above); with the whole law {}: the "
                                    "interval{} of {} hold{} only if those terms are absent",
                                    term.name, fmt::join(held, ", "), fmt::join(shifts, ", "),
                                    names.size() == 1 ? "" : "s", fmt::join(names, ", "), names.size() == 1 ? "s" : "");
        out.push_back(std::move(caveat));
    }
    return out;
}

}  // namespace mhb::pmsm
