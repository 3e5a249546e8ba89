#pragma once
// The search over sets of effects (docs/effects.md, "Several effects at once"): forward selection of
// library effects with backward pruning.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "problems/pmsm/diagnosis/diagnosis.hpp"

namespace mhb::pmsm {

struct Addition {
    std::string effect;
    ModelFit fit;
    int added_parameters = 0;
};

// `fit`'s model with each of `effects` added in turn, from `fit`'s values, only the new effect's
// parameters searched. The fits are independent, so they run in parallel with the same result on
// any number of threads.
std::vector<Addition> fit_additions(const Measurement& data, const ModelSpec& spec, const ModelFit& fit,
                                    const std::vector<std::string>& effects, const FitOptions& options);

struct SearchStep {
    ModelFit fit;
    StepKind kind = StepKind::Start;
    std::string effect;        // added or pruned; empty for the start
    int added_parameters = 0;  // negative when pruned
    std::string reduced_law;   // RoundChoice::reduced_law of the addition
    Eigen::VectorXd whole_law_base;  // RoundChoice::whole_law_base of the addition
};

struct SetSearch {
    std::vector<SearchStep> steps;  // steps[0]: the model diagnosed
    std::vector<std::string> pruned;
    std::vector<std::string> tie;   // when the search stopped on two or more alternatives it cannot order
    ModelSpec tie_spec;
    Eigen::VectorXd tie_values;
    std::vector<UnpredictiveAddition> unpredictive;  // of the round that added nothing
    WindowNoise data_noise;  // window_noise on the model diagnosed: each round's evidence floor
};

// One round of forward selection from `current`: the supported addition with the strongest evidence
// that the design can identify and that predicts held-out segments, and the effects tied with it.
struct RoundChoice {
    const Addition* best = nullptr;  // into the round or `reduced`; none when no addition qualifies
    // When the best is an effect's law with fewer terms (Effect::law_terms), because the whole law
    // does not predict held-out segments: that addition, and why, in words.
    std::shared_ptr<const Addition> reduced;
    std::string reduced_law;
    // Then the base parameters (Rs, Ld, Lq, psi_f) of the whole law's fit, which the terms held at
    // their defaults would give if they are there (interval_caveats.hpp); empty otherwise.
    Eigen::VectorXd whole_law_base;
    std::vector<std::string> tie;    // the best first, then each effect the evidence or the design cannot separate from it
                                     // (search_effect_sets keeps those that are alternatives to it)
    // Supported additions with stronger evidence than the best (all of them, without a best) that
    // predict too few held-out segments.
    std::vector<UnpredictiveAddition> unpredictive;
};
// `data_noise` is the data's noise (window_noise).
RoundChoice choose_addition(const Measurement& data, const Measurement& design, const ModelFit& current, const std::vector<Addition>& round,
                            const WindowNoise& data_noise, const DiagnosisOptions& options);

// The effect of `current` (not in `spec`) whose removal costs least, when that is less than strong
// evidence: the model without it, polished with `compared`.
std::optional<SearchStep> weakest_effect(const Measurement& data, const ModelSpec& spec, const ModelFit& current, const WindowNoise& data_noise,
                                         const FitOptions& compared);

// The search from `model` (the fit of `spec`), its first round being `first_round` (each library
// effect added to it once). `design` is design_of the data (design.hpp).
SetSearch search_effect_sets(const Measurement& data, const Measurement& design, const ModelSpec& spec, const ModelFit& model,
                             const std::vector<std::string>& library, const std::vector<Candidate>& first_round,
                             const DiagnosisOptions& options);

}  // namespace mhb::pmsm
