#include <catch2/catch.hpp>

#include "framework/input_error.hpp"
#include "framework/results_store.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;

TEST_CASE("trial records survive a JSON round trip, infinities included", "[results_store]") {
    TrialRecord r;
    r.optimizer = "gwo";
    r.problem = "F1";
    r.trial = 4;
    r.seed = 0xFFFFFFFFFFFFFFFFULL;
    r.ok = false;
    r.error = "boom";
    r.best_fitness = 1.0 / 3.0;
    r.best_position = Vector::LinSpaced(3, -1, 1);
    r.evaluations = 30;
    r.iterations = 2;
    r.seconds = 0.25;
    r.trace_evaluations = {10, 20, 30};
    r.trace_best = {std::numeric_limits<double>::infinity(), 2.0, 1.0 / 3.0};
    r.trace_position = {Vector::Zero(3), Vector::Ones(3), r.best_position};
    const auto back = trial_from_json(to_json(r));
    REQUIRE(back.seed == r.seed);
    REQUIRE_FALSE(back.ok);
    REQUIRE(back.error == "boom");
    REQUIRE(back.best_fitness == r.best_fitness);
    REQUIRE(back.best_position == r.best_position);
    REQUIRE(std::isinf(back.trace_best[0]));
    REQUIRE(back.trace_best[2] == r.trace_best[2]);
    REQUIRE(back.trace_position[1] == Vector::Ones(3));
}

TEST_CASE("a corrupt line in the middle of a results file is bad input", "[results_store]") {
    testing::TemporaryDirectory dir;
    TrialRecord r;
    r.best_position = Vector::Zero(1);
    const std::string good = to_json(r).dump();
    const auto path = dir.write("results.jsonl", good + "\n{not json\n" + good + "\n");
    try {
        read_results(path);
        FAIL("accepted");
    } catch (const InputError& e) {
        REQUIRE(e.line() == 2);
    }
}

TEST_CASE("many records read back in file order, an incomplete last line as a note and the first bad line by its number", "[results_store]") {
    // Enough lines that the parallel parse splits them between threads.
    testing::TemporaryDirectory dir;
    std::string text;
    for (int k = 0; k < 500; ++k) {
        TrialRecord r;
        r.trial = k;
        r.best_fitness = 1.0 / (k + 1);
        r.best_position = Vector::Constant(2, k);
        text += to_json(r).dump() + "\n";
    }
    const std::string cut = text + R"({"optimizer":"gw)";
    const auto loaded = read_results(dir.write("cut.jsonl", cut));
    REQUIRE(loaded.records.size() == 500);
    for (int k = 0; k < 500; ++k) {
        REQUIRE(loaded.records[static_cast<std::size_t>(k)].trial == k);
        REQUIRE(loaded.records[static_cast<std::size_t>(k)].best_fitness == 1.0 / (k + 1));
    }
    REQUIRE(loaded.notes.size() == 1);
    REQUIRE_THAT(loaded.notes[0], Catch::Contains(":501: ignored an incomplete last line"));

    // Bad lines at 401 and 101 (1-based), the cut line at the end: the error names line 101.
    std::string bad;
    int line = 0;
    for (std::size_t start = 0; start < text.size(); ++line) {
        const std::size_t end = text.find('\n', start);
        bad += (line == 100 || line == 400) ? std::string("{not json\n") : text.substr(start, end - start + 1);
        start = end + 1;
    }
    try {
        read_results(dir.write("bad.jsonl", bad + R"({"optimizer":"gw)"));
        FAIL("accepted");
    } catch (const InputError& e) {
        REQUIRE(e.line() == 101);
    }
}

TEST_CASE("experiment.json from before the config text and provenance were recorded still reads", "[results_store]") {
    ExperimentInfo info;
    info.name = "old";
    info.trials = 3;
    info.config_text = "name = \"old\"\n";
    info.runs.push_back(current_provenance(4));
    auto j = to_json(info);
    const auto back = experiment_from_json(j);
    REQUIRE(back.config_text == info.config_text);
    REQUIRE(back.runs.size() == 1);
    REQUIRE(back.runs[0].threads == 4);
    REQUIRE(back.runs[0].date == info.runs[0].date);
    REQUIRE(back.runs[0].system == info.runs[0].system);
    j.erase("config_text");
    j.erase("runs");
    const auto old = experiment_from_json(j);
    REQUIRE(old.name == "old");
    REQUIRE(old.config_text.empty());
    REQUIRE(old.runs.empty());
}
