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

ProblemContext problem_context(const ExperimentSpec& spec, std::uint64_t trial_seed, std::shared_ptr<SharedProblemData> shared) {
    std::uint64_t state = trial_seed ^ 0xA5A5A5A5DEADBEEFULL;  // a stream apart from the optimiser's
    return ProblemContext{fs::absolute(spec.file).parent_path(), splitmix64(state), std::move(shared)};
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
    } catch (const InputError& e) {
        if (e.file() == spec.file.string()) throw;
        // A file the problem reads (its `data`): say which entry of the config named it.
        throw InputError(spec.file.string(), v.line, "problem " + v.label, e.what());
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
    std::error_code ec;
    fs::resize_file(path, cut == std::string::npos ? 0 : cut + 1, ec);
    if (ec) throw InputError(path.string(), 0, "", "cannot cut off the incomplete last record: " + ec.message());
}

// Moves an earlier run's results.jsonl and experiment.json into previous/N (the first free N), so
// that no rerun ever overwrites a run before it. Returns the directory they went to.
fs::path keep_previous_run(const fs::path& output) {
    const fs::path kept_root = output / "previous";
    std::error_code ec;
    fs::create_directories(kept_root, ec);
    if (ec) throw InputError(kept_root.string(), 0, "output", "cannot create the directory for earlier runs: " + ec.message());
    fs::path kept;
    // create_directory fails on an existing directory, so two runs started at once never share one.
    for (int n = 1;; ++n) {
        kept = kept_root / std::to_string(n);
        if (fs::create_directory(kept, ec)) break;
        if (ec) throw InputError(kept.string(), 0, "output", "cannot create the directory for the earlier run: " + ec.message());
    }
    for (const char* name : {"results.jsonl", "experiment.json"}) {
        if (!fs::exists(output / name, ec)) continue;
        fs::rename(output / name, kept / name, ec);
        if (ec) throw InputError((output / name).string(), 0, "output", "cannot move the earlier run aside: " + ec.message());
    }
    return kept;
}

std::string settings_text(const std::map<std::string, ParameterValue>& values) {
    std::string out;
    for (const auto& [k, v] : values) out += (out.empty() ? "" : ", ") + k + " = " + to_string(v);
    return out.empty() ? "defaults" : out;
}

// A variant's settings with the defaults filled in, so that writing a default out or leaving it
// away counts as the same setting.
template <class RegistryT>
std::map<std::string, ParameterValue> resolved(const RegistryT& registry, const std::string& name,
                                               const std::map<std::string, ParameterValue>& given) {
    const auto* entry = registry.find(name);
    if (!entry) return given;
    try {
        return ParameterSet(entry->parameters, given).values();
    } catch (const ParameterError&) {  // a parameter that no longer exists: compare as written
        return given;
    }
}

