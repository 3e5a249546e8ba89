#pragma once
// Diagnosing a model against a measurement (docs/effects.md, "How diagnose decides"): where the
// model fails, which library effect is most likely missing, and how sure that is.
//
//  - The noise: the long-run variance of each axis' residual within segments (AR(1)-prewhitened
//    Newey-West, linear_fit.hpp), measured on the best-fitting model tried, so that hundreds of
//    serially correlated samples per operating point count as what they are worth.
//  - Each library effect whose columns are present is added to the model and fitted. Its evidence:
//    the fall in residual; a likelihood ratio scaled by that long-run variance, and from it a BIC with
//    the effective sample count; leave-one-segment-out prediction error; plausibility of the refitted
//    values (inside the effect's declared range, base parameters physically possible).
//  - Identifiability is judged on the design, not the noise: the data with each segment's currents and
//    speed at their means (the logged angle and the temperature trend kept). An effect whose Jacobian
//    columns lie in the span of the model's own there is absorbed without trace; hypothetical extra
//    operating points show which experiment would reveal it.
#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "problems/pmsm/fit/model_fit.hpp"
#include "problems/pmsm/diagnosis/shared_noise.hpp"
#include "problems/pmsm/model/sample_and_hold.hpp"

namespace mhb::pmsm {

struct DiagnosisOptions {
    FitOptions fit;
    bool leave_one_out = true;  // leave-one-segment-out prediction (needs 3 segments or more)
    int max_effects = 6;        // effects the search over sets may add to the model
    // Whether the search may add a law of several terms (Effect::law_terms) with fewer of them when
    // the whole law does not predict held-out segments (docs/diagnosis.md, section 1).
    bool reduced_laws = true;
    // A set reaches the noise floor when its residual has no significant structure, or structure
    // with less than this fraction of the noise power (the steady-state model's own error on effects
    // that make the currents ripple, docs/effects.md).
    double floor_tolerance = 0.25;
    // The machine's pole pairs (0: not known), which tell a harmonic at a mechanical order k/p of the
    // electrical frequency from an electrical one (docs/diagnosis.md, "Harmonics at mechanical orders").
    int pole_pairs = 0;
    // The drive's control period (0: not known), and its carrier: the recommended model's base
    // parameters are also given corrected for its sample and hold (model/sample_and_hold.hpp).
    DriveTiming timing;
};

// The noise of the data (noise.hpp, window_noise): per axis the standard deviation of the diagnosed
// model's residual within segments less each segment's trend and what is locked to the angle, the
// lag-one correlation of what is left, the degrees of freedom, and the angle the bins were had
// from (empty: no angle, the trend alone).
struct WindowNoise {
    Eigen::Vector2d sigma{0.0, 0.0};
    Eigen::Vector2d correlation{0.0, 0.0};
    double dof = 0.0;
    std::string angle;
};

struct NoiseEstimate {
    std::string model;                  // the fit it was measured on
    Eigen::Vector2d sigma{0.0, 0.0};    // within-segment residual standard deviation per axis (V)
    Eigen::Vector2d long_run{0.0, 0.0}; // long-run standard deviation per axis (V): sigma of a mean times sqrt(n)
    double effective_samples = 0.0;     // both axes: sum of n sigma^2 / long_run^2
    double dispersion = 1.0;            // lack of fit of that model's segment means per degree of freedom, at least 1
    // Measured from the data, not from the residual's level (noise.hpp, window_noise).
    WindowNoise window;
    // Per axis: the evidence is measured in the window noise instead of the residual's, because the
    // residual holds structure within segments (noise.hpp, noise_of_best).
    std::array<bool, 2> from_windows{false, false};
};

// A hypothetical operating point added to the design, and what it would do for an effect.
struct Experiment {
    std::string name;         // "the other direction"
    std::string description;  // the operating point, in numbers
    double unique_after = 0.0;  // unique fraction of the effect's signature with this point added
};

// The smallest size of an effect's size parameter that a log would reveal (detection_limits.hpp).
struct DetectionLimit {
    std::string effect, parameter, unit;  // parameter as "<effect>.<name>"
    double limit = 0.0;                   // infinite: no size of it shows in this log
    double typical = 0.0;                 // the parameter's declared typical value
    // Which of the search's tests asks more of a size: the evidence (its likelihood ratio scatters
    // about its mean, so at the limit about half of such logs pass), or the voltage it must change
    // (relevant_voltage; a change fitted more precisely than that, so the step from refused to found
    // may be sharper). Rates measured at the limits: docs/diagnosis.md, section 5.
    bool set_by_relevant_size = false;
    // Its name in the outputs: "evidence" or "relevant size"; null where no size shows.
    const char* set_by() const { return !std::isfinite(limit) ? nullptr : set_by_relevant_size ? "relevant size" : "evidence"; }
};

enum class Identifiability { Identifiable, MostlyAbsorbed, NotIdentifiable };
const char* to_string(Identifiability level);

// What an unidentifiable effect parameter does to the base parameters: pinned at a typical value
// (its declared default, or 1 % of its range when that is zero) the base parameters shift while the
// residual stays put; extrapolated, some base parameter reaches zero.
struct Absorption {
    std::string parameter;                 // effect.parameter
    double typical = 0.0;
    Eigen::Vector4d base_shift;            // relative change of Rs, Ld, Lq, psi_f from the model's fit
    double rss_change = 0.0;               // in long-run noise variances
    std::vector<std::pair<std::string, double>> impossible_from;  // base parameter, effect value where it reaches zero (inside the range)
};

// Partial: strong evidence and good prediction, but the values it takes alone are implausible: it
// explains part of the excess residual while another effect is still missing (it biases the fit).
// How many left-out segments a candidate predicts better than the model it extends, and the one rule
// that reads a verdict from them (docs/diagnosis.md, section 1), for the single additions and the
// search over sets alike.
struct HeldOutVote {
    int better = 0;    // segments it predicts better than the model does
    int segments = 0;  // segments held out (0: untested)
    // The segments whose held-out squared error the candidate changes by at least
    // evidence::deciding_change (1 %) of the model's, and how many of them it predicts better.
    // Elsewhere the two predict alike and the noise decides which is "better": a coin toss.
    int better_deciding = 0;
    int deciding = 0;

