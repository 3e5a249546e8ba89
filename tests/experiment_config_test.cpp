#include <catch2/catch.hpp>

#include "framework/experiment_config.hpp"
#include "framework/experiment_runner.hpp"
#include "framework/input_error.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;

namespace {
const char* valid = R"(name = "t"
trials = 3
seed = 11

[budget]
iterations = 10

[[optimizer]]
name = "random_search"
batch = [5, 10]

[[optimizer]]
name = "random_search"
label = "RS"

[[problem]]
name = "test_sphere"
dimension = [2, 3]
shift = 0.5

[analysis]
baseline = "RS"
)";

// Loads `text` and returns the InputError message, or "" when it loads.
std::string error_of(const std::string& text) {
    testing::TemporaryDirectory dir;
    const auto file = dir.write("exp.toml", text);
    try {
        load_experiment(file);
        return "";
    } catch (const InputError& e) {
        return e.what();
    }
}

std::string replace(std::string text, const std::string& from, const std::string& to) {
    const auto pos = text.find(from);
    REQUIRE(pos != std::string::npos);
    return text.replace(pos, from.size(), to);
}
}  // namespace

TEST_CASE("a valid experiment expands its grids and resolves paths", "[experiment_config]") {
    testing::TemporaryDirectory dir;
    const auto spec = load_experiment(dir.write("exp.toml", valid));
    REQUIRE(spec.trials == 3);
    REQUIRE(spec.seed == 11);
    REQUIRE(spec.budget.max_iterations == 10);
    REQUIRE(spec.optimizers.size() == 3);
    REQUIRE(spec.optimizers[0].label == "random_search(batch=5)");
    REQUIRE(spec.optimizers[1].label == "random_search(batch=10)");
    REQUIRE(spec.optimizers[2].label == "RS");
    REQUIRE(spec.problems.size() == 2);
    REQUIRE(spec.problems[1].label == "test_sphere(dimension=3)");
    REQUIRE(std::get<double>(spec.problems[1].values.at("shift")) == 0.5);
    REQUIRE(spec.baseline == "RS");
    REQUIRE(spec.output == (dir.path().parent_path() / "results" / "t").lexically_normal());
}

TEST_CASE("bad experiments are refused with file, line and field", "[experiment_config]") {
    CHECK_THAT(error_of("trials = 3\nseed = [1\n"), Catch::Contains("exp.toml:2") && Catch::Contains("TOML syntax"));
    CHECK_THAT(error_of(replace(valid, "trials = 3", "trials = 0")), Catch::Contains("exp.toml:2: trials: must be >= 1"));
    CHECK_THAT(error_of(replace(valid, "trials = 3", "trials = \"many\"")), Catch::Contains("trials: expects an integer"));
    CHECK_THAT(error_of(replace(valid, "name = \"random_search\"\nbatch", "name = \"gwoo\"\nbatch")),
               Catch::Contains("exp.toml:9: optimizer[0].name: unknown optimizer 'gwoo'") && Catch::Contains("random_search"));
    CHECK_THAT(error_of(replace(valid, "name = \"test_sphere\"", "name = \"nope\"")),
               Catch::Contains("problem[0].name: unknown problem 'nope'"));
    CHECK_THAT(error_of(replace(valid, "batch = [5, 10]", "batch = [5, 0]")),
               Catch::Contains("exp.toml:10: optimizer[0].batch: must lie in [1, 1000000] (got 0)"));
    CHECK_THAT(error_of(replace(valid, "batch = [5, 10]", "batch = 2.5")), Catch::Contains("optimizer[0].batch: expects an integer"));
    CHECK_THAT(error_of(replace(valid, "shift = 0.5", "shfit = 0.5")),
               Catch::Contains("exp.toml:19: problem[0].shfit: unknown parameter; known: dimension, shift"));
    CHECK_THAT(error_of(replace(valid, "iterations = 10", "iterations = -1")), Catch::Contains("budget.iterations: must be >= 1"));
    CHECK_THAT(error_of(replace(valid, "iterations = 10", "")), Catch::Contains("budget: set iterations, evaluations or both"));
    CHECK_THAT(error_of(replace(valid, "baseline = \"RS\"", "baseline = \"GWO\"")),
               Catch::Contains("analysis.baseline: 'GWO' is not an optimizer label"));
    CHECK_THAT(error_of(replace(valid, "label = \"RS\"", "label = \"random_search(batch=5)\"")),
               Catch::Contains("both labelled 'random_search(batch=5)'"));
    CHECK_THAT(error_of(replace(valid, "seed = 11", "seed = 11\ntrails = 4")), Catch::Contains("exp.toml:4: trails: unknown key"));
    CHECK_THAT(error_of(replace(valid, "batch = [5, 10]", "batch = []")), Catch::Contains("an empty list gives no variant"));
    REQUIRE(error_of(valid).empty());
}

TEST_CASE("sizes a config asks for are checked against their stated limits before a trial runs", "[experiment_config]") {
    CHECK_THAT(error_of(replace(valid, "iterations = 10", "iterations = 9223372036854775807")),
               Catch::Contains("exp.toml:6: budget.iterations: must be <= " + std::to_string(max_budget_iterations)));
    CHECK_THAT(error_of(replace(valid, "iterations = 10", "evaluations = 99999999999")),
               Catch::Contains("exp.toml:6: budget.evaluations: must be <= " + std::to_string(max_budget_evaluations)));
    CHECK_THAT(error_of(replace(valid, "trials = 3", "trials = 100000000")),
               Catch::Contains("exp.toml:2: trials: must be <= " + std::to_string(max_trials)));
    CHECK(error_of(replace(valid, "iterations = 10", "iterations = " + std::to_string(max_budget_iterations))).empty());
}

