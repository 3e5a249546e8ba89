// L-SHADE (Tanabe & Fukunaga, CEC 2014): the population size reduction schedule, the memory update
// on a hand example, the framework's contract, and the optima it reaches on easy functions.
#include <catch2/catch.hpp>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "framework/registry.hpp"
#include "framework/trial.hpp"
#include "optimizers/lshade.hpp"
#include "tests/manual_run.hpp"
#include "tests/optimizer_contract.hpp"
#include "tests/sphere_fixture.hpp"

using namespace mhb;

namespace {

// Share of runs whose error f - f* ends at most 1e-8 (the competitions' "solved").
double solved_rate(const std::string& optimizer, const std::string& problem_name, int dimension,
                   std::int64_t evaluations, int runs) {
    const auto problem = make_problem(problem_name, {{"dimension", std::int64_t{dimension}}});
    int solved = 0;
    for (int seed = 1; seed <= runs; ++seed) {
        auto opt = make_optimizer(optimizer);
        const auto r = run_trial(*opt, *problem, {Budget{0, evaluations}, static_cast<std::uint64_t>(seed), false});
        REQUIRE(r.ok);
        if (r.best_fitness - *problem->truth().optimum_value <= 1e-8) ++solved;
    }
    return static_cast<double>(solved) / runs;
}

}  // namespace

TEST_CASE("lshade: the planned population N_{G+1} = round((N_min - N_init) NFE/MAX_NFE + N_init)", "[lshade]") {
    // By hand, N_init = 180 (18 x 10), N_min = 4.
    CHECK(shade::planned_population(180, 4, 0.0) == 180);
    CHECK(shade::planned_population(180, 4, 0.25) == 136);  // -44 + 180
    CHECK(shade::planned_population(180, 4, 0.5) == 92);
    CHECK(shade::planned_population(180, 4, 0.999) == 4);   // 4.176 rounds to 4
    CHECK(shade::planned_population(180, 4, 1.0) == 4);
    CHECK(shade::planned_population(180, 4, 0.0031) == 179);  // 179.45
}

TEST_CASE("lshade follows the reduction schedule generation by generation, down to 4", "[lshade]") {
    testing::ShiftedSphere sphere(10, -5, 5, 1.0);
    const std::int64_t budget = 20000;
    auto optimizer = make_optimizer("lshade");
    auto* lshade = dynamic_cast<shade::Lshade*>(optimizer.get());
    REQUIRE(lshade != nullptr);
    testing::ManualRun run(sphere, Budget{0, budget}, 5);
    run.initialize(*optimizer);
    CHECK(lshade->population_size() == 180);
    CHECK(run.evaluator.evaluations() == 180);
    int generations = 0;
    while (run.evaluator.remaining() > 0) {
        const auto before = lshade->population_size();
        run.iterate(*optimizer);
        ++generations;
        // Each generation evaluates one trial per individual, then shrinks to the plan at the NFE reached.
        const double used = static_cast<double>(run.evaluator.evaluations()) / budget;
        const auto planned = static_cast<Eigen::Index>(std::round((4.0 - 180.0) * used + 180.0));
        INFO("generation " << generations << ", NFE " << run.evaluator.evaluations());
        CHECK(run.evaluator.evaluations() - run.progress.evaluations == std::min<std::int64_t>(before, budget - run.progress.evaluations));
        CHECK(lshade->population_size() == std::max<Eigen::Index>(4, planned));
    }
    CHECK(lshade->population_size() == 4);
    CHECK(run.evaluator.evaluations() == budget);
}

TEST_CASE("lshade: weighted Lehmer mean and memory update on a hand example", "[lshade]") {
    // S_F = {0.5, 1.0} with improvements 1 and 3: w = 1/4, 3/4;
    // mean_WL = (0.25*0.25 + 0.75*1) / (0.25*0.5 + 0.75*1) = 0.8125 / 0.875 = 13/14.
    CHECK(shade::weighted_lehmer_mean({0.5, 1.0}, {1.0, 3.0}) == Approx(13.0 / 14.0).epsilon(1e-15));
    // Equal improvements: the plain Lehmer mean, (0.04 + 0.36) / (0.2 + 0.6) = 0.5.
    CHECK(shade::weighted_lehmer_mean({0.2, 0.6}, {2.0, 2.0}) == Approx(0.5).epsilon(1e-15));
    auto optimizer = make_optimizer("lshade");
    const auto& lshade = dynamic_cast<const shade::Lshade&>(*optimizer);
    // L-SHADE replaces the entry by the means; a terminal CR entry stays terminal (Algorithm 1).
    CHECK(lshade.updated_memory(0.5, 0.5, 13.0 / 14.0, 0.7) == std::pair{13.0 / 14.0, 0.7});
    CHECK(lshade.updated_memory(0.5, shade::terminal_cr, 0.6, 0.7) == std::pair{0.6, shade::terminal_cr});
    CHECK(lshade.updated_memory(0.5, 0.5, 0.6, shade::terminal_cr) == std::pair{0.6, shade::terminal_cr});
    // The paper's constants.
    CHECK(lshade.p_best_rate(0.3) == 0.11);
}

