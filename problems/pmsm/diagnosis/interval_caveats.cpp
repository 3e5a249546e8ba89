#include "problems/pmsm/diagnosis/interval_caveats.hpp"

#include <cmath>
#include <limits>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "problems/pmsm/diagnosis/model_checks.hpp"
#include "problems/pmsm/diagnosis/segments.hpp"
#include "problems/pmsm/model/steady_state_model.hpp"

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

// Where `fit`'s laws bend its flux linkage away from the line its L_d, L_q and psi_f draw from zero
// current (psi_f + L_d i_d, L_q i_q, with psi_f as each row's temperature makes it): the segment
// whose mean current is smallest, its mean |i| and the mean distance of the flux from that line
// there (Wb). A flux harmonic averages out over a segment; saturation does not.
struct NearestBend {
    std::string label;  // the segment's
    double current = 0.0, distance = 0.0;
};
NearestBend nearest_bend(const Measurement& data, const ModelFit& fit) {
    const auto model = make_model(fit.spec, data);
    const auto ranges = segment_ranges(data);
    std::vector<double> current(ranges.size(), 0.0), bend_d(ranges.size(), 0.0), bend_q(ranges.size(), 0.0);
    const double ld = fit.values[1], lq = fit.values[2];
    ModelState state;
    std::size_t range = 0;
    for (Eigen::Index b = 0; b < model->blocks(); ++b) {
        const Eigen::Index first = model->block_first(b), rows = model->block_size(b);
        if (state.size() != rows) state = model->make_state(rows);
        model->predict(fit.values.data(), state, first);
        for (Eigen::Index k = 0; k < rows; ++k) {
            const Eigen::Index row = first + k;
            while (row >= ranges[range].first + ranges[range].rows) ++range;
            current[range] += std::hypot(state.i_d[k], state.i_q[k]);
            bend_d[range] += state.psi_d[k] - state.psi_f[k] - ld * state.i_d[k];
            bend_q[range] += state.psi_q[k] - lq * state.i_q[k];
        }
    }
    NearestBend out;
    double smallest = std::numeric_limits<double>::infinity();
    for (std::size_t r = 0; r < ranges.size(); ++r) {
        const double rows = static_cast<double>(ranges[r].rows);
        if (current[r] / rows < smallest) {
            smallest = current[r] / rows;
            out = {data.has_segments() ? data.segment_labels[static_cast<std::size_t>(data.segment[ranges[r].first])] : std::string("all rows"),
                   smallest, std::hypot(bend_d[r], bend_q[r]) / rows};
        }
    }
    return out;
}

// The sign of omega i_q that every segment shows, among those whose speed and q current are both at
// least a twentieth of the log's largest (a point at standstill or without load shows neither); 0
// when they differ or fewer than two show one.
int one_power_flow(const std::vector<SegmentConditions>& segments) {
    double omega = 0.0, i_q = 0.0;
    for (const auto& s : segments) {
        omega = std::max(omega, std::abs(s.omega));
        i_q = std::max(i_q, std::abs(s.i_q));
    }
    int sign = 0, shown = 0;
    for (const auto& s : segments) {
        if (std::abs(s.omega) < omega / 20.0 || std::abs(s.i_q) < i_q / 20.0) continue;
        const int here = s.omega * s.i_q > 0.0 ? 1 : -1;
        if (shown++ > 0 && here != sign) return 0;
        sign = here;
    }
    return shown >= 2 ? sign : 0;
}

}  // namespace

std::vector<IntervalCaveat> interval_caveats(const Measurement& data, const Diagnosis& d, const FitOptions& options) {
    std::vector<IntervalCaveat> out;
    const bool from_path = &d.recommended_fit() != &d.model;
    const ModelFit& recommended = d.recommended_fit();
    for (auto& bias : recommended.unseen_biases()) out.push_back({std::move(bias.text), bias.base});

    // The recommended fit's intervals: the model diagnosed has them, a step of the search gets them
    // by one polish, made only when a caveat below needs them.
    std::optional<ModelFit> polished;
    const auto with_intervals = [&]() -> const ModelFit& {
        if (!from_path) return recommended;
        if (!polished) {
            FitOptions polish = options;
            polish.intervals = true;
            polish.keep_residual = false;
            polished = polish_model(data, recommended.spec, recommended.values, polish);
        }
        return *polished;
    };

    // L_d, L_q and psi_f are the values at zero current. Where the laws bend the flux away from their
    // line by more than psi_f's interval already at the logged operating point nearest zero current,
    // the values below it are the laws' extrapolation, which no interval holds.
    if (!recommended.spec.effects.empty()) {
        const NearestBend bend = nearest_bend(data, recommended);
        // Laws that leave the flux alone leave it to rounding (no polish for them).
        const bool bent = bend.distance > 1e-6 * std::abs(recommended.values[3]);
        const double half_width = bent ? 0.5 * (with_intervals().upper[3] - with_intervals().lower[3]) : 0.0;
        if (bent && std::isfinite(half_width) && bend.distance > half_width) {
            out.push_back({fmt::format("its L_d, L_q and psi_f are the values at zero current, and already at the logged operating point "
                                       "nearest it ({}, mean |i| {:.3g} A) its flux linkage lies {:.3g} mWb off the line they draw, more than "
                                       "psi_f's interval (+-{:.3g} mWb): below the logged currents they are its laws' extrapolation, which "
                                       "the intervals of Ld, Lq and psi_f take as exact",
                                       bend.label, bend.current, 1e3 * bend.distance, 1e3 * half_width),
                           {false, true, true, true}});
        }
    }
    // A flux law known only to its stated accuracy leaves a misfit omega times a flux error; where
    // q current changes sign with the speed on every logged point (all motor, or all generate), R_s i
    // changes with it from point to point and R_s takes part of that misfit. Measured on the Baldor
    // map (docs/effects.md, "The Baldor study"): R_s 8 % off with every point motoring, within 1.5 %
    // in ten of twelve designs with the negative direction generating.
    if (const auto [law, accuracy] = stated_law_accuracy(recommended.spec); !law.empty()) {
        if (const int flow = one_power_flow(d.segments); flow != 0)
            out.push_back({fmt::format("every logged operating point {} (its q current {} its speed), so R_s i and omega times the {} law's "
                                       "misfit (stated: {:g} % of the flux linkage) change together from point to point, and R_s takes part "
                                       "of that misfit; points at the same currents with the opposite flow of power separate them (on a "
                                       "measured map: R_s 8 % off with motoring points only, within 1.5 % with generating ones, docs/effects.md)",
                                       flow > 0 ? "motors" : "generates", flow > 0 ? "with" : "against", law, 100.0 * accuracy),
                           {true, false, false, false}});
    }
    if (!from_path) return out;

    for (const auto& term : recommended.spec.effects) {
        const PathStep* step = reduced_step_of(d, term);
        if (!step) continue;
        // The held terms' pull on a base parameter, measured as what the whole law gives at the step
        // that reduced it, against the interval the reduced law's parameter gets.
        IntervalCaveat caveat;
        std::vector<std::string> shifts, names;
        for (std::size_t j = 0; j < 4; ++j) {
            const auto k = static_cast<Eigen::Index>(j);
            const double reduced = step->fit.values[k], whole = step->whole_law_base[k];
            const double half_width = 0.5 * (with_intervals().upper[k] - with_intervals().lower[k]);
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
