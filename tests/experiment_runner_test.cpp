#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>

#include "framework/experiment_runner.hpp"
#include "framework/input_error.hpp"
#include "framework/registry.hpp"
#include "framework/report_tables.hpp"
#include "tests/same_results.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
using mhb::testing::require_same_results;

namespace {
std::string config(const std::string& optimizers, const std::string& problems, int trials = 6) {
    return "name = \"r\"\ntrials = " + std::to_string(trials) + "\nseed = 99\n[budget]\niterations = 15\n" + optimizers + problems;
}
const std::string two_optimizers = "[[optimizer]]\nname = \"random_search\"\nbatch = [4, 16]\n";
const std::string two_problems = "[[problem]]\nname = \"test_sphere\"\ndimension = [2, 5]\n";

// Runs the config `body` (written to dir/e.toml) into dir/out without a progress line; its records.
std::vector<TrialRecord> run_quietly(const testing::TemporaryDirectory& dir, const std::string& body) {
    RunOptions options;
    options.output = dir.path() / "out";
    options.progress = false;
    run_experiment(load_experiment(dir.write("e.toml", body)), options);
    return read_results(dir.path() / "out" / "results.jsonl").records;
}

}  // namespace

TEST_CASE("results are bitwise identical on 1 and 2 threads", "[experiment_runner]") {
    testing::TemporaryDirectory dir;
    const auto spec = load_experiment(dir.write("e.toml", config(two_optimizers, two_problems)));
    RunOptions one, two;
    one.threads = 1;
    one.output = dir.path() / "one";
    two.threads = 2;
    two.output = dir.path() / "two";
    const auto s1 = run_experiment(spec, one);
    const auto s2 = run_experiment(spec, two);
    REQUIRE(s1.ran == 2 * 2 * 6);
    REQUIRE(s1.failed == 0);
    const auto r1 = read_results(dir.path() / "one" / "results.jsonl").records;
    const auto r2 = read_results(dir.path() / "two" / "results.jsonl").records;
    REQUIRE(r1.size() == 24);
    require_same_results(r1, r2);
    for (const auto& r : r1) REQUIRE(r.evaluations == (r.optimizer == "random_search(batch=4)" ? 4 * 16 : 16 * 16));
}

TEST_CASE("the records a run keeps for its tables are what its results file gives back, in its order", "[experiment_runner]") {
    testing::TemporaryDirectory dir;
    const auto spec = load_experiment(dir.write("e.toml", config(two_optimizers, two_problems)));
    RunOptions o;
    o.threads = 2;
    o.output = dir.path() / "out";
    o.keep_records = true;
    const auto summary = run_experiment(spec, o);
    REQUIRE(summary.records);
    const auto& kept = *summary.records;
    const auto file = read_results(dir.path() / "out" / "results.jsonl").records;
    REQUIRE(kept.size() == 24);
    REQUIRE(kept.size() == file.size());
    require_same_results(kept, file);
    for (std::size_t k = 0; k < kept.size(); ++k) {
        REQUIRE(to_json(kept[k]).dump() == to_json(file[k]).dump());
        REQUIRE(kept[k].seconds == file[k].seconds);
    }
    // A file that held records before the run (resumed) is read back: nothing is kept.
    o.resume = true;
    REQUIRE_FALSE(run_experiment(spec, o).records);
    // Nor without asking.
    RunOptions plain;
    plain.output = dir.path() / "plain";
    REQUIRE_FALSE(run_experiment(spec, plain).records);
}

TEST_CASE("an interrupted run resumes without losing or repeating trials", "[experiment_runner]") {
    testing::TemporaryDirectory dir;
    const auto spec = load_experiment(dir.write("e.toml", config(two_optimizers, two_problems)));
    RunOptions full;
    full.output = dir.path() / "full";
    run_experiment(spec, full);
    const auto reference = read_results(dir.path() / "full" / "results.jsonl").records;

    // Simulate an interruption: keep 10 lines and half of the 11th.
    RunOptions part;
    part.output = dir.path() / "part";
    run_experiment(spec, part);
    const auto path = dir.path() / "part" / "results.jsonl";
    std::ifstream in(path);
    std::string line, kept;
    for (int i = 0; i < 11 && std::getline(in, line); ++i) kept += i < 10 ? line + "\n" : line.substr(0, line.size() / 2);
    in.close();
    std::ofstream(path) << kept;

    part.resume = true;
    const auto summary = run_experiment(spec, part);
    REQUIRE(summary.skipped == 10);
    REQUIRE(summary.ran == 14);
    auto loaded = read_results(path);
    std::vector<TrialRecord> complete;
    for (auto& r : loaded.records) complete.push_back(r);
    require_same_results(complete, reference);
}

