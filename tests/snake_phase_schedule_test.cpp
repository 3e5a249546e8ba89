// ISOA's second strategy is a pair of thresholds; this checks where they put the phase
// boundaries, in the schedule and in what the optimiser actually runs.
#include <catch2/catch.hpp>

#include <cmath>

#include "framework/registry.hpp"
#include "optimizers/snake/snake_optimizer.hpp"
#include "tests/manual_run.hpp"
#include "tests/sphere_fixture.hpp"

using namespace mhb;

namespace {

struct PhaseCounts {
    int exploration = 0, hot = 0, fight = 0, mating = 0;
    int last_exploration = 0, last_hot = 0;  // last iteration t of each phase
};

PhaseCounts run_phases(const SnakePhaseSchedule& schedule, int iterations) {
    testing::ShiftedSphere sphere(2, -5, 5, 1.0);
    SnakeSettings settings;
    settings.population = 4;
    settings.schedule = schedule;
    SnakeOptimizer so(settings);
    testing::ManualRun run(sphere, Budget{iterations, 0}, 17);
    run.initialize(so);
    PhaseCounts c;
    for (int t = 1; t <= iterations; ++t) {
        run.iterate(so);
        switch (so.last_phase()) {
            case SnakePhase::Exploration: ++c.exploration; c.last_exploration = t; break;
            case SnakePhase::Hot: ++c.hot; c.last_hot = t; break;
            case SnakePhase::Fight: ++c.fight; break;
            case SnakePhase::Mating: ++c.mating; break;
        }
    }
    return c;
}

}  // namespace

TEST_CASE("Q and Temp follow eq. (7) and (9)", "[snake_phase_schedule]") {
    REQUIRE(SnakePhaseSchedule::food_quantity(0.0) == Approx(0.5 / std::exp(1.0)));
    REQUIRE(SnakePhaseSchedule::food_quantity(1.0) == Approx(0.5));
    REQUIRE(SnakePhaseSchedule::temperature(0.5) == Approx(std::exp(-0.5)));
}

namespace {

// The schedule switches at the fractions `exploration_end` and `hot_end` (derived by hand from the
// thresholds), and a 1000-iteration run spends exactly t = 1..floor(1000 x) in each phase.
PhaseCounts require_boundaries(const SnakePhaseSchedule& schedule, double exploration_end, double hot_end) {
    REQUIRE(schedule.exploring(exploration_end - 1e-4));
    REQUIRE_FALSE(schedule.exploring(exploration_end + 1e-4));
    REQUIRE(schedule.hot(hot_end - 1e-4));
    REQUIRE_FALSE(schedule.hot(hot_end + 1e-4));
    const int last_exploration = static_cast<int>(1000 * exploration_end), last_hot = static_cast<int>(1000 * hot_end);
    const auto c = run_phases(schedule, 1000);
    REQUIRE(c.exploration == last_exploration);
    REQUIRE(c.last_exploration == last_exploration);
    REQUIRE(c.hot == last_hot - last_exploration);
    REQUIRE(c.last_hot == last_hot);
    REQUIRE(c.fight + c.mating == 1000 - last_hot);
    return c;
}

}  // namespace

TEST_CASE("SO's thresholds: exploration for t < 0.307 T, hot for t < 0.511 T", "[snake_phase_schedule]") {
    // Q = 0.5 exp(t/T - 1) < 0.25  <=>  t/T < 1 - ln 2 = 0.306853;
    // exp(-t/T) > 0.6              <=>  t/T < -ln 0.6 = 0.510826.
    const auto c = require_boundaries({0.25, 0.6}, 0.306853, 0.510826);
    // 490 cold iterations, fight with probability 0.4 (SO.m: rand > 0.6 is fight): mean 196, sd 10.8.
    REQUIRE(std::abs(c.fight - 196) < 54);
}

TEST_CASE("ISOA's thresholds: exploration for t < 0.179 T, hot for t < 0.223 T", "[snake_phase_schedule]") {
    // Q < 0.22  <=>  t/T < 1 + ln 0.44 = 0.179019;  exp(-t/T) > 0.8  <=>  t/T < -ln 0.8 = 0.223144.
    require_boundaries({0.22, 0.8}, 0.179019, 0.223144);
}

TEST_CASE("the registered names carry the thresholds of their strategies", "[snake_phase_schedule]") {
    const auto& soa = OptimizerRegistry::instance().at("soa", "optimizer");
    const auto& isoa = OptimizerRegistry::instance().at("isoa", "optimizer");
    const ParameterSet soa_defaults(soa.parameters, {}), isoa_defaults(isoa.parameters, {});
    REQUIRE(soa_defaults.real("food_threshold") == 0.25);
    REQUIRE(soa_defaults.real("temperature_threshold") == 0.6);
    REQUIRE(isoa_defaults.real("food_threshold") == 0.22);
    REQUIRE(isoa_defaults.real("temperature_threshold") == 0.8);
}
