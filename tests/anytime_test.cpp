// Anytime records: what the evaluator reports while a trial runs, checked against a replay of every
// evaluation the problem saw.
#include <catch2/catch.hpp>

#include <cmath>

#include "framework/anytime.hpp"
#include "framework/experiment_config.hpp"
#include "framework/input_error.hpp"
#include "framework/registry.hpp"
#include "framework/results_store.hpp"
#include "framework/trial.hpp"
#include "tests/recording_problem.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;

TEST_CASE("COCO's targets: 10^2 down to 10^-8, five per decade, powers of ten exact", "[anytime]") {
    const auto t = bbob_targets();
    REQUIRE(t.size() == 51);
    CHECK(t.front() == 100.0);
    CHECK(t.back() == 1e-8);
    CHECK(t[15] == 1e-1);
    CHECK(t[25] == 1e-3);
    for (std::size_t i = 1; i < t.size(); ++i) CHECK(t[i - 1] / t[i] == Approx(std::pow(10.0, 0.2)).epsilon(1e-12));
}

TEST_CASE("checkpoints are log-spaced evaluation counts, each once", "[anytime]") {
    AnytimeSpec spec;
    spec.targets = {1.0};
    for (const auto& [per_decade, want] : std::vector<std::pair<int, std::vector<std::int64_t>>>{
             {5, {1, 2, 3, 4, 7, 10, 16, 26, 40, 64, 100, 159, 252, 399, 631, 1000}},
             {1, {1, 10, 100, 1000}},
             {20, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 12, 13, 15, 16, 18, 20, 23, 26, 29, 32, 36, 40}}}) {
        spec.points_per_decade = per_decade;
        AnytimeRecorder recorder(spec, 0.0);
        const std::int64_t last = want.back();
        for (std::int64_t k = 1; k <= last; ++k) recorder.observe(k, 10.0 / static_cast<double>(k));
        const auto record = recorder.take();
        INFO(per_decade << " per decade");
        CHECK(record.evaluations == want);
        for (std::size_t i = 0; i < want.size(); ++i) CHECK(record.best[i] == 10.0 / static_cast<double>(want[i]));
        CHECK(record.hits == std::vector<std::int64_t>{10});  // 10 / k <= 1 first at k = 10
    }
    spec.points_per_decade = 0;
    AnytimeRecorder none(spec, 0.0);
    for (std::int64_t k = 1; k <= 100; ++k) none.observe(k, 5.0);
    const auto record = none.take();
    CHECK(record.evaluations.empty());
    CHECK(record.hits == std::vector<std::int64_t>{0});
    CHECK(std::isnan(record.hit_best[0]));
}

