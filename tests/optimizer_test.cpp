// The evaluator is the framework's guard on every optimiser: it counts, enforces the budget and
// refuses candidates outside the box.
#include <catch2/catch.hpp>

#include "framework/input_error.hpp"
#include "framework/optimizer.hpp"
#include "tests/sphere_fixture.hpp"

using namespace mhb;

TEST_CASE("evaluator counts evaluations and stops exactly at the budget", "[evaluator]") {
    testing::ShiftedSphere sphere(3, -5, 5, 1.0);
    Evaluator ev(sphere, Budget{0, 25});
    Matrix x = Matrix::Constant(3, 10, 1.0);
    x(0, 4) = 2.0;
    Vector f(10);
    REQUIRE(ev.evaluate(x, f) == 10);
    REQUIRE(f[4] == 1.0);
    REQUIRE(ev.evaluate(x, f) == 10);
    REQUIRE(ev.evaluate(x, f) == 5);  // only 5 remain
    REQUIRE(std::isinf(f[5]));
    REQUIRE(ev.exhausted());
    REQUIRE(ev.evaluations() == 25);
    REQUIRE(ev.evaluate(x, f) == 0);
    REQUIRE(ev.best_fitness() == 0.0);
}

TEST_CASE("evaluator refuses candidates outside the box or not finite", "[evaluator]") {
    testing::ShiftedSphere sphere(2, -1, 1, 0.0);
    Evaluator ev(sphere, Budget{10, 0});
    Matrix x = Matrix::Zero(2, 3);
    Vector f(3);
    x(1, 2) = 1.0000001;
    REQUIRE_THROWS_AS(ev.evaluate(x, f), PluginFault);
    x(1, 2) = std::nan("");
    REQUIRE_THROWS_AS(ev.evaluate(x, f), PluginFault);
}

TEST_CASE("progress fraction follows the budget kind", "[evaluator]") {
    Progress p;
    p.budget = Budget{200, 0};
    p.iteration = 50;
    REQUIRE(p.fraction() == Approx(0.25));
    REQUIRE(p.fraction(-1) == Approx(49.0 / 200.0));
    p.budget = Budget{0, 1000};
    p.evaluations = 300;
    p.last_step_evaluations = 100;
    REQUIRE(p.fraction() == Approx(0.3));
    // GWO.m's l/T under an evaluation budget: one step back.
    REQUIRE(p.fraction(-1) == Approx(0.2));
}
