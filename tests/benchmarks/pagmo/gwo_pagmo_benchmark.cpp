// pagmo2's GWO beside ours at an equal budget (30 wolves, 200 generations: 30 + 30 * 200 = 6030
// evaluations each) on the 30-dimensional sphere. Built only when CMake finds pagmo; never required.
#include <benchmark/benchmark.h>

#include <utility>

#include <pagmo/algorithm.hpp>
#include <pagmo/algorithms/gwo.hpp>
#include <pagmo/population.hpp>
#include <pagmo/problem.hpp>
#include <pagmo/types.hpp>

#include "framework/registry.hpp"
#include "framework/trial.hpp"
#include "tests/sphere_fixture.hpp"

namespace {

constexpr unsigned kDimension = 30;
constexpr unsigned kPopulation = 30;
constexpr unsigned kGenerations = 200;

struct PagmoSphere {
    pagmo::vector_double fitness(const pagmo::vector_double& x) const {
        double sum = 0.0;
        for (double v : x) sum += v * v;
        return {sum};
    }
    std::pair<pagmo::vector_double, pagmo::vector_double> get_bounds() const {
        return {pagmo::vector_double(kDimension, -100.0), pagmo::vector_double(kDimension, 100.0)};
    }
};

void pagmo2_gwo(benchmark::State& state) {
    std::int64_t evaluations = 0;
    unsigned seed = 1;
    for (auto _ : state) {
        pagmo::population population{pagmo::problem{PagmoSphere{}}, kPopulation, seed};
        pagmo::algorithm algorithm{pagmo::gwo(kGenerations, seed)};
        population = algorithm.evolve(population);
        ++seed;
        evaluations += static_cast<std::int64_t>(population.get_problem().get_fevals());
        benchmark::DoNotOptimize(population.champion_f());
    }
    state.counters["evals/s"] = benchmark::Counter(static_cast<double>(evaluations), benchmark::Counter::kIsRate);
}

void mhbench_gwo(benchmark::State& state, const std::string& variant) {
    const mhb::testing::ShiftedSphere sphere(kDimension, -100.0, 100.0, 0.0);
    std::int64_t evaluations = 0;
    std::uint64_t seed = 1;
    for (auto _ : state) {
        auto optimizer = mhb::make_optimizer("gwo", {{"variant", variant}, {"population", std::int64_t{kPopulation}}});
        const auto record = mhb::run_trial(*optimizer, sphere, {mhb::Budget{kGenerations, 0}, seed++, false});
        evaluations += record.evaluations;
        benchmark::DoNotOptimize(record.best_fitness);
    }
    state.counters["evals/s"] = benchmark::Counter(static_cast<double>(evaluations), benchmark::Counter::kIsRate);
}

}  // namespace

BENCHMARK(pagmo2_gwo)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mhbench_gwo, pagmo2_variant, std::string("pagmo2"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mhbench_gwo, original, std::string("original"))->Unit(benchmark::kMillisecond);