TEST_CASE("every earlier run in the directory is kept, with its experiment.json, under its own name", "[experiment_runner]") {
    testing::TemporaryDirectory dir;
    RunOptions o;
    o.output = dir.path() / "out";
    // Three runs of different sizes: each kept file must hold its own run's records.
    std::vector<std::string> results, infos;
    for (int trials : {1, 2, 3}) {
        const auto spec = load_experiment(dir.write("e.toml", config(two_optimizers, two_problems, trials)));
        const auto s = run_experiment(spec, o);
        REQUIRE(s.notes.size() == (trials == 1 ? 0u : 1u));
        results.push_back(testing::read_file(dir.path() / "out" / "results.jsonl"));
        infos.push_back(testing::read_file(dir.path() / "out" / "experiment.json"));
    }
    for (std::size_t n = 1; n <= 2; ++n) {
        const auto kept = dir.path() / "out" / "previous" / std::to_string(n);
        REQUIRE(testing::read_file(kept / "results.jsonl") == results[n - 1]);
        REQUIRE(testing::read_file(kept / "experiment.json") == infos[n - 1]);
        REQUIRE(read_results(kept / "results.jsonl").records.size() == 4 * n);
    }
    REQUIRE(read_results(dir.path() / "out" / "results.jsonl").records.size() == 12);
}

TEST_CASE("experiment.json records the config's text and each run's provenance, and a resume adds its own", "[experiment_runner]") {
    testing::TemporaryDirectory dir;
    const std::string text = config(two_optimizers, two_problems, 2);
    const auto spec = load_experiment(dir.write("e.toml", text));
    RunOptions o;
    o.output = dir.path() / "out";
    o.threads = 2;
    run_experiment(spec, o);
    const auto first = read_experiment_info(dir.path() / "out");
    REQUIRE(first.config_text == text);
    REQUIRE(first.runs.size() == 1);
    const auto& run = first.runs.front();
    REQUIRE(run.threads == 2);
    REQUIRE_FALSE(run.version.empty());
    REQUIRE_FALSE(run.commit.empty());
    REQUIRE_FALSE(run.host.empty());
    REQUIRE(run.hardware_threads > 0);
    // ISO 8601 in UTC, to the second.
    REQUIRE(run.date.size() == 20);
    REQUIRE(run.date[10] == 'T');
    REQUIRE(run.date.back() == 'Z');

    o.resume = true;
    o.threads = 1;
    run_experiment(load_experiment(dir.write("e.toml", config(two_optimizers, two_problems, 3))), o);
    const auto resumed = read_experiment_info(dir.path() / "out");
    REQUIRE(resumed.runs.size() == 2);
    REQUIRE(resumed.runs[0].date == run.date);
    REQUIRE(resumed.runs[0].threads == 2);
    REQUIRE(resumed.runs[1].threads == 1);

    // A fresh run (the earlier one moved to previous/) starts its own list.
    o.resume = false;
    run_experiment(spec, o);
    REQUIRE(read_experiment_info(dir.path() / "out").runs.size() == 1);
}

TEST_CASE("a plugin that throws or returns NaN fails only its own trials", "[experiment_runner]") {
    testing::TemporaryDirectory dir;
    const std::string optimizers =
        "[[optimizer]]\nname = \"test_throwing\"\nat = 3\n[[optimizer]]\nname = \"random_search\"\nbatch = 3\n";
    const std::string problems = "[[problem]]\nname = \"test_nan\"\n[[problem]]\nname = \"test_sphere\"\n";
    const auto spec = load_experiment(dir.write("e.toml", config(optimizers, problems, 5)));
    RunOptions o;
    o.output = dir.path() / "out";
    const auto s = run_experiment(spec, o);
    REQUIRE(s.ran == 20);
    const auto records = read_results(dir.path() / "out" / "results.jsonl").records;
    std::size_t failed = 0;
    for (const auto& r : records) {
        if (r.optimizer == "test_throwing(at=3)") {
            REQUIRE_FALSE(r.ok);
            // A NaN may come first on test_nan; otherwise the deliberate throw.
            REQUIRE((r.error.find("deliberate failure at iteration 3") != std::string::npos ||
                     r.error.find("NaN") != std::string::npos));
        }
        if (r.optimizer == "random_search(batch=3)" && r.problem == "test_sphere") REQUIRE(r.ok);
        if (!r.ok) ++failed;
    }
    // random_search draws 3 x 16 = 48 points in [-1,1]^2 per trial on test_nan: P(no x1 > 0.9) = 0.95^48 < 0.09,
    // so across 5 trials NaN faults are all but certain to occur (seeded, so this is deterministic).
    REQUIRE(failed > 10);
    REQUIRE(s.failed == failed);
    REQUIRE_FALSE(s.failures.empty());
}

