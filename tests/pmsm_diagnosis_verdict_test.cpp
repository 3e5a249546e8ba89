// The verdict rules alone (problems/pmsm/diagnosis/verdict.hpp): hand-made candidates on each side of
// every threshold, independent of any fit.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "problems/pmsm/diagnosis/verdict.hpp"

using namespace mhb::pmsm;
using namespace mhb::pmsm::evidence;

namespace {

Candidate candidate(double delta_bic, bool plausible = true, Identifiability identifiability = Identifiability::Identifiable) {
    Candidate c;
    c.delta_bic = delta_bic;
    c.plausible = plausible;
    c.identifiability = identifiability;
    return c;
}

// Every segment decides (or none: the same vote), so no harmonic is asked for.
Candidate held_out(double delta_bic, int better, int segments) {
    Candidate c = candidate(delta_bic);
    c.held_out = {better, segments, better, segments};
    c.predicts_held_out = c.held_out.passes([]() -> bool { throw std::logic_error("asked for harmonics where the votes agree"); });
    return c;
}

}  // namespace

TEST_CASE("the verdict on a plausible identifiable candidate follows its dBIC across both thresholds", "[pmsm][diagnosis][verdict]") {
    CHECK(verdict_of(candidate(supported_bic)) == Verdict::Supported);
    CHECK(verdict_of(candidate(std::nextafter(supported_bic, 0.0))) == Verdict::Weak);
    CHECK(verdict_of(candidate(weak_bic)) == Verdict::Weak);
    CHECK(verdict_of(candidate(std::nextafter(weak_bic, 0.0))) == Verdict::NotSupported);
    CHECK(verdict_of(candidate(-1000.0)) == Verdict::Supported);
    CHECK(verdict_of(candidate(5.0)) == Verdict::NotSupported);
}

TEST_CASE("strong evidence needs a majority of held-out segments predicted at least as well", "[pmsm][diagnosis][verdict]") {
    CHECK(verdict_of(held_out(-50.0, 3, 5)) == Verdict::Supported);
    CHECK(verdict_of(held_out(-50.0, 2, 4)) == Verdict::Supported);  // half counts
    CHECK(verdict_of(held_out(-50.0, 2, 5)) == Verdict::Weak);       // still at least weak evidence
    CHECK(verdict_of(held_out(-50.0, 0, 5)) == Verdict::Weak);
    // Untested (no segments to hold out) counts as predicting.
    CHECK(verdict_of(held_out(-50.0, 0, 0)) == Verdict::Supported);
}

TEST_CASE("the held-out vote counts the deciding segments unless a harmonic outside the library is in the residual",
          "[pmsm][diagnosis][verdict]") {
    int asked = 0;
    const auto outside = [&] { ++asked; return true; };
    const auto inside = [&] { ++asked; return false; };
    // 3 of 9 better, but 3 of the 4 that decide: the deciding segments pass it, every segment does not.
    const HeldOutVote split{3, 9, 3, 4};
    CHECK_FALSE(split.every_segment());
    CHECK(split.where_deciding());
    CHECK(split.passes(inside));
    CHECK_FALSE(split.passes(outside));
    CHECK(asked == 2);
    // The reverse: 6 of 9 better, 1 of the 4 that decide.
    const HeldOutVote reverse{6, 9, 1, 4};
    CHECK_FALSE(reverse.passes(inside));
    CHECK(reverse.passes(outside));
    // No segment decides: every segment votes, and no harmonic is asked for.
    asked = 0;
    CHECK(HeldOutVote{5, 9, 0, 0}.passes(outside));
    CHECK_FALSE(HeldOutVote{4, 9, 0, 0}.passes(inside));
    CHECK(asked == 0);
    // Half passes, in both counts.
    CHECK(HeldOutVote{2, 9, 2, 4}.passes(inside));
    CHECK_FALSE(HeldOutVote{2, 9, 2, 4}.passes(outside));
}

TEST_CASE("implausible values make strong evidence partial and the rest implausible, and unidentifiable overrides all",
          "[pmsm][diagnosis][verdict]") {
    CHECK(verdict_of(candidate(supported_bic, false)) == Verdict::Partial);
    CHECK(verdict_of(candidate(std::nextafter(supported_bic, 0.0), false)) == Verdict::Implausible);
    CHECK(verdict_of(candidate(5.0, false)) == Verdict::Implausible);
    Candidate failing = held_out(-50.0, 1, 5);
    failing.plausible = false;
    CHECK(verdict_of(failing) == Verdict::Implausible);
    CHECK(verdict_of(candidate(-1000.0, true, Identifiability::NotIdentifiable)) == Verdict::NotIdentifiable);
    CHECK(verdict_of(candidate(-1000.0, false, Identifiability::NotIdentifiable)) == Verdict::NotIdentifiable);
    // Mostly absorbed is judged by its evidence like an identifiable one.
    CHECK(verdict_of(candidate(-1000.0, true, Identifiability::MostlyAbsorbed)) == Verdict::Supported);
}

TEST_CASE("identifiability from the unique fraction: absorbed below 1e-6, clear from a tenth", "[pmsm][diagnosis][verdict]") {
    CHECK(identifiability_of(std::numeric_limits<double>::quiet_NaN()) == Identifiability::NotIdentifiable);
    CHECK(identifiability_of(0.0) == Identifiability::NotIdentifiable);
    CHECK(identifiability_of(std::nextafter(absorbed_below, 0.0)) == Identifiability::NotIdentifiable);
    CHECK(identifiability_of(absorbed_below) == Identifiability::MostlyAbsorbed);
    CHECK(identifiability_of(std::nextafter(clear_above, 0.0)) == Identifiability::MostlyAbsorbed);
    CHECK(identifiability_of(clear_above) == Identifiability::Identifiable);
    CHECK(identifiability_of(1.0) == Identifiability::Identifiable);
}

TEST_CASE("the ranking puts supported and partial together by evidence, then the other verdicts in order", "[pmsm][diagnosis][verdict]") {
    Candidate partial = candidate(-50.0, false), supported = candidate(-20.0), weak = candidate(-100.0), none = candidate(-1.0);
    partial.verdict = Verdict::Partial;
    supported.verdict = Verdict::Supported;
    weak.verdict = Verdict::Weak;  // a verdict, not the dBIC, orders different ranks
    none.verdict = Verdict::NotSupported;
    CHECK(ranks_before(partial, supported));
    CHECK_FALSE(ranks_before(supported, partial));
    CHECK(ranks_before(supported, weak));
    CHECK_FALSE(ranks_before(weak, supported));
    CHECK(ranks_before(weak, none));
    Candidate implausible = candidate(-1.0, false), hidden = candidate(-1.0);
    implausible.verdict = Verdict::Implausible;
    hidden.verdict = Verdict::NotIdentifiable;
    CHECK(ranks_before(none, implausible));
    CHECK(ranks_before(implausible, hidden));
    CHECK_FALSE(ranks_before(supported, supported));
}
