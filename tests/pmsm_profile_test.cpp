#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <set>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "framework/input_error.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
using namespace mhb::pmsm;

namespace {

const std::filesystem::path experiments = std::filesystem::path(MHBENCH_SOURCE_DIR) / "experiments" / "pmsm";

InputError profile_refusal(const std::string& text) {
    try {
        parse_simulation_profile(text, "p.toml", ".");
    } catch (const InputError& e) {
        return e;
    }
    FAIL("the profile was accepted:\n" << text);
    throw std::logic_error("unreachable");
}

const std::string minimal_segment = "[[segment]]\nspeed = 10.0\nsamples = 5\n";

}  // namespace

TEST_CASE("the paper profile is the seed's data collection", "[pmsm][profile]") {
    const auto spec = read_simulation_profile(experiments / "paper_profile.toml");
    CHECK(spec.motor.rs == 46.0);
    CHECK(spec.motor.ld == 0.02025);
    CHECK(spec.motor.lq == 0.02025);
    CHECK(spec.motor.psi_f == 0.04375);
    CHECK(spec.motor.pole_pairs == 16);
    CHECK(spec.mechanics.total_inertia() == Approx(1e-4 + 1.07 / 1e4));
    CHECK(spec.logging.period == 0.4e-3);
    REQUIRE(spec.segments.size() == 2);
    CHECK(spec.segments[0].samples + spec.segments[1].samples == 1000);
    CHECK(spec.segments[0].i_d == 0.0);
    CHECK(spec.segments[1].i_d == -0.1);
    // The injection lasts settle + window = 600 ms.
    CHECK(spec.segments[1].settle + spec.segments[1].samples * spec.logging.period == Approx(0.6));
    CHECK(spec.segments[0].speed_rpm == 10.0);
    CHECK(spec.effects.empty());

    const auto result = simulate(spec);
    CHECK(result.data.size() == 1000);
    CHECK(result.data.segment_labels == std::vector<std::string>{"id0", "id-0.1"});
    // About one electrical period at 10 r/min: 16 * 10 / 60 Hz for 0.4 s.
    CHECK(result.data.omega_e.mean() == Approx(16 * 10 * 2 * std::numbers::pi / 60).epsilon(1e-3));

    const testing::TemporaryDirectory dir;
    const auto path = dir.path() / "paper_profile.csv";
    write_simulation(path, spec, result, "paper_profile.toml");
    const auto truth = read_sidecar_truth(path);
    REQUIRE(truth.has_value());
    CHECK(*truth == Eigen::Vector4d(46.0, 0.02025, 0.02025, 0.04375));
    std::ifstream in(sidecar_path(path));
    const auto j = nlohmann::json::parse(in);
    CHECK(j["seed"] == 1);
    CHECK(j["noise"]["current"] == 1e-3);
    CHECK(j["segments"][1]["first_row"] == 500);
    CHECK(j["profile"] == "paper_profile.toml");
    CHECK(read_measurement(path).u_q == result.data.u_q);
}

TEST_CASE("the multi-point profile covers both directions, loads and d currents", "[pmsm][profile]") {
    const auto spec = read_simulation_profile(experiments / "multi_point_profile.toml");
    REQUIRE(spec.segments.size() >= 8);
    std::set<double> speeds, currents, loads;
    for (const auto& s : spec.segments) {
        speeds.insert(s.speed_rpm);
        currents.insert(s.i_d);
        loads.insert(s.load_torque);
    }
    CHECK(*speeds.begin() < 0);
    CHECK(*speeds.rbegin() > 0);
    CHECK(speeds.size() >= 4);
    CHECK(currents.size() >= 3);
    CHECK(loads.size() >= 3);
}

