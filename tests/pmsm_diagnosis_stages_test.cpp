// The diagnosis's stages alone (problems/pmsm/diagnosis/diagnosis_stages.hpp): the recommendation
// judged on paths built by hand.
#include <catch2/catch.hpp>

#include "problems/pmsm/diagnosis/diagnosis_stages.hpp"

using namespace mhb::pmsm;

namespace {

PathStep step_of(const std::string& spec, StepKind kind, const std::string& effect, bool plausible, bool at_floor, double explained) {
    PathStep s;
    s.fit.spec = parse_model_spec(spec);
    s.kind = kind;
    s.effect = effect;
    s.plausible = plausible;
    s.at_noise_floor = at_floor;
    s.explained = explained;
    return s;
}

Recommendation recommend_on(const std::vector<PathStep>& path, bool model_left_significant = true) {
    PathTrace trace;
    trace.path = path;
    trace.left.resize(path.size());
    LackOfFit model_left;
    model_left.significant = model_left_significant;
    return recommend(parse_model_spec("base"), SetSearch{}, trace, model_left, Measurement{}, {});
}

}  // namespace

TEST_CASE("an implausible addition after a complete plausible set does not undo it", "[pmsm][diagnosis][stages]") {
    // base+deadtime reaches the noise floor with plausible values; the search then adds an effect
    // whose values no machine has. The recommendation is the plausible set, judged complete.
    const Recommendation r = recommend_on({step_of("base", StepKind::Start, "", true, false, 0.0),
                                           step_of("base+deadtime", StepKind::Added, "deadtime", true, true, 0.98),
                                           step_of("base+deadtime+rs_thermal", StepKind::Added, "rs_thermal", false, true, 1.0)});
    CHECK(r.step == 1);
    CHECK(r.recommended.text() == "base+deadtime");
    CHECK_FALSE(r.incomplete);
    CHECK_FALSE(r.not_in_library);
    CHECK(r.winner == std::optional<std::string>("deadtime"));

    SECTION("a run of implausible additions is passed over whole") {
        const Recommendation two = recommend_on({step_of("base", StepKind::Start, "", true, false, 0.0),
                                                 step_of("base+deadtime", StepKind::Added, "deadtime", true, true, 0.98),
                                                 step_of("base+deadtime+rs_thermal", StepKind::Added, "rs_thermal", false, true, 0.99),
                                                 step_of("base+deadtime+rs_thermal+delay", StepKind::Added, "delay", false, true, 1.0)});
        CHECK(two.step == 1);
        CHECK(two.recommended.text() == "base+deadtime");
    }
    SECTION("not across a pruning, which already judged the larger sets") {
        const Recommendation pruned = recommend_on({step_of("base", StepKind::Start, "", true, false, 0.0),
                                                    step_of("base+deadtime", StepKind::Added, "deadtime", true, true, 0.98),
                                                    step_of("base+deadtime+delay", StepKind::Added, "delay", true, true, 0.99),
                                                    step_of("base+delay", StepKind::Pruned, "deadtime", false, true, 0.99)});
        CHECK(pruned.step == 3);
        CHECK(pruned.recommended.text() == "base");
    }
    SECTION("with no plausible set at all, nothing is recommended and the structure is outside the library") {
        const Recommendation none = recommend_on({step_of("base", StepKind::Start, "", true, false, 0.0),
                                                  step_of("base+saturation", StepKind::Added, "saturation", false, true, 0.9)});
        CHECK(none.step == 1);
        CHECK(none.recommended.text() == "base");
        CHECK(none.not_in_library);
    }
}

TEST_CASE("a plausible set short of the floor is recommended when it explains most of the excess, and is then incomplete",
          "[pmsm][diagnosis][stages]") {
    const Recommendation most = recommend_on({step_of("base", StepKind::Start, "", true, false, 0.0),
                                              step_of("base+saturation", StepKind::Added, "saturation", true, false, 0.97)});
    CHECK(most.recommended.text() == "base+saturation");
    CHECK(most.incomplete);
    const Recommendation little = recommend_on({step_of("base", StepKind::Start, "", true, false, 0.0),
                                                step_of("base+saturation", StepKind::Added, "saturation", true, false, 0.3)});
    CHECK(little.recommended.text() == "base");
    CHECK_FALSE(little.incomplete);
    CHECK(little.not_in_library);
}
