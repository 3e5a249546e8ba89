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

}  // namespace mhb::pmsm::evidence

namespace mhb::pmsm {

// From the unique fraction of an effect's most distinct parameter on the design (NaN: no signature).
Identifiability identifiability_of(double unique_fraction);

// The verdict on a single addition from its identifiability, plausibility, delta_bic and held-out
// prediction (loso_better of loso_segments; none tested counts as predicting).
Verdict verdict_of(const Candidate& c);

// The order of the ranking: by verdict, supported and partial sharing a rank, then by evidence.
bool ranks_before(const Candidate& a, const Candidate& b);

}  // namespace mhb::pmsm
