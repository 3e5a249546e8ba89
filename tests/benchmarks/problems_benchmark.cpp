// Throughput of population evaluation for the test-function plugins: candidates per second for a
// population of 100, the size the GWO/SO experiments use.
#include <benchmark/benchmark.h>

#include <map>
#include <string>

#include "framework/optimizer.hpp"
#include "framework/registry.hpp"

namespace {

void evaluate_population(benchmark::State& state, const std::string& name,
                         std::map<std::string, mhb::ParameterValue> parameters) {
    const auto problem = mhb::make_problem(name, parameters);
    mhb::Rng rng(1);
    mhb::Matrix x(problem->dimension(), 100);
    mhb::fill_uniform(x, problem->bounds(), rng);
    mhb::Vector f(100);
    for (auto _ : state) {
        problem->evaluate(x, f);
        benchmark::DoNotOptimize(f.data());
    }
    state.SetItemsProcessed(state.iterations() * x.cols());
}

using P = std::map<std::string, mhb::ParameterValue>;
BENCHMARK_CAPTURE(evaluate_population, F1_D30, "F1", P{});
BENCHMARK_CAPTURE(evaluate_population, F8_D30, "F8", P{});
BENCHMARK_CAPTURE(evaluate_population, F12_D30, "F12", P{});
BENCHMARK_CAPTURE(evaluate_population, F23, "F23", P{});
BENCHMARK_CAPTURE(evaluate_population, bbob_f1_D10, "bbob_f1", P{});
BENCHMARK_CAPTURE(evaluate_population, bbob_f15_D10, "bbob_f15", P{});
BENCHMARK_CAPTURE(evaluate_population, bbob_f21_D10, "bbob_f21", P{});
BENCHMARK_CAPTURE(evaluate_population, bbob_f23_D10, "bbob_f23", P{});
BENCHMARK_CAPTURE(evaluate_population, bbob_f15_D40, "bbob_f15", P{{"dimension", std::int64_t{40}}});

}  // namespace
