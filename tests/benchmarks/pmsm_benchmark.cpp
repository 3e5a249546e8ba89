// PMSM identification speed: the problem's batch evaluation (population 100, 1000 samples), the same
// fitness summed sample by sample for comparison, and the drive simulator on the paper profile.
#include <filesystem>

#include <benchmark/benchmark.h>

#include "framework/optimizer.hpp"
#include "framework/random.hpp"
#include "framework/registry.hpp"
#include "problems/pmsm/fit/base_model_fit.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"
#include "tests/temporary_directory.hpp"

namespace {

using namespace mhb;
using namespace mhb::pmsm;

const std::filesystem::path paper_profile = std::filesystem::path(MHBENCH_SOURCE_DIR) / "experiments" / "pmsm" / "paper_profile.toml";

// The paper profile's 1000 samples, simulated once into a directory of this run's own (removed at exit).
const std::filesystem::path& paper_data() {
    static const mhb::testing::TemporaryDirectory directory;
    static const std::filesystem::path path = [] {
        const auto spec = read_simulation_profile(paper_profile);
        const auto p = directory.path() / "paper_profile.csv";
        write_simulation(p, spec, simulate(spec), paper_profile.string());
        return p;
    }();
    return path;
}

Matrix population(const Problem& problem, Eigen::Index size) {
    Rng rng(1);
    Matrix x(problem.dimension(), size);
    fill_uniform(x, problem.bounds(), rng);
    return x;
}

void BM_PmsmBatchEvaluation(benchmark::State& state) {
    const auto problem = make_problem("pmsm_identification", {{"data", paper_data().string()}});
    const Matrix x = population(*problem, state.range(0));
    Vector f(x.cols());
    for (auto _ : state) {
        problem->evaluate(x, f);
        benchmark::DoNotOptimize(f.data());
    }
    state.SetItemsProcessed(state.iterations() * x.cols());
    state.counters["evaluations_per_second"] = benchmark::Counter(static_cast<double>(state.iterations() * x.cols()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_PmsmBatchEvaluation)->Arg(100);

// The fitness as eq. (6) is usually coded: predict every sample for every candidate.
void BM_PmsmDirectEvaluation(benchmark::State& state) {
    const auto problem = make_problem("pmsm_identification", {{"data", paper_data().string()}});
    const Measurement m = read_measurement(paper_data());
    const Matrix x = population(*problem, state.range(0));
    Vector f(x.cols());
    const Eigen::ArrayXd id = m.i_d.array(), iq = m.i_q.array(), w = m.omega_e.array(), ud = m.u_d.array(), uq = m.u_q.array();
    const Eigen::ArrayXd wid = w * id, wiq = w * iq;
    for (auto _ : state) {
        for (Eigen::Index j = 0; j < x.cols(); ++j) {
            const double rs = x(0, j), ld = x(1, j), lq = x(2, j), psi = x(3, j);
            f[j] = ((ud - rs * id + lq * wiq).square() + (uq - rs * iq - ld * wid - psi * w).square()).mean();
        }
        benchmark::DoNotOptimize(f.data());
    }
    state.SetItemsProcessed(state.iterations() * x.cols());
    state.counters["evaluations_per_second"] = benchmark::Counter(static_cast<double>(state.iterations() * x.cols()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_PmsmDirectEvaluation)->Arg(100);

void BM_PmsmSimulatePaperProfile(benchmark::State& state) {
    const auto spec = read_simulation_profile(paper_profile);
    std::int64_t steps = 0;
    for (auto _ : state) {
        const auto result = simulate(spec);
        steps += result.integration_steps;
        benchmark::DoNotOptimize(result.data.u_q.data());
    }
    state.counters["rk4_steps_per_second"] = benchmark::Counter(static_cast<double>(steps), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_PmsmSimulatePaperProfile)->Unit(benchmark::kMillisecond);

// The device plant on its diagnosis profile (9 operating points, 4.24 s of drive): every carrier
// period split at its switching instants, RK4 across each interval. Arg 1: the same profile with
// dead time, magnet harmonics and the thermal network on (more intervals, per-phase harmonic flux).
void BM_PmsmSimulateDevicePlant(benchmark::State& state) {
    auto spec = read_simulation_profile(std::filesystem::path(MHBENCH_SOURCE_DIR) / "experiments" / "pmsm" / "device_diagnosis_profile.toml");
    if (state.range(0) == 1) {
        spec.device->inverter.dead_time = 1e-6;
        spec.device->rotor_flux.harmonics = {{5, 0.01, 0.0}, {7, 0.005, 0.0}};
        spec.device->thermal.enabled = true;
    }
    std::int64_t steps = 0;
    double simulated = 0.0;
    for (auto _ : state) {
        const auto result = simulate(spec);
        steps += result.integration_steps;
        simulated += result.simulated_time;
        benchmark::DoNotOptimize(result.data.u_q.data());
    }
    state.counters["rk4_steps_per_second"] = benchmark::Counter(static_cast<double>(steps), benchmark::Counter::kIsRate);
    state.counters["simulated_seconds_per_second"] = benchmark::Counter(simulated, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_PmsmSimulateDevicePlant)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
