// The optimisers' own overhead: evaluations per second on a 30-dimensional sphere, whose
// evaluation costs about 60 flops per candidate, so what is measured is mostly the optimiser
// (random numbers, moves, selection, bookkeeping). `sphere_evaluation_only` is the floor: the same
// evaluations without any optimiser.
#include <benchmark/benchmark.h>

#include <map>
#include <string>

#include "framework/registry.hpp"
#include "framework/trial.hpp"
#include "tests/sphere_fixture.hpp"

namespace {

constexpr int kDimension = 30;
constexpr std::int64_t kPopulation = 30;
constexpr std::int64_t kIterations = 200;

void run_optimizer(benchmark::State& state, const std::string& name, std::map<std::string, mhb::ParameterValue> parameters) {
    const mhb::testing::ShiftedSphere sphere(kDimension, -100.0, 100.0, 0.0);
    parameters[name == "random_search" ? "batch" : "population"] = kPopulation;
    std::int64_t evaluations = 0;
    std::uint64_t seed = 1;
    for (auto _ : state) {
        auto optimizer = mhb::make_optimizer(name, parameters);
        const auto record = mhb::run_trial(*optimizer, sphere, {mhb::Budget{kIterations, 0}, seed++, false});
        if (!record.ok) state.SkipWithError(record.error.c_str());
        evaluations += record.evaluations;
        benchmark::DoNotOptimize(record.best_fitness);
    }
    state.counters["evals/s"] = benchmark::Counter(static_cast<double>(evaluations), benchmark::Counter::kIsRate);
}

void sphere_evaluation_only(benchmark::State& state) {
    const mhb::testing::ShiftedSphere sphere(kDimension, -100.0, 100.0, 0.0);
    mhb::Matrix x(kDimension, kPopulation);
    mhb::Rng rng(1);
    mhb::fill_uniform(x, sphere.bounds(), rng);
    mhb::Vector f(kPopulation);
    std::int64_t evaluations = 0;
    for (auto _ : state) {
        sphere.evaluate(x, f);
        benchmark::DoNotOptimize(f.data());
        evaluations += kPopulation;
    }
    state.counters["evals/s"] = benchmark::Counter(static_cast<double>(evaluations), benchmark::Counter::kIsRate);
}

using Parameters = std::map<std::string, mhb::ParameterValue>;

}  // namespace

BENCHMARK(sphere_evaluation_only);
BENCHMARK_CAPTURE(run_optimizer, random_search, std::string("random_search"), Parameters{})->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(run_optimizer, gwo_original, std::string("gwo"), Parameters{{"variant", std::string("original")}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(run_optimizer, gwo_greedy_top3, std::string("gwo"), Parameters{{"variant", std::string("greedy_top3")}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(run_optimizer, gwo_async_demotion, std::string("gwo"),
                  Parameters{{"variant", std::string("async_demotion")}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(run_optimizer, gwo_pagmo2, std::string("gwo"), Parameters{{"variant", std::string("pagmo2")}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(run_optimizer, soa, std::string("soa"), Parameters{})->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(run_optimizer, soa_shifted, std::string("soa"), Parameters{{"fitness_ratio", std::string("shifted")}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(run_optimizer, soa_tent, std::string("soa+tent"), Parameters{})->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(run_optimizer, soa_cuckoo, std::string("soa+cuckoo"), Parameters{})->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(run_optimizer, isoa, std::string("isoa"), Parameters{})->Unit(benchmark::kMillisecond);
