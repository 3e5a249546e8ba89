// The hot paths of `mhbench fit` and `mhbench diagnose` on a long log: the device plant's diagnosis
// profile with a 1 µs dead time and 6 667 samples per operating point (60 003 rows, simulated once),
// so the numbers carry over to the rows-against-time table in docs/performance.md.
//   predict rows        one prediction of every row (blocks in parallel)
//   affine split        the offset and the four base columns of every row (what each optimiser
//                       evaluation of the effect parameters costs)
//   normal equations    J'J, J'r per segment (a Levenberg-Marquardt iteration, leave-one-segment-out)
//   read CSV            parsing the log
//   fit                 fit_model of base+deadtime, search, polish and intervals
#include <filesystem>

#include <benchmark/benchmark.h>

#include "problems/pmsm/diagnosis/diagnosis.hpp"
#include "problems/pmsm/diagnosis/model_checks.hpp"
#include "problems/pmsm/fit/model_fit.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"
#include "tests/temporary_directory.hpp"

namespace {

using namespace mhb;
using namespace mhb::pmsm;

const Measurement& long_log() {
    static const Measurement data = [] {
        auto spec = read_simulation_profile(std::filesystem::path(MHBENCH_SOURCE_DIR) / "experiments" / "pmsm" / "device_diagnosis_profile.toml");
        spec.device->inverter.dead_time = 1e-6;
        for (auto& s : spec.segments) s.samples = 6667;
        return simulate(spec).data;
    }();
    return data;
}

void rows_counter(benchmark::State& state, Eigen::Index rows) {
    state.counters["rows_per_second"] = benchmark::Counter(static_cast<double>(rows) * static_cast<double>(state.iterations()),
                                                           benchmark::Counter::kIsRate);
}

void BM_PmsmPredictRows(benchmark::State& state) {
    const auto model = make_model(parse_model_spec("base+deadtime+flux_harmonic"), long_log());
    const Eigen::VectorXd values = model->parameters_of(MotorParameters{});
    Eigen::VectorXd u(2 * long_log().size());
    for (auto _ : state) {
        model->predict_rows(values.data(), u.data(), u.data() + long_log().size());
        benchmark::DoNotOptimize(u.data());
    }
    rows_counter(state, long_log().size());
}
BENCHMARK(BM_PmsmPredictRows)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_PmsmAffineSplit(benchmark::State& state) {
    const auto model = make_model(parse_model_spec("base+deadtime+flux_harmonic"), long_log());
    const Eigen::VectorXd values = model->parameters_of(MotorParameters{});
    auto full = model->make_affine(SteadyStateModel::block_rows);
    auto tail = model->make_affine(model->block_size(model->blocks() - 1));
    for (auto _ : state) {
        for (Eigen::Index b = 0; b < model->blocks(); ++b) {
            auto& a = model->block_size(b) == SteadyStateModel::block_rows ? full : tail;
            model->predict_affine(values.data(), a, model->block_first(b));
            benchmark::DoNotOptimize(a.phi_q.data());
        }
    }
    rows_counter(state, long_log().size());
}
BENCHMARK(BM_PmsmAffineSplit)->Unit(benchmark::kMillisecond);

void BM_PmsmNormalEquations(benchmark::State& state) {
    const auto model = make_model(parse_model_spec("base+deadtime"), long_log());
    const Eigen::VectorXd values = model->parameters_of(MotorParameters{});
    const std::vector<Eigen::Index> columns{0, 1, 2, 3, 4, 5};
    std::vector<Eigen::Index> starts;
    for (Eigen::Index k = 0; k < long_log().size(); ++k)
        if (k == 0 || long_log().segment[k] != long_log().segment[k - 1]) starts.push_back(k);
    for (auto _ : state) benchmark::DoNotOptimize(range_normal_equations(*model, values, columns, starts).total.data());
    rows_counter(state, long_log().size());
}
BENCHMARK(BM_PmsmNormalEquations)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_PmsmReadCsv(benchmark::State& state) {
    static const mhb::testing::TemporaryDirectory directory;
    const auto path = directory.path() / "long.csv";
    write_measurement(path, long_log());
    for (auto _ : state) benchmark::DoNotOptimize(read_measurement(path).u_q.data());
    rows_counter(state, long_log().size());
}
BENCHMARK(BM_PmsmReadCsv)->Unit(benchmark::kMillisecond);

void BM_PmsmFitDeadTime(benchmark::State& state) {
    const auto spec = parse_model_spec("base+deadtime");
    for (auto _ : state) benchmark::DoNotOptimize(fit_model(long_log(), spec, FitOptions{}).values.data());
    rows_counter(state, long_log().size());
}
BENCHMARK(BM_PmsmFitDeadTime)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_PmsmLeaveOneSegmentOut(benchmark::State& state) {
    const auto spec = parse_model_spec("base+deadtime");
    const auto fit = fit_model(long_log(), spec, FitOptions{});
    for (auto _ : state) benchmark::DoNotOptimize(leave_one_segment_out(long_log(), spec, fit.values).data());
    rows_counter(state, long_log().size());
}
BENCHMARK(BM_PmsmLeaveOneSegmentOut)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
