#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "problems/pmsm/measurement.hpp"
#include "tests/mhbench_cli.hpp"

namespace {

using Run = mhb::testing::CliRun;

Run run_cli(const std::string& arguments) {
    return mhb::testing::run_mhbench(arguments, std::filesystem::temp_directory_path() / "mhbench_simulate_cli.log");
}

const std::filesystem::path work = std::filesystem::temp_directory_path() / "mhbench_simulate_cli";

std::filesystem::path write_profile(const std::string& name, const std::string& text) {
    std::filesystem::create_directories(work);
    const auto path = work / name;
    std::ofstream(path) << text;
    return path;
}

const char* small_profile = R"(
[noise]
seed = 3
current = 1e-3
[[segment]]
label = "id0"
speed = 10.0
load_torque = 0.1
settle = 0.3
samples = 40
)";

}  // namespace

TEST_CASE("mhbench simulate writes the CSV and its sidecar", "[pmsm][cli]") {
    const auto profile = write_profile("small.toml", small_profile);
    const auto out = work / "small.csv";
    const auto run = run_cli("simulate " + profile.string() + " --out " + out.string());
    INFO(run.output);
    REQUIRE(run.exit_code == 0);
    CHECK(run.output.find("40 samples in 1 segments") != std::string::npos);
    const auto data = mhb::pmsm::read_measurement(out);
    CHECK(data.size() == 40);
    CHECK(data.warnings.empty());
    CHECK(std::filesystem::exists(work / "small.json"));

    // The seed fixes the noise; --seed overrides the profile's.
    const auto again = work / "again.csv";
    REQUIRE(run_cli("simulate " + profile.string() + " --out " + again.string()).exit_code == 0);
    CHECK(mhb::pmsm::read_measurement(again).u_d == data.u_d);
    const auto other = work / "other.csv";
    REQUIRE(run_cli("simulate " + profile.string() + " --out " + other.string() + " --seed 4").exit_code == 0);
    CHECK(mhb::pmsm::read_measurement(other).u_d != data.u_d);
    std::ifstream sidecar(work / "other.json");
    std::stringstream text;
    text << sidecar.rdbuf();
    CHECK(text.str().find("\"seed\": 4") != std::string::npos);
}

TEST_CASE("mhbench simulate refuses a bad profile with one located line and exit code 2", "[pmsm][cli]") {
    const auto profile = write_profile("bad.toml", "[noise]\nseed = 3\ncurrent = -1\n[[segment]]\nsamples = 4\n");
    const auto run = run_cli("simulate " + profile.string() + " --out " + (work / "bad.csv").string());
    CHECK(run.exit_code == 2);
    CHECK(run.output == "error: " + profile.string() + ":3: noise.current: must lie in [0, 1000000] (got -1)\n");
    CHECK_FALSE(std::filesystem::exists(work / "bad.csv"));
}