TEST_CASE("an output directory that cannot be written is bad input", "[experiment_runner]") {
    testing::TemporaryDirectory dir;
    const auto spec = load_experiment(dir.write("e.toml", config(two_optimizers, two_problems, 1)));
    dir.write("blocker", "a file, not a directory");
    RunOptions o;
    o.output = dir.path() / "blocker" / "sub";
    REQUIRE_THROWS_AS(run_experiment(spec, o), InputError);
}

TEST_CASE("resuming is refused, naming the difference, when an optimizer, problem or budget setting changed", "[experiment_runner]") {
    testing::TemporaryDirectory dir;
    const std::string optimizer = "[[optimizer]]\nname = \"random_search\"\nlabel = \"RS\"\n";
    const std::string problem = "[[problem]]\nname = \"test_sphere\"\nlabel = \"P\"\ndimension = 2\n";
    RunOptions o;
    o.output = dir.path() / "out";
    run_experiment(load_experiment(dir.write("e.toml", config(optimizer + "batch = 4\n", problem, 2))), o);
    const auto before = testing::read_file(dir.path() / "out" / "results.jsonl");
    o.resume = true;
    auto refused = [&](const std::string& text) -> std::string {
        const auto spec = load_experiment(dir.write("e.toml", text));
        try {
            run_experiment(spec, o);
        } catch (const InputError& e) {
            return e.what();
        }
        return "accepted";
    };
    const auto optimizer_changed = refused(config(optimizer + "batch = 8\n", problem, 2));
    CHECK_THAT(optimizer_changed, Catch::Contains("optimizer RS") && Catch::Contains("batch = 8") &&
                                      Catch::Contains("batch = 4") && Catch::Contains("e.toml:6"));
    const auto problem_changed = refused(config(optimizer + "batch = 4\n", "[[problem]]\nname = \"test_sphere\"\nlabel = \"P\"\ndimension = 3\n", 2));
    CHECK_THAT(problem_changed, Catch::Contains("problem P") && Catch::Contains("dimension = 3") && Catch::Contains("dimension = 2"));
    const auto box_changed = refused(config(optimizer + "batch = 4\n", problem + "lower = -1\n", 2));
    CHECK_THAT(box_changed, Catch::Contains("lower/upper"));
    std::string budget = config(optimizer + "batch = 4\n", problem, 2);
    budget.replace(budget.find("iterations = 15"), 15, "iterations = 16");
    CHECK_THAT(refused(budget), Catch::Contains("budget.iterations") && Catch::Contains("16") && Catch::Contains("15"));
    // Nothing was touched by the refusals.
    REQUIRE(testing::read_file(dir.path() / "out" / "results.jsonl") == before);

    // More trials with the same settings is a continuation, not a different experiment.
    const auto s = run_experiment(load_experiment(dir.write("e.toml", config(optimizer + "batch = 4\n", problem, 3))), o);
    REQUIRE(s.skipped == 2);
    REQUIRE(s.ran == 1);
}

TEST_CASE("resuming accepts a default written out that the earlier run left away", "[experiment_runner]") {
    testing::TemporaryDirectory dir;
    const std::string problem = "[[problem]]\nname = \"test_sphere\"\nlabel = \"P\"\ndimension = 2\n";
    RunOptions o;
    o.output = dir.path() / "out";
    run_experiment(load_experiment(dir.write("e.toml", config("[[optimizer]]\nname = \"random_search\"\nlabel = \"RS\"\n", problem, 2))), o);
    o.resume = true;
    const auto& defaults = OptimizerRegistry::instance().at("random_search", "optimizer").parameters;
    const std::string batch = to_string(defaults.front().default_value);
    const auto s = run_experiment(
        load_experiment(dir.write("e.toml", config("[[optimizer]]\nname = \"random_search\"\nlabel = \"RS\"\n" +
                                                       defaults.front().name + " = " + batch + "\n", problem, 2))), o);
    REQUIRE(s.skipped == 2);
}

