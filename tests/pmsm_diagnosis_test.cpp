// The parts of a diagnosis beyond ranking: ties stated instead of decided, implausible fits, effects
// the data cannot carry, and `mhbench diagnose` with its JSON contract and its report.
#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <numbers>
#include <regex>

#include <nlohmann/json.hpp>

#include "problems/pmsm/data/measurement.hpp"
#include "problems/pmsm/report/diagnosis_report.hpp"
#include "tests/gnuplot_data_rows.hpp"
#include "tests/pmsm_diagnosis_fixture.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
using namespace mhb::pmsm;
using namespace mhb::pmsm::testing;

namespace {

const Candidate* candidate(const Diagnosis& d, const std::string& effect) {
    for (const auto& c : d.candidates)
        if (c.effect == effect) return &c;
    return nullptr;
}

}  // namespace

TEST_CASE("at one speed in one direction an encoder offset and a voltage offset are a tie, with the experiment that separates them",
          "[pmsm][diagnosis]") {
    // Both leave a constant on u_d when the speed does not change: omega psi_f delta, or u_d0.
    auto spec = read_simulation_profile(profile_path("diagnosis_profile.toml"));
    spec.segments = {{"a", 10.0, 0.05, 0.0, 0.8, 150},  {"b", 10.0, 0.10, -0.15, 0.3, 150}, {"c", 10.0, 0.15, -0.3, 0.3, 150},
                     {"d", 10.0, 0.10, 0.0, 0.3, 150},  {"e", 10.0, 0.05, -0.3, 0.3, 150},  {"f", 10.0, 0.15, -0.15, 0.3, 150}};
    spec.logging.temperatures = false;
    spec.effects.push_back(make_effect("encoder_offset", {{"offset", 0.05}}));
    const auto data = simulate(spec).data;
    const auto d = diagnose(data, parse_model_spec("base"), DiagnosisOptions{});
    CHECK(d.missing_effect_found);
    CHECK_FALSE(d.winner);
    REQUIRE(d.tie.size() >= 2);
    CHECK(std::find(d.tie.begin(), d.tie.end(), "encoder_offset") != d.tie.end());
    CHECK(std::find(d.tie.begin(), d.tie.end(), "voltage_offset") != d.tie.end());
    std::vector<std::string> experiments;
    for (const auto& e : d.tie_experiments) experiments.push_back(e.name);
    CHECK(std::find(experiments.begin(), experiments.end(), "the other direction") != experiments.end());
    CHECK(std::find(experiments.begin(), experiments.end(), "another speed") != experiments.end());
    // Another d-axis current does not separate two constants on u_d.
    CHECK(std::find(experiments.begin(), experiments.end(), "another d-axis current") == experiments.end());
    // Effects needing temperatures were not tried, and the diagnosis says which column is missing.
    REQUIRE(d.not_tried.size() == 2);
    for (const auto& n : d.not_tried) CHECK(n.column == (n.effect == "rs_thermal" ? "temp_winding" : "temp_magnet"));
}

TEST_CASE("a candidate whose fit needs an impossible value is called implausible and ranked below", "[pmsm][diagnosis]") {
    // The clean diagnosis data log temperatures that the plant ignores: rs_thermal can only fit with
    // alpha at the lower end of its copper range, and is worse than no effect at all.
    const auto d = diagnose(diagnosis_data({}), parse_model_spec("base"), DiagnosisOptions{});
    const auto* rs = candidate(d, "rs_thermal");
    REQUIRE(rs);
    CHECK(rs->verdict == Verdict::Implausible);
    CHECK_FALSE(rs->plausible);
    REQUIRE_FALSE(rs->implausible.empty());
    CHECK(rs->implausible.front().find("rs_thermal.alpha") != std::string::npos);
    CHECK(rs->delta_bic > 0.0);
    CHECK(&d.candidates.back() >= rs);
    for (const auto& c : d.candidates)
        if (c.verdict == Verdict::NotSupported) CHECK(&c < rs);
}