    // Half of the held-out segments, not the pooled error: one operating point at the edge of the
    // range, where a polynomial extrapolates, must not outvote all the others.
    bool every_segment() const { return 2 * better >= segments; }
    // The same share of the segments that decide; every_segment() when none does.
    bool where_deciding() const { return deciding == 0 ? every_segment() : 2 * better_deciding >= deciding; }
    // The deciding segments vote, except while the residual of the model being extended holds a
    // harmonic no library law makes (`outside_harmonic()`, asked only where the two votes differ):
    // then something outside the library is there, and its segment means are what a law of several
    // terms can take and predict, so every segment votes.
    template <class OutsideHarmonic>
    bool passes(OutsideHarmonic&& outside_harmonic) const {
        if (every_segment() == where_deciding()) return every_segment();
        return outside_harmonic() ? every_segment() : where_deciding();
    }
};

// " (4 of the 6 it changes by 1 % or more)" after "4 of 9": the count of the segments that
// decide, when some but not all of the segments do; empty otherwise.
std::string deciding_count(const HeldOutVote& vote);
// "4 of 9 left-out segments (4 of the 6 it changes by 1 % or more)".
inline std::string held_out_count(const HeldOutVote& vote) {
    return std::to_string(vote.better) + " of " + std::to_string(vote.segments) + " left-out segments" + deciding_count(vote);
}

enum class Verdict { Supported, Partial, Weak, NotSupported, Implausible, NotIdentifiable };
const char* to_string(Verdict verdict);

struct Candidate {
    std::string effect;
    ModelFit fit;                         // the model with this effect added
    int added_parameters = 0;             // free parameters the effect adds
    double likelihood_ratio = 0.0;        // sum over axes of (RSS_model - RSS_candidate) / long-run variance
    double delta_bic = 0.0;               // -likelihood_ratio + added_parameters ln(effective samples)
    std::optional<double> loso_rms;       // leave-one-segment-out prediction error (V)
    HeldOutVote held_out;                 // held-out segments predicted better than by the model
    bool predicts_held_out = true;        // by held_out.passes (none tested counts as predicting)
    bool plausible = true;
    std::vector<std::string> implausible;  // why not
    Identifiability identifiability = Identifiability::Identifiable;
    double unique_fraction = 1.0;         // of its most distinct parameter's signature on the design
    std::vector<Experiment> experiments;  // what would reveal it (when not clearly identifiable)
    std::vector<Absorption> absorption;   // when not identifiable
    Eigen::Vector4d base_shift;           // candidate's base parameters relative to the model's, minus 1
    double explained = 0.0;               // fraction of the model's excess residual (over the noise floor) it removes
    Verdict verdict = Verdict::NotSupported;
};

// What a step of the search over sets of effects did to the set before it.
enum class StepKind { Start, Added, Pruned };

// One step of the search over sets of effects: the model after adding `effect` to the previous step,
// or pruning it.
// The structure a set's effect laws may leave by their stated accuracy (Effect::law_accuracy).
struct LawAllowance {
    double power = 0.0;   // relative to the noise power, as LackOfFit::structure
    std::string source;   // "saturation (2 % of the flux linkage)", empty when none
};

struct PathStep {
    ModelFit fit;
    StepKind kind = StepKind::Start;      // Start: the model diagnosed
    std::string effect;                   // added or pruned (empty for the start)
    double delta_bic = 0.0;               // against the previous step (0 for the first)
    double explained = 0.0;               // fraction of the first step's excess residual removed so far
    bool plausible = true;                // the whole set's values (base and effects)
    std::vector<std::string> implausible;
    bool at_noise_floor = false;          // no lack of fit left, or less than the tolerance (DiagnosisOptions) and the laws' allowance
    double structure = 0.0;               // power of the significant structure left, relative to the noise's
    LawAllowance allowance;               // the structure the set's laws may leave by their stated accuracy
    std::string signature;                // of that structure, in words (empty when none is significant)
    // When the set's free fit left parameters at an end of their range and the fit with them held
    // at their material values (Effect::material_value) is as good as far as the data can tell: what
    // was held, in words; the step's fit is then the held one.
    std::string held_at_material;
    // When the effect added is its law with fewer terms, because the whole law does not predict
    // held-out segments: which terms, and why, in words (the step's fit is the reduced law's).
    std::string reduced_law;
    // Then the whole law's base parameters (RoundChoice::whole_law_base); empty otherwise.
    Eigen::VectorXd whole_law_base;

