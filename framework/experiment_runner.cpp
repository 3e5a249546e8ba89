#include "framework/experiment_runner.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <fstream>
#include <mutex>
#include <set>
#include <tuple>

#include <fmt/format.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "framework/input_error.hpp"
#include "framework/progress.hpp"
#include "framework/registry.hpp"
#include "framework/trial.hpp"

namespace mhb {
namespace {

namespace fs = std::filesystem;

ProblemContext problem_context(const ExperimentSpec& spec, std::uint64_t trial_seed) {
    std::uint64_t state = trial_seed ^ 0xA5A5A5A5DEADBEEFULL;  // a stream apart from the optimiser's
    return ProblemContext{fs::absolute(spec.file).parent_path(), splitmix64(state)};
}

// The problem with the config's box applied, if it gives one.
std::unique_ptr<Problem> instantiate(const PluginVariant& v, const ProblemContext& ctx) {
    auto problem = make_problem(v.name, v.values, ctx);
    if (!v.lower.empty() || !v.upper.empty()) {
        auto expand = [&](const std::vector<double>& given, const Vector& own) -> Vector {
            if (given.empty()) return own;
            if (given.size() == 1) return Vector::Constant(problem->dimension(), given[0]);
            return Eigen::Map<const Vector>(given.data(), static_cast<Eigen::Index>(given.size()));
        };
        problem->override_bounds(expand(v.lower, problem->bounds().lower), expand(v.upper, problem->bounds().upper));
    }
    return problem;
}

std::unique_ptr<Problem> create_problem(const ExperimentSpec& spec, const PluginVariant& v, const ProblemContext& ctx) {
    try {
        return instantiate(v, ctx);
    } catch (const InputError&) {
        throw;
    } catch (const std::invalid_argument& e) {
        throw InputError(spec.file.string(), v.bounds_line, v.label + " lower/upper", e.what());
    } catch (const std::exception& e) {
        throw InputError(spec.file.string(), v.line, "problem " + v.label, e.what());
    }
}

// An interrupted write leaves a last line without its newline; appending after it would corrupt
// the next record, so it is cut off before resuming (it is rerun).
void drop_incomplete_last_line(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::string text((std::istreambuf_iterator<char>(in)), {});
    in.close();
    if (text.empty() || text.back() == '\n') return;
    const auto cut = text.find_last_of('\n');
    fs::resize_file(path, cut == std::string::npos ? 0 : cut + 1);
}

}  // namespace

ExperimentInfo describe_experiment(const ExperimentSpec& spec) {
    ExperimentInfo info;
    info.name = spec.name;
    info.description = spec.description;
    info.config_file = spec.file.string();
    info.trials = spec.trials;
    info.seed = spec.seed;
    info.budget = spec.budget;
    info.optimizers = spec.optimizers;
    info.baseline = spec.baseline;
    info.references = spec.references;
    info.plots = spec.plots;
    info.published = spec.published;
    for (const auto& v : spec.problems) {
        const auto problem = create_problem(spec, v, problem_context(spec, derive_seed(spec.seed, "", v.label, 0)));
        ProblemInfo p;
        p.label = v.label;
        p.name = v.name;
        p.dimension = problem->dimension();
        p.parameter_names = problem->parameter_names();
        p.named_parameters = problem->has_named_parameters();
        p.truth = problem->truth();
        p.description = problem->describe();
        info.problems.push_back(std::move(p));
    }
    for (const auto& pub : spec.published)
        for (const auto& p : info.problems)
            if (p.label == pub.problem)
                for (const auto* values : {&pub.mean, &pub.sd})
                    for (const auto& [name, v] : *values)
                        if (std::find(p.parameter_names.begin(), p.parameter_names.end(), name) == p.parameter_names.end())
                            throw InputError(spec.file.string(), pub.line, "published." + name,
                                             "problem '" + p.label + "' has no parameter named '" + name + "'");
    for (const auto& v : spec.optimizers) {
        try {
            (void)make_optimizer(v.name, v.values);
        } catch (const std::exception& e) {
            throw InputError(spec.file.string(), v.line, "optimizer " + v.label, e.what());
        }
    }
    return info;
}

RunSummary run_experiment(const ExperimentSpec& spec, const RunOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    RunSummary summary;
    summary.output = options.output ? *options.output : spec.output;
    summary.info = describe_experiment(spec);
    const fs::path results_path = summary.output / "results.jsonl";

    std::error_code ec;
    fs::create_directories(summary.output, ec);
    if (ec || !fs::is_directory(summary.output))
        throw InputError(summary.output.string(), 0, "output", "cannot create the output directory: " +
                                                                   (ec ? ec.message() : std::string("not a directory")));

    std::set<std::tuple<std::string, std::string, std::int64_t>> done;
    if (fs::exists(results_path) && fs::file_size(results_path) > 0) {
        if (options.resume) {
            if (fs::exists(summary.output / "experiment.json")) {
                const auto previous = read_experiment_info(summary.output);
                if (previous.seed != spec.seed || previous.budget.max_iterations != spec.budget.max_iterations ||
                    previous.budget.max_evaluations != spec.budget.max_evaluations)
                    throw InputError(spec.file.string(), 0, "seed/budget",
                                     "differs from the run being resumed in " + summary.output.string() +
                                         "; resuming would mix two experiments (use another --out)");
            }
            drop_incomplete_last_line(results_path);
            auto loaded = read_results(results_path);
            summary.notes = loaded.notes;
            for (const auto& r : loaded.records) done.emplace(r.optimizer, r.problem, r.trial);
        } else {
            // Never destroy finished results: keep the previous run beside the new one.
            fs::path kept = summary.output / "results.previous.jsonl";
            fs::rename(results_path, kept, ec);
            if (ec) throw InputError(results_path.string(), 0, "output", "cannot move the previous results aside: " + ec.message());
            summary.notes.push_back("previous results kept as " + kept.string() + " (use --resume to continue a run)");
        }
    }
    write_experiment_info(summary.output, summary.info);
    ResultsWriter writer(results_path);

    struct Task {
        std::size_t optimizer, problem;
        std::int64_t trial;
    };
    std::vector<Task> tasks;
    for (std::size_t p = 0; p < spec.problems.size(); ++p)
        for (std::size_t o = 0; o < spec.optimizers.size(); ++o)
            for (std::int64_t t = 0; t < spec.trials; ++t) {
                ++summary.total;
                if (done.count({spec.optimizers[o].label, spec.problems[p].label, t})) {
                    ++summary.skipped;
                    continue;
                }
                tasks.push_back({o, p, t});
            }

    ProgressLine progress(tasks.size(), options.progress && ProgressLine::stderr_is_terminal());
    std::atomic<std::size_t> failed{0};
    std::mutex failures_mutex;
    std::exception_ptr write_error;
    const int threads = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
    tbb::task_arena arena(threads);
    arena.execute([&] {
        tbb::parallel_for(std::size_t{0}, tasks.size(), [&](std::size_t k) {
            const Task& task = tasks[k];
            const auto& ov = spec.optimizers[task.optimizer];
            const auto& pv = spec.problems[task.problem];
            const std::uint64_t seed = derive_seed(spec.seed, ov.label, pv.label, static_cast<std::uint64_t>(task.trial));
            TrialRecord record;
            try {
                auto problem = instantiate(pv, problem_context(spec, seed));
                auto optimizer = make_optimizer(ov.name, ov.values);
                TrialSetup setup{spec.budget, seed, problem->has_named_parameters()};
                record = run_trial(*optimizer, *problem, setup);
            } catch (const std::exception& e) {  // a factory that throws fails only this trial
                record.ok = false;
                record.seed = seed;
                record.error = e.what();
            }
            record.optimizer = ov.label;
            record.problem = pv.label;
            record.trial = task.trial;
            if (!record.ok) {
                ++failed;
                std::lock_guard lock(failures_mutex);
                if (summary.failures.size() < 5)
                    summary.failures.push_back(fmt::format("{} on {}, trial {}: {}", ov.label, pv.label, task.trial, record.error));
            }
            try {
                writer.append(record);
            } catch (...) {
                std::lock_guard lock(failures_mutex);
                if (!write_error) write_error = std::current_exception();
            }
            progress.advance();
        });
    });
    progress.finish();
    if (write_error) std::rethrow_exception(write_error);
    summary.ran = tasks.size();
    summary.failed = failed;
    summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return summary;
}

}  // namespace mhb
