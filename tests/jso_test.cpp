// jSO (Brest, Maučec & Bošković, CEC 2017): each rule it changes in L-SHADE against the paper's
// numbers, and the optima it reaches on easy functions.
#include <catch2/catch.hpp>

#include "framework/registry.hpp"
#include "framework/trial.hpp"
#include "optimizers/jso.hpp"
#include "tests/optimizer_contract.hpp"

using namespace mhb;

namespace {

const shade::Jso& jso_of(const Optimizer& o) { return dynamic_cast<const shade::Jso&>(o); }

}  // namespace

TEST_CASE("jso: initial population round(25 ln(D) sqrt(D)) and its schedules of CR, F, F_w and p", "[jso]") {
    const auto optimizer = make_optimizer("jso");
    const auto& jso = jso_of(*optimizer);
    // 25 ln(10) sqrt(10) = 182.03, 25 ln(30) sqrt(30) = 465.73, 25 ln(50) sqrt(50) = 691.55 , 25 ln(100) sqrt(100) = 1151.29.
    CHECK(jso.initial_population(10) == 182);
    CHECK(jso.initial_population(30) == 466);
    CHECK(jso.initial_population(50) == 692);
    CHECK(jso.initial_population(100) == 1151);
    // CR at least 0.7 in the first quarter of the budget, at least 0.6 in the second.
    CHECK(jso.adjusted_cr(0.2, 0.0) == 0.7);
    CHECK(jso.adjusted_cr(0.9, 0.1) == 0.9);
    CHECK(jso.adjusted_cr(0.2, 0.25) == 0.6);
    CHECK(jso.adjusted_cr(0.2, 0.5) == 0.2);
    // F at most 0.7 in the first 60 %.
    CHECK(jso.adjusted_f(0.9, 0.59) == 0.7);
    CHECK(jso.adjusted_f(0.9, 0.6) == 0.9);
    // F_w = 0.7 F, 0.8 F, 1.2 F.
    CHECK(jso.pbest_factor(0.5, 0.1) == Approx(0.35));
    CHECK(jso.pbest_factor(0.5, 0.3) == Approx(0.4));
    CHECK(jso.pbest_factor(0.5, 0.4) == Approx(0.6));
    // p from 0.25 down to 0.125; the pbest may be the target only in the second half.
    CHECK(jso.p_best_rate(0.0) == 0.25);
    CHECK(jso.p_best_rate(1.0) == 0.125);
    CHECK(jso.p_best_rate(0.5) == Approx(0.1875));
    CHECK_FALSE(jso.pbest_may_be_target(0.49));
    CHECK(jso.pbest_may_be_target(0.5));
    // The last of H = 5 memory slots is fixed at (0.9, 0.9).
    CHECK(jso.memory_means(4) == std::pair{0.9, 0.9});
}

TEST_CASE("jso: the memory update averages the old entry with the generation's Lehmer means", "[jso]") {
    const auto optimizer = make_optimizer("jso");
    const auto& jso = jso_of(*optimizer);
    // Initial entries 0.3 and 0.8; Lehmer means 13/14 (the hand example of lshade_test) and 0.6.
    const auto [f, cr] = jso.updated_memory(0.3, 0.8, 13.0 / 14.0, 0.6);
    CHECK(f == Approx((13.0 / 14.0 + 0.3) / 2));
    CHECK(cr == Approx(0.7));
    // Every successful CR was 0: the terminal -1 averaged with 0.8 gives -0.1, read as CR = 0.
    CHECK(jso.updated_memory(0.3, 0.8, 0.5, shade::terminal_cr).second == Approx(-0.1));
    // By default a slot below 0 leaves ⊥ as later means pull it up: (-0.1 + 0.6) / 2 = 0.25.
    CHECK(jso.updated_memory(0.3, -0.1, 0.5, 0.6).second == Approx(0.25));
    // sticky_terminal_cr = true keeps it at ⊥; F is averaged as before.
    const auto sticky = make_optimizer("jso", {{"sticky_terminal_cr", true}});
    const auto [sticky_f, sticky_cr] = jso_of(*sticky).updated_memory(0.3, -0.1, 0.5, 0.6);
    CHECK(sticky_f == Approx(0.4));
    CHECK(sticky_cr == shade::terminal_cr);
    CHECK(jso_of(*sticky).updated_memory(0.3, 0.8, 13.0 / 14.0, 0.6).second == Approx(0.7));
}

TEST_CASE("jso keeps the framework's contract: a seed fixes the run, affine maps of f change nothing, never outside the box", "[jso]") {
    testing::check_seed_fixes_run("jso", {{"population", std::int64_t{20}}});
    // Not to any monotone map of f: the memory weighs successes by their improvement |f(u) - f(x)|
    // (a rank-based optimiser passes check_invariance_to_monotone_transform); to a positive affine one, yes.
    testing::check_invariance_to_affine_transform("jso", {{"population", std::int64_t{20}}});
    const auto corner = testing::run_against_corner("jso", {}, 6000, 3);
    CHECK(corner.best_fitness == Approx(12.0).epsilon(1e-6));
}

TEST_CASE("jso solves CEC2017 F1 and F3 at D = 10 in every one of 10 runs", "[jso]") {
    const auto f1 = make_problem("cec2017_f1", {{"dimension", std::int64_t{10}}});
    const auto f3 = make_problem("cec2017_f3", {{"dimension", std::int64_t{10}}});
    for (const Problem* problem : {f1.get(), f3.get()})
        for (std::uint64_t seed = 1; seed <= 10; ++seed) {
            auto opt = make_optimizer("jso");
            const auto r = run_trial(*opt, *problem, {Budget{0, 100000}, seed, false});
            REQUIRE(r.ok);
            CHECK(r.best_fitness - *problem->truth().optimum_value <= 1e-8);
        }
}
