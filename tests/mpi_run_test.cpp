// `mpirun -np N mhbench run`: a real mpirun of the built CLI on this machine, against a run in one
// process. Compiled only when mhbench is built with MPI (MHBENCH_WITH_MPI).
#ifdef MHBENCH_WITH_MPI
#include <catch2/catch.hpp>

#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "framework/experiment_runner.hpp"
#include "tests/mhbench_cli.hpp"
#include "tests/same_results.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
using mhb::testing::require_same_results;
using mhb::testing::TemporaryDirectory;
namespace fs = std::filesystem;

namespace {

// Two optimisers on two problems, 5 trials: 20 trials, which 2 and 3 ranks divide unevenly.
const char* config = R"(name = "spread"
trials = 5
seed = 11
[budget]
evaluations = 3000
[[optimizer]]
name = "gwo"
[[optimizer]]
name = "cmaes"
[[problem]]
name = "F9"
dimension = 6
[[problem]]
name = "bbob_f8"
dimension = 4
)";

using Outcome = testing::CliRun;
const auto run = testing::run_command;

// mpirun as CI runs it: as root, more ranks than cores, and without the kernel's cross-memory
// attach, which containers often forbid.
Outcome mpirun(int ranks, std::vector<std::string> arguments, const fs::path& log) {
    std::vector<std::string> argv{"env", "OMPI_ALLOW_RUN_AS_ROOT=1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1",
                                  "OMPI_MCA_btl_vader_single_copy_mechanism=none", MHBENCH_MPIEXEC, "-n", std::to_string(ranks),
                                  "--oversubscribe", MHBENCH_CLI};
    argv.insert(argv.end(), arguments.begin(), arguments.end());
    return run(argv, log);
}

}  // namespace

TEST_CASE("mpirun -np 2 gives the records and tables of a run in one process, and experiment.json says how it was spread",
          "[mpi][cli]") {
    TemporaryDirectory dir;
    const auto file = dir.write("spread.toml", config).string();
    const auto single = run({MHBENCH_CLI, "run", file, "--out", (dir.path() / "single").string(), "--quiet", "--no-plots"},
                            dir.path() / "single.log");
    REQUIRE(single.exit_code == 0);
    for (const auto& [ranks, threads] : std::vector<std::pair<int, std::string>>{{2, ""}, {3, "2"}}) {
        const fs::path out = dir.path() / ("ranks" + std::to_string(ranks));
        std::vector<std::string> arguments{"run", file, "--out", out.string(), "--quiet", "--no-plots"};
        if (!threads.empty()) arguments.insert(arguments.end(), {"--threads", threads});
        const auto spread = mpirun(ranks, arguments, dir.path() / "spread.log");
        INFO(spread.output);
        REQUIRE(spread.exit_code == 0);
        CHECK(spread.output.find(fmt::format("Spread over {} MPI ranks.", ranks)) != std::string::npos);
        const auto records = read_results(out / "results.jsonl").records;
        REQUIRE(records.size() == 20);
        require_same_results(records, read_results(dir.path() / "single" / "results.jsonl").records);
        CHECK(testing::table_csv_without_time(out) == testing::table_csv_without_time(dir.path() / "single"));
        for (const auto& entry : fs::directory_iterator(out)) CHECK_FALSE(entry.path().filename().string().starts_with("results.rank-"));
        const auto info = read_experiment_info(out);
        REQUIRE(info.runs.size() == 1);
        CHECK(info.runs[0].ranks == ranks);
        if (!threads.empty()) CHECK(info.runs[0].threads == 2);
    }
}

TEST_CASE("a distributed run that was killed resumes with another number of ranks, losing and repeating nothing",
          "[mpi][cli]") {
    TemporaryDirectory dir;
    const auto file = dir.write("spread.toml", config).string();
    const fs::path reference = dir.path() / "reference", killed = dir.path() / "killed";
    REQUIRE(run({MHBENCH_CLI, "run", file, "--out", reference.string(), "--quiet", "--no-plots"}, dir.path() / "ref.log").exit_code == 0);

    // What a killed 2-rank run leaves: results.jsonl from before, each rank's file with what it
    // finished (one record also already in results.jsonl, from a fold cut short), and a line one
    // rank was writing when it died.
    std::vector<std::string> lines;
    {
        std::ifstream in(reference / "results.jsonl");
        for (std::string line; std::getline(in, line);) lines.push_back(line);
    }
    REQUIRE(lines.size() == 20);
    fs::create_directories(killed);
    fs::copy_file(reference / "experiment.json", killed / "experiment.json");
    std::ofstream(killed / "results.jsonl") << lines[0] << "\n" << lines[1] << "\n" << lines[2] << "\n";
    std::ofstream(killed / "results.rank-0.jsonl") << lines[3] << "\n" << lines[4] << "\n" << lines[1] << "\n";
    std::ofstream(killed / "results.rank-1.jsonl") << lines[5] << "\n" << lines[6].substr(0, lines[6].size() / 2);

    const auto resumed = mpirun(3, {"run", file, "--out", killed.string(), "--resume", "--quiet", "--no-plots"}, dir.path() / "resume.log");
    INFO(resumed.output);
    REQUIRE(resumed.exit_code == 0);
    CHECK(resumed.output.find("14 trials run, 6 skipped (already done)") != std::string::npos);
    const auto records = read_results(killed / "results.jsonl").records;
    CHECK(records.size() == 20);  // each trial once
    require_same_results(records, read_results(reference / "results.jsonl").records);
    for (const auto& entry : fs::directory_iterator(killed)) CHECK_FALSE(entry.path().filename().string().starts_with("results.rank-"));
}
#endif
