// The CEC suites' batch evaluation (one matrix product per rotation for a whole population) against
// a point-by-point loop over the same problem, at D = 10, 30, 100 (docs/performance.md).
#include <benchmark/benchmark.h>

#include <string>

#include "framework/optimizer.hpp"
#include "framework/registry.hpp"

namespace {

constexpr Eigen::Index population = 100;

struct Setup {
    std::unique_ptr<mhb::Problem> problem;
    mhb::Matrix x;
    mhb::Vector f;
};

Setup setup(const std::string& name, std::int64_t dimension) {
    Setup s{mhb::make_problem(name, {{"dimension", dimension}}), {}, {}};
    mhb::Rng rng(1);
    s.x.resize(dimension, population);
    mhb::fill_uniform(s.x, s.problem->bounds(), rng);
    s.f.resize(population);
    return s;
}

void batch(benchmark::State& state, const std::string& name) {
    auto s = setup(name, state.range(0));
    for (auto _ : state) {
        s.problem->evaluate(s.x, s.f);
        benchmark::DoNotOptimize(s.f.data());
    }
    state.SetItemsProcessed(state.iterations() * population);
}

void point_by_point(benchmark::State& state, const std::string& name) {
    auto s = setup(name, state.range(0));
    for (auto _ : state) {
        for (Eigen::Index j = 0; j < population; ++j) s.problem->evaluate(s.x.col(j), s.f.segment(j, 1));
        benchmark::DoNotOptimize(s.f.data());
    }
    state.SetItemsProcessed(state.iterations() * population);
}

// F1 bent cigar (one rotation, a cheap basic function), F5 Rastrigin (one rotation, a cosine per
// coordinate), F15 a hybrid (one rotation and a shuffle), F27 a composition of six rotated functions.
#define CEC_PAIR(function)                                                                   \
    BENCHMARK_CAPTURE(batch, function, #function)->Arg(10)->Arg(30)->Arg(100);          \
    BENCHMARK_CAPTURE(point_by_point, function, #function)->Arg(10)->Arg(30)->Arg(100);

CEC_PAIR(cec2017_f1)
CEC_PAIR(cec2017_f5)
CEC_PAIR(cec2017_f15)
CEC_PAIR(cec2017_f27)

}  // namespace
