#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "problems/pmsm/data/measurement.hpp"
#include "tests/mhbench_cli.hpp"
#include "tests/temporary_directory.hpp"

namespace {

using Run = mhb::testing::CliRun;

// Each test case gets its own directory: profiles, outputs and the CLI's log go there.
struct Workspace {
    mhb::testing::TemporaryDirectory dir;
    const std::filesystem::path& path() const { return dir.path(); }
    std::filesystem::path write_profile(const std::string& name, const std::string& text) const { return dir.write(name, text); }
    Run run_cli(const std::string& arguments) const { return mhb::testing::run_mhbench(arguments, dir.path() / "cli.log"); }
};

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
    const Workspace ws;
    const auto& work = ws.path();
    const auto profile = ws.write_profile("small.toml", small_profile);
    const auto out = work / "small.csv";
    const auto run = ws.run_cli("simulate " + profile.string() + " --out " + out.string());
    INFO(run.output);
    REQUIRE(run.exit_code == 0);
    CHECK(run.output.find("40 samples in 1 segments") != std::string::npos);
    const auto data = mhb::pmsm::read_measurement(out);
    CHECK(data.size() == 40);
    CHECK(data.warnings.empty());
    CHECK(std::filesystem::exists(work / "small.json"));

    // The seed fixes the noise; --seed overrides the profile's.
    const auto again = work / "again.csv";
    REQUIRE(ws.run_cli("simulate " + profile.string() + " --out " + again.string()).exit_code == 0);
    CHECK(mhb::pmsm::read_measurement(again).u_d == data.u_d);
    const auto other = work / "other.csv";
    REQUIRE(ws.run_cli("simulate " + profile.string() + " --out " + other.string() + " --seed 4").exit_code == 0);
    CHECK(mhb::pmsm::read_measurement(other).u_d != data.u_d);
    std::ifstream sidecar(work / "other.json");
    std::stringstream text;
    text << sidecar.rdbuf();
    CHECK(text.str().find("\"seed\": 4") != std::string::npos);
}

TEST_CASE("mhbench simulate refuses a bad profile with one located line and exit code 2", "[pmsm][cli]") {
    const Workspace ws;
    const auto& work = ws.path();
    const auto profile = ws.write_profile("bad.toml", "[noise]\nseed = 3\ncurrent = -1\n[[segment]]\nsamples = 4\n");
    const auto run = ws.run_cli("simulate " + profile.string() + " --out " + (work / "bad.csv").string());
    CHECK(run.exit_code == 2);
    CHECK(run.output == "error: " + profile.string() + ":3: noise.current: must lie in [0, 1000000] (got -1)\n");
    CHECK_FALSE(std::filesystem::exists(work / "bad.csv"));
}

TEST_CASE("mhbench simulate refuses an integer beyond 2^53 and a profile too large, naming file, line and field", "[pmsm][cli]") {
    const Workspace ws;
    const auto huge = ws.write_profile("huge.toml", "[motor]\nrs = 9007199254740993\n[[segment]]\nsamples = 4\n");
    auto run = ws.run_cli("simulate " + huge.string() + " --out " + (ws.path() / "huge.csv").string());
    CHECK(run.exit_code == 2);
    CHECK(run.output == "error: " + huge.string() + ":2: motor.rs: must lie in (0, 1000000] (got 9007199254740993)\n");
    const auto many = ws.write_profile("many.toml", "[[segment]]\nsamples = 100000000\n[[segment]]\nsamples = 100000000\n");
    run = ws.run_cli("simulate " + many.string() + " --out " + (ws.path() / "many.csv").string());
    CHECK(run.exit_code == 2);
    CHECK(run.output == "error: " + many.string() + ":2: segment[1].samples: must lie in [1, " +
                            std::to_string(mhb::pmsm::max_measurement_rows) + "] (got 100000000)\n");
}

TEST_CASE("fit and diagnose stop with a message when --json or --report cannot be written", "[pmsm][cli]") {
    const Workspace ws;
    const auto profile = ws.write_profile("small.toml", small_profile);
    const auto data = ws.path() / "small.csv";
    REQUIRE(ws.run_cli("simulate " + profile.string() + " --out " + data.string()).exit_code == 0);
    // A regular file where a directory is needed: no permission setting makes this writable, even for root.
    const auto blocker = ws.dir.write("blocker", "a file");
    const auto json = (blocker / "fit.json").string();
    for (const std::string command : {"fit", "diagnose"}) {
        const auto run = ws.run_cli(command + " --data " + data.string() + " --json " + json);
        INFO(run.output);
        CHECK(run.exit_code == 2);
        CHECK(run.output.find("error: " + json + ": cannot write the file: Not a directory") != std::string::npos);
        CHECK(run.output.find("JSON: ") == std::string::npos);
    }
    const auto report = ws.run_cli("diagnose --data " + data.string() + " --report " + (blocker / "report").string());
    INFO(report.output);
    CHECK(report.exit_code == 2);
    CHECK(report.output.find((blocker / "report").string()) != std::string::npos);
    CHECK(report.output.find("report: ") == std::string::npos);
}

TEST_CASE("numeric options outside their range are refused, naming the option and the range", "[pmsm][cli]") {
    const Workspace ws;
    const auto data = (ws.path() / "absent.csv").string();
    const std::pair<std::string, std::string> cases[] = {
        {"fit --data " + data + " --evaluations -5", "--evaluations: expects a whole number in [0, 10000000] (got '-5')"},
        {"fit --data " + data + " --evaluations 99999999999999999999",
         "--evaluations: expects a whole number in [0, 10000000] (got '99999999999999999999')"},
        {"diagnose --data " + data + " --settle -1", "--settle: expects a number in [0, 1000000] (got '-1')"},
        {"fit --data " + data + " --seed -1", "--seed: expects a whole number in [0, 18446744073709551615] (got '-1')"},
        {"run absent.toml --threads abc", "--threads: expects a whole number in [1, 4096] (got 'abc')"},
    };
    for (const auto& [arguments, message] : cases) {
        const auto run = ws.run_cli(arguments);
        INFO(arguments << "\n" << run.output);
        CHECK(run.exit_code == 2);
        CHECK(run.output.find(message) != std::string::npos);
    }
}