// Refuses to resume when a setting that shapes a trial differs from the run being resumed: the
// records of both would otherwise end up in one table under one label.
void check_resumable(const ExperimentSpec& spec, const ExperimentInfo& previous, const fs::path& output,
                     const std::optional<Shard>& shard) {
    auto refuse = [&](long line, const std::string& field, const std::string& difference) {
        throw InputError(spec.file.string(), line, field,
                         difference + " in the run being resumed in " + output.string() +
                             "; resuming would mix two experiments (drop --resume to keep that run and start anew, "
                             "or use another --out)");
    };
    if (previous.seed != spec.seed)
        refuse(0, "seed", fmt::format("is {} here but was {}", spec.seed, previous.seed));
    if (previous.anytime != spec.anytime)
        refuse(0, "anytime", "differs from the [anytime] of the run being resumed (its records would not match)");
    if (previous.shard != shard) {
        const auto text = [](const std::optional<Shard>& s) {
            return s ? fmt::format("shard {} of {}", s->index, s->count) : std::string("all trials");
        };
        throw InputError("command line", 0, "--shard",
                         fmt::format("this run is {} but the run being resumed in {} was {}; resume it with the same --shard",
                                     text(shard), output.string(), text(previous.shard)));
    }
    if (previous.budget.max_iterations != spec.budget.max_iterations)
        refuse(0, "budget.iterations", fmt::format("is {} here but was {}", spec.budget.max_iterations, previous.budget.max_iterations));
    if (previous.evaluations_per_dimension != spec.evaluations_per_dimension)
        refuse(0, "budget.evaluations_per_dimension",
               fmt::format("is {} here but was {}", spec.evaluations_per_dimension, previous.evaluations_per_dimension));
    if (previous.evaluations_by_dimension != spec.evaluations_by_dimension)
        refuse(spec.evaluations_by_dimension_line, "budget.evaluations_by_dimension", "differs from the run's");
    if (previous.error_threshold != spec.error_threshold)
        refuse(spec.error_threshold_line, "analysis.error_threshold",
               fmt::format("is {:g} here but was {:g}", spec.error_threshold, previous.error_threshold));
    if (previous.selected_dimension != spec.selected_dimension)
        throw InputError("command line", 0, "--dimension",
                         fmt::format("this run selects {} but the run being resumed in {} selected {}; resume it with the same --dimension",
                                     spec.selected_dimension ? "dimension " + std::to_string(spec.selected_dimension) : std::string("every dimension"),
                                     output.string(),
                                     previous.selected_dimension ? "dimension " + std::to_string(previous.selected_dimension)
                                                                 : std::string("every dimension")));
    if (previous.budget.max_evaluations != spec.budget.max_evaluations)
        refuse(0, "budget.evaluations",
               fmt::format("is {} here but was {}", spec.budget.max_evaluations, previous.budget.max_evaluations));
    for (const auto& v : spec.optimizers)
        for (const auto& p : previous.optimizers) {
            if (p.label != v.label) continue;
            const auto& registry = OptimizerRegistry::instance();
            const auto now = resolved(registry, v.name, v.values), then = resolved(registry, p.name, p.values);
            if (p.name != v.name || now != then)
                refuse(v.line, "optimizer " + v.label,
                       fmt::format("is {} ({}) here but was {} ({})", v.name, settings_text(now), p.name, settings_text(then)));
        }
    for (const auto& v : spec.problems)
        for (const auto& p : previous.problems) {
            if (p.label != v.label) continue;
            if (!p.settings_recorded)
                refuse(v.line, "problem " + v.label, "cannot be compared: its settings are not recorded");
            const auto& registry = ProblemRegistry::instance();
            const auto now = resolved(registry, v.name, v.values), then = resolved(registry, p.name, p.parameters);
            if (p.name != v.name || now != then)
                refuse(v.line, "problem " + v.label,
                       fmt::format("is {} ({}) here but was {} ({})", v.name, settings_text(now), p.name, settings_text(then)));
            if (p.lower != v.lower || p.upper != v.upper)
                refuse(v.bounds_line, "problem " + v.label + " lower/upper",
                       fmt::format("the box is [{}] .. [{}] here but was [{}] .. [{}]", fmt::join(v.lower, ", "),
                                   fmt::join(v.upper, ", "), fmt::join(p.lower, ", "), fmt::join(p.upper, ", ")));
        }
}

}  // namespace

std::string shard_directory_name(const Shard& shard) { return fmt::format("shard-{}-of-{}", shard.index, shard.count); }

