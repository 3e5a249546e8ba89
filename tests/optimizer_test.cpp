// The evaluator is the framework's guard on every optimiser: it counts, enforces the budget and
// refuses candidates outside the box.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

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

TEST_CASE("evaluator refuses every kind of bad coordinate wherever it stands, and names the first", "[evaluator]") {
    // D = 3: coordinates 1 and 2 are checked two at a time, coordinate 3 alone.
    testing::ShiftedSphere sphere(3, -1, 1, 0.0);
    const double inf = std::numeric_limits<double>::infinity();
    for (const double bad : {-1.5, 1.5, std::nan(""), inf, -inf}) {
        for (Eigen::Index row = 0; row < 3; ++row) {
            for (Eigen::Index column = 0; column < 4; ++column) {
                Evaluator ev(sphere, Budget{10, 0});
                Matrix x = Matrix::Constant(3, 4, 0.5);
                x(row, column) = bad;
                Vector f(4);
                INFO("value " << bad << " at x" << row + 1 << " of candidate " << column);
                try {
                    ev.evaluate(x, f);
                    FAIL("not refused");
                } catch (const PluginFault& e) {
                    const std::string what = e.what();
                    REQUIRE_THAT(what, Catch::Contains("x" + std::to_string(row + 1)));
                    REQUIRE_THAT(what, Catch::EndsWith("in candidate " + std::to_string(column)));
                }
                REQUIRE(ev.evaluations() == 0);
            }
        }
    }
    SECTION("the first bad coordinate, column by column, is the one named") {
        Evaluator ev(sphere, Budget{10, 0});
        Matrix x = Matrix::Zero(3, 3);
        x(2, 1) = 2.0;
        x(0, 2) = std::nan("");
        Vector f(3);
        REQUIRE_THROWS_WITH(ev.evaluate(x, f), "optimizer produced x3 = 2 outside [-1, 1] in candidate 1");
    }
    SECTION("the bounds themselves are inside") {
        Evaluator ev(sphere, Budget{10, 0});
        Matrix x(3, 2);
        x << -1, 1, 1, -1, -1, 1;
        Vector f(2);
        REQUIRE(ev.evaluate(x, f) == 2);
    }
    SECTION("an infinity is refused even in an infinite box") {
        testing::ShiftedSphere unbounded(3, -inf, inf, 0.0);
        Evaluator ev(unbounded, Budget{10, 0});
        Matrix x = Matrix::Zero(3, 2);
        x(1, 1) = inf;
        Vector f(2);
        REQUIRE_THROWS_WITH(ev.evaluate(x, f), "optimizer produced a non-finite coordinate x2 = inf in candidate 1");
    }
    SECTION("columns past the budget are neither evaluated nor checked") {
        Evaluator ev(sphere, Budget{0, 2});
        Matrix x = Matrix::Zero(3, 3);
        x(0, 2) = 5.0;
        Vector f(3);
        REQUIRE(ev.evaluate(x, f) == 2);
        REQUIRE(std::isinf(f[2]));
    }
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

TEST_CASE("clamp_to_bounds gives what Eigen's cwiseMax(lower).cwiseMin(upper) gives, NaN and infinities included", "[evaluator]") {
    const double inf = std::numeric_limits<double>::infinity();
    Bounds box{Vector(5), Vector(5)};
    box.lower << -1, -2, -inf, 0, -3;
    box.upper << 1, 2, 4, 0, inf;
    const double values[] = {-5.0, -1.0, -0.0, 0.0, 0.5, 1.0, 3.0, inf, -inf, std::nan("")};
    Matrix x(5, 10 * 10);
    Eigen::Index c = 0;
    for (const double a : values)
        for (const double b : values) {
            for (Eigen::Index j = 0; j < 5; ++j) x(j, c) = (j % 2 == 0) ? a : b;
            ++c;
        }
    Matrix expected = x;
    for (Eigen::Index i = 0; i < expected.cols(); ++i)
        expected.col(i) = expected.col(i).cwiseMax(box.lower).cwiseMin(box.upper);
    clamp_to_bounds(x, box);
    // Bit for bit: the same NaNs in the same places, the same signed zeros.
    REQUIRE(std::memcmp(x.data(), expected.data(), sizeof(double) * static_cast<std::size_t>(x.size())) == 0);
    // A block of columns of a larger matrix (an outer stride other than the rows) is clamped in place.
    Matrix wide = Matrix::Constant(5, 4, 10.0);
    clamp_to_bounds(wide.middleCols(1, 2), box);
    REQUIRE(wide.col(0).isConstant(10.0));
    REQUIRE(wide.col(3).isConstant(10.0));
    REQUIRE(wide.col(1) == Vector((Vector(5) << 1, 2, 4, 0, 10).finished()));
}
