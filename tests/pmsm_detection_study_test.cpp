// The hidden-effect study: its file format and refusals, the cases it makes, the Wilson interval,
// and, run over several noise seeds, the search over sets of effects finding clear single effects,
// pairs and a triple exactly, with no false alarm on clean data.
#include <catch2/catch.hpp>

#include <tbb/global_control.h>
#include <toml++/toml.h>

#include "framework/input_error.hpp"
#include "problems/pmsm/study/detection_study.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
using namespace mhb::pmsm;

namespace {

std::string study_text(const std::string& profile, const std::string& extra, const std::string& seeds = "3") {
    return "name = \"t\"\ndescription = \"test\"\nprofile = \"" + profile + "\"\nseeds = " + seeds + "\noutput = \"out\"\n" + extra;
}

const std::string deadtime = "[[effect]]\nname = \"deadtime\"\nclear = { effects.deadtime = { voltage = 0.28, current_band = 0.01 } }\n"
                             "weak = { effects.deadtime = { voltage = 0.03 } }\n";
const std::string rs_thermal = "[[effect]]\nname = \"rs_thermal\"\nclear = { effects.rs_thermal = { alpha = 0.00393 } }\n"
                               "weak = { effects.rs_thermal = {}, temperature.winding = [[0.0, 25.0], [5.0, 30.0]] }\n";
const std::string psi_thermal = "[[effect]]\nname = \"psi_thermal\"\nclear = { effects.psi_thermal = { alpha = -0.001 } }\n"
                                "weak = { effects.psi_thermal = {}, temperature.magnet = [[0.0, 25.0], [5.0, 30.0]] }\n";

std::string profile_path() { return std::string(MHBENCH_SOURCE_DIR) + "/experiments/pmsm/diagnosis_profile.toml"; }

}  // namespace

TEST_CASE("the Wilson interval matches its closed form at known points", "[pmsm][study]") {
    // 0 of 10: upper end z^2 / (n + z^2); 10 of 10 mirrors it; 5 of 10 is symmetric about 1/2.
    const double z2 = 1.959963984540054 * 1.959963984540054;
    auto [lo0, hi0] = wilson_interval(0, 10);
    CHECK(lo0 == 0.0);
    CHECK(hi0 == Approx(z2 / (10 + z2)).epsilon(1e-12));
    auto [lo10, hi10] = wilson_interval(10, 10);
    CHECK(lo10 == Approx(1.0 - hi0).epsilon(1e-12));
    CHECK(hi10 == Approx(1.0).epsilon(1e-12));
    auto [lo5, hi5] = wilson_interval(5, 10);
    CHECK(lo5 + hi5 == Approx(1.0));
    CHECK(lo5 == Approx(0.2365931).epsilon(1e-6));
}

TEST_CASE("a study file makes clean, single, pair, triple and outside cases with merged settings", "[pmsm][study]") {
    testing::TemporaryDirectory dir;
    const auto file = dir.write("s.toml", study_text(profile_path(), "triples = [[\"deadtime\", \"psi_thermal\", \"rs_thermal\"]]\n" + deadtime +
                                                                         rs_thermal + psi_thermal +
                                                                         "[[outside]]\nname = \"offset_on_u_q\"\nsettings = { effects.voltage_offset = { u_d = 0.0, u_q = 0.05 } }\n"));
    const auto spec = read_study(file);
    CHECK(spec.seeds == std::vector<std::uint64_t>{1, 2, 3});
    const auto cases = study_cases(spec);
    // clean + 3 effects x 2 magnitudes + 3 pairs + 1 triple + 1 outside
    REQUIRE(cases.size() == 1 + 6 + 3 + 1 + 1);
    CHECK(cases.front().kind == "clean");
    CHECK(cases.front().truth.empty());
    const auto& triple = cases[10];
    CHECK(triple.kind == "triple");
    CHECK(triple.truth == std::vector<std::string>{"deadtime", "psi_thermal", "rs_thermal"});
    CHECK(cases.back().outside);
    CHECK(cases[1].sizes.at("deadtime").empty());  // not stated in this file

    // The case's profile: the study's settings and the seed merged into the profile, which the
    // simulator then reads with its own checks.
    const auto text = case_profile(spec, triple, 2);
    const auto sim = parse_simulation_profile(text, "merged", spec.profile.parent_path());
    CHECK(sim.seed == 2);
    REQUIRE(sim.effects.size() == 3);
    const auto weak = case_profile(spec, cases[5], 1);  // rs_thermal near the limit: 5 K winding rise
    const auto weak_sim = parse_simulation_profile(weak, "merged", spec.profile.parent_path());
    CHECK(weak_sim.temp_winding.at(5.0) == 30.0);
    CHECK(weak_sim.temp_magnet.at(5.0) == 85.0);  // the profile's own
}

