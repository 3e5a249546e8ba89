// ERT, its bootstrap interval and the runtime ECDF: against hand-computed values, against a runtime
// distribution whose ERT is known, and on a real experiment's records.
#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>

#include <fmt/format.h>

#include "framework/anytime_analysis.hpp"
#include "framework/experiment_runner.hpp"
#include "framework/random.hpp"
#include "framework/report_tables.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;

namespace {
// Runs the experiment into `out` and returns what its experiment.json says.
ExperimentInfo run_into(const std::filesystem::path& out, const ExperimentSpec& spec) {
    RunOptions options;
    options.output = out;
    options.progress = false;
    run_experiment(spec, options);
    return read_experiment_info(out);
}
}  // namespace

TEST_CASE("ERT is the evaluations of all runs until success over the successes", "[anytime]") {
    const auto ert = expected_running_time({{100, 1000}, {0, 1000}, {300, 1000}}, 0, 1);
    CHECK(ert.value == 700.0);  // (100 + 1000 + 300) / 2
    CHECK(ert.low == 700.0);
    CHECK(ert.high == 700.0);
    CHECK(ert.successes == 2);
    CHECK(ert.runs == 3);
    CHECK(std::isinf(expected_running_time({{0, 50}, {0, 50}}, 100, 1).value));
    // Identical runs: every resample is the same, so is the interval.
    const auto same = expected_running_time({{40, 90}, {40, 90}, {40, 90}}, 500, 3);
    CHECK(same.low == 40.0);
    CHECK(same.high == 40.0);
    // A resample without a success has an infinite ERT: the upper end says so.
    const auto rare = expected_running_time({{10, 100}, {0, 100}, {0, 100}, {0, 100}, {0, 100}, {0, 100}}, 1000, 5);
    CHECK(rare.value == 510.0);
    CHECK(std::isinf(rare.high));
    CHECK(rare.low <= rare.value);
}

TEST_CASE("the bootstrap interval of ERT covers the true ERT at about its nominal rate", "[anytime]") {
    // Runs succeed with probability p at a time uniform on [1, 2a], else stop at the budget B:
    // ERT = E[T | success] + (1 - p) / p * B = a + 0.5 + (1 - p) / p * B.
    const double p = 0.6, a = 400.0, budget = 2000.0;
    const double truth = a + 0.5 + (1 - p) / p * budget;
    Rng rng(20261123);
    int covered = 0;
    const int datasets = 300;
    for (int s = 0; s < datasets; ++s) {
        std::vector<RunToTarget> runs;
        for (int r = 0; r < 40; ++r)
            runs.push_back({rng.uniform() < p ? 1 + static_cast<std::int64_t>(rng.below(static_cast<std::uint64_t>(2 * a))) : 0,
                            static_cast<std::int64_t>(budget)});
        const auto ert = expected_running_time(runs, 1000, derive_seed(7, "ert", "coverage", static_cast<std::uint64_t>(s)));
        covered += ert.low <= truth && truth <= ert.high;
    }
    const double rate = static_cast<double>(covered) / datasets;
    INFO("coverage " << rate);
    // 95 % nominal; the percentile bootstrap runs a little short at n = 40. Binomial sd at 300 sets: 1.3 %.
    CHECK(rate >= 0.88);
    CHECK(rate <= 0.99);
}

TEST_CASE("the runtime ECDF averages the functions' fractions of (run, target) pairs", "[anytime]") {
    // Dimension 2; two targets. Function A: one run, reaching the targets at 4 and 40 evaluations.
    // Function B: two runs, one reaching the first target at 10, one reaching nothing.
    const std::vector<std::vector<std::vector<std::int64_t>>> runs{{{4, 40}}, {{10, 0}, {0, 0}}};
    const auto ecdf = runtime_ecdf(runs, 2, {1.0, 2.0, 5.0, 20.0, 1e9}, 0, 1);
    // Budgets are evaluations / dimension: 2, 4, 10, 40, ... evaluations.
    const std::vector<double> want{(0.0 + 0.0) / 2, (0.5 + 0.0) / 2, (0.5 + 0.25) / 2, (1.0 + 0.25) / 2, (1.0 + 0.25) / 2};
    REQUIRE(ecdf.value.size() == want.size());
    for (std::size_t g = 0; g < want.size(); ++g) CHECK(ecdf.value[g] == Approx(want[g]));
    const auto bands = runtime_ecdf(runs, 2, {1.0, 2.0, 5.0, 20.0, 1e9}, 400, 9);
    for (std::size_t g = 0; g < want.size(); ++g) {
        CHECK(bands.low[g] <= bands.value[g] + 1e-12);
        CHECK(bands.high[g] >= bands.value[g] - 1e-12);
    }
    CHECK(bands.low[4] == Approx(1.0 / 2));    // B's resample of two failures: (1 + 0) / 2
    CHECK(bands.high[4] == Approx(1.5 / 2));   // and of two of its successful run: (1 + 0.5) / 2
}