TEST_CASE("a trial's anytime record equals the replay of every evaluation, for whole populations at once", "[anytime]") {
    AnytimeSpec spec;
    spec.targets = bbob_targets();
    spec.points_per_decade = 5;
    spec.checkpoints = {0.01, 0.3, 0.999, 1.0};  // 25, 750, 2500 and 2503 of the budget of 2503
    // Odd population sizes and a budget that ends inside a population.
    for (const auto& [name, values] : std::vector<std::pair<std::string, std::map<std::string, ParameterValue>>>{
             {"random_search", {{"batch", std::int64_t{7}}}}, {"cmaes", {}}, {"isoa", {}}}) {
        INFO(name);
        testing::RecordingSphere problem(4, -5.0, 5.0, 1.5);
        const double optimum = 0.0;
        auto optimizer = make_optimizer(name, values);
        TrialSetup setup{Budget{0, 2503}, 17, false};
        setup.anytime = &spec;
        setup.optimum = optimum;
        const auto rec = run_trial(*optimizer, problem, setup);
        REQUIRE(rec.ok);
        REQUIRE(rec.evaluations == 2503);

        // The replay: best-so-far after each evaluation, in the order the problem saw them.
        std::vector<double> best_after{};
        double best = std::numeric_limits<double>::infinity();
        for (const auto& batch : problem.batches())
            for (Eigen::Index i = 0; i < batch.f.size(); ++i) {
                best = std::min(best, batch.f[i]);
                best_after.push_back(best);
            }
        REQUIRE(best_after.size() == 2503);
        REQUIRE(rec.anytime.hits.size() == spec.targets.size());
        std::size_t reached = 0;
        for (std::size_t t = 0; t < spec.targets.size(); ++t) {
            std::int64_t first = 0;
            for (std::size_t k = 0; k < best_after.size() && first == 0; ++k)
                if (best_after[k] - optimum <= spec.targets[t]) first = static_cast<std::int64_t>(k + 1);
            CHECK(rec.anytime.hits[t] == first);
            if (first > 0) {
                ++reached;
                CHECK(rec.anytime.hit_best[t] == best_after[static_cast<std::size_t>(first - 1)]);
            }
        }
        CHECK(reached > 0);  // the check compared hits, not only misses
        for (std::size_t c = 0; c < rec.anytime.evaluations.size(); ++c)
            CHECK(rec.anytime.best[c] == best_after[static_cast<std::size_t>(rec.anytime.evaluations[c] - 1)]);
        CHECK(rec.anytime.evaluations.back() == 1585);  // the last checkpoint within 2503
        REQUIRE(rec.anytime.checkpoint_evaluations == std::vector<std::int64_t>{25, 750, 2500, 2503});
        for (std::size_t c = 0; c < 4; ++c)
            CHECK(rec.anytime.checkpoint_best[c] == best_after[static_cast<std::size_t>(rec.anytime.checkpoint_evaluations[c] - 1)]);

        // Without the per-iteration trace: the same anytime record, and the final state as the trace.
        testing::RecordingSphere again_problem(4, -5.0, 5.0, 1.5);
        auto again_optimizer = make_optimizer(name, values);
        setup.record_trace = false;
        const auto lean = run_trial(*again_optimizer, again_problem, setup);
        CHECK(lean.anytime.hits == rec.anytime.hits);
        CHECK(lean.anytime.best == rec.anytime.best);
        CHECK(lean.best_fitness == rec.best_fitness);
        CHECK(lean.trace_evaluations == std::vector<std::int64_t>{2503});
        CHECK(lean.trace_best == std::vector<double>{rec.best_fitness});
        CHECK(rec.trace_best.size() > 10);

        // Through JSON and back, bit for bit.
        const auto again = trial_from_json(nlohmann::json::parse(to_json(rec).dump()));
        CHECK(again.anytime.evaluations == rec.anytime.evaluations);
        CHECK(again.anytime.best == rec.anytime.best);
        CHECK(again.anytime.hits == rec.anytime.hits);
        CHECK(again.anytime.checkpoint_evaluations == rec.anytime.checkpoint_evaluations);
        CHECK(again.anytime.checkpoint_best == rec.anytime.checkpoint_best);
        for (std::size_t t = 0; t < rec.anytime.hit_best.size(); ++t)
            CHECK((again.anytime.hit_best[t] == rec.anytime.hit_best[t] ||
                   (std::isnan(again.anytime.hit_best[t]) && std::isnan(rec.anytime.hit_best[t]))));
    }
}

TEST_CASE("the budget's checkpoints: the CEC 2017 and CEC 2022 rules as their reports state them", "[anytime]") {
    AnytimeSpec spec;
    REQUIRE(set_named_checkpoints(spec, "cec2017"));
    // Awad et al. 2016, 2.2: (0.01, 0.02, 0.03, 0.05, 0.1, 0.2, ..., 1.0) x MaxFES; MaxFES = 10000 D.
    CHECK(checkpoint_evaluations(spec, 10, 100000) ==
          std::vector<std::int64_t>{1000, 2000, 3000, 5000, 10000, 20000, 30000, 40000, 50000, 60000, 70000, 80000, 90000, 100000});
    REQUIRE(set_named_checkpoints(spec, "cec2022"));
    // Kumar et al. 2021, 2.2: floor(D^(k/5 - 3) MaxFES), k = 0..15 (the report's example at D = 10
    // names 200 000 / 10 = 20 000 as k = 10); the values below are that formula worked out apart.
    CHECK(checkpoint_evaluations(spec, 10, 200000) == std::vector<std::int64_t>{200, 316, 502, 796, 1261, 2000, 3169, 5023, 7962, 12619,
                                                                                20000, 31697, 50237, 79621, 126191, 200000});
    CHECK(checkpoint_evaluations(spec, 20, 1000000) == std::vector<std::int64_t>{125, 227, 414, 754, 1373, 2500, 4551, 8286, 15085,
                                                                                 27464, 50000, 91028, 165722, 301708, 549280, 1000000});
    CHECK_FALSE(set_named_checkpoints(spec, "cec2014"));
    // A small budget: counts of at least 1, each once.
    AnytimeSpec fractions;
    fractions.checkpoints = {0.001, 0.002, 0.5, 1.0};
    CHECK(checkpoint_evaluations(fractions, 3, 100) == std::vector<std::int64_t>{1, 50, 100});
    CHECK(checkpoint_evaluations(fractions, 3, 0).empty());  // no evaluation budget, no checkpoints
}

