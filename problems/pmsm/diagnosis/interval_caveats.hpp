#pragma once
// Why a 95 % interval of the recommended model's base parameters may miss the truth although the
// residual it leaves is noise as far as the log shows: what the diagnosis states beside the
// intervals (docs/diagnosis.md, section 4, "What no interval here holds").
#include "problems/pmsm/diagnosis/diagnosis.hpp"

namespace mhb::pmsm {

// For `d`, diagnosed up to its recommendation: the biases the recommended effects' laws state
// (Effect::unseen_bias, each on the base parameters it moves); L_d, L_q and psi_f when the laws bend
// the flux, at the logged operating point nearest zero current, further from the line those
// zero-current values draw than psi_f's interval (below the logged currents they are the laws'
// extrapolation); and, for a law the search reduced to fewer terms, the base parameters whose
// whole-law value lies outside their interval: the held terms are a choice the log could not check,
// and those intervals hold only if the terms are absent. The recommended fit is polished once with
// intervals when one of these needs them and it is a step of the search (the model diagnosed has them).
std::vector<IntervalCaveat> interval_caveats(const Measurement& data, const Diagnosis& d, const FitOptions& options);

}  // namespace mhb::pmsm
