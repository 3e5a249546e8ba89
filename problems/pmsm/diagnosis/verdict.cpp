#include "problems/pmsm/diagnosis/verdict.hpp"

namespace mhb::pmsm {

using namespace evidence;

Identifiability identifiability_of(double unique) {
    return !(unique >= absorbed_below) ? Identifiability::NotIdentifiable
           : unique < clear_above      ? Identifiability::MostlyAbsorbed
                                       : Identifiability::Identifiable;
}

Verdict verdict_of(const Candidate& c) {
    const bool strong = c.delta_bic <= supported_bic && c.predicts_held_out;
    if (c.identifiability == Identifiability::NotIdentifiable) return Verdict::NotIdentifiable;
    if (!c.plausible) return strong ? Verdict::Partial : Verdict::Implausible;
    if (strong) return Verdict::Supported;
    if (c.delta_bic <= weak_bic) return Verdict::Weak;
    return Verdict::NotSupported;
}

namespace {

// Supported and partial share a rank: between them the evidence decides.
int rank_of(Verdict v) { return v == Verdict::Partial ? static_cast<int>(Verdict::Supported) : static_cast<int>(v); }

}  // namespace

bool ranks_before(const Candidate& a, const Candidate& b) {
    if (rank_of(a.verdict) != rank_of(b.verdict)) return rank_of(a.verdict) < rank_of(b.verdict);
    return a.delta_bic < b.delta_bic;
}

const char* to_string(Identifiability level) {
    switch (level) {
        case Identifiability::Identifiable: return "identifiable";
        case Identifiability::MostlyAbsorbed: return "mostly absorbed";
        case Identifiability::NotIdentifiable: return "not identifiable";
    }
    return "?";
}

const char* to_string(Verdict verdict) {
    switch (verdict) {
        case Verdict::Supported: return "supported";
        case Verdict::Partial: return "partial";
        case Verdict::Weak: return "weak";
        case Verdict::NotSupported: return "not supported";
        case Verdict::Implausible: return "implausible";
        case Verdict::NotIdentifiable: return "not identifiable";
    }
    return "?";
}

}  // namespace mhb::pmsm
