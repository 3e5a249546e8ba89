#pragma once
// The stages of `diagnose`, in the order it runs them, each handing a typed result to the next:
// fit the baseline, screen the library, fit the candidates, search over sets of effects
// (effect_set_search.hpp), measure the noise, check the model, score the candidates, trace the
// search's path, recommend, and state the findings (findings.hpp).
#include <optional>
#include <string>
#include <vector>

#include "problems/pmsm/diagnosis/design.hpp"
#include "problems/pmsm/diagnosis/diagnosis.hpp"
#include "problems/pmsm/diagnosis/effect_set_search.hpp"
#include "problems/pmsm/diagnosis/shaft_angle.hpp"

namespace mhb::pmsm {

// The model diagnosed and its prefixes, base, base+A, ..., up to it (one entry when it is base).
struct Baseline {
    ModelFit model;
    std::vector<ModelFit> build_up;
};
Baseline fit_baseline(const Measurement& data, const ModelSpec& spec, const FitOptions& options);

// The library effects not in the model: those the data have the columns for, and the others.
struct LibraryScreen {
    std::vector<std::string> library;
    std::vector<NotTried> not_tried;
};
LibraryScreen screen_library(const Measurement& data, const ModelSpec& spec);

// `model` with each effect of `library` added alone, in library order; only the fit, the added
// parameters and the base shift are filled in (score_candidates does the rest).
std::vector<Candidate> fit_candidates(const Measurement& data, const ModelSpec& spec, const ModelFit& model,
                                      const std::vector<std::string>& library, const FitOptions& options);

// design_of the rows the optimiser searches on (all rows unless FitOptions::search_rows).
Measurement search_design(const Measurement& data, const FitOptions& options);

// The noise, measured where the residual is smallest: on the search's last set or on a single
// addition, whichever fits best (noise_of_best, with overdispersion).
NoiseEstimate measure_noise(const Measurement& data, const SetSearch& search, const std::vector<Candidate>& candidates);

// Where the model fails: its lack of fit (with the harmonics of `shaft`), held-out prediction,
// plausibility, each segment's conditions and apparent values, and the drifts of those.
struct ModelCheck {
    LackOfFit lack_of_fit;
    std::vector<double> folds;  // the model's leave_one_segment_out (empty without)
    std::optional<double> loso_rms;
    std::vector<std::string> base_problems;
    std::vector<SegmentConditions> segments;
    std::vector<std::string> apparent_names;
    std::vector<Drift> drifts;
};
ModelCheck check_model(const Measurement& data, const ModelSpec& spec, const Baseline& baseline, const NoiseEstimate& noise,
                       const DiagnosisOptions& options, const ShaftAngle& shaft);

// Fraction of `model`'s excess residual over `floor_rss` (the within-segment noise) that `fit` removes.
double explained_fraction(const ModelFit& model, const ModelFit& fit, double floor_rss);

// Each candidate's evidence against `model` under `noise`, plausibility, identifiability on
// `design` (with the experiments that would reveal it and what it is absorbed into when it is not
// identifiable), held-out prediction against `model_folds` (by HeldOutVote::passes, with the
// harmonics of `model_left`, the model's lack of fit) and verdict; then ranked best first.
void score_candidates(std::vector<Candidate>& candidates, const Measurement& data, const Measurement& design,
                      const std::vector<Proposal>& proposals, const ModelFit& model, const NoiseEstimate& noise,
                      const std::vector<double>& model_folds, const LackOfFit& model_left);

// The search's steps scored with the final noise, so that they compare with each other, and as the
// search decided them (without overdispersion: the noise floor at the end is the safeguard).
struct PathTrace {
    std::vector<PathStep> path;
    std::vector<LackOfFit> left;  // each step's lack of fit; left[0] is the model's
};
PathTrace trace_path(const Measurement& data, const SetSearch& search, const ModelFit& model, const LackOfFit& model_left,
                     const NoiseEstimate& noise, double floor_tolerance, const ShaftAngle& shaft);

struct Recommendation {
    ModelSpec recommended;
    bool missing_effect_found = false;
    std::optional<std::string> winner;
    std::optional<LackOfFit> after_winner;
    std::vector<std::string> tie;
    std::vector<Experiment> tie_experiments;
    bool not_in_library = false;
    // Recommended without reaching the noise floor: something else is missing too.
    bool incomplete = false;
    // The step of the path the recommendation is judged on: the last, or, when the last additions
    // are implausible, the latest plausible set before them.
    std::size_t step = 0;
};
// The last set of the path when it is plausible and reaches the noise floor (or the search stopped on
// a tie), or explains most of the model's excess residual (evidence::most_of_the_excess; then
// `incomplete`); `spec` otherwise. "Not in the library" only when no set of library effects is
// recommended while the model leaves structure.
Recommendation recommend(const ModelSpec& spec, const SetSearch& search, const PathTrace& trace, const LackOfFit& model_left,
                         const Measurement& design, const std::vector<Proposal>& proposals);

}  // namespace mhb::pmsm