TEST_CASE("effects, temperatures and logging switches are read from the profile", "[pmsm][profile]") {
    const auto spec = parse_simulation_profile(R"(
[drive]
control_period = 50e-6
integration_step = 5e-6
[logging]
period = 0.2e-3
theta = false
[temperature]
winding = [[0.0, 25.0], [2.0, 45.0]]
magnet = 30
[effects.deadtime]
voltage = 0.3
[effects.encoder_offset]
enabled = false
offset = 0.05
[effects.saturation]
flux_map = "map.csv"
q_self = 0.1
[[segment]]
label = 7
speed = -5
duration = 0.01
)", "p.toml", "/data");
    CHECK(spec.control.control_period == 50e-6);
    CHECK_FALSE(spec.logging.theta);
    CHECK(spec.logging.temperatures);
    CHECK(spec.temp_winding.at(1.0) == Approx(35.0));
    CHECK(spec.temp_winding.at(5.0) == 45.0);
    CHECK(spec.temp_magnet.at(0.3) == 30.0);
    REQUIRE(spec.effects.size() == 2);  // encoder_offset is switched off
    CHECK(spec.effects[0]->name() == "deadtime");
    CHECK(spec.effects[0]->values()[0] == 0.3);
    CHECK(spec.effects[1]->name() == "saturation");
    CHECK(spec.effects[1]->settings().text("flux_map") == "map.csv");
    CHECK(spec.base_directory == "/data");
    CHECK(spec.segments[0].label == "7");
    CHECK(spec.segments[0].samples == 50);
}

TEST_CASE("bad profiles are refused naming file, line and field", "[pmsm][profile]") {
    SECTION("TOML syntax") {
        const auto e = profile_refusal("[motor]\nrs = = 3\n");
        CHECK(e.file() == "p.toml");
        CHECK(e.line() == 2);
    }
    SECTION("unknown key") {
        const auto e = profile_refusal("[motor]\nrs = 46\nresistance = 3\n" + minimal_segment);
        CHECK(e.line() == 3);
        CHECK(e.field() == "motor.resistance");
    }
    SECTION("unknown table") {
        const auto e = profile_refusal("[motors]\nrs = 46\n" + minimal_segment);
        CHECK(e.field() == "motors");
    }
    SECTION("wrong type") {
        const auto e = profile_refusal("[drive]\ndc_voltage = \"28 V\"\n" + minimal_segment);
        CHECK(e.line() == 2);
        CHECK(e.field() == "drive.dc_voltage");
    }
    SECTION("out of range") {
        const auto e = profile_refusal("[motor]\n\nld = -0.02\n" + minimal_segment);
        CHECK(e.line() == 3);
        CHECK(e.field() == "motor.ld");
    }
    SECTION("integration step that does not divide the control period") {
        const auto e = profile_refusal("[drive]\ncontrol_period = 100e-6\nintegration_step = 30e-6\n" + minimal_segment);
        CHECK(e.line() == 3);
        CHECK(e.field() == "drive.integration_step");
    }
    SECTION("logging period that is not a whole number of control periods") {
        const auto e = profile_refusal("[logging]\nperiod = 0.25e-3\n" + minimal_segment);
        CHECK(e.line() == 2);
        CHECK(e.field() == "logging.period");
    }
    SECTION("unknown effect") {
        const auto e = profile_refusal("[effects.backlash]\nangle = 1\n" + minimal_segment);
        CHECK(e.field() == "effects.backlash");
        CHECK(e.message().find("deadtime") != std::string::npos);
    }
    SECTION("effect parameter out of its plausible range") {
        const auto e = profile_refusal("[effects.deadtime]\nvoltage = 0.2\ncurrent_band = -1\n" + minimal_segment);
        CHECK(e.line() == 3);
        CHECK(e.field() == "effects.deadtime.current_band");
    }
    SECTION("unknown effect parameter") {
        const auto e = profile_refusal("[effects.delay]\ntau = 1e-4\ntaux = 1\n" + minimal_segment);
        CHECK(e.line() == 3);
        CHECK(e.field() == "effects.delay.taux");
    }
    SECTION("no segment") {
        const auto e = profile_refusal("[motor]\nrs = 46\n");
        CHECK(e.field() == "segment");
    }
    SECTION("segment with both samples and duration") {
        const auto e = profile_refusal("[[segment]]\nspeed = 1\nsamples = 3\nduration = 1.0\n");
        CHECK(e.line() == 1);
        CHECK(e.field() == "segment[1]");
    }
    SECTION("label that CSV cannot carry") {
        const auto e = profile_refusal("[[segment]]\nsamples = 3\n[[segment]]\nsamples = 3\nlabel = \"a,b\"\n");
        CHECK(e.line() == 5);
        CHECK(e.field() == "segment[2].label");
    }
    SECTION("an integer beyond 2^53 where a number is expected (toml++ gives no double for it)") {
        const auto e = profile_refusal("[motor]\nrs = 9007199254740993\n" + minimal_segment);
        CHECK(e.line() == 2);
        CHECK(e.field() == "motor.rs");
        CHECK(e.message().find("9007199254740993") != std::string::npos);
        const auto speed = profile_refusal("[[segment]]\nsamples = 3\nspeed = 18888888888888888\n");
        CHECK(speed.line() == 3);
        CHECK(speed.field() == "segment[1].speed");
        const auto point = profile_refusal("[temperature]\nwinding = [[0, 20],\n  [9007199254740993, 30]]\n" + minimal_segment);
        CHECK(point.line() == 3);
        CHECK(point.field() == "temperature.winding");
    }
    SECTION("more samples in total than the stated limit, refused before anything is simulated") {
        const std::string half = fmt::format("[[segment]]\nsamples = {}\n", max_measurement_rows / 2 + 1);
        const auto e = profile_refusal(half + half);
        CHECK(e.line() == 3);
        CHECK(e.field() == "segment[2]");
        CHECK(e.message().find(std::to_string(max_measurement_rows)) != std::string::npos);
        const auto one = profile_refusal(fmt::format("[[segment]]\nsamples = {}\n", max_measurement_rows + 1));
        CHECK(one.field() == "segment[1].samples");
        // 10^5 s at the default 0.4 ms logging period is 2.5 * 10^8 samples.
        const auto duration = profile_refusal("[[segment]]\nduration = 1e5\n");
        CHECK(duration.line() == 2);
        CHECK(duration.field() == "segment[1].duration");
        CHECK(duration.message().find(std::to_string(max_measurement_rows)) != std::string::npos);
    }
    SECTION("temperature points out of order") {
        const auto e = profile_refusal("[temperature]\nwinding = [[0, 20], [2, 30],\n  [1, 40]]\n" + minimal_segment);
        CHECK(e.line() == 3);
        CHECK(e.field() == "temperature.winding");
    }
}

