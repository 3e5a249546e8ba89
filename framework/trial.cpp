#include "framework/trial.hpp"

#include <algorithm>
#include <chrono>
#include <exception>
#include <optional>

#include "framework/input_error.hpp"

namespace mhb {

TrialRecord run_trial(Optimizer& optimizer, const Problem& problem, const TrialSetup& setup) {
    TrialRecord rec;
    rec.seed = setup.seed;
    const auto start = std::chrono::steady_clock::now();
    Evaluator evaluator(problem, setup.budget);
    Rng rng(setup.seed);
    std::optional<AnytimeRecorder> anytime;
    if (setup.anytime) {
        anytime.emplace(*setup.anytime, setup.optimum,
                        checkpoint_evaluations(*setup.anytime, problem.dimension(), setup.budget.max_evaluations));
        evaluator.record_anytime(&*anytime);
    }

    auto record = [&] {
        if (!setup.record_trace) return;
        rec.trace_evaluations.push_back(evaluator.evaluations());
        rec.trace_best.push_back(evaluator.best_fitness());
        if (setup.record_positions) rec.trace_position.push_back(evaluator.best_position());
    };
    // Only a first guess at the trace's length: an iteration budget can be far more than the trial
    // reaches (it may stop on evaluations first), and max_iterations + 1 overflows at the int64 maximum.
    constexpr std::int64_t reserve_cap = 4096;
    const auto reserve = static_cast<std::size_t>(
        setup.budget.max_iterations > 0 ? std::min(setup.budget.max_iterations, reserve_cap - 1) + 1 : 256);
    if (setup.record_trace) {
        rec.trace_evaluations.reserve(reserve);
        rec.trace_best.reserve(reserve);
    }

    try {
        optimizer.initialize(evaluator, rng);
        record();
        bool stopped = setup.stop && setup.stop(evaluator, 0);
        Progress progress;
        progress.budget = setup.budget;
        progress.last_step_evaluations = evaluator.evaluations();
        while (!stopped && !evaluator.exhausted() &&
               (setup.budget.max_iterations <= 0 || rec.iterations < setup.budget.max_iterations)) {
            progress.iteration = rec.iterations + 1;
            progress.evaluations = evaluator.evaluations();
            const auto before = evaluator.evaluations();
            optimizer.iterate(progress, evaluator, rng);
            ++rec.iterations;
            progress.last_step_evaluations = evaluator.evaluations() - before;
            record();
            // An optimiser that stops evaluating would loop forever under an evaluation-only budget.
            if (setup.budget.max_iterations <= 0 && evaluator.evaluations() == before)
                throw PluginFault("optimizer iteration made no evaluation under an evaluation-only budget");
            stopped = setup.stop && setup.stop(evaluator, rec.iterations);
        }
    } catch (const std::exception& e) {
        rec.ok = false;
        rec.error = e.what();
    } catch (...) {
        rec.ok = false;
        rec.error = "unknown exception";
    }
    rec.best_fitness = evaluator.best_fitness();
    rec.best_position = evaluator.best_position();
    rec.evaluations = evaluator.evaluations();
    if (!setup.record_trace) {
        rec.trace_evaluations.assign(1, rec.evaluations);
        rec.trace_best.assign(1, rec.best_fitness);
        if (setup.record_positions) rec.trace_position.assign(1, rec.best_position);
    }
    if (anytime) rec.anytime = anytime->take();
    rec.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return rec;
}

}  // namespace mhb
