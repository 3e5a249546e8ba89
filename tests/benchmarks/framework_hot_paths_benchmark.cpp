// The framework's per-evaluation and per-run hot paths, alone: the evaluator's checks of every
// candidate (finite, inside the box) with its best-so-far record, clamping a population into the box,
// and reading a results file back for the tables. Each at the sizes of the sphere benchmarks (D = 30,
// 30 candidates) and of Table 3 (D = 4, 100 candidates; 90 records of 201 trace points).
#include <benchmark/benchmark.h>

#include "framework/optimizer.hpp"
#include "framework/problem.hpp"
#include "framework/results_store.hpp"
#include "framework/trial.hpp"
#include "tests/temporary_directory.hpp"

namespace {

// A problem whose evaluation costs nothing, so that what is measured is the evaluator around it.
class ZeroProblem final : public mhb::Problem {
public:
    explicit ZeroProblem(int dimension) { set_domain(dimension, -100.0, 100.0); }
    void evaluate(const Eigen::Ref<const mhb::Matrix>& x, Eigen::Ref<mhb::Vector> f) const override {
        (void)x;
        f.setZero();
    }
};

// Evaluator::evaluate on a population inside the box: the checks and the best-so-far update.
void evaluator_checks(benchmark::State& state) {
    const int dimension = static_cast<int>(state.range(0));
    const auto population = static_cast<Eigen::Index>(state.range(1));
    const ZeroProblem problem(dimension);
    mhb::Evaluator evaluator(problem, mhb::Budget{1, 0});
    mhb::Matrix x(dimension, population);
    mhb::Rng rng(1);
    mhb::fill_uniform(x, problem.bounds(), rng);
    mhb::Vector f(population);
    for (auto _ : state) {
        evaluator.evaluate(x, f);
        benchmark::DoNotOptimize(f.data());
    }
    state.SetItemsProcessed(state.iterations() * population);
}

// clamp_to_bounds on a population of which about half the coordinates lie outside the box at first
// (inside after the first pass: the work per coordinate is the same either way, a max and a min).
void clamp_population(benchmark::State& state) {
    const int dimension = static_cast<int>(state.range(0));
    const auto population = static_cast<Eigen::Index>(state.range(1));
    const ZeroProblem problem(dimension);
    mhb::Matrix x(dimension, population);
    mhb::Rng rng(1);
    for (Eigen::Index i = 0; i < x.size(); ++i) x.data()[i] = rng.uniform(-200.0, 200.0);
    for (auto _ : state) {
        mhb::clamp_to_bounds(x, problem.bounds());
        benchmark::DoNotOptimize(x.data());
    }
    state.SetItemsProcessed(state.iterations() * population);
}

// read_results on 90 records shaped like Table 3's (D = 4, a trace of 201 points each).
void read_table3_sized_results(benchmark::State& state) {
    const mhb::testing::TemporaryDirectory directory;
    const auto path = directory.path() / "results.jsonl";
    {
        mhb::ResultsWriter writer(path);
        mhb::Rng rng(1);
        for (int k = 0; k < 90; ++k) {
            mhb::TrialRecord record;
            record.optimizer = k < 30 ? "GWO" : k < 60 ? "SOA" : "ISOA";
            record.problem = "pmsm";
            record.trial = k % 30;
            record.seed = rng();
            record.best_fitness = rng.uniform();
            record.best_position = mhb::Vector::NullaryExpr(4, [&] { return rng.uniform(); });
            record.evaluations = 20100;
            record.iterations = 200;
            for (int t = 0; t <= 200; ++t) {
                record.trace_evaluations.push_back(100 * (t + 1));
                record.trace_best.push_back(rng.uniform());
            }
            writer.append(record);
        }
    }
    for (auto _ : state) {
        const auto loaded = mhb::read_results(path);
        benchmark::DoNotOptimize(loaded.records.data());
    }
    state.SetItemsProcessed(state.iterations() * 90);
}

}  // namespace

BENCHMARK(evaluator_checks)->Args({30, 30})->Args({4, 100});
BENCHMARK(clamp_population)->Args({30, 30})->Args({4, 100});
BENCHMARK(read_table3_sized_results)->Unit(benchmark::kMillisecond);
