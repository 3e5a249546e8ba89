#pragma once
// The rules of evidence of a diagnosis (docs/effects.md, "How diagnose decides"), in one place: the
// thresholds, what a unique fraction says about identifiability, and a candidate's verdict. Every
// stage that judges evidence (the scoring of single additions, the search over sets, the lack of
// fit) takes its thresholds from here.
#include "problems/pmsm/diagnosis/diagnosis.hpp"

namespace mhb::pmsm::evidence {

inline constexpr double supported_bic = -10.0;  // "very strong" on Kass and Raftery's scale of 2 ln B
inline constexpr double weak_bic = -2.0;
inline constexpr double tie_margin = 6.0;       // below "strong" preference between two candidates
inline constexpr double absorbed_below = 1e-6;  // unique fraction: in the span of the model's columns
inline constexpr double clear_above = 0.1;      // unique fraction: at least a tenth of the signature is its own
inline constexpr double significance = 1e-3;    // p-value of structure beyond chance (lack of fit, drifts)
// A plausible set that does not reach the noise floor is still recommended when it explains at least
// this share of the model's excess residual: then what it adds is most of what is missing, and the
// rest is named as "something else", with its signature.
inline constexpr double most_of_the_excess = 0.5;
// Evidence alone grows with the rows: on a long log, or beside a model whose shape misses the data,
// any effect with a free parameter would earn its place by absorbing a sliver of the misfit. So an
// effect is added to a set only when it is also relevant, by two measures that do not grow with the
// rows: it explains at least `relevant_share` of the excess residual the set still leaves, and it
// changes the modelled voltage by at least `relevant_voltage` of the noise's rms (the resolution of
// one sample).
inline constexpr double relevant_share = 0.1;
inline constexpr double relevant_voltage = 0.1;
// A held-out segment decides between a candidate and the model when the candidate changes its
// squared prediction error by at least this fraction: the relevant voltage's, squared (1 %).
inline constexpr double deciding_change = relevant_voltage * relevant_voltage;

}  // namespace mhb::pmsm::evidence

namespace mhb::pmsm {

// From the unique fraction of an effect's most distinct parameter on the design (NaN: no signature).
Identifiability identifiability_of(double unique_fraction);

// The verdict on a single addition from its identifiability, plausibility, delta_bic and held-out
// prediction (predicts_held_out).
Verdict verdict_of(const Candidate& c);

// The order of the ranking: by verdict, supported and partial sharing a rank, then by evidence.
bool ranks_before(const Candidate& a, const Candidate& b);

}  // namespace mhb::pmsm
