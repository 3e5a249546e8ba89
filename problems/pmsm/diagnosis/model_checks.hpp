#pragma once
// Checks of a fitted model against the data: held-out prediction, plausibility of its values, the
// values each segment asks for and their drifts, and what an unidentifiable effect would do.
#include <map>
#include <string>
#include <vector>

#include "problems/pmsm/diagnosis/diagnosis.hpp"

namespace mhb::pmsm {

// Squared prediction error of each segment (range of rows with one label) when `spec` is refitted
// on all the other segments, starting from `values` (its fit on all rows): the Gauss-Newton step of
// the model linearised at `values`, exact where the prediction is linear in the free parameters.
// Empty with fewer than three segments.
std::vector<double> leave_one_segment_out(const Measurement& data, const ModelSpec& spec, const Eigen::VectorXd& values);
// The same for `fit` (of `data`) at its values, from the per-segment sums its intervals made
// (ModelFit::segment_sums) when it kept them: the same numbers without another pass over the rows.
std::vector<double> leave_one_segment_out(const Measurement& data, const ModelFit& fit);

// The rms prediction error over both axes of `samples` rows from their squared errors per segment.
double pooled_rms(const std::vector<double>& sse, Eigen::Index samples);

// A candidate's held-out prediction against the model it extends.
struct HeldOutComparison {
    std::vector<double> folds;  // the candidate's leave_one_segment_out
    HeldOutVote vote;
};

// `model_folds`: the extended model's leave_one_segment_out (not empty).
HeldOutComparison compare_held_out(const Measurement& data, const ModelFit& candidate, const std::vector<double>& model_folds);

// The largest accuracy the laws of `spec`'s effects state (Effect::law_accuracy) and the first
// effect that states it; an empty name and 0 when none states one. Made from the effects' names
// alone, without a pass over any data.
struct StatedAccuracy {
    std::string effect;
    double accuracy = 0.0;
};
StatedAccuracy stated_law_accuracy(const ModelSpec& spec);

// The structure a fit's effect laws may leave by their stated accuracy (Effect::law_accuracy): the
// largest accuracy among them, squared, times the power of the voltage the flux linkage makes
// (u - Rs i, every row), relative to the noise power. Zero when no law states an error.
LawAllowance law_allowance(const Measurement& data, const ModelFit& fit, const NoiseEstimate& noise);

// Each effect of d's recommended set added on its search path after a law with a stated accuracy
// whose addition changed the prediction (residual before less residual after, over every row of
// `data`) by no more energy than the law's stated error may have (LawAllowance of the set it was
// added to): a size test, not a shape test, so a real effect that small is named too, rightly (the
// law could have made it). Effects added before the law, or pruned again, are not judged.
std::vector<LawStandIn> law_stand_ins(const Measurement& data, const Diagnosis& d);

// Whether what `left` measures is at the noise floor: nothing significant, or less than the
// tolerance (DiagnosisOptions::floor_tolerance) and the laws' allowance.
bool at_noise_floor(const LackOfFit& left, double floor_tolerance, const LawAllowance& allowance);

// Appends to `problems` each base parameter that is not positive or outside Table 2's box.
void check_base(const ModelFit& fit, std::vector<std::string>& problems);

// Appends to `problems` each effect parameter at an end of its plausible range (but a magnitude at 0,
// and a shape whose effect says its range end is not implausible),
// with what that end means when its effect says, and each effect's reason why the fitted machine is
// physically impossible at the logged currents (Effect::implausible_reason).
void check_effects(const ModelFit& fit, const Measurement& data, std::vector<std::string>& problems);

// The effect parameters of `fit` that check_effects finds at an end of their plausible range, each
// with its material value (Effect::material_value), by effect and parameter name; empty when there
// is none, or when any of them has no material value.
std::map<std::string, std::map<std::string, double>> material_values_at_range_ends(const ModelFit& fit, const Measurement& data);

// Each free parameter refitted alone on each segment, the others held at the global fit: the value
// that segment asks for, appended to each segment's `apparent` (and the parameter names to `names`).
// A drift of these with temperature, current or speed shows what is missing. `residual` is the
// fit's (residual_of).
void apparent_values(const SteadyStateModel& model, const ModelFit& fit, const Eigen::VectorXd& residual, const NoiseEstimate& noise,
                     std::vector<SegmentConditions>& segments, std::vector<std::string>& names);

// Apparent parameters that vary between segments beyond the noise (four determined segments or
// more), with the operating condition each follows most closely when |r| >= 0.8.
std::vector<Drift> drifts_of(const std::vector<SegmentConditions>& segments, const std::vector<std::string>& names);

// Each parameter of an unidentifiable candidate pinned at a typical value (the others at their
// defaults), the model refitted around it: how far the base parameters move for no change in residual.
std::vector<Absorption> absorption_of(const Measurement& data, const ModelSpec& spec, const ModelFit& model, const Candidate& c,
                                      const NoiseEstimate& noise);

}  // namespace mhb::pmsm