TEST_CASE("mhbench diagnose writes the JSON contract and a report with plots, before and after", "[pmsm][diagnosis][cli]") {
    mhb::testing::TemporaryDirectory dir;
    const auto csv = dir.path() / "hidden.csv";
    write_measurement(csv, diagnosis_data({{"encoder_offset", {}}}));
    const auto json_path = dir.path() / "diagnosis.json";
    const auto report = dir.path() / "report";
    auto run = run_mhbench("diagnose --data " + csv.string() + " --model base --json " + json_path.string() + " --report " + report.string(),
                           dir.path() / "log");
    INFO(run.output);
    REQUIRE(run.exit_code == 0);
    CHECK(run.output.find("Missing effect: encoder_offset") != std::string::npos);
    const auto j = nlohmann::json::parse(mhb::testing::read_file(json_path));
    CHECK(j["model"] == "base");
    CHECK(j["missing_effect_found"] == true);
    CHECK(j["winner"] == "encoder_offset");
    for (const char* name : {"Rs", "Ld", "Lq", "psi_f"}) CHECK(j["parameters"][name]["ci95"].size() == 2);
    REQUIRE(j["candidates"].size() == 9);
    const auto& first = j["candidates"][0];
    CHECK(first["effect"] == "encoder_offset");
    CHECK(first["plausible"] == true);
    CHECK(first["rms_after"]["total"].get<double>() < j["rms"]["total"].get<double>());
    CHECK(first["parameters"]["encoder_offset.offset"]["ci95"].size() == 2);
    CHECK(first["parameters"]["Rs"]["value"].get<double>() > 0.0);
    for (std::size_t k = 1; k < j["candidates"].size(); ++k) CHECK(j["candidates"][k]["rms_after"]["total"].is_number());
    // The search over sets: one step, to the recommended model, whose rms is that candidate's.
    CHECK(j["recommended_model"] == "base+encoder_offset");
    REQUIRE(j["path"].size() == 2);
    CHECK(j["path"][0]["model"] == "base");
    CHECK(j["path"][0]["rms"].get<double>() == j["rms"]["total"].get<double>());
    CHECK(j["path"][1]["model"] == "base+encoder_offset");
    CHECK(j["path"][1]["rms"].get<double>() == first["rms_after"]["total"].get<double>());
    CHECK(j["path"][1]["dbic"].get<double>() < -10.0);
    CHECK(run.output.find("next: mhbench fit --data " + csv.string() + " --model base+encoder_offset") != std::string::npos);
    // base misses the offset, so its intervals are not valid; the recommended model's are.
    CHECK(j["intervals_valid"] == false);
    CHECK(j["recommended_intervals_valid"] == true);
    // An encoder offset states no bias beyond its intervals, and no law was reduced.
    CHECK(j["recommended_interval_caveats"].is_array());
    CHECK(j["recommended_interval_caveats"].empty());
    CHECK(run.output.find("Model incomplete: the 95 % intervals of base are not valid") != std::string::npos);
    // A limit for each size of each effect left out: none for the recommended offset, none for a shape.
    bool dead_time_voltage = false;
    for (const auto& l : j["detection_limits"]) {
        CHECK(l["effect"] != "encoder_offset");
        CHECK(l["parameter"] != "deadtime.current_band");
        if (l["parameter"] == "deadtime.voltage") dead_time_voltage = l["limit"].get<double>() > 0.0;
        // Which of the search's tests sets it, for every finite limit.
        if (!l["limit"].is_null()) CHECK((l["set_by"] == "evidence" || l["set_by"] == "relevant size"));
    }
    CHECK(dead_time_voltage);
    // No law with a stated accuracy is in the recommended set: nothing stands in for one.
    CHECK(j["law_stand_ins"].is_array());
    CHECK(j["law_stand_ins"].empty());

    // The report: every image it shows exists, and it names the missing effect.
    const std::string md = mhb::testing::read_file(report / "report.md");
    CHECK(md.find("Missing effect: encoder_offset") != std::string::npos);
    CHECK(md.find("mhbench fit --data " + csv.string() + " --model base+encoder_offset") != std::string::npos);
    int images = 0;
    const std::regex image(R"(!\[[^\]]*\]\(([^)]+)\))");
    for (auto it = std::sregex_iterator(md.begin(), md.end(), image); it != std::sregex_iterator(); ++it, ++images)
        CHECK(std::filesystem::exists(report / (*it)[1].str()));
    for (const char* png : {"residual_time.png", "residual_angle.png", "residual_speed.png", "residual_current.png", "residual_temperature.png",
                            "segment_rms.png", "apparent_parameters.png", "candidates.png", "path.png"})
        CHECK(md.find(png) != std::string::npos);
    CHECK(images == 9);
    // Beside base, the plots and the table of segments show what the recommended model leaves: its
    // residual, recomputed for the plot from its parameters, has the rms its fit in the search had.
    CHECK(md.find("rms recommended") != std::string::npos);
    const auto rows = mhb::testing::data_rows(report / "plot-data" / "residual_time.dat");
    std::size_t logged = 0;
    for (const auto& segment : j["segments"]) logged += segment["rows"].get<std::size_t>();
    REQUIRE(rows.size() == logged);
    double squares = 0.0;
    for (const auto& row : rows) {
        REQUIRE(row.size() == 7);  // x, the model's r_d r_q, base's, the recommended model's
        squares += row[5] * row[5] + row[6] * row[6];
    }
    CHECK(std::sqrt(squares / (2.0 * static_cast<double>(rows.size()))) == Approx(j["path"][1]["rms"].get<double>()).epsilon(1e-5));
    CHECK(mhb::testing::read_file(report / "plot-data" / "residual_time.gp").find("recommended base+encoder_offset") != std::string::npos);
    const auto bars = mhb::testing::read_file(report / "plot-data" / "segment_rms.dat");
    CHECK(bars.find("recommended_total") != std::string::npos);

    // The next round shows the error before and after.
    run = run_mhbench("diagnose --data " + csv.string() + " --model base+encoder_offset --report " + report.string(), dir.path() / "log");
    REQUIRE(run.exit_code == 0);
    CHECK(run.output.find("No missing effect") != std::string::npos);
    CHECK(run.output.find("detection limits of this log") != std::string::npos);
    const std::string after = mhb::testing::read_file(report / "report.md");
    CHECK(after.find("Error before and after the effects") != std::string::npos);
    CHECK(after.find("| `base` |") != std::string::npos);
    CHECK(after.find("| `base+encoder_offset` |") != std::string::npos);
    // The model diagnosed is the one recommended: nothing is drawn twice.
    CHECK(after.find("rms recommended") == std::string::npos);
    for (const auto& row : mhb::testing::data_rows(report / "plot-data" / "residual_time.dat")) CHECK(row.size() == 5);

    run = run_mhbench("diagnose --data " + csv.string() + " --model 'base+rs_thermal(alpha=0.01)'", dir.path() / "log");
    CHECK(run.exit_code == 2);
    CHECK(run.output.find("error: --model: rs_thermal.alpha: 0.01 is outside the plausible range [0.0035, 0.0045] 1/K") != std::string::npos);
}