TEST_CASE("a study's designs run every case on each variant of the profile, and a label gives one effect more sizes", "[pmsm][study]") {
    testing::TemporaryDirectory dir;
    const std::string psi_10 = "[[effect]]\nname = \"psi_thermal\"\nlabel = \"psi_thermal_10K\"\n"
                               "clear = { effects.psi_thermal = {}, temperature.magnet = [[0.0, 20.0], [5.0, 30.0]] }\n";
    const std::string designs = "[[design]]\nname = \"slow\"\ndescription = \"half the speed\"\nsettings = { noise.current = 0.002 }\n"
                                "[[design]]\nname = \"quiet\"\nsettings = { noise.current = 0.0005, temperature.magnet = [[0.0, 20.0]] }\n";
    const auto file = dir.write("s.toml", study_text(profile_path(), deadtime + psi_thermal + psi_10 + designs));
    const auto spec = read_study(file);
    REQUIRE(spec.designs.size() == 2);
    CHECK(spec.designs[0].description == "half the speed");
    const auto cases = study_cases(spec);
    // Per design: clean, three clear, two weak, and the pairs of different effects (deadtime with each
    // size of psi_thermal; the two sizes of psi_thermal never together).
    const std::size_t per_design = 1 + 3 + 2 + 2;
    REQUIRE(cases.size() == 2 * per_design);
    CHECK(cases[0].design == "slow");
    CHECK(cases[per_design].design == "quiet");
    CHECK(case_name(cases[per_design]) == "quiet/clean");
    const auto ten = std::find_if(cases.begin(), cases.end(), [](const StudyCase& c) { return c.label == "psi_thermal_10K"; });
    REQUIRE(ten != cases.end());
    CHECK(ten->truth == std::vector<std::string>{"psi_thermal"});
    const auto pair = std::find_if(cases.begin(), cases.end(), [](const StudyCase& c) { return c.label == "deadtime+psi_thermal_10K"; });
    REQUIRE(pair != cases.end());
    CHECK(pair->truth == std::vector<std::string>{"deadtime", "psi_thermal"});
    // The design's settings are merged first; the case's own win where both set a key.
    const auto quiet_ten = std::find_if(cases.begin(), cases.end(), [](const StudyCase& c) { return c.design == "quiet" && c.label == "psi_thermal_10K"; });
    const auto sim = parse_simulation_profile(case_profile(spec, *quiet_ten, 1), "merged", spec.profile.parent_path());
    CHECK(sim.noise.current == 0.0005);
    CHECK(sim.temp_magnet.at(5.0) == 30.0);
    const auto quiet_clean = parse_simulation_profile(case_profile(spec, cases[per_design], 1), "merged", spec.profile.parent_path());
    CHECK(quiet_clean.temp_magnet.at(5.0) == 20.0);
    // --only sees the design.
    auto only = spec;
    only.only = "quiet/psi";
    CHECK(study_cases(only).size() == 3);

    // Effects the profile holds in every drive (a measured flux map) are in every case's truth.
    const auto held = read_study(dir.write("held.toml", study_text(profile_path(), "profile_effects = [\"saturation\"]\n" + deadtime)));
    const auto held_cases = study_cases(held);
    CHECK(held_cases.front().truth == std::vector<std::string>{"saturation"});
    CHECK(held_cases[1].truth == std::vector<std::string>{"deadtime", "saturation"});
}