TEST_CASE("a full disk stops the run with a message naming the results file", "[experiment_runner]") {
    testing::TemporaryDirectory dir;
    const auto spec = load_experiment(dir.write("e.toml", config(two_optimizers, two_problems, 2)));
    std::filesystem::create_directories(dir.path() / "out");
    // /dev/full accepts the open and fails every write with ENOSPC, as a full disk does.
    std::filesystem::create_symlink("/dev/full", dir.path() / "out" / "results.jsonl");
    RunOptions o;
    o.output = dir.path() / "out";
    try {
        run_experiment(spec, o);
        FAIL("a failed write went unnoticed");
    } catch (const InputError& e) {
        CHECK_THAT(e.what(), Catch::Contains("results.jsonl") && Catch::Contains("No space left on device") &&
                                 Catch::Contains("--resume"));
    }
}

TEST_CASE("a budget per dimension gives each problem its dimension times the evaluations, as COCO's do", "[experiment_runner]") {
    testing::TemporaryDirectory dir;
    const std::string body = "name = \"d\"\ntrials = 2\nseed = 4\n[budget]\nevaluations_per_dimension = 30\n" + two_optimizers + two_problems;
    const auto records = run_quietly(dir, body);
    REQUIRE(records.size() == 8);
    for (const auto& r : records) CHECK(r.evaluations == (r.problem == "test_sphere(dimension=2)" ? 60 : 150));
    CHECK(read_experiment_info(dir.path() / "out").evaluations_per_dimension == 30);

    const auto both = dir.write("both.toml", "trials = 1\nseed = 1\n[budget]\nevaluations = 10\nevaluations_per_dimension = 30\n" +
                                                 two_optimizers + two_problems);
    CHECK_THROWS_WITH(load_experiment(both), Catch::Contains("both.toml:5: budget.evaluations_per_dimension: set evaluations or "
                                                             "evaluations_per_dimension, not both"));
}

TEST_CASE("a budget by dimension gives each problem the evaluations listed for its dimension", "[experiment_runner]") {
    testing::TemporaryDirectory dir;
    const std::string body = "name = \"d\"\ntrials = 2\nseed = 4\n[budget]\nevaluations_by_dimension = { 2 = 40, 5 = 96 }\n" +
                             two_optimizers + two_problems;
    const auto records = run_quietly(dir, body);
    REQUIRE(records.size() == 8);
    for (const auto& r : records) CHECK(r.evaluations == (r.problem == "test_sphere(dimension=2)" ? 40 : 96));
    CHECK(read_experiment_info(dir.path() / "out").evaluations_by_dimension == std::map<int, std::int64_t>{{2, 40}, {5, 96}});
    CHECK_THAT(markdown_report(read_experiment_info(dir.path() / "out"), records), Catch::Contains("40 at D = 2, 96 at D = 5"));

    auto error = [&](const std::string& budget) -> std::string {
        try {
            describe_experiment(load_experiment(dir.write("b.toml", "trials = 1\nseed = 1\n[budget]\n" + budget + two_optimizers + two_problems)));
        } catch (const InputError& e) {
            return e.what();
        }
        return "(accepted)";
    };
    CHECK_THAT(error("evaluations_by_dimension = { 2 = 40 }\n"),
               Catch::Contains("b.toml:8: problem test_sphere(dimension=5): has dimension 5, for which budget.evaluations_by_dimension "
                               "(line 4) gives no budget"));
    CHECK_THAT(error("evaluations_by_dimension = { two = 40 }\n"),
               Catch::Contains("b.toml:4: budget.evaluations_by_dimension.two: a key must be a dimension"));
    CHECK_THAT(error("evaluations_by_dimension = { 2 = 0 }\n"),
               Catch::Contains("b.toml:4: budget.evaluations_by_dimension.2: expects a whole number of evaluations from 1"));
    CHECK_THAT(error("evaluations_by_dimension = 40\n"), Catch::Contains("b.toml:4: budget.evaluations_by_dimension: expects a table"));
    CHECK_THAT(error("evaluations = 10\nevaluations_by_dimension = { 2 = 40 }\n"),
               Catch::Contains("b.toml:5: budget.evaluations_by_dimension: set one of evaluations"));
}

