// `mhbench complexity OPTIMIZER... --suite cec2017|cec2022` (or --problem P --dimension D...): the
// algorithm-complexity table of the CEC competitions' reports (Awad et al. 2016, section 3; Kumar
// et al. 2021, section 2.2 4)): T0, the time of a fixed loop of arithmetic; T1, the time of the
// problem's evaluations alone; T2, the mean time of a whole run of the optimiser with that many
// evaluations; and (T2 - T1) / T0, the optimiser's own cost in units of the machine's speed.
#include <ctime>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "framework/cli/commands.hpp"
#include "framework/cli/option_ranges.hpp"
#include "framework/cli/problem_option.hpp"
#include "framework/input_error.hpp"
#include "framework/provenance.hpp"
#include "framework/registry.hpp"
#include "framework/trial.hpp"

namespace mhb::cli {
namespace {

// The calling thread's CPU time, not the wall clock: on a shared machine the wall clock also counts
// the time other processes hold the core, which varies from one measurement to the next (measured:
// T1 above T2 though T2 makes the same evaluations), where the reports mean the computing time.
// Every timed step runs on this one thread (a trial and a batch evaluation start no others).
double cpu_seconds() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}
double seconds_since(double start) { return cpu_seconds() - start; }

// T0: the reports' test program, x = 0.55 and then, `iterations` times, x = x + x; x = x/2; x = x*x;
// x = sqrt(x); x = log(x); x = exp(x); x = x/(x + 2). The start value is read through a volatile
// and the result written to one, so the compiler can neither fold nor drop the loop.
double time_t0(std::int64_t iterations) {
    volatile double start = 0.55;
    volatile double sink = 0;
    const double begin = cpu_seconds();
    double x = start;
    for (std::int64_t i = 0; i < iterations; ++i) {
        x = x + x;
        x = x / 2;
        x = x * x;
        x = std::sqrt(x);
        x = std::log(x);
        x = std::exp(x);
        x = x / (x + 2);
    }
    sink = x;
    (void)sink;
    return seconds_since(begin);
}

// T1: `evaluations` evaluations of the problem alone, in populations of `batch` uniform points (the
// reports ask T1 to be measured in the style the optimisers evaluate, and mhbench's optimisers
// evaluate whole populations). The points are drawn before the clock starts.
double time_t1(const Problem& problem, std::int64_t evaluations, Eigen::Index batch) {
    Rng rng(1);
    Matrix x(problem.dimension(), batch);
    fill_uniform(x, problem.bounds(), rng);
    Vector f(batch);
    volatile double sink = 0;
    const double begin = cpu_seconds();
    for (std::int64_t done = 0; done < evaluations; done += batch) {
        const Eigen::Index n = static_cast<Eigen::Index>(std::min<std::int64_t>(batch, evaluations - done));
        problem.evaluate(x.leftCols(n), f.head(n));
        sink = sink + f[0];
    }
    return seconds_since(begin);
}

struct Suite {
    std::string problem;
    std::vector<std::int64_t> dimensions;
    std::int64_t t0_iterations;
};

// The reports' choices: CEC 2017 times F18 at D = 10, 30, 50 and loops T0 10^6 times; CEC 2022
// times F1 at D = 10, 20 and loops T0 200 000 times. Both take 200 000 evaluations and 5 runs.
std::optional<Suite> named_suite(const std::string& name) {
    if (name == "cec2017") return Suite{"cec2017_f18", {10, 30, 50}, 1'000'000};
    if (name == "cec2022") return Suite{"cec2022_f1", {10, 20}, 200'000};
    return std::nullopt;
}

const bool complexity_registered = register_command("complexity", [](CLI::App& app) {
    auto* cmd = app.add_subcommand("complexity",
                                   "The CEC reports' algorithm-complexity table: T0 (a fixed arithmetic loop), T1 (the problem's "
                                   "evaluations alone), T2 (a whole run, mean of several) and (T2 - T1)/T0, per optimizer and dimension");
    struct Args {
        std::vector<std::string> optimizers;
        std::string suite, problem;
        std::vector<std::int64_t> dimensions;
        std::int64_t evaluations = 200'000, runs = 5, t0_iterations = 0, batch = 100;
    };
    auto a = std::make_shared<Args>();
    cmd->add_option("OPTIMIZER", a->optimizers, "registered optimizer names (`mhbench list optimizers`), with their default parameters")
        ->required();
    cmd->add_option("--suite", a->suite, "cec2017 (F18 at D = 10, 30, 50; T0 loops 10^6 times) or cec2022 (F1 at D = 10, 20; 200 000)");
    cmd->add_option("--problem", a->problem, "the problem timed (instead of the suite's)");
    cmd->add_option("--dimension", a->dimensions, "dimensions (instead of the suite's)")->check(whole_number_in<std::int64_t>(1, 100000));
    cmd->add_option("--evaluations", a->evaluations, "evaluations of T1 and of each run of T2 (default 200000)")
        ->check(whole_number_in<std::int64_t>(1, 1'000'000'000));
    cmd->add_option("--runs", a->runs, "runs whose mean time is T2 (default 5)")->check(whole_number_in<std::int64_t>(1, 1000));
    cmd->add_option("--t0-iterations", a->t0_iterations, "iterations of T0's loop (instead of the suite's)")
        ->check(whole_number_in<std::int64_t>(1, 1'000'000'000'000));
    cmd->add_option("--batch", a->batch, "points per evaluation call in T1 (default 100)")->check(whole_number_in<std::int64_t>(1, 1'000'000));
    return std::function<int()>([a] {
        Suite suite{a->problem, a->dimensions, a->t0_iterations};
        if (!a->suite.empty()) {
            const auto named = named_suite(a->suite);
            if (!named) throw InputError("command line", 0, "--suite", fmt::format("expects cec2017 or cec2022 (got '{}')", a->suite));
            if (suite.problem.empty()) suite.problem = named->problem;
            if (suite.dimensions.empty()) suite.dimensions = named->dimensions;
            if (suite.t0_iterations == 0) suite.t0_iterations = named->t0_iterations;
        }
        if (suite.problem.empty()) throw InputError("command line", 0, "--problem", "give --suite cec2017|cec2022 or a --problem to time");
        if (suite.t0_iterations == 0) throw InputError("command line", 0, "--t0-iterations", "give --suite or the iterations of T0's loop");
        std::vector<std::unique_ptr<Problem>> problems;
        if (suite.dimensions.empty()) problems.push_back(problem_from_command_line(suite.problem, std::nullopt, std::nullopt));
        for (auto d : suite.dimensions) problems.push_back(problem_from_command_line(suite.problem, d, std::nullopt));
        for (const auto& name : a->optimizers) (void)make_optimizer(name);  // unknown names refused before anything is timed

        const auto machine = current_provenance(1);
        fmt::print("Algorithm complexity as the CEC reports define it: {} evaluations of {}, T2 the mean of {} runs; "
                   "one thread, its CPU time; mhbench {} (commit {}), {}, {}.\n\n",
                   a->evaluations, suite.problem, a->runs, machine.version, machine.commit, machine.host, machine.system);
        const double t0 = time_t0(suite.t0_iterations);
        fmt::print("T0 = {:.6f} s ({} iterations of the reports' loop)\n\n", t0, suite.t0_iterations);
        fmt::print("| optimizer | D | T0 (s) | T1 (s) | T2 (s) | (T2 - T1)/T0 |\n|---|---|---|---|---|---|\n");
        for (const auto& problem : problems) {
            const double t1 = time_t1(*problem, a->evaluations, static_cast<Eigen::Index>(a->batch));
            for (const auto& name : a->optimizers) {
                double total = 0;
                for (std::int64_t r = 0; r < a->runs; ++r) {
                    auto optimizer = make_optimizer(name);
                    TrialSetup setup{Budget{0, a->evaluations}, static_cast<std::uint64_t>(r + 1), false, false};
                    const double begin = cpu_seconds();
                    const auto record = run_trial(*optimizer, *problem, setup);
                    total += seconds_since(begin);
                    if (!record.ok) throw InputError("command line", 0, name, "the run failed: " + record.error);
                }
                const double t2 = total / static_cast<double>(a->runs);
                fmt::print("| {} | {} | {:.6f} | {:.6f} | {:.6f} | {:.2f} |\n", name, problem->dimension(), t0, t1, t2, (t2 - t1) / t0);
                std::fflush(stdout);
            }
        }
        return exit_ok;
    });
});

}  // namespace
}  // namespace mhb::cli
