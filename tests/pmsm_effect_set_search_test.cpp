// The search over sets of effects alone (problems/pmsm/diagnosis/effect_set_search.hpp), on the
// diagnosis profile with one hidden effect whose truth the simulation knows: a round picks it, the
// search stops after it, and pruning removes an effect the data do not need; two effects of about
// equal evidence that are both present are both added.
#include <filesystem>

#include <catch2/catch.hpp>

#include "problems/pmsm/diagnosis/design.hpp"
#include "problems/pmsm/diagnosis/effect_set_search.hpp"
#include "problems/pmsm/diagnosis/noise.hpp"
#include "problems/pmsm/study/detection_study.hpp"
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

TEST_CASE("a law of several terms that the operating points cannot pin whole is added with fewer terms, and never to clean data",
          "[pmsm][diagnosis][search][hidden]") {
    // The device servo's saturating iron (a co-energy of the stored magnetic energy, which shares no
    // code with the saturation law the diagnosis fits) on its nine operating points: the whole law's
    // six parameters do not predict left-out points (seed 1: 2 of 9), a law with fewer terms may.
    // Seeds and a noise level the study does not use (experiments/pmsm/detection_study.toml: seeds
    // 1-20, 1 mA); the same drives without saturation as the control. Measured (2026-11-26, only the
    // held-out segments that decide voting): found alone in 10 of 10 drives at 1 mA (7 with fewer
    // terms) and 8 of 10 at 2 mA, all 8 with fewer terms (with every segment voting: 10 (4) and 7 (7);
    // with whole laws only, 0 at 2 mA); the clean drives 20 of 20 at base. Of the Ld, Lq and psi_f
    // intervals of the drives found with fewer terms, 0 missed the plant's value at 1 mA and 5 at
    // 2 mA, each with its caveat. Since a law is not offered with fewer terms while a harmonic no
    // library law makes is left (2026-11-27): 10 of 10 at 1 mA (5 with fewer terms), 8 of 10 at 2 mA
    // (8).
    const std::string profile = std::string(MHBENCH_SOURCE_DIR) + "/experiments/pmsm/device_diagnosis_profile.toml";
    const auto law = make_effect("saturation");
    const auto saturation_terms = law->law_terms();
    const auto& defaults = law->values();
    const auto& names = law->parameter_names();
    for (const double current_noise : {1e-3, 2e-3}) {
        int found = 0, reduced = 0, clean_quiet = 0, missed_intervals = 0;
        constexpr int seeds = 10;
        for (int seed = 101; seed < 101 + seeds; ++seed) {
            for (const double saturation_current : {0.0, 0.3}) {
                auto drive = read_simulation_profile(profile);
                drive.seed = static_cast<std::uint64_t>(seed);
                drive.noise.current = current_noise;
                drive.device->saturation.saturation_current = saturation_current;
                DiagnosisOptions options;
                options.pole_pairs = drive.motor.pole_pairs;
                const Diagnosis d = diagnose(simulate(drive).data, parse_model_spec("base"), options);
                INFO("noise " << current_noise << " A, seed " << seed << ", saturation current " << saturation_current << " A: recommended "
                              << d.recommended.text());
                if (saturation_current == 0.0) {
                    clean_quiet += d.recommended.effects.empty() ? 1 : 0;
                    continue;
                }
                if (d.recommended.effects.size() != 1 || d.recommended.effects.front().name != "saturation") continue;
                ++found;
                const auto& held = d.recommended.effects.front().fixed;
                if (held.empty()) continue;
                ++reduced;
                // Whole terms are held, each at the defaults that drop it, and the finding says why.
                for (const auto& term : saturation_terms) {
                    const bool dropped = held.count(names[term.front()]) > 0;
                    for (const auto k : term) {
                        CHECK(held.count(names[k]) == (dropped ? 1U : 0U));
                        if (dropped) CHECK(held.at(names[k]) == defaults[static_cast<Eigen::Index>(k)]);
                    }
                }
                CHECK(held.size() < names.size());
                // The held terms pull the inductances: an interval of Ld, Lq or psi_f that misses the
                // plant's small-current value comes with the caveat that names it. (Rs is left out:
                // current sampled at the carrier peak in saturating iron biases it by 0.15 %, which
                // no caveat states yet; docs/effects.md.)
                const ModelFit& fit = d.path[d.recommended_step].fit;
                FitOptions with_intervals;
                with_intervals.intervals = true;
                const ModelFit polished = polish_model(simulate(drive).data, fit.spec, fit.values, with_intervals);
                const Eigen::Vector4d truth(drive.motor.rs, drive.motor.ld, drive.motor.lq, drive.motor.psi_f);
                for (std::size_t j = 1; j < 4; ++j) {
                    const auto k = static_cast<Eigen::Index>(j);
                    INFO(fit.names[j] << " interval [" << polished.lower[k] << ", " << polished.upper[k] << "], plant " << truth[k]);
                    if (!(polished.lower[k] <= truth[k] && truth[k] <= polished.upper[k])) {
                        ++missed_intervals;
                        CHECK(d.recommended_interval_marked(j));
                    }
                }
                CHECK(std::any_of(d.findings.begin(), d.findings.end(), [](const std::string& f) {
                    return f.rfind("Only the terms of its law this log pins: saturation with ", 0) == 0 &&
                           f.find("the whole law, with 6 parameters, ") != std::string::npos;
                }));
            }
        }
        INFO("noise " << current_noise << " A: saturation found alone in " << found << " of " << seeds << " drives (" << reduced
                      << " with fewer terms, " << missed_intervals << " intervals missing the plant's value, each marked); clean "
                      << "drives left at base: " << clean_quiet);
        CHECK(found >= (current_noise < 1.5e-3 ? 9 : 5));
        CHECK(reduced >= 1);
        CHECK(clean_quiet == seeds);
    }
}