TEST_CASE("an error threshold reports errors below it as 0 in the tables, and checkpoints get their table", "[experiment_runner]") {
    testing::TemporaryDirectory dir;
    // CMA-ES ends a 2-D sphere far below 1e-8 (but not at 0); random search stays far above it.
    const std::string common = "trials = 4\nseed = 11\n[budget]\nevaluations = 600\n[anytime]\ncheckpoints = [0.1, 1]\n"
                               "[[optimizer]]\nname = \"cmaes\"\n[[optimizer]]\nname = \"random_search\"\n"
                               "[[problem]]\nname = \"test_sphere\"\ndimension = 2\n";
    const auto with = load_experiment(dir.write("t.toml", common + "[analysis]\nerror_threshold = 1e-8\n"));
    const auto without = load_experiment(dir.write("u.toml", common));
    CHECK(with.error_threshold == 1e-8);
    RunOptions options;
    options.progress = false;
    options.output = dir.path() / "with";
    run_experiment(with, options);
    options.output = dir.path() / "without";
    run_experiment(without, options);
    const auto info = read_experiment_info(dir.path() / "with");
    CHECK(info.error_threshold == 1e-8);
    const auto records = read_results(dir.path() / "with" / "results.jsonl").records;
    double cmaes_largest = 0, random_smallest = INFINITY;
    for (const auto& r : records) {
        REQUIRE(r.anytime.checkpoint_evaluations == std::vector<std::int64_t>{60, 600});
        CHECK(r.anytime.checkpoint_best.back() == r.best_fitness);
        if (r.optimizer == "cmaes") cmaes_largest = std::max(cmaes_largest, r.best_fitness);
        else random_smallest = std::min(random_smallest, r.best_fitness);
    }
    REQUIRE(cmaes_largest > 0);  // the raw errors are not 0: only the threshold makes them so
    REQUIRE(cmaes_largest < 1e-8);
    REQUIRE(random_smallest > 1e-8);
    const auto table = results_table(info, records);
    const auto plain = results_table(read_experiment_info(dir.path() / "without"), read_results(dir.path() / "without" / "results.jsonl").records);
    const auto csv_with = csv(table), csv_without = csv(plain);
    CHECK_THAT(csv_with, Catch::Contains("test_sphere(dimension=2),cmaes,4,0,0,0,0,0,0,"));
    CHECK_THAT(csv_without, !Catch::Contains("test_sphere(dimension=2),cmaes,4,0,0,0,0,0,0,"));
    const std::string md = markdown_report(info, records);
    CHECK_THAT(md, Catch::Contains("Errors f − f* below 1e-08 are counted as 0"));
    CHECK_THAT(md, Catch::Contains("error f − f* at the budget's checkpoints") && Catch::Contains("| 60 | 600 |"));

    const auto no_optimum = dir.write("n.toml", "trials = 1\nseed = 1\n[budget]\nevaluations = 10\n[analysis]\nerror_threshold = 1e-8\n"
                                                "[[optimizer]]\nname = \"random_search\"\n[[problem]]\nname = \"test_nan\"\n");
    CHECK_THROWS_WITH(describe_experiment(load_experiment(no_optimum)),
                      Catch::Contains("n.toml:9: problem test_nan: does not know its optimum f*, which analysis.error_threshold needs (line 6)"));
    CHECK_THROWS_WITH(load_experiment(dir.write("m.toml", common + "[analysis]\nerror_threshold = -1\n")),
                      Catch::Contains("m.toml:15: analysis.error_threshold: expects a number >= 0"));
}

TEST_CASE("run with --dimension D runs the config's problems of dimension D and says so in the results", "[experiment_runner]") {
    testing::TemporaryDirectory dir;
    auto spec = load_experiment(dir.write("e.toml", config(two_optimizers, two_problems, 2)));
    select_dimension(spec, 5);
    REQUIRE(spec.problems.size() == 1);
    CHECK(spec.problems[0].label == "test_sphere(dimension=5)");
    RunOptions options;
    options.progress = false;
    options.output = dir.path() / "out";
    run_experiment(spec, options);
    const auto info = read_experiment_info(dir.path() / "out");
    CHECK(info.selected_dimension == 5);
    CHECK(info.problems.size() == 1);
    const auto records = read_results(dir.path() / "out" / "results.jsonl").records;
    CHECK(records.size() == 4);
    CHECK_THAT(markdown_report(info, records), Catch::Contains("Only the config's problems of dimension 5 were run"));

    // Resuming without the selection would mix two experiments.
    auto all = load_experiment(dir.path() / "e.toml");
    options.resume = true;
    CHECK_THROWS_WITH(run_experiment(all, options), Catch::Contains("--dimension") && Catch::Contains("selected dimension 5"));
    auto none = load_experiment(dir.path() / "e.toml");
    CHECK_THROWS_WITH(select_dimension(none, 7), Catch::Contains("--dimension: no problem of") && Catch::Contains("has dimension 7; its dimensions are 2, 5"));
}