TEST_CASE("a bad study file is refused naming the file, line and field", "[pmsm][study]") {
    testing::TemporaryDirectory dir;
    auto refused = [&](const std::string& text, const std::string& expected) {
        const auto file = dir.write("bad.toml", text);
        try {
            const auto spec = read_study(file);
            study_cases(spec);
            FAIL("accepted: " << text);
        } catch (const InputError& e) {
            CHECK_THAT(e.what(), Catch::Contains(expected));
        }
    };
    refused(study_text(profile_path(), "colour = 3\n"), "bad.toml:6: colour: unknown key");
    refused(study_text(profile_path(), "[[effect]]\nname = \"deadtiem\"\nclear = {}\nweak = {}\n"), "bad.toml:7: effect[0].name: ");
    refused(study_text(profile_path(), "pairs = [[\"deadtime\", \"delay\"]]\n" + deadtime), "pairs: 'delay' is not one of the study's [[effect]] names");
    refused(study_text(profile_path(), "[[effect]]\nname = \"delay\"\nclear = 3\nweak = {}\n"), "bad.toml:8: effect[0].clear: expects a table");
    // A stated true size must name a parameter of its own effect, be a number, and have a case to belong to.
    refused(study_text(profile_path(), "[[effect]]\nname = \"deadtime\"\nclear = {}\nweak = {}\nclear_size = { \"deadtime.volts\" = 0.28 }\n"),
            "bad.toml:10: effect[0].clear_size.deadtime.volts: not a parameter of deadtime: one of deadtime.voltage, deadtime.current_band");
    refused(study_text(profile_path(), "[[effect]]\nname = \"deadtime\"\nclear = {}\nweak = {}\nweak_size = { \"deadtime.voltage\" = \"a lot\" }\n"),
            "effect[0].weak_size.deadtime.voltage: expects a finite number");
    refused(study_text(profile_path(), "[[effect]]\nname = \"delay\"\nclear = {}\nweak_size = { \"delay.tau\" = 1e-5 }\n"),
            "effect[0].weak_size: there is no near-limit case");
    refused(study_text(profile_path(), "[[effect]]\nname = \"saturation\"\nclear = {}\npseudo_true_size = 1\n"),
            "bad.toml:9: effect[0].pseudo_true_size: expects true or false");
    refused(study_text(profile_path(), "[[effect]]\nname = \"saturation\"\nclear = {}\nclear_size = { \"saturation.cross\" = 0.1 }\npseudo_true_size = true\n"),
            "effect[0].pseudo_true_size: the sizes are either stated (clear_size, weak_size) or fitted");
    refused(study_text(profile_path(), deadtime + "[[effect]]\nname = \"deadtime\"\nclear = {}\n"), "effect[1].name: 'deadtime' is listed twice (a `label`");
    refused(study_text(profile_path(), deadtime + "[[effect]]\nname = \"deadtime\"\nlabel = \"dead time\"\nclear = {}\n"),
            "effect[1].label: expects a non-empty name without");
    refused(study_text(profile_path(), "[[design]]\nname = \"a\"\nsettings = {}\n[[design]]\nname = \"a\"\nsettings = {}\n"), "design[1].name: 'a' is listed twice");
    refused(study_text(profile_path(), "[[design]]\nname = \"a\"\n"), "design[0].settings: is required");
    refused(study_text(profile_path(), "[[design]]\nname = \"a\"\nsettings = {}\nspeed = 3\n"), "design[0].speed: unknown key");
    refused(study_text(profile_path(), "profile_effects = [\"deadtime\"]\n" + deadtime), "effect: 'deadtime' is in profile_effects");
    refused(study_text(profile_path(), "profile_effects = [\"saturaton\"]\n"), "profile_effects: ");
    // Two effects that set one profile key differently cannot make one drive.
    refused(study_text(profile_path(), "[[effect]]\nname = \"rs_thermal\"\nclear = { effects.rs_thermal = {}, temperature.winding = [[0.0, 25.0], [5.0, 30.0]] }\n"
                                       "weak = {}\n[[effect]]\nname = \"voltage_offset\"\n"
                                                    "clear = { effects.voltage_offset = {}, temperature.winding = [[0.0, 20.0]] }\nweak = {}\n"),
            "temperature.winding: set differently by ");
}