TEST_CASE("mhbench diagnose --report into a directory named in shell syntax runs nothing", "[pmsm][diagnosis][cli][plots]") {
    mhb::testing::TemporaryDirectory dir;
    const auto csv = dir.path() / "hidden.csv";
    write_measurement(csv, diagnosis_data({{"encoder_offset", {}}}));
    const auto marker = dir.path() / "pwned";
    const auto report = dir.path() / ("rep_$(touch " + marker.string() + ")`touch " + marker.string() + "`'");
    const auto run = run_mhbench(std::vector<std::string>{"diagnose", "--data", csv.string(), "--model", "base", "--report", report.string()},
                                 dir.path() / "log");
    INFO(run.output);
    REQUIRE(run.exit_code == 0);
    REQUIRE(std::filesystem::exists(report / "report.md"));
    REQUIRE(std::filesystem::exists(report / "candidates.png"));
    REQUIRE_FALSE(std::filesystem::exists(marker));
}

TEST_CASE("an effect turned down for its held-out prediction is named with what it would explain (an example: one drive)",
          "[pmsm][diagnosis][search]") {
    // Seed 1 of the device study's clear saturation: nine operating points for the law's six
    // parameters. The search's evidence for saturation is strong and it explains most of what base
    // leaves, but fitted without one operating point it predicts that point worse in most of them.
    // Only the whole law is offered here (a law with fewer terms is: tests/pmsm_effect_set_search_test.cpp).
    auto drive = read_simulation_profile(std::string(MHBENCH_SOURCE_DIR) + "/experiments/pmsm/device_diagnosis_profile.toml");
    drive.seed = 1;
    drive.device->saturation.saturation_current = 0.3;
    DiagnosisOptions options;
    options.pole_pairs = drive.motor.pole_pairs;
    options.reduced_laws = false;
    const Diagnosis d = diagnose(simulate(drive).data, parse_model_spec("base"), options);
    REQUIRE(d.recommended.text() == "base");
    REQUIRE(d.unpredictive.size() == 1);
    const auto& u = d.unpredictive.front();
    CHECK(u.effect == "saturation");
    CHECK(u.delta_bic < -10.0);
    CHECK(u.explained > 0.5);
    CHECK(u.held_out.segments == 9);
    CHECK(2 * u.held_out.better < u.held_out.segments);
    CHECK(std::any_of(d.findings.begin(), d.findings.end(),
                      [](const std::string& f) { return f.rfind("saturation would explain", 0) == 0; }));
    CHECK(diagnosis_json(d).at("unpredictive_additions").size() == 1);
}