ExperimentInfo describe_experiment(const ExperimentSpec& spec, std::shared_ptr<SharedProblemData> shared) {
    ExperimentInfo info;
    info.name = spec.name;
    info.description = spec.description;
    info.config_file = spec.file.string();
    info.config_text = spec.text;
    info.trials = spec.trials;
    info.seed = spec.seed;
    info.budget = spec.budget;
    info.evaluations_per_dimension = spec.evaluations_per_dimension;
    info.evaluations_by_dimension = spec.evaluations_by_dimension;
    info.error_threshold = spec.error_threshold;
    info.selected_dimension = spec.selected_dimension;
    info.optimizers = spec.optimizers;
    info.baseline = spec.baseline;
    info.references = spec.references;
    info.plots = spec.plots;
    info.per_problem = spec.per_problem;
    info.published = spec.published;
    info.anytime = spec.anytime;
    for (const auto& v : spec.problems) {
        const auto problem = create_problem(spec, v, problem_context(spec, derive_seed(spec.seed, "", v.label, 0), shared));
        ProblemInfo p;
        p.label = v.label;
        p.name = v.name;
        p.dimension = problem->dimension();
        p.parameter_names = problem->parameter_names();
        p.named_parameters = problem->has_named_parameters();
        p.truth = problem->truth();
        p.description = problem->describe();
        p.parameters = v.values;
        p.lower = v.lower;
        p.upper = v.upper;
        if (spec.anytime && !p.truth.optimum_value)
            throw InputError(spec.file.string(), v.line, "problem " + v.label,
                             "does not know its optimum f*, which [anytime] needs: its targets are precisions f - f*");
        if (spec.error_threshold > 0 && !p.truth.optimum_value)
            throw InputError(spec.file.string(), v.line, "problem " + v.label,
                             "does not know its optimum f*, which analysis.error_threshold needs (line " +
                                 std::to_string(spec.error_threshold_line) + "): it applies to errors f - f*");
        if (!spec.evaluations_by_dimension.empty() && !spec.evaluations_by_dimension.count(p.dimension))
            throw InputError(spec.file.string(), v.line, "problem " + v.label,
                             fmt::format("has dimension {}, for which budget.evaluations_by_dimension (line {}) gives no budget",
                                         p.dimension, spec.evaluations_by_dimension_line));
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

void select_dimension(ExperimentSpec& spec, int dimension) {
    std::vector<PluginVariant> kept;
    std::set<int> found;
    auto shared = std::make_shared<SharedProblemData>();
    for (const auto& v : spec.problems) {
        const int d = create_problem(spec, v, problem_context(spec, derive_seed(spec.seed, "", v.label, 0), shared))->dimension();
        found.insert(d);
        if (d == dimension) kept.push_back(v);
    }
    if (kept.empty())
        throw InputError("command line", 0, "--dimension",
                         fmt::format("no problem of {} has dimension {}; its dimensions are {}", spec.file.string(), dimension,
                                     fmt::join(found, ", ")));
    spec.problems = std::move(kept);
    spec.selected_dimension = dimension;
    // A reference number quoted for a problem left out has no row to stand beside.
    std::erase_if(spec.published, [&](const PublishedResult& r) {
        return std::none_of(spec.problems.begin(), spec.problems.end(), [&](const PluginVariant& v) { return v.label == r.problem; });
    });
}

std::string rank_results_name(int rank) { return fmt::format("results.rank-{}.jsonl", rank); }

std::vector<std::string> fold_rank_results(const fs::path& output) {
    std::vector<std::string> notes;
    std::vector<fs::path> rank_files;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(output, ec)) {
        const auto name = entry.path().filename().string();
        if (name.starts_with("results.rank-") && name.ends_with(".jsonl")) rank_files.push_back(entry.path());
    }
    if (rank_files.empty()) return notes;
    std::sort(rank_files.begin(), rank_files.end());
    const fs::path results_path = output / "results.jsonl";
    std::set<TrialKey> kept;
    if (fs::exists(results_path, ec)) {
        drop_incomplete_last_line(results_path);
        for (const auto& r : read_results(results_path).records) kept.emplace(r.optimizer, r.problem, r.trial);
    }
    std::size_t joined = 0, twice = 0;
    {
        ResultsWriter writer(results_path);
        for (const auto& file : rank_files) {
            auto loaded = read_results(file);
            for (const auto& note : loaded.notes) notes.push_back(file.string() + ": " + note);
            for (const auto& r : loaded.records) {
                if (!kept.emplace(r.optimizer, r.problem, r.trial).second) {
                    ++twice;
                    continue;
                }
                writer.append(r);
                ++joined;
            }
        }
    }
    // Only now: a kill before this point leaves the rank files, and the next fold skips what was joined.
    for (const auto& file : rank_files) fs::remove(file, ec);
    notes.push_back(fmt::format("joined {} records from {} rank file(s) of an earlier distributed run{}", joined, rank_files.size(),
                                twice ? fmt::format(" ({} already held, kept once)", twice) : std::string()));
    return notes;
}

PreparedRun prepare_run(const ExperimentSpec& spec, const RunOptions& options, int ranks) {
    PreparedRun prepared;
    prepared.output = options.output ? *options.output
                      : options.shard ? spec.output / shard_directory_name(*options.shard)
                                      : spec.output;
    // One measurement read and one set of statistics per problem variant, shared by all its trials.
    prepared.shared = std::make_shared<SharedProblemData>();
    prepared.info = describe_experiment(spec, prepared.shared);
    prepared.info.shard = options.shard;
    const fs::path results_path = prepared.output / "results.jsonl";

    std::error_code ec;
    fs::create_directories(prepared.output, ec);
    if (ec || !fs::is_directory(prepared.output))
        throw InputError(prepared.output.string(), 0, "output", "cannot create the output directory: " +
                                                                    (ec ? ec.message() : std::string("not a directory")));
    // Records a killed distributed run left in its ranks' files belong to it, resumed or kept aside.
    prepared.notes = fold_rank_results(prepared.output);

    const bool earlier_results = fs::file_size(results_path, ec) > 0 && !ec;
    const bool earlier_info = fs::exists(prepared.output / "experiment.json", ec);
    const int threads = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
    if (earlier_results || earlier_info) {
        if (options.resume) {
            if (earlier_info) {
                const auto earlier = read_experiment_info(prepared.output);
                check_resumable(spec, earlier, prepared.output, options.shard);
                // The trials kept came from the earlier runs: their provenance stays beside this one's.
                if (earlier_results) prepared.info.runs = earlier.runs;
            }
            if (earlier_results) {
                drop_incomplete_last_line(results_path);
                auto loaded = read_results(results_path);
                prepared.notes.insert(prepared.notes.end(), loaded.notes.begin(), loaded.notes.end());
                for (const auto& r : loaded.records) prepared.done.emplace(r.optimizer, r.problem, r.trial);
            }
        } else if (earlier_results) {
            const fs::path kept = keep_previous_run(prepared.output);
            prepared.notes.push_back("the earlier run's results and experiment.json are kept in " + kept.string() +
                                     " (use --resume to continue a run instead)");
        }
    }
    auto provenance = current_provenance(threads);
    provenance.ranks = ranks;
    prepared.info.runs.push_back(provenance);
    write_experiment_info(prepared.output, prepared.info);
    return prepared;
}

PreparedRun attach_to_run(const ExperimentSpec& spec, const RunOptions& options) {
    PreparedRun prepared;
    prepared.output = options.output ? *options.output : spec.output;
    prepared.shared = std::make_shared<SharedProblemData>();
    prepared.info = describe_experiment(spec, prepared.shared);
    std::error_code ec;
    if (fs::exists(prepared.output / "results.jsonl", ec))
        for (const auto& r : read_results(prepared.output / "results.jsonl").records) prepared.done.emplace(r.optimizer, r.problem, r.trial);
    return prepared;
}

RunSummary run_experiment(const ExperimentSpec& spec, const RunOptions& options) {
    const auto prepared = prepare_run(spec, options);
    return run_prepared(spec, options, prepared, options.shard, prepared.output / "results.jsonl");
}

RunSummary run_prepared(const ExperimentSpec& spec, const RunOptions& options, const PreparedRun& prepared,
                        const std::optional<Shard>& share, const fs::path& results_path) {
    const auto start = std::chrono::steady_clock::now();
    RunSummary summary;
    summary.output = prepared.output;
    summary.info = prepared.info;
    summary.notes = prepared.notes;
    const auto& done = prepared.done;
    const auto& shared = prepared.shared;
    const int threads = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
    std::error_code size_error;
    const bool fresh_file = !fs::exists(results_path, size_error) || fs::file_size(results_path, size_error) == 0;
    std::vector<TrialRecord> kept;
    std::vector<TrialRecord>* keep = options.keep_records && fresh_file && !size_error ? &kept : nullptr;
    ResultsWriter writer(results_path);

    struct Task {
        std::size_t optimizer, problem;
        std::int64_t trial;
    };
    std::vector<Task> tasks;
    std::int64_t position = 0;  // in the fixed order that shards divide
    for (std::size_t p = 0; p < spec.problems.size(); ++p)
        for (std::size_t o = 0; o < spec.optimizers.size(); ++o)
            for (std::int64_t t = 0; t < spec.trials; ++t, ++position) {
                if (share && !share->holds(position)) continue;
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
    // After a failed write (a full disk) the remaining trials are skipped: their records could not be kept.
    std::atomic<bool> writes_failed{false};
    tbb::task_arena arena(threads);
    arena.execute([&] {
        tbb::parallel_for(std::size_t{0}, tasks.size(), [&](std::size_t k) {
            if (writes_failed) return;
            const Task& task = tasks[k];
            const auto& ov = spec.optimizers[task.optimizer];
            const auto& pv = spec.problems[task.problem];
            const std::uint64_t seed = derive_seed(spec.seed, ov.label, pv.label, static_cast<std::uint64_t>(task.trial));
            TrialRecord record;
            try {
                auto problem = instantiate(pv, problem_context(spec, seed, shared));
                auto optimizer = make_optimizer(ov.name, ov.values);
                TrialSetup setup{spec.budget, seed, problem->has_named_parameters()};
                setup.budget.max_evaluations = evaluation_budget(spec.budget, spec.evaluations_per_dimension,
                                                                 spec.evaluations_by_dimension, problem->dimension());
                if (spec.anytime) {
                    setup.record_trace = spec.anytime->iteration_trace;
                    setup.anytime = &*spec.anytime;
                    setup.optimum = *problem->truth().optimum_value;
                }
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
                writer.append(record, keep);
            } catch (...) {
                writes_failed = true;
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
    if (keep) summary.records = std::move(kept);
    return summary;
}

}  // namespace mhb