TEST_CASE("lshade and jso: archive_entry archives the replaced parent (default) or the successful trial", "[lshade][jso]") {
    testing::ShiftedSphere sphere(10, -5, 5, 1.0);
    for (const std::string name : {"lshade", "jso"})
        for (const std::string entry : {"", "parent", "trial"}) {
            INFO(name << ", archive_entry = '" << entry << "'");
            std::map<std::string, ParameterValue> given{{"population", std::int64_t{20}}};
            if (!entry.empty()) given["archive_entry"] = entry;
            auto optimizer = make_optimizer(name, given);
            const auto& shade = dynamic_cast<const shade::Lshade&>(*optimizer);
            // So large a budget that the first generation removes nobody: column i is individual i
            // before and after it, and the archive (at least 20 places) is not full.
            testing::ManualRun run(sphere, Budget{0, 1'000'000'000}, 7);
            run.initialize(*optimizer);
            REQUIRE(shade.archive().cols() == 0);
            const Matrix before = shade.population();
            const Vector fitness_before = shade.fitness();
            run.iterate(*optimizer);
            REQUIRE(shade.population().cols() == 20);
            // The successes are the individuals whose fitness fell strictly (a trial replaces its
            // parent also on a tie, but only a strict improvement archives anything); a not yet full
            // archive takes them in index order.
            std::vector<Eigen::Index> improved;
            for (Eigen::Index i = 0; i < 20; ++i)
                if (shade.fitness()[i] < fitness_before[i]) improved.push_back(i);
            REQUIRE(!improved.empty());
            REQUIRE(shade.archive().cols() == static_cast<Eigen::Index>(improved.size()));
            const Matrix& source = entry == "trial" ? shade.population() : before;
            for (std::size_t k = 0; k < improved.size(); ++k)
                CHECK((shade.archive().col(static_cast<Eigen::Index>(k)).array() == source.col(improved[k]).array()).all());
        }
}

TEST_CASE("lshade: sticky_terminal_cr keeps a CR slot at ⊥ (the paper, default) or lets the next update replace it (Tanabe's code)", "[lshade]") {
    testing::ShiftedSphere sphere(10, -5, 5, 1.0);
    for (const bool sticky : {true, false}) {
        INFO("sticky_terminal_cr = " << sticky);
        // One memory slot, so that every update writes slot 0.
        auto optimizer = make_optimizer("lshade", {{"population", std::int64_t{20}}, {"memory_size", std::int64_t{1}},
                                                   {"sticky_terminal_cr", sticky}});
        auto& lshade = dynamic_cast<shade::Lshade&>(*optimizer);
        testing::ManualRun run(sphere, Budget{0, 100000}, 3);
        run.initialize(*optimizer);
        REQUIRE(lshade.memory_cr() == std::vector<double>{0.5});
        // Every successful CR 0: ⊥ either way. S_F = {0.5, 1} with Δf = {1, 3}: 13/14 (the hand example above).
        lshade.update_memory({0.5, 1.0}, {0.0, 0.0}, {1.0, 3.0});
        CHECK(lshade.memory_f()[0] == Approx(13.0 / 14.0).epsilon(1e-15));
        CHECK(lshade.memory_cr()[0] == shade::terminal_cr);
        // Then S_CR = {0.3, 0.6}, Δf = {1, 3}: w = 1/4, 3/4, mean_WL = (0.0225 + 0.27) / (0.075 + 0.45) = 39/70;
        // S_F = {0.2, 0.6}: (0.01 + 0.27) / (0.05 + 0.45) = 0.56.
        lshade.update_memory({0.2, 0.6}, {0.3, 0.6}, {1.0, 3.0});
        CHECK(lshade.memory_f()[0] == Approx(0.56).epsilon(1e-15));
        if (sticky)
            CHECK(lshade.memory_cr()[0] == shade::terminal_cr);
        else
            CHECK(lshade.memory_cr()[0] == Approx(39.0 / 70.0).epsilon(1e-15));
        // No success: the memory is left as it is.
        const auto kept = lshade.memory_cr();
        lshade.update_memory({}, {}, {});
        CHECK(lshade.memory_cr() == kept);
    }
    // The default is the paper's.
    const auto optimizer = make_optimizer("lshade");
    CHECK(dynamic_cast<const shade::Lshade&>(*optimizer).updated_memory(0.5, shade::terminal_cr, 0.6, 0.7).second == shade::terminal_cr);
}

TEST_CASE("lshade keeps the framework's contract: a seed fixes the run, affine maps of f change nothing, never outside the box", "[lshade]") {
    testing::check_seed_fixes_run("lshade", {{"population", std::int64_t{20}}});
    // Not to any monotone map of f: the memory weighs successes by their improvement |f(u) - f(x)|
    // (a rank-based optimiser passes check_invariance_to_monotone_transform); to a positive affine one, yes.
    testing::check_invariance_to_affine_transform("lshade", {{"population", std::int64_t{20}}});
    const auto corner = testing::run_against_corner("lshade", {}, 6000, 3);
    CHECK(corner.best_fitness == Approx(12.0).epsilon(1e-6));
}

TEST_CASE("lshade solves CEC2017 F1 and F3 at D = 10 in every one of 10 runs", "[lshade]") {
    CHECK(solved_rate("lshade", "cec2017_f1", 10, 100000, 10) == 1.0);
    CHECK(solved_rate("lshade", "cec2017_f3", 10, 100000, 10) == 1.0);
}

TEST_CASE("lshade refuses an initial population below the final one", "[lshade]") {
    CHECK_THROWS_WITH(make_optimizer("lshade", {{"population", std::int64_t{3}}}), Catch::Contains("at least 4"));
}