    // The change as the JSON and the text write it: "+effect", "-effect", empty for the start.
    std::string change() const {
        return kind == StepKind::Added ? "+" + effect : kind == StepKind::Pruned ? "-" + effect : std::string();
    }
};

// An effect of the recommended set, added after a law with a stated accuracy (Effect::law_accuracy),
// whose addition changed the modelled voltage by no more than that accuracy lets the law's own error
// change it: it may stand in for the law's misfit rather than be in the machine (on the Baldor map
// with generating operating points, an encoder offset the plant lacks; docs/effects.md, "The Baldor
// study").
struct LawStandIn {
    std::string effect;
    std::string law;             // LawAllowance::source: "saturation (2 % of the flux linkage)"
    double change_rms = 0.0;     // V: what adding it changed in the prediction, rms over rows and axes
    double allowance_rms = 0.0;  // V: the law's stated error, accuracy |u - R_s i|, rms over the same
};

struct NotTried {
    std::string effect;
    std::string column;  // the column the data lack
};

// An addition the search turned down only because it predicts too few left-out segments: strong
// evidence and a relevant share of the residual, but a shape that does not carry over to an
// operating point it was not fitted to (docs/diagnosis.md, section 1).
struct UnpredictiveAddition {
    std::string effect;
    double delta_bic = 0.0;     // the search's evidence for it
    double explained = 0.0;     // share of the excess residual of the set it would extend
    int added_parameters = 0;
    HeldOutVote held_out;       // against that set
    // A law of several terms whose fewer terms were not tried: a harmonic no library law makes was
    // left (choose_addition says why).
    bool fewer_terms_withheld = false;
};

struct Harmonic {
    int order = 0;                                  // of the electrical angle
    Eigen::Vector2d amplitude{0.0, 0.0};            // V, d and q
    double standard_error = 0.0;                    // V, of each amplitude component under noise alone
    double p_value = 1.0;
    bool significant = false;                       // beyond chance after Bonferroni over every harmonic tested
};

// A harmonic of the shaft's mechanical angle at an order that is not an electrical one: something
// that turns with the shaft (docs/diagnosis.md, "Harmonics at mechanical orders").
struct MechanicalHarmonic {
    int order = 0;                        // cycles per mechanical turn: order / pole_pairs of the electrical frequency
    int pole_pairs = 0;
    // V, d and q. With the logged angle the fitted amplitude; with the integrated one the rms over the
    // segments of each one's own amplitude, less the share the noise adds to it.
    Eigen::Vector2d amplitude{0.0, 0.0};
    Eigen::Vector2d amplitude_standard_error{0.0, 0.0};  // V, of the amplitude under noise alone
    // rad, u = s A cos(order theta_m + phase) against the logged theta_m's zero, s the sign of the
    // speed (an EMF turns sign with it); none when the angle is integrated (its zero differs per segment).
    std::optional<Eigen::Vector2d> phase;
    Eigen::Vector2d phase_standard_error{0.0, 0.0};      // rad, standard error / amplitude
    double standard_error = 0.0;          // V, of each amplitude component under noise alone (as Harmonic's)
    double p_value = 1.0;                 // of the more significant axis
    bool significant = false;             // beyond chance after Bonferroni over every harmonic tested
    int segments = 0;                     // segments that span a whole period of it: only those carry it
    Eigen::Index rows = 0;                // rows of those segments
};

struct LackOfFit {
    bool means_available = false;  // more segment-mean equations than free parameters
    double statistic = 0.0;        // sum over segments and axes of n_s mean^2 / long-run variance
    int dof = 0;
    double p_value = 1.0;
    std::vector<Harmonic> harmonics;  // when theta_e is logged
    std::vector<MechanicalHarmonic> mechanical_harmonics;  // the orders tested (a shaft angle, segments spanning a period)
    std::string mechanical_angle;     // how the shaft angle was had and which orders were tested, or why none (empty: not asked)
    bool significant = false;         // means or any harmonic beyond chance (p < 1e-3 after Bonferroni)
    double structure = 0.0;           // power of the significant structure (means, harmonics) relative to the noise's
    std::string signature;            // in words
    // The same, part by part, each with the order of the electrical angle it names (0: the segment
    // means, a mechanical order): a sentence that has named some harmonics lists the rest.
    std::vector<std::pair<int, std::string>> signature_parts;
    std::string signature_without(const std::vector<int>& orders) const;
};

struct ApparentValue {
    double value = 0.0;
    double standard_error = 0.0;
    bool determined = false;  // the segment moves the prediction with this parameter
};

struct SegmentConditions {
    std::string label;
    Eigen::Index first = 0, rows = 0;
    double omega = 0.0, i_d = 0.0, i_q = 0.0;             // means
    std::optional<double> temp_winding, temp_magnet, time;  // means
    SegmentResidual model, before;                        // the model's residual; the base model's when the model has effects
    Eigen::Vector2d mean_standard_error{0.0, 0.0};        // of the mean residual under noise alone
    std::vector<ApparentValue> apparent;                  // per free parameter of the model
};

// An apparent parameter that varies between segments beyond the noise, and the operating condition
// it follows (|r| >= 0.8), if one does.
struct Drift {
    std::string parameter, variable;  // "Rs", "temp_winding"; variable empty: follows none alone
    double correlation = 0.0;
    double slope = 0.0;               // parameter unit per unit of the variable
};

// A reason the 95 % intervals of some of the recommended model's base parameters may not hold the
// truth, beyond the noise they count (interval_caveats.hpp).
struct IntervalCaveat {
    std::string reason;            // a clause, as the findings write it after "Beyond the intervals of <model>: "
    std::array<bool, 4> base{};    // which of Rs, Ld, Lq, psi_f it concerns
};

struct Diagnosis {
    std::string source;
    Eigen::Index samples = 0;
    double current_loop_bandwidth = 0.0, current_loop_delay = 0.0;  // as the data state them (Measurement)
    std::vector<std::string> columns;  // optional columns present
    ModelFit model;
    std::vector<ModelFit> build_up;    // the model's prefixes: base, base+A, ... up to the model (one entry when it is base)
    NoiseEstimate noise;
    LackOfFit lack_of_fit;             // of the model
    std::optional<LackOfFit> after_winner;
    std::vector<SegmentConditions> segments;
    std::vector<std::string> apparent_names;
    std::vector<Drift> drifts;
    std::optional<double> model_loso_rms;
    int mean_equations = 0;            // 2 x segments
    bool base_plausible = true;
    std::vector<std::string> base_problems;
    std::vector<Candidate> candidates;  // ranked, best first
    std::vector<NotTried> not_tried;
    bool missing_effect_found = false;
    std::optional<std::string> winner;   // the first effect of the recommended set (unless a tie)
    std::vector<std::string> tie;        // effects the evidence cannot order (at the step where the search stopped)
    std::vector<Experiment> tie_experiments;
    bool not_in_library = false;
    // Significant, relevant harmonics of the electrical angle that the recommended model leaves at
    // orders no library law makes (library_orders.hpp): they make the verdict "not in the library",
    // or "something else is missing", even below the floor's tolerance.
    std::vector<Harmonic> outside_harmonics;
    // "Not in the library" said although the model diagnosed is at the noise floor: only its
    // outside harmonics say it (the findings name them, the report points there).
    bool not_in_library_by_harmonics() const {
        return not_in_library && !path.empty() && path.front().at_noise_floor && !outside_harmonics.empty();
    }
    // The recommended set explains most of the excess residual but not all: something else is
    // missing too, of the signature its residual shows (path.back().signature).
    bool incomplete = false;
    // The recommended set reaches the noise floor only by its laws' stated accuracy: what it leaves is
    // more than the noise's tolerance, the law's own error, which its intervals do not count.
    bool law_error_beyond_noise = false;
    // The search over sets of effects (forward selection with backward pruning, docs/effects.md):
    // the steps from the model diagnosed to the last set the evidence supports, the effects pruned
    // again because the others explain them, and the recommendation: the last set when it reaches
    // the noise floor with plausible values, the model diagnosed otherwise.
    std::vector<PathStep> path;
    // The step of the path the recommendation was judged on: the last, or the latest plausible set
    // before a run of implausible additions (docs/diagnosis.md, section 2).
    std::size_t recommended_step = 0;
    std::vector<std::string> pruned;
    // The additions the search's last round turned down only for their held-out prediction, when
    // that round added nothing: what a log with more operating points could decide.
    std::vector<UnpredictiveAddition> unpredictive;
    ModelSpec recommended;
    // For each library effect the recommended model leaves out, the smallest size of each of its
    // size parameters this log would reveal.
    std::vector<DetectionLimit> detection_limits;
    std::vector<std::string> findings;   // plain statements, most important first
    // The harmonics at mechanical orders that the last set of the path leaves beyond chance (the
    // findings name them).
    std::vector<MechanicalHarmonic> mechanical_left;
    // What the recommended model's intervals do not hold although it leaves only noise; the findings
    // state each one.
    std::vector<IntervalCaveat> interval_caveats;
    // The effects of the recommended set that may stand in for a law's misfit (law_stand_ins).
    std::vector<LawStandIn> law_stand_ins;
    // With DiagnosisOptions::control_period: what its sample and hold does to the recommended model's base parameters.
    std::optional<SampleAndHold> sample_and_hold;
    // What noise the current and the voltage share does to the recommended model's base parameters
    // (shared_noise.hpp); nothing when the data have no angle or no window to measure it in.
    std::optional<SharedNoise> shared_noise;