TEST_CASE("[anytime] in a config: defaults, lists, and refusals that name the line", "[anytime][config]") {
    testing::TemporaryDirectory dir;
    const std::string head = "trials = 2\nseed = 1\n";
    const std::string tail = "[budget]\nevaluations = 100\n[[optimizer]]\nname = \"random_search\"\n[[problem]]\nname = \"test_sphere\"\n";
    auto load = [&](const std::string& anytime) { return load_experiment(dir.write("a.toml", head + anytime + tail)); };
    auto error = [&](const std::string& anytime) -> std::string {
        try {
            load(anytime);
        } catch (const InputError& e) {
            return e.what();
        }
        return "(accepted)";
    };

    CHECK_FALSE(load("").anytime.has_value());
    const auto defaults = load("[anytime]\n").anytime;
    REQUIRE(defaults.has_value());
    CHECK(defaults->targets == bbob_targets());
    CHECK(defaults->ert_targets == std::vector<double>{1e1, 1e-1, 1e-3, 1e-5, 1e-7});
    CHECK(defaults->points_per_decade == 5);
    CHECK(defaults->bootstrap == 1000);

    const auto listed = load("[anytime]\ntargets = [1e-3, 1, 1e-1, 1]\nert_targets = [1]\npoints_per_decade = 2\nbootstrap = 0\n").anytime;
    CHECK(listed->targets == std::vector<double>{1.0, 1e-1, 1e-3});  // sorted, duplicates dropped
    CHECK(listed->ert_targets == std::vector<double>{1.0});
    CHECK(listed->points_per_decade == 2);
    CHECK(listed->iteration_trace);
    CHECK_FALSE(load("[anytime]\niteration_trace = false\n").anytime->iteration_trace);
    CHECK_THAT(error("[anytime]\niteration_trace = 0\n"), Catch::Contains("a.toml:4: anytime.iteration_trace: expects true or false"));

    CHECK_THAT(error("[anytime]\ntargets = [1, -2]\n"), Catch::Contains("a.toml:4: anytime.targets: expects positive finite numbers"));
    CHECK_THAT(error("[anytime]\ntargets = \"coco\"\n"), Catch::Contains("anytime.targets: expects \"bbob\" or a list"));
    CHECK_THAT(error("[anytime]\ntargets = [1, 1e-2]\nert_targets = [1e-1]\n"),
               Catch::Contains("a.toml:5: anytime.ert_targets: 0.1 is not among anytime.targets"));
    CHECK_THAT(error("[anytime]\npoints_per_decade = 1000\n"), Catch::Contains("anytime.points_per_decade: must be <= 100"));
    CHECK_THAT(error("[anytime]\nevery = 3\n"), Catch::Contains("a.toml:4: anytime.every: unknown key"));

    CHECK(load("[anytime]\ncheckpoints = [1, 0.5, 0.5]\n").anytime->checkpoints == std::vector<double>{0.5, 1.0});
    const auto cec = load("[anytime]\ncheckpoints = \"cec2022\"\n").anytime;
    CHECK(cec->checkpoints_rule == "cec2022");
    CHECK(cec->checkpoint_exponents.size() == 16);
    CHECK_THAT(error("[anytime]\ncheckpoints = [0.5, 1.5]\n"),
               Catch::Contains("a.toml:4: anytime.checkpoints: expects \"cec2017\", \"cec2022\" or a list of fractions"));
    CHECK_THAT(error("[anytime]\ncheckpoints = \"cec2014\"\n"), Catch::Contains("a.toml:4: anytime.checkpoints: expects"));
    CHECK_THAT(error("[anytime]\ncheckpoints = []\n"), Catch::Contains("a.toml:4: anytime.checkpoints: expects"));
    const auto iterations_only = dir.write("i.toml", head + "[anytime]\ncheckpoints = [1]\n[budget]\niterations = 10\n"
                                                           "[[optimizer]]\nname = \"random_search\"\n[[problem]]\nname = \"test_sphere\"\n");
    CHECK_THROWS_WITH(load_experiment(iterations_only),
                      Catch::Contains("i.toml:4: anytime.checkpoints: are fractions of the evaluation budget"));
}
