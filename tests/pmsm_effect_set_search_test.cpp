// The search over sets of effects alone (problems/pmsm/diagnosis/effect_set_search.hpp), on the
// diagnosis profile with one hidden effect whose truth the simulation knows: a round picks it, the
// search stops after it, and pruning removes an effect the data do not need.
#include <catch2/catch.hpp>

#include "problems/pmsm/diagnosis/design.hpp"
#include "problems/pmsm/diagnosis/effect_set_search.hpp"
#include "problems/pmsm/diagnosis/noise.hpp"
#include "tests/pmsm_diagnosis_fixture.hpp"

using namespace mhb::pmsm;
using namespace mhb::pmsm::testing;

namespace {

const Measurement& encoder_offset_data() { return diagnosis_data({{"encoder_offset", {}}}); }

}  // namespace

TEST_CASE("a round of forward selection picks the hidden effect, alone", "[pmsm][diagnosis][search]") {
    const auto& data = encoder_offset_data();
    const DiagnosisOptions options;
    const ModelSpec base = parse_model_spec("base");
    const ModelFit model = fit_model(data, base, options.fit);
    const auto round = fit_additions(data, base, model, {"rs_thermal", "encoder_offset"}, options.fit);
    REQUIRE(round.size() == 2);
    CHECK(round[1].effect == "encoder_offset");
    CHECK(round[1].added_parameters == 1);
    CHECK(round[1].fit.spec.text() == "base+encoder_offset");
    const RoundChoice choice = choose_addition(data, design_of(data), model, round, window_noise(data, model), options);
    REQUIRE(choice.best);
    CHECK(choice.best->effect == "encoder_offset");
    CHECK(choice.tie == std::vector<std::string>{"encoder_offset"});

    // The whole search from base: it adds the effect and finds nothing more to add or prune.
    std::vector<Candidate> first_round;
    for (const auto& a : round) {
        Candidate c;
        c.effect = a.effect;
        c.fit = a.fit;
        c.added_parameters = a.added_parameters;
        first_round.push_back(c);
    }
    const SetSearch s = search_effect_sets(data, design_of(data), base, model, {"rs_thermal", "encoder_offset"}, first_round, options);
    REQUIRE(s.steps.size() == 2);
    CHECK(s.steps[0].kind == StepKind::Start);
    CHECK(s.steps[0].effect.empty());
    CHECK(s.steps[1].kind == StepKind::Added);
    CHECK(s.steps[1].effect == "encoder_offset");
    CHECK(s.pruned.empty());
    CHECK(s.tie.empty());
}

TEST_CASE("pruning removes the effect the others make unnecessary, and never one of the model's own", "[pmsm][diagnosis][search]") {
    const auto& data = encoder_offset_data();
    const DiagnosisOptions options;
    const ModelFit both = fit_model(data, parse_model_spec("base+encoder_offset+voltage_offset"), options.fit);
    const auto weakest = weakest_effect(data, parse_model_spec("base"), both, window_noise(data, both), options.fit);
    REQUIRE(weakest);
    CHECK(weakest->kind == StepKind::Pruned);
    CHECK(weakest->effect == "voltage_offset");
    CHECK(weakest->fit.spec.text() == "base+encoder_offset");
    CHECK(weakest->added_parameters == -static_cast<int>(both.free_count() - weakest->fit.free_count()));
    CHECK(weakest->added_parameters < 0);
    // With voltage_offset in the model diagnosed, only what the search added may go: the hidden effect stays.
    CHECK_FALSE(weakest_effect(data, parse_model_spec("base+voltage_offset"), both, window_noise(data, both), options.fit));
}

TEST_CASE("a path step writes its change as the JSON and the text do", "[pmsm][diagnosis][search]") {
    PathStep step;
    CHECK(step.change().empty());
    step.kind = StepKind::Added;
    step.effect = "deadtime";
    CHECK(step.change() == "+deadtime");
    step.kind = StepKind::Pruned;
    CHECK(step.change() == "-deadtime");
}
