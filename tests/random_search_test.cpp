#include <catch2/catch.hpp>

#include "framework/registry.hpp"
#include "framework/trial.hpp"
#include "tests/sphere_fixture.hpp"

using namespace mhb;

TEST_CASE("random search uses exactly its budget and improves with more samples", "[random_search]") {
    testing::ShiftedSphere sphere(2, -5, 5, 1.5);
    auto opt = make_optimizer("random_search", {{"batch", std::int64_t{50}}});
    const auto small = run_trial(*opt, sphere, {Budget{0, 120}, 9, false});
    REQUIRE(small.ok);
    REQUIRE(small.evaluations == 120);
    REQUIRE(small.trace_evaluations.back() == 120);
    // Expected best of n uniform samples in a 2-D box of side 10: P(f < r^2) = pi r^2 / 100, so
    // with 20000 samples the best is below 0.01 with probability 1 - (1 - pi/1e4)^20000 > 0.998.
    auto opt2 = make_optimizer("random_search", {{"batch", std::int64_t{100}}});
    const auto big = run_trial(*opt2, sphere, {Budget{199, 0}, 9, false});
    REQUIRE(big.evaluations == 20000);
    REQUIRE(big.best_fitness < 0.01);
    // best-so-far never increases
    for (std::size_t k = 1; k < big.trace_best.size(); ++k) REQUIRE(big.trace_best[k] <= big.trace_best[k - 1]);
}

TEST_CASE("a seed fixes the whole trial", "[random_search]") {
    testing::ShiftedSphere sphere(4, -5, 5, 0.0);
    auto a = make_optimizer("random_search");
    auto b = make_optimizer("random_search");
    const auto ra = run_trial(*a, sphere, {Budget{20, 0}, 77, true});
    const auto rb = run_trial(*b, sphere, {Budget{20, 0}, 77, true});
    REQUIRE(ra.best_fitness == rb.best_fitness);
    REQUIRE(ra.trace_best == rb.trace_best);
    REQUIRE(ra.trace_position.size() == 21);
}

TEST_CASE("an iteration budget at the int64 maximum runs to the evaluation budget (no overflow, no huge reservation)", "[random_search]") {
    testing::ShiftedSphere sphere(2, -5, 5, 1.5);
    auto opt = make_optimizer("random_search", {{"batch", std::int64_t{10}}});
    const auto r = run_trial(*opt, sphere, {Budget{std::numeric_limits<std::int64_t>::max(), 100}, 3, false});
    REQUIRE(r.ok);
    REQUIRE(r.evaluations == 100);
    REQUIRE(r.iterations == 9);  // 10 at initialisation, then 9 batches of 10
}
