#include <catch2/catch.hpp>

#include <fstream>

#include "framework/experiment_runner.hpp"
#include "framework/input_error.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;

namespace {
std::string config(const std::string& optimizers, const std::string& problems, int trials = 6) {
    return "name = \"r\"\ntrials = " + std::to_string(trials) + "\nseed = 99\n[budget]\niterations = 15\n" + optimizers + problems;
}
const std::string two_optimizers = "[[optimizer]]\nname = \"random_search\"\nbatch = [4, 16]\n";
const std::string two_problems = "[[problem]]\nname = \"test_sphere\"\ndimension = [2, 5]\n";

std::map<std::tuple<std::string, std::string, std::int64_t>, TrialRecord> by_key(const std::vector<TrialRecord>& records) {
    std::map<std::tuple<std::string, std::string, std::int64_t>, TrialRecord> out;
    for (const auto& r : records) out[{r.optimizer, r.problem, r.trial}] = r;
    return out;
}

void require_same_results(const std::vector<TrialRecord>& a, const std::vector<TrialRecord>& b) {
    const auto ka = by_key(a), kb = by_key(b);
    REQUIRE(ka.size() == kb.size());
    for (const auto& [key, ra] : ka) {
        const auto& rb = kb.at(key);
        REQUIRE(ra.seed == rb.seed);
        REQUIRE(ra.best_fitness == rb.best_fitness);  // bitwise
        REQUIRE(ra.trace_best == rb.trace_best);
        REQUIRE(ra.evaluations == rb.evaluations);
    }
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

TEST_CASE("a new run keeps the previous results aside instead of deleting them", "[experiment_runner]") {
    testing::TemporaryDirectory dir;
    const auto spec = load_experiment(dir.write("e.toml", config(two_optimizers, two_problems, 2)));
    RunOptions o;
    o.output = dir.path() / "out";
    run_experiment(spec, o);
    const auto first = testing::read_file(dir.path() / "out" / "results.jsonl");
    const auto s = run_experiment(spec, o);
    REQUIRE(testing::read_file(dir.path() / "out" / "results.previous.jsonl") == first);
    REQUIRE(s.notes.size() == 1);
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
