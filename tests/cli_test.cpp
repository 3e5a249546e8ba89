// End to end through the `mhbench` binary, as a user runs it.
#include <catch2/catch.hpp>

#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "framework/results_store.hpp"
#include "framework/statistics.hpp"
#include "tests/mhbench_cli.hpp"
#include "tests/table_comparison.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;

namespace {
struct Outcome {
    int code;
    std::string err;  // standard output and error together
};
Outcome run_cli(const std::string& args, const testing::TemporaryDirectory& dir) {
    const auto run = testing::run_mhbench(args, dir.path() / "stdout.txt");
    return {run.exit_code, run.output};
}

}  // namespace

TEST_CASE("a TOML experiment through the CLI gives identical, correct tables on 1 and 2 threads", "[cli]") {
    testing::TemporaryDirectory dir;
    const std::string config = std::string(MHBENCH_SOURCE_DIR) + "/experiments/smoke.toml";
    REQUIRE(run_cli("run " + config + " --threads 1 --quiet --out " + (dir.path() / "t1").string(), dir).code == 0);
    REQUIRE(run_cli("run " + config + " --threads 2 --quiet --no-plots --out " + (dir.path() / "t2").string(), dir).code == 0);
    const auto csv1 = testing::read_file(dir.path() / "t1" / "table.csv");
    const auto csv2 = testing::read_file(dir.path() / "t2" / "table.csv");
    REQUIRE_FALSE(csv1.empty());
    REQUIRE(testing::without_times(csv1) == testing::without_times(csv2));
    REQUIRE(std::filesystem::exists(dir.path() / "t1" / "convergence_F1_dimension_5.png"));
    REQUIRE(std::filesystem::exists(dir.path() / "t1" / "boxplot_bbob_f1_dimension_3.svg"));

    // The table's numbers are those of the trial records: recompute F1's mean from results.jsonl.
    const auto records = read_results(dir.path() / "t1" / "results.jsonl").records;
    REQUIRE(records.size() == 2 * 2 * 5);
    std::vector<double> f;
    for (const auto& r : records)
        if (r.problem == "F1(dimension=5)" && r.optimizer == "random_search(batch=40)") f.push_back(r.best_fitness);
    REQUIRE(f.size() == 5);
    const double mean = stats::summarize(f).mean;
    REQUIRE_THAT(csv1, Catch::Contains(fmt::format("F1(dimension=5),random_search(batch=40),5,0,{:.17g},", mean)));

    // `table` remakes the same table from the directory alone.
    REQUIRE(run_cli("table " + (dir.path() / "t2").string() + " --no-plots", dir).code == 0);
    REQUIRE(testing::read_file(dir.path() / "t2" / "table.csv") == csv2);
}

TEST_CASE("bad input through the CLI: one message naming file and line, exit code 2", "[cli]") {
    testing::TemporaryDirectory dir;
    const auto bad = dir.write("bad.toml", "name = \"x\"\ntrials = 2\nseed = 1\n[budget]\niterations = 5\n"
                                           "[[optimizer]]\nname = \"random_search\"\nbatch = -3\n[[problem]]\nname = \"F1\"\n");
    auto out = run_cli("run " + bad.string(), dir);
    REQUIRE(out.code == 2);
    REQUIRE_THAT(out.err, Catch::Contains("bad.toml:8: optimizer[0].batch: must lie in [1, 1000000] (got -3)"));
    out = run_cli("run " + (dir.path() / "missing.toml").string(), dir);
    REQUIRE(out.code == 2);
    REQUIRE_THAT(out.err, Catch::Contains("missing.toml: cannot open the experiment file: No such file"));
    out = run_cli("run", dir);
    REQUIRE(out.code == 2);
    out = run_cli("run " + bad.string() + " --threads 0", dir);
    REQUIRE(out.code == 2);
    REQUIRE_THAT(out.err, Catch::Contains("--threads"));
    out = run_cli("frobnicate", dir);
    REQUIRE(out.code == 2);
    out = run_cli("table " + dir.path().string(), dir);
    REQUIRE(out.code == 2);
    REQUIRE_THAT(out.err, Catch::Contains("experiment.json: missing"));
}

TEST_CASE("`mhbench list` shows every registered plugin with its parameters", "[cli]") {
    testing::TemporaryDirectory dir;
    REQUIRE(run_cli("list", dir).code == 0);
    const auto out = testing::read_file(dir.path() / "stdout.txt");
    REQUIRE_THAT(out, Catch::Contains("random_search") && Catch::Contains("batch") && Catch::Contains("bbob_f24") &&
                          Catch::Contains("F23"));
}

TEST_CASE("unknown names on the command line name the option and suggest the closest name", "[cli]") {
    testing::TemporaryDirectory dir;
    auto out = run_cli("fitt --data x.csv", dir);
    REQUIRE(out.code == 2);
    REQUIRE_THAT(out.err, Catch::StartsWith("error: command line: unknown command 'fitt'; did you mean 'fit'?") &&
                              Catch::Contains("\n  diagnose\n"));
    const auto data = dir.write("d.csv", "i_d,i_q,u_d,u_q,omega_e\n0,0.1,0,1,10\n0,0.2,0,2,20\n");
    out = run_cli("fit --data " + data.string() + " --optimizer cmaez", dir);
    REQUIRE(out.code == 2);
    REQUIRE_THAT(out.err, Catch::StartsWith("error: command line: --optimizer: unknown optimizer 'cmaez'; did you mean 'cmaes'?") &&
                              Catch::Contains("\n  gwo\n"));
}

TEST_CASE("a missing data file named in a config names the config's line as well as the file", "[cli]") {
    testing::TemporaryDirectory dir;
    const auto config = dir.write("pmsm.toml", "name = \"p\"\ntrials = 1\nseed = 1\n[budget]\niterations = 5\n"
                                               "[[optimizer]]\nname = \"random_search\"\n"
                                               "[[problem]]\nname = \"pmsm_identification\"\ndata = \"absent.csv\"\n");
    const auto out = run_cli("run " + config.string() + " --out " + (dir.path() / "out").string(), dir);
    REQUIRE(out.code == 2);
    REQUIRE_THAT(out.err, Catch::Contains(config.string() + ":8: problem pmsm_identification(data=absent.csv): ") &&
                              Catch::Contains("absent.csv: cannot open the measurement file: No such file or directory"));
}