TEST_CASE("while a harmonic no library law makes is left, every held-out segment votes and no law is offered with fewer terms, so a "
          "law does not take the missing effect's segment means",
          "[pmsm][diagnosis][search][hidden]") {
    // The 100 kW machine's 2 % gain error of the phase a current sensor, which the library lacks
    // (its signature is a second harmonic of the electrical angle). Its segment means follow the
    // current's size, which the saturation law can take and predict on the segments whose held-out
    // error it changes; the coin tosses of the others had kept it out. Seeds the study does not use
    // (experiments/pmsm/detection_study_100kw.toml: 1-20). Measured (2026-11-26): "not in the library"
    // with nothing added in 6 of 10, saturation added (with fewer terms) in 4; with only the segments
    // that decide voting whatever the residual holds, 3 and 7 (the study's 20 seeds: 14 and 6, 5
    // and 15 that way). The 4 took the law with fewer terms, the best of 14 shapes; with none offered
    // while the harmonic is left (2026-11-27): 10 of 10 and 0 (the study's seeds: 20 and 0). The
    // second harmonic is named in 10 of 10 either way.
    const std::string profile = std::string(MHBENCH_SOURCE_DIR) + "/experiments/pmsm/device_100kw_profile.toml";
    constexpr int seeds = 10;
    int not_in_library = 0, saturation = 0;
    for (int seed = 101; seed < 101 + seeds; ++seed) {
        auto drive = read_simulation_profile(profile);
        drive.seed = static_cast<std::uint64_t>(seed);
        drive.device->current_sensors.gain_a = 1.02;
        DiagnosisOptions options;
        options.pole_pairs = drive.motor.pole_pairs;
        const Diagnosis d = diagnose(simulate(drive).data, parse_model_spec("base"), options);
        INFO("seed " << seed << ": recommended " << d.recommended.text());
        not_in_library += d.not_in_library && d.recommended.effects.empty() ? 1 : 0;
        saturation += d.recommended.contains("saturation") ? 1 : 0;
        // Whatever is recommended, the second harmonic is named: no library law makes it.
        CHECK(std::any_of(d.outside_harmonics.begin(), d.outside_harmonics.end(), [](const Harmonic& h) { return h.order == 2; }));
    }
    INFO("not in the library, nothing added: " << not_in_library << " of " << seeds << "; saturation added: " << saturation);
    CHECK(not_in_library >= 9);
    CHECK(saturation <= 1);
}

TEST_CASE("two effects of about equal evidence and different signatures are both added, not called a tie (examples: two drives)",
          "[pmsm][diagnosis][search]") {
    // The 5 kW machine with a dead time and a voltage offset each at twice its printed detection
    // limit (experiments/pmsm/detection_limit_study_5kw.toml): their dBIC from base lie within the tie
    // margin, but each is still supported beside the other. Before the search asked that, seed 8
    // ended as "base (tie)", and so did seed 12 of the current offset with the dead time.
    for (const auto& [pair, seed] : {std::pair{"deadtime+voltage_offset", 8UL}, std::pair{"current_offset+deadtime", 12UL}}) {
        auto spec = read_study(std::filesystem::path(MHBENCH_SOURCE_DIR) / "experiments" / "pmsm" / "detection_limit_study_5kw.toml");
        spec.only = pair;
        spec.seeds = {seed};
        const StudyRun run = run_study(spec, study_cases(spec), DiagnosisOptions{});
        REQUIRE(run.records.size() == 1);
        INFO(pair << ", seed " << seed << ": recommended " << run.records.front().recommended);
        CHECK_FALSE(run.records.front().tie);
        CHECK(run.records.front().correct);
    }
}