namespace {

// The 100 kW study's deadtime+rs_thermal drive of `seed`: a 1 us dead time and a winding heating
// from 32 to 163 °C, steady segments (experiments/pmsm/detection_study_100kw.toml).
SimulationResult deadtime_and_heating_100kw(std::uint64_t seed) {
    auto drive = read_simulation_profile(std::string(MHBENCH_SOURCE_DIR) + "/experiments/pmsm/device_100kw_profile.toml");
    drive.seed = seed;
    drive.device->inverter.dead_time = 1.0e-6;
    auto& thermal = drive.device->thermal;
    thermal.enabled = true;
    thermal.winding_capacity = 4.0;
    thermal.winding_to_ambient = 0.03;
    thermal.winding_to_magnet = 1.0e6;
    return simulate(drive);
}

}  // namespace

TEST_CASE("a coefficient at its range end that copper's value fits as well is held there (an example: one drive)", "[pmsm][diagnosis][search]") {
    // Seed 1 of the 100 kW study's deadtime+rs_thermal: the free fit leaves rs_thermal.alpha at an
    // end of its plausible range; held at copper's 0.00393 it loses less than the chi-squared 95 %
    // point of one degree of freedom (3.84) in noise units, so the held set is recommended. (Seed 2
    // was the example while the dead-time band was linear; its free fit is now inside the range.)
    const Measurement data = deadtime_and_heating_100kw(1).data;
    DiagnosisOptions options;
    options.pole_pairs = 4;
    const Diagnosis d = diagnose(data, parse_model_spec("base"), options);
    REQUIRE(d.path.size() == 3);
    CHECK(d.path.back().plausible);
    CHECK(d.recommended.text() == "base+deadtime+rs_thermal(alpha=0.00393)");
    CHECK(d.recommended.contains("rs_thermal"));
    CHECK(std::any_of(d.findings.begin(), d.findings.end(),
                      [](const std::string& f) { return f.rfind("Held at its material value: rs_thermal.alpha = 0.00393", 0) == 0; }));
}

TEST_CASE("the residual's mean against the angle is not drawn across angles the log never reached", "[pmsm][diagnosis][plots]") {
    // A log without the rows whose electrical angle lies between 90 and 150 degrees.
    auto spec = read_simulation_profile(profile_path("diagnosis_profile.toml"));
    const auto all = simulate(spec).data;
    std::vector<Eigen::Index> kept;
    for (Eigen::Index k = 0; k < all.size(); ++k) {
        const double deg = std::remainder((*all.theta_e)[k], 2.0 * std::numbers::pi) * 180.0 / std::numbers::pi;
        if (deg < 90.0 || deg > 150.0) kept.push_back(k);
    }
    REQUIRE(static_cast<Eigen::Index>(kept.size()) < all.size());
    const auto data = select_rows(all, kept);
    const auto d = diagnose(data, parse_model_spec("base"), DiagnosisOptions{});
    mhb::testing::TemporaryDirectory dir;
    write_diagnosis_report(dir.path() / "report", data, d, "gap.csv");
    // The bins' file: a line of data for each 5-degree bin that holds rows, a blank line after each
    // run of them; two data lines in a row are neighbouring bins.
    std::ifstream bins(dir.path() / "report" / "plot-data" / "residual_angle_bins.dat");
    REQUIRE(bins);
    std::string line;
    double previous = NAN;
    int runs = 0, rows = 0;
    while (std::getline(bins, line)) {
        if (line.starts_with("#")) continue;
        if (line.empty()) {
            previous = NAN;
            continue;
        }
        const double centre = std::stod(line);
        ++rows;
        if (std::isnan(previous)) ++runs;
        else CHECK(centre - previous == Approx(5.0));
        CHECK_FALSE((centre > 90.0 && centre < 150.0));
        previous = centre;
    }
    CHECK(runs == 2);        // below 90 degrees from -180, and above 150
    CHECK(rows == 72 - 12);  // the 12 bins between 90 and 150 degrees are empty
}