TEST_CASE("a directory or an empty file given as the config says so", "[experiment_config]") {
    testing::TemporaryDirectory dir;
    auto message = [](const std::filesystem::path& file) -> std::string {
        try {
            load_experiment(file);
        } catch (const InputError& e) {
            return e.what();
        }
        return "";
    };
    CHECK_THAT(message(dir.path()), Catch::Contains(dir.path().string() + ": is a directory"));
    CHECK_THAT(message(dir.write("empty.toml", "")), Catch::Contains("empty.toml: empty file"));
    CHECK_THAT(message(dir.write("blank.toml", "\n  \n")), Catch::Contains("blank.toml: empty file"));
    CHECK_THAT(message(dir.path() / "absent.toml"), Catch::Contains("absent.toml: cannot open the experiment file: No such file"));
}

TEST_CASE("grid expansion is the cartesian product in declaration order", "[experiment_config]") {
    const auto grid = expand_grid({{"a", {std::int64_t{1}, std::int64_t{2}}}, {"b", {true, false}}, {"c", {0.5}}});
    REQUIRE(grid.size() == 4);
    REQUIRE(std::get<std::int64_t>(grid[1].at("a")) == 1);
    REQUIRE(std::get<bool>(grid[1].at("b")) == false);
    REQUIRE(std::get<std::int64_t>(grid[2].at("a")) == 2);
}

TEST_CASE("a problem's box can be replaced from the config, and lower > upper is refused", "[experiment_config]") {
    testing::TemporaryDirectory dir;
    const std::string base = "name = \"b\"\ntrials = 1\nseed = 1\n[budget]\niterations = 2\n"
                             "[[optimizer]]\nname = \"random_search\"\n[[problem]]\nname = \"test_sphere\"\n";
    auto spec = load_experiment(dir.write("ok.toml", base + "lower = -2\nupper = [1, 2, 3]\n"));
    const auto info = describe_experiment(spec);
    (void)info;
    RunOptions o;
    o.output = dir.path() / "out";
    run_experiment(spec, o);
    for (const auto& r : read_results(dir.path() / "out" / "results.jsonl").records) {
        REQUIRE(r.ok);
        REQUIRE(r.best_position.minCoeff() >= -2.0);
        REQUIRE(r.best_position[0] <= 1.0);
    }
    spec = load_experiment(dir.write("bad.toml", base + "lower = [0, 0, 5]\nupper = [1, 2, 3]\n"));
    try {
        describe_experiment(spec);
        FAIL("accepted lower > upper");
    } catch (const InputError& e) {
        REQUIRE(e.line() == 11);
        REQUIRE_THAT(e.what(), Catch::Contains("lower > upper for x3"));
    }
    spec = load_experiment(dir.write("short.toml", base + "lower = [0, 0]\n"));
    REQUIRE_THROWS_WITH(describe_experiment(spec), Catch::Contains("bounds need 3 values"));
}

TEST_CASE("published numbers are read and checked against the experiment's problems", "[experiment_config]") {
    testing::TemporaryDirectory dir;
    const std::string base = "name = \"p\"\ntrials = 1\nseed = 1\n[budget]\niterations = 2\n"
                             "[[optimizer]]\nname = \"random_search\"\n[[problem]]\nname = \"test_sphere\"\nlabel = \"S\"\n";
    const auto spec = load_experiment(dir.write("ok.toml", base + "[[published]]\nlabel = \"X (paper)\"\nproblem = \"S\"\n"
                                                                 "source = \"a paper\"\nmean = { x1 = 1.5 }\nfitness_mean = 0.25\n"));
    REQUIRE(spec.published.size() == 1);
    REQUIRE(spec.published[0].mean.at("x1") == 1.5);
    REQUIRE(*spec.published[0].fitness_mean == 0.25);
    REQUIRE_NOTHROW(describe_experiment(spec));
    CHECK_THAT(error_of(base + "[[published]]\nlabel = \"X\"\nproblem = \"T\"\nsource = \"s\"\n"),
               Catch::Contains("published[0].problem: 'T' is not a problem label"));
    const auto bad = load_experiment(dir.write("bad.toml", base + "[[published]]\nlabel = \"X\"\nproblem = \"S\"\nsource = \"s\"\nmean = { Rs = 1 }\n"));
    REQUIRE_THROWS_WITH(describe_experiment(bad), Catch::Contains("published.Rs: problem 'S' has no parameter named 'Rs'"));
}

TEST_CASE("every experiment config shipped in experiments/ loads", "[experiment_config]") {
    std::size_t configs = 0;
    for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::path(MHBENCH_SOURCE_DIR) / "experiments")) {
        if (entry.path().extension() != ".toml") continue;
        INFO(entry.path().string());
        const auto spec = load_experiment(entry.path());
        CHECK_FALSE(spec.optimizers.empty());
        ++configs;
    }
    CHECK(configs >= 10);
    // The campaign: 13 optimizers x 24 functions x 6 dimensions x 15 instances, budgets 10^4 x D.
    const auto campaign = load_experiment(std::filesystem::path(MHBENCH_SOURCE_DIR) / "experiments" / "bbob_campaign.toml");
    CHECK(campaign.optimizers.size() * campaign.problems.size() * static_cast<std::size_t>(campaign.trials) == 28080);
    CHECK(campaign.evaluations_per_dimension == 10000);
    CHECK(campaign.anytime.has_value());
}