TEST_CASE("device plant, several noise seeds: clear effects found alone, in a pair and as a triple, no alarm on clean data, a sensor "
          "gain error outside the library",
          "[pmsm][study][hidden]") {
    // The drives come from the device plant (switching inverter, thermal network, sensors), which
    // shares no code with the model terms the diagnosis fits.
    testing::TemporaryDirectory dir;
    const std::string device_profile = std::string(MHBENCH_SOURCE_DIR) + "/experiments/pmsm/device_diagnosis_profile.toml";
    const std::string effects =
        "[[effect]]\nname = \"deadtime\"\nclear = { plant.inverter.dead_time = 1.0e-6 }\n"
        "[[effect]]\nname = \"rs_thermal\"\nclear = { plant.thermal = { enabled = true, winding_capacity = 0.04, winding_to_magnet = 1.0e6 } }\n"
        "[[effect]]\nname = \"psi_thermal\"\nclear = { plant.thermal = { enabled = true, winding_capacity = 1.0e6, winding_to_magnet = 1.0e6, "
        "initial_magnet = 60.0, magnet_capacity = 0.8, magnet_to_ambient = 3.0 } }\n"
        "[[together]]\neffects = [\"psi_thermal\", \"rs_thermal\"]\nsettings = { plant.thermal.winding_capacity = 0.04 }\n"
        "[[outside]]\nname = \"phase_a_gain\"\nsettings = { plant.current_sensors.gain_a = 1.02 }\n";
    const auto file = dir.write("s.toml", study_text(device_profile,
                                                     "pairs = [[\"deadtime\", \"rs_thermal\"]]\ntriples = [[\"deadtime\", \"psi_thermal\", \"rs_thermal\"]]\n" +
                                                         effects,
                                                     "[21, 22, 23]"));
    const auto spec = read_study(file);
    const auto run = run_study(spec, study_cases(spec), DiagnosisOptions{});
    REQUIRE(run.records.size() == 3 * (1 + 3 + 1 + 1 + 1));
    for (const auto& r : run.records) {
        const auto& c = run.cases[r.case_index];
        INFO(c.label << " seed " << r.seed << ": recommended " << r.recommended << (r.not_in_library ? ", not in the library" : ""));
        CHECK(r.correct);
        CHECK(r.false_positives.empty());
        CHECK(r.not_in_library == c.outside);
        // Refitted with the right set, the base parameters come back within a few per cent, and the
        // data determine an interval for each of them.
        if (r.correct && !c.outside) {
            CHECK(r.base_error.cwiseAbs().maxCoeff() < 0.05);
            for (int covered : r.covered) CHECK(covered >= 0);
        }
        // Dead time's pulse shift is stated beside every base parameter's interval; a clean drive's
        // intervals come without a mark and owe the truth.
        const bool dead_time = std::find(c.truth.begin(), c.truth.end(), "deadtime") != c.truth.end();
        for (std::size_t j = 0; j < 4; ++j) {
            if (r.correct && dead_time) CHECK(r.interval_marked[j]);
            if (c.kind == "clean") CHECK_FALSE(r.interval_marked[j]);
        }
    }
    const std::string table = study_markdown(spec, run);
    CHECK_THAT(table, Catch::Contains("95 % intervals holding the truth when correct: Rs, Ld, Lq, psi_f"));
    const auto record = study_record_json(run, run.records.front());
    CHECK(record["interval_holds_truth"].size() == 4);
    CHECK(record["interval_marked"].size() == 4);
    CHECK_THAT(table, Catch::Contains("the same of the intervals not marked (not valid, or a stated bias)"));
    CHECK(record["structure_left"].get<double>() >= 0.0);
    CHECK_THAT(table, Catch::Contains("the same where no structure is left"));
}

