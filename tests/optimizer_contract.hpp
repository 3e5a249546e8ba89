#pragma once
// What every population-based optimiser plugin owes the framework, checked the same way for each:
// it spends exactly its budget, a seed fixes the whole run, a comparison-based optimiser ignores a
// monotone transformation of f, and it never hands the evaluator a point outside the box (the
// evaluator would fail the trial). Also the shared runs for the convergence tests.
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "framework/registry.hpp"
#include "framework/trial.hpp"
#include "tests/sphere_fixture.hpp"

namespace mhb::testing {

using PluginValues = std::map<std::string, ParameterValue>;

// `population`: evaluations per iteration (and in initialize()) with `values` on a 4-D problem.
inline void check_exact_budgets(const std::string& name, const PluginValues& values, std::int64_t population) {
    ShiftedSphere sphere(4, -5, 5, 1.0);
    auto by_iterations = make_optimizer(name, values);
    const auto r = run_trial(*by_iterations, sphere, {Budget{7, 0}, 11, false});
    REQUIRE(r.ok);
    REQUIRE(r.iterations == 7);
    REQUIRE(r.evaluations == population * 8);
    REQUIRE(r.trace_best.size() == 8);

    // Not a multiple of the population: the last generation is cut at the budget.
    const std::int64_t budget = population * 9 + population / 2 + 1;
    auto by_evaluations = make_optimizer(name, values);
    const auto e = run_trial(*by_evaluations, sphere, {Budget{0, budget}, 11, false});
    REQUIRE(e.ok);
    REQUIRE(e.evaluations == budget);
    REQUIRE(e.trace_evaluations.back() == budget);
    REQUIRE(e.iterations == 9);
}

// 30 iterations on `problem` with positions recorded.
inline TrialRecord run_thirty_iterations(const std::string& name, const PluginValues& values, const Problem& problem,
                                         std::uint64_t seed) {
    auto opt = make_optimizer(name, values);
    auto r = run_trial(*opt, problem, {Budget{30, 0}, seed, true});
    REQUIRE(r.ok);
    return r;
}

inline void check_seed_fixes_run(const std::string& name, const PluginValues& values) {
    ShiftedSphere sphere(5, -5, 5, 0.7);
    auto reused = make_optimizer(name, values);
    const auto first = run_trial(*reused, sphere, {Budget{30, 0}, 2024, true});
    REQUIRE(first.ok);
    // The same object run again starts afresh (initialize() resets all state), and so does a new one.
    const auto again = run_trial(*reused, sphere, {Budget{30, 0}, 2024, true});
    const auto fresh = run_thirty_iterations(name, values, sphere, 2024);
    REQUIRE(again.trace_best == first.trace_best);
    REQUIRE(fresh.trace_best == first.trace_best);
    REQUIRE(fresh.trace_position == first.trace_position);
    const auto other = run_thirty_iterations(name, values, sphere, 2025);
    REQUIRE(other.trace_best != first.trace_best);
}

// The shifted sphere seen through a strictly increasing map of f: the same ranking of every set of
// points, other values.
template <class Map>
class MappedSphere final : public Problem {
public:
    MappedSphere(int dimension, double lower, double upper, double shift, Map map) : sphere_(dimension, lower, upper, shift), map_(map) {
        set_domain(dimension, lower, upper);
    }
    void evaluate(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) const override {
        sphere_.evaluate(x, f);
        f = f.unaryExpr(map_);
    }

private:
    ShiftedSphere sphere_;
    Map map_;
};

// An optimiser that only compares fitness values makes the same moves on f and on any strictly
// increasing function of f.
inline void check_invariance_to_monotone_transform(const std::string& name, const PluginValues& values) {
    const auto ra = run_thirty_iterations(name, values, ShiftedSphere(5, -5, 5, 0.7), 99);
    const auto rb = run_thirty_iterations(name, values, MappedSphere(5, -5, 5, 0.7, [](double v) { return std::sqrt(v); }), 99);
    REQUIRE(ra.trace_position == rb.trace_position);
    REQUIRE(rb.best_fitness == Approx(std::sqrt(ra.best_fitness)));
}

// The same moves on f and on 3 f + 7 (up to rounding in the weights, so positions agree to 1e-9).
inline void check_invariance_to_affine_transform(const std::string& name, const PluginValues& values) {
    const auto ra = run_thirty_iterations(name, values, ShiftedSphere(5, -5, 5, 0.7), 99);
    // A positive affine map: an optimiser that weighs by differences of f (L-SHADE's memory weights)
    // still makes the same moves.
    const auto rb = run_thirty_iterations(name, values, MappedSphere(5, -5, 5, 0.7, [](double v) { return 3.0 * v + 7.0; }), 99);
    REQUIRE(ra.trace_position.size() == rb.trace_position.size());
    for (std::size_t k = 0; k < ra.trace_position.size(); ++k)
        REQUIRE((ra.trace_position[k] - rb.trace_position[k]).cwiseAbs().maxCoeff() <= 1e-9);
    REQUIRE(rb.best_fitness == Approx(3.0 * ra.best_fitness + 7.0));
}

// Best fitness after `evaluations` on the 10-D sphere centred at 1.5 in [-5, 5]^10, for seeds 1, 2, 3:
// each convergence test sets its bound from measurements over more seeds.
inline std::vector<double> best_on_sphere(const std::string& name, const PluginValues& values,
                                          std::int64_t evaluations) {
    ShiftedSphere sphere(10, -5, 5, 1.5);
    std::vector<double> best;
    for (std::uint64_t seed : {1u, 2u, 3u}) {
        auto opt = make_optimizer(name, values);
        const auto r = run_trial(*opt, sphere, {Budget{0, evaluations}, seed, false});
        REQUIRE(r.ok);
        best.push_back(r.best_fitness);
    }
    return best;
}

// The sphere's centre lies outside the box, beyond the corner (5, 5, 5), so the best point of the box
// is that corner with f = 3 (7 - 5)^2 = 12 and the search presses against three walls all run long.
inline TrialRecord run_against_corner(const std::string& name, const PluginValues& values, std::int64_t evaluations,
                                      std::uint64_t seed) {
    ShiftedSphere beyond_corner(3, -5, 5, 7.0);
    auto opt = make_optimizer(name, values);
    auto r = run_trial(*opt, beyond_corner, {Budget{0, evaluations}, seed, false});
    REQUIRE(r.ok);  // the evaluator fails the trial on any candidate outside the box
    REQUIRE(r.evaluations == evaluations);
    return r;
}

}  // namespace mhb::testing