TEST_CASE("functions pool their instances and keep dimensions and other settings apart", "[anytime]") {
    ExperimentInfo info;
    auto problem = [](std::string label, std::string name, int dimension, std::map<std::string, ParameterValue> parameters) {
        ProblemInfo p;
        p.label = std::move(label);
        p.name = std::move(name);
        p.dimension = dimension;
        p.parameters = std::move(parameters);
        return p;
    };
    info.problems = {problem("a", "bbob_f3", 2, {{"dimension", std::int64_t{2}}, {"instance", std::int64_t{1}}}),
                     problem("b", "bbob_f3", 2, {{"dimension", std::int64_t{2}}, {"instance", std::int64_t{2}}}),
                     problem("c", "bbob_f3", 5, {{"dimension", std::int64_t{5}}, {"instance", std::int64_t{1}}}),
                     problem("d", "F1", 2, {{"scale", 2.0}}),
                     problem("e", "F1", 2, {{"scale", 3.0}})};
    const auto functions = anytime_functions(info);
    REQUIRE(functions.size() == 4);
    CHECK(functions[0].label == "bbob_f3");
    CHECK(functions[0].problems == std::vector<std::size_t>{0, 1});
    CHECK(functions[1].dimension == 5);
    CHECK(functions[2].label == "F1(scale=2)");
    CHECK(functions[3].label == "F1(scale=3)");
}

TEST_CASE("an experiment with [anytime] tables the ERT its records give, and draws the ECDFs", "[anytime]") {
    testing::TemporaryDirectory dir;
    const auto spec = load_experiment(dir.write("e.toml", R"(name = "a"
trials = 4
seed = 3
[budget]
evaluations = 600
[anytime]
targets = [1, 1e-2, 1e-4]
ert_targets = [1e-2]
bootstrap = 200
[[optimizer]]
name = "random_search"
batch = 10
[[optimizer]]
name = "cmaes"
[[problem]]
name = "test_sphere"
dimension = 2
)"));
    const auto info = run_into(dir.path() / "out", spec);
    REQUIRE(info.anytime == spec.anytime);
    const auto records = read_results(dir.path() / "out" / "results.jsonl").records;
    const std::string md = markdown(anytime_section(info, records));
    for (const std::string optimizer : {"random_search(batch=10)", "cmaes"}) {
        double used = 0;
        int successes = 0;
        for (const auto& r : records)
            if (r.optimizer == optimizer) {
                REQUIRE(r.anytime.hits.size() == 3);
                used += static_cast<double>(r.anytime.hits[1] > 0 ? r.anytime.hits[1] : r.evaluations);
                successes += r.anytime.hits[1] > 0;
            }
        INFO(md);
        const std::string cell = successes ? fmt::format("| test_sphere | {} | {:.0f} [", optimizer, used / successes)
                                           : fmt::format("| test_sphere | {} | inf (0/4) |", optimizer);
        CHECK(md.find(cell) != std::string::npos);
        CHECK(md.find(fmt::format("({}/4) |", successes)) != std::string::npos);
    }
    CHECK(md.find("| 2 | cmaes | 1 |") != std::string::npos);  // the ECDF at the end: dimension 2, one function

    std::vector<std::string> rendered;
    write_ecdf_plots(dir.path() / "out", dir.path() / "out", info, records,
                     [&](const std::filesystem::path& base, const std::string& body, int, int) {
                         rendered.push_back(base.filename().string());
                         CHECK(body.find("cmaes") != std::string::npos);
                         return true;
                     });
    CHECK(rendered == std::vector<std::string>{"ecdf_D2"});
}

TEST_CASE("a campaign without per-problem tables keeps every CSV row and the summaries across problems", "[anytime]") {
    testing::TemporaryDirectory dir;
    const auto spec = load_experiment(dir.write("e.toml", R"(name = "c"
trials = 2
seed = 3
[budget]
evaluations_per_dimension = 100
[anytime]
targets = [1, 1e-2]
ert_targets = [1e-2]
bootstrap = 50
[analysis]
per_problem = false
[[optimizer]]
name = "random_search"
[[optimizer]]
name = "cmaes"
[[problem]]
name = "test_sphere"
dimension = [2, 3]
shift = [0.5, 1.0]
)"));
    const auto info = run_into(dir.path() / "out", spec);
    CHECK_FALSE(info.per_problem);
    const auto records = read_results(dir.path() / "out" / "results.jsonl").records;
    const std::string md = markdown(write_tables(dir.path() / "out", info, records));
    CHECK(md.find("## test_sphere") == std::string::npos);
    CHECK(md.find("table.csv has a row for each of the 4 problems") != std::string::npos);
    CHECK(md.find("### ERT, dimension 2") != std::string::npos);
    CHECK(md.find("| test_sphere(shift=0.5) | cmaes |") != std::string::npos);  // shift tells functions apart
    CHECK(md.find("| test_sphere(shift=1) | cmaes |") != std::string::npos);
    std::ifstream csv(dir.path() / "out" / "table.csv");
    std::size_t lines = 0;
    for (std::string line; std::getline(csv, line);) ++lines;
    CHECK(lines == 1 + 4 * 2);
}