TEST_CASE("an outside case on a profile of its own counts as correct only when its mechanical order is named", "[pmsm][study][hidden]") {
    testing::TemporaryDirectory dir;
    const std::string whole_turns = std::string(MHBENCH_SOURCE_DIR) + "/experiments/pmsm/device_whole_turns_profile.toml";
    const std::string eccentric = "settings = { plant.rotor_flux = { eccentricity = 0.02, eccentricity_phase = 0.6 } }\n";
    const auto file = dir.write(
        "s.toml", study_text(profile_path(),
                             "[[outside]]\nname = \"eccentric\"\nprofile = \"" + whole_turns + "\"\nmechanical_order = 1\n" + eccentric +
                                 "[[outside]]\nname = \"claimed_twice_per_turn\"\nprofile = \"" + whole_turns + "\"\nmechanical_order = 2\n" + eccentric,
                             "[5]"));
    const auto spec = read_study(file);
    auto cases = study_cases(spec);
    std::erase_if(cases, [](const StudyCase& c) { return c.kind == "clean"; });
    REQUIRE(cases.size() == 2);
    CHECK(cases[0].profile == whole_turns);
    const auto run = run_study(spec, cases, DiagnosisOptions{});
    REQUIRE(run.records.size() == 2);
    for (const auto& r : run.records) {
        INFO(run.cases[r.case_index].label);
        CHECK(r.not_in_library);
        CHECK(r.found.empty());
        CHECK(r.mechanical_orders == std::vector<int>{1});
    }
    CHECK(run.records[0].correct);
    CHECK_FALSE(run.records[1].correct);  // "not in the library" said, but not at the order the case states
    CHECK(study_record_json(run, run.records[0])["mechanical_orders"] == nlohmann::ordered_json::array({1}));
}

TEST_CASE("an outside case's profile and mechanical order are checked", "[pmsm][study]") {
    testing::TemporaryDirectory dir;
    auto refused = [&](const std::string& extra, const std::string& expected) {
        const auto file = dir.write("bad.toml", study_text(profile_path(), extra));
        try {
            read_study(file);
            FAIL("accepted: " << extra);
        } catch (const InputError& e) {
            CHECK_THAT(e.what(), Catch::Contains(expected));
        }
    };
    refused("[[outside]]\nname = \"x\"\nsettings = {}\nmechanical_order = 5\n", "outside[0].mechanical_order: expects a whole number in [1, 4]");
    refused("[[outside]]\nname = \"x\"\nsettings = {}\nmechanical_order = \"once\"\n", "outside[0].mechanical_order");
    refused("[[outside]]\nname = \"x\"\nsettings = {}\nprofile = \"no_such_profile.toml\"\n", "no_such_profile.toml");
    refused("[[outside]]\nname = \"x\"\nsettings = {}\norder = 1\n", "outside[0].order: unknown key");
}

TEST_CASE("a study on a saturating plant records how far the recommended flux model lies from the plant's", "[pmsm][study]") {
    // One drive of the Baldor study (the measured map as the plant) and one clean drive of a linear plant.
    auto baldor = read_study(std::filesystem::path(MHBENCH_SOURCE_DIR) / "experiments" / "pmsm" / "baldor_study.toml");
    baldor.only = "low_small_quiet/clean";
    baldor.seeds = {1};
    const StudyRun saturated = run_study(baldor, study_cases(baldor), DiagnosisOptions{});
    REQUIRE(saturated.records.size() == 1);
    const StudyRecord& r = saturated.records.front();
    CHECK(r.recommended == "base+saturation");
    // The bound for the fitted law against the measured map over the logged currents: 3 %.
    REQUIRE(std::isfinite(r.flux_error));
    CHECK(r.flux_error > 0.0);
    CHECK(r.flux_error < 0.03);
    CHECK(study_record_json(saturated, r).contains("flux_error"));

    testing::TemporaryDirectory dir;
    auto linear = read_study(dir.write("s.toml", study_text(profile_path(), "", "[1]")));
    const StudyRun clean = run_study(linear, study_cases(linear), DiagnosisOptions{});
    REQUIRE(clean.records.size() == 1);
    CHECK(std::isnan(clean.records.front().flux_error));
    CHECK_FALSE(study_record_json(clean, clean.records.front()).contains("flux_error"));
}