    // Whether the 95 % intervals of the model diagnosed, and of the model recommended, can be trusted:
    // only when nothing the data show is left out of it (an interval assumes the residual is noise).
    bool model_intervals_valid() const { return !missing_effect_found && !not_in_library; }
    // The fit of the recommended model, the one every figure of it is read from (its corrections,
    // detection limits, interval caveats, the studies' errors): the model diagnosed when that is
    // recommended (its fit has intervals and took every row), else the search's step that made it.
    const ModelFit& recommended_fit() const {
        const bool from_path = recommended.text() != model.spec.text() && !path.empty() &&
                               path[recommended_step].fit.spec.text() == recommended.text();
        return from_path ? path[recommended_step].fit : model;
    }
    bool recommended_intervals_valid() const { return !incomplete && !not_in_library && tie.empty() && !law_error_beyond_noise; }
    // Whether the recommended model's interval of base parameter `j` (Rs, Ld, Lq, psi_f) comes with
    // a mark: not valid, or a caveat that concerns it. An interval without one owes the truth.
    bool recommended_interval_marked(std::size_t j) const {
        if (!recommended_intervals_valid()) return true;
        for (const auto& c : interval_caveats)
            if (c.base[j]) return true;
        return false;
    }
};

// Fits `spec` to `data` and answers where it fails, what is missing and how sure that is: the
// stages of diagnosis_stages.hpp in turn.
Diagnosis diagnose(const Measurement& data, const ModelSpec& spec, const DiagnosisOptions& options);

}  // namespace mhb::pmsm