TEST_CASE("a sidecar that is not JSON is refused with its line", "[pmsm][profile]") {
    const testing::TemporaryDirectory dir;
    const auto csv = dir.path() / "bad_sidecar.csv";
    std::ofstream(sidecar_path(csv)) << "{\n  \"true_parameters\": {\n    \"Rs\": 4,\n  }\n}\n";
    try {
        read_sidecar_truth(csv);
        FAIL("accepted");
    } catch (const InputError& e) {
        CHECK(e.line() == 4);
    }
    std::ofstream(sidecar_path(csv)) << R"({"true_parameters": {"Rs": 4, "Ld": 1, "Lq": 2}})";
    CHECK_THROWS_AS(read_sidecar_truth(csv), InputError);
    std::ofstream(sidecar_path(csv)) << R"({"seed": 4})";
    CHECK_FALSE(read_sidecar_truth(csv).has_value());
}

TEST_CASE("the flux-map profile drives the measured machine from the repository's copy of the map", "[pmsm][profile]") {
    const auto spec = read_simulation_profile(experiments / "flux_map_profile.toml");
    REQUIRE(spec.effects.size() == 1);
    CHECK(spec.effects[0]->name() == "saturation");
    const auto result = simulate(spec);
    CHECK(result.data.size() == 700);
    CHECK(result.data.i_q.cwiseAbs().maxCoeff() > 10.0);  // well into saturation
    const testing::TemporaryDirectory dir;
    const auto path = dir.path() / "flux_map_profile.csv";
    write_simulation(path, spec, result, "flux_map_profile.toml");
    // A flux map has no single Ld, Lq: the sidecar says so instead of giving true parameters.
    CHECK_FALSE(read_sidecar_truth(path).has_value());
    std::ifstream in(sidecar_path(path));
    const auto j = nlohmann::json::parse(in);
    CHECK(j.contains("true_parameters_note"));
}