TEST_CASE("a law the plant does not share is sized by fitting it to the drive without noise, and a miss below what that shows is below the limit",
          "[pmsm][study]") {
    // The servo study's saturating iron (its own law, not the library's) at its two sizes, one seed each.
    auto spec = read_study(std::filesystem::path(MHBENCH_SOURCE_DIR) / "experiments" / "pmsm" / "detection_study.toml");
    spec.only = "saturation";
    spec.seeds = {1};
    const StudyRun run = run_study(spec, study_cases(spec), DiagnosisOptions{});
    REQUIRE(run.records.size() == 2);
    for (const auto& r : run.records) {
        const StudyCase& c = run.cases[r.case_index];
        INFO(c.magnitude << ": " << r.recommended);
        REQUIRE(c.pseudo_true_sized == std::vector<std::string>{"saturation"});
        // Every size parameter of the law, none of its shapes (knee, exponent).
        CHECK(r.pseudo_true_size.size() == 4);
        CHECK(r.pseudo_true_size.count("saturation.cross") == 1);
        CHECK(r.pseudo_true_size.count("saturation.q_knee") == 0);
        CHECK(r.pseudo_true_evidence > 0.0);
        CHECK(r.pseudo_true_voltage > 0.0);
        const auto json = study_record_json(run, r);
        CHECK(json.contains("pseudo_true_size"));
        CHECK(json.contains("pseudo_true_shows"));
    }
    const StudyRecord& clear = run.records[0];
    const StudyRecord& weak = run.records[1];
    REQUIRE(run.cases[clear.case_index].magnitude == "clear");
    // The iron that saturates at 0.3 A shows more than twice what the search needs; at 0.6 A, less than half.
    CHECK(clear.pseudo_true_evidence > 2.0 * clear.pseudo_true_needed);
    CHECK(weak.pseudo_true_evidence < 0.5 * weak.pseudo_true_needed);
    CHECK(weak.pseudo_true_evidence < clear.pseudo_true_evidence);
    CHECK_FALSE(clear.pseudo_true_below());
    CHECK(weak.pseudo_true_below());
    // A miss of the weak one is a miss below this log's limit, and the answer right for this log.
    if (!weak.correct) {
        CHECK(weak.below_limit == std::vector<std::string>{"saturation"});
        CHECK(weak.right_for_this_log());
    }
    // Cases without the key fit nothing.
    auto plain = read_study(std::filesystem::path(MHBENCH_SOURCE_DIR) / "experiments" / "pmsm" / "detection_study.toml");
    for (const auto& c : study_cases(plain))
        if (c.label != "saturation") CHECK(c.pseudo_true_sized.empty());
}

TEST_CASE("a drive whose simulation fails stops the study with its case and seed named, also on two threads", "[pmsm][study]") {
    // The 5 kW machine's iron saturating at 12 A cannot carry its profile's loads: the saturating law
    // bounds the q flux at L_q I_sat, and a transient asks for more ("no current produces the flux
    // linkage"). On two threads the clean drives are being diagnosed while it fails; the failure used
    // to leave the task and cancel their parallel work, which crashed (SIGSEGV) instead of reporting.
    testing::TemporaryDirectory dir;
    const std::string profile = std::string(MHBENCH_SOURCE_DIR) + "/experiments/pmsm/device_5kw_profile.toml";
    const auto file = dir.write("s.toml", study_text(profile, "[[effect]]\nname = \"saturation\"\nclear = { plant.saturation.saturation_current = 12.0 }\n",
                                                     "[1, 2]"));
    const auto spec = read_study(file);
    tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
    CHECK_THROWS_MATCHES(run_study(spec, study_cases(spec), DiagnosisOptions{}), InputError,
                         Catch::Predicate<InputError>(
                             [](const InputError& e) {
                                 const std::string m = e.what();
                                 return m.find("case saturation") != std::string::npos && m.find("simulation failed") != std::string::npos &&
                                        m.find("no current produces the flux linkage") != std::string::npos;
                             },
                             "names the case, says the simulation failed and why"));
}

TEST_CASE("a study of raw logs finds each drive's operating points and sets the noise it measures beside the simulated", "[pmsm][study]") {
    // The averaged servo logged as a bench logs it, every settling and no segment column: the
    // diagnosis finds the windows itself, one per operating point of the profile, and measures the
    // noise from the data; the study's truth is the same drive simulated without noise.
    testing::TemporaryDirectory dir;
    const std::string raw = "[[design]]\nname = \"raw\"\nsettings = { logging.transients = true, logging.segment = false }\n";
    const auto spec = read_study(dir.write("s.toml", study_text(profile_path(), raw, "[1, 2]")));
    const std::size_t segments = read_simulation_profile(profile_path()).segments.size();
    const StudyRun run = run_study(spec, study_cases(spec), DiagnosisOptions{});
    REQUIRE(run.records.size() == 2);
    for (const auto& r : run.records) {
        CHECK(r.raw());
        CHECK(r.windows == segments);
        CHECK(r.recommended == "base");
        for (int a = 0; a < 2; ++a) {
            INFO("seed " << r.seed << ", axis " << a);
            CHECK(r.noise_simulated[a] > 0.0);
            CHECK(r.noise_from_data[a] == Approx(r.noise_simulated[a]).epsilon(0.2));
        }
        const auto json = study_record_json(run, r);
        CHECK(json.at("steady_windows_found") == segments);
        CHECK(json.contains("noise_simulated"));
    }
    CHECK_THAT(study_markdown(spec, run), Catch::Contains("noise within 20 % on both axes") && Catch::Contains("| 2/2 |"));
    CHECK_THAT(study_csv(run), Catch::Contains("noise_within_20_percent"));

    // A log with its segments measures nothing of the kind, and its outputs say nothing of it.
    const auto steady = read_study(dir.write("steady.toml", study_text(profile_path(), "", "[1]")));
    const StudyRun logged = run_study(steady, study_cases(steady), DiagnosisOptions{});
    REQUIRE(logged.records.size() == 1);
    CHECK_FALSE(logged.records.front().raw());
    CHECK_FALSE(study_record_json(logged, logged.records.front()).contains("noise_simulated"));
    CHECK_THAT(study_markdown(steady, logged), !Catch::Contains("noise within 20 %"));
}

TEST_CASE("a study that states the current loop tells each device drive's diagnosis the loop's bandwidth (an example: one drive)",
          "[pmsm][study]") {
    // Seed 1 of the 5 kW machine's dead time with winding heating: without the loop the search adds a
    // flux harmonic for what the 400 Hz loop leaves in the current (docs/diagnosis.md, section 8);
    // told the loop, it finds both effects (15 of 20 seeds with the loop in time, 2026-11-27).
    auto spec = read_study(std::filesystem::path(MHBENCH_SOURCE_DIR) / "experiments" / "pmsm" / "detection_study_5kw.toml");
    spec.only = "deadtime+rs_thermal";
    spec.seeds = {1};
    CHECK(spec.current_loop);  // the 5 kW study states it
    const StudyRun run = run_study(spec, study_cases(spec), DiagnosisOptions{});
    REQUIRE(run.records.size() == 1);
    // Winding heating's coefficient may be held at copper's value, which is the plant's.
    INFO("recommended " << run.records.front().recommended);
    CHECK(run.records.front().correct);
    CHECK(study_markdown(spec, run).find("told the drive's current-loop bandwidth") != std::string::npos);

    testing::TemporaryDirectory dir;
    const auto file = dir.write("s.toml", study_text(profile_path(), "current_loop = 1\n"));
    try {
        read_study(file);
        FAIL("a current_loop that is not a boolean was accepted");
    } catch (const InputError& e) {
        CHECK(e.field() == "current_loop");
        CHECK(std::string(e.what()).find("expects true or false") != std::string::npos);
    }
}
