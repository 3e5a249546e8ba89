// `mhbench run FILE [--threads N] [--out DIR] [--resume] [--shard K/N] [--dimension D]`, `mhbench table DIR` and
// `mhbench merge DIR... [--out DIR]`.
#include <cstdio>
#include <memory>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <tbb/task_arena.h>

#include "framework/cli/commands.hpp"
#include "framework/cli/option_ranges.hpp"
#include "framework/experiment_report.hpp"
#include "framework/distributed_launch.hpp"
#include "framework/experiment_runner.hpp"
#include "framework/input_error.hpp"
#ifdef MHBENCH_WITH_MPI
#include "framework/mpi/distributed_run.hpp"
#include "framework/optional_library.hpp"
#endif
#include "framework/plots.hpp"
#include "framework/report_tables.hpp"
#include "framework/shard_merge.hpp"

namespace mhb::cli {
namespace {

namespace fs = std::filesystem;

// Tables, plots and report.html from whatever the directory holds; prints table.md unless `quiet`.
// `records`: the run's own, when it has them (RunSummary::records); null: read from the directory.
void publish(const fs::path& directory, bool plots, bool quiet, const std::vector<TrialRecord>* records = nullptr) {
    const auto info = read_experiment_info(directory);
    LoadedResults loaded;
    if (!records) {
        loaded = read_results(directory / "results.jsonl");
        records = &loaded.records;
    }
    for (const auto& note : loaded.notes) std::fprintf(stderr, "note: %s\n", note.c_str());
    const Document report = write_tables(directory, info, *records);
    ExperimentPlots drawn;
    if (!plots) {
        drawn.absent_because = "No plots: they were not drawn (--no-plots).";
    } else if (!info.plots) {
        drawn.absent_because = "No plots: the experiment's config switches them off (plots = false).";
    } else {
        const auto outcome = write_plots(directory, info, *records);
        for (const auto& note : outcome.notes) std::fprintf(stderr, "note: %s\n", note.c_str());
        drawn.images = outcome.images;
        drawn.absent_because = outcome.notes.empty() ? "No plots: no trial has finished successfully."
                                                     : "No plots: " + outcome.notes.front() + ".";
    }
    write_experiment_report(directory, info, report, drawn);
    if (!quiet) {
        fmt::print("{}\n", markdown(report));
        fmt::print("Wrote {}/table.md, table.csv, report.html", directory.string());
        if (!drawn.images.empty()) fmt::print(" and {} plots (PNG + SVG)", drawn.images.size());
        fmt::print(".\n");
    }
}

// "K/N" with 1 <= K <= N; CLI11 prefixes the option's name to the message.
CLI::Validator shard_format() {
    return CLI::Validator(
        [](std::string& text) -> std::string {
            long long k = 0, n = 0;
            char slash = 0, extra = 0;
            if (std::sscanf(text.c_str(), "%lld%c%lld%c", &k, &slash, &n, &extra) != 3 || slash != '/' || k < 1 || n < 1 ||
                k > n || n > 1'000'000)
                return "expects K/N, the K-th of N shares with 1 <= K <= N <= 1000000, e.g. 2/8 (got '" + text + "')";
            return {};
        },
        "K/N");
}

Shard parse_shard(const std::string& text) {
    long long k = 0, n = 0;
    std::sscanf(text.c_str(), "%lld/%lld", &k, &n);
    return Shard{k, n};
}

const bool run_registered = register_command("run", [](CLI::App& app) {
    auto* cmd = app.add_subcommand("run", "Run an experiment described in a TOML file; write results, tables and plots");
    struct Args {
        std::string file, out, shard;
        int threads = 0, dimension = 0;
        bool resume = false, no_plots = false, quiet = false;
    };
    auto a = std::make_shared<Args>();
    cmd->add_option("FILE", a->file, "experiment TOML file (see experiments/ and docs/config-reference.md)")->required();
    cmd->add_option("--shard", a->shard,
                    "run only the K-th of N deterministic shares of the trials, into <output>/shard-K-of-N unless --out "
                    "is given; `mhbench merge` joins the shares (docs/campaigns.md)")
        ->check(shard_format());
    cmd->add_option("--threads", a->threads, "worker threads (default: all cores)")->check(whole_number_in(1, 4096));
    cmd->add_option("--out", a->out, "output directory (default: the config's `output`)");
    cmd->add_option("--dimension", a->dimension, "run only the config's problems of this dimension (recorded with the results)")
        ->check(whole_number_in(1, 100000));
    cmd->add_flag("--resume", a->resume, "keep the trials already in the output's results.jsonl and run only the missing ones");
    cmd->add_flag("--no-plots", a->no_plots, "write tables only");
    cmd->add_flag("--quiet", a->quiet, "do not print the tables");
    auto action = [a]() -> int {
        auto spec = load_experiment(a->file);
        if (a->dimension > 0) select_dimension(spec, a->dimension);
        RunOptions options;
        options.threads = a->threads;
        options.resume = a->resume;
        if (!a->out.empty()) options.output = fs::path(a->out);
        if (!a->shard.empty()) options.shard = parse_shard(a->shard);
        if (!a->quiet && launched_rank() == 0)
            std::fprintf(stderr, "Running %s: %zu optimizer(s) x %zu problem(s) x %lld trials\n", spec.name.c_str(),
                         spec.optimizers.size(), spec.problems.size(), static_cast<long long>(spec.trials));
        RunSummary summary;
        if (launched_ranks() > 1) {
#ifdef MHBENCH_WITH_MPI
            DistributedOutcome outcome;
            try {
                const auto run = optional_library_entry<DistributedRun()>("mpi", "mhbench_mpi_run")();
                outcome = run(spec, options);
            } catch (const RunStoppedOnAnotherRank&) {
                return exit_bad_input;
            }
            if (!outcome.summary) return exit_ok;  // rank 0 reports for all
            summary = std::move(*outcome.summary);
            std::fprintf(stderr, "Spread over %d MPI ranks.\n", outcome.ranks);
#else
            throw InputError("command line", 0, "mpirun",
                             fmt::format("started as one of {} MPI processes, but this mhbench was built without MPI, so "
                                         "every process would run every trial; install libopenmpi-dev and libboost-mpi-dev "
                                         "and rebuild, or divide the trials with --shard K/N (docs/campaigns.md)",
                                         launched_ranks()));
#endif
        } else {
            options.keep_records = true;  // for the tables below (a distributed run's rank 0 has its share only)
            summary = run_experiment(spec, options);
        }
        for (const auto& note : summary.notes) std::fprintf(stderr, "note: %s\n", note.c_str());
        // The tables, which read the records back in parallel when they must: on no more threads than
        // the trials were given.
        tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
        arena.execute([&] { publish(summary.output, !a->no_plots, a->quiet, summary.records ? &*summary.records : nullptr); });
        std::fprintf(stderr, "%zu trials run, %zu skipped (already done), %zu failed, in %.3f s wall time.\n", summary.ran,
                     summary.skipped, summary.failed, summary.seconds);
        if (options.shard)
            std::fprintf(stderr, "This was shard %s of the trials, in %s; its tables cover that share only. When all %lld "
                                 "have run: mhbench merge <their directories> (docs/campaigns.md).\n",
                         a->shard.c_str(), summary.output.string().c_str(), static_cast<long long>(options.shard->count));
        if (summary.failed > 0) {
            std::fprintf(stderr, "error: %zu trial(s) failed; their reasons are in %s/results.jsonl. First:\n", summary.failed,
                         summary.output.string().c_str());
            for (const auto& f : summary.failures) std::fprintf(stderr, "  %s\n", f.c_str());
            return exit_bad_input;
        }
        return exit_ok;
    };
    return std::function<int()>([action] {
        if (launched_ranks() > 1 && launched_rank() != 0) {
            // Under mpirun every rank reads the config; rank 0 alone says what is wrong, once.
            try {
                return action();
            } catch (const std::exception&) {
                return exit_bad_input;
            }
        }
        return action();
    });
});

const bool table_registered = register_command("table", [](CLI::App& app) {
    auto* cmd = app.add_subcommand("table", "Remake the tables (and plots) of a results directory");
    struct Args {
        std::string dir;
        bool no_plots = false;
    };
    auto a = std::make_shared<Args>();
    cmd->add_option("DIR", a->dir, "a directory written by `mhbench run`")->required();
    cmd->add_flag("--no-plots", a->no_plots, "write tables only");
    return std::function<int()>([a] {
        publish(a->dir, !a->no_plots, false);
        return exit_ok;
    });
});

const bool merge_registered = register_command("merge", [](CLI::App& app) {
    auto* cmd = app.add_subcommand("merge", "Join the shard directories of one experiment (run --shard K/N) into one; write its tables and plots");
    struct Args {
        std::vector<std::string> dirs;
        std::string out;
        bool no_plots = false, quiet = false;
    };
    auto a = std::make_shared<Args>();
    cmd->add_option("DIR", a->dirs, "the shards' directories (shard-K-of-N), all of them")->required();
    cmd->add_option("--out", a->out, "where the merged results go (default: the directory holding the shards)");
    cmd->add_flag("--no-plots", a->no_plots, "write tables only");
    cmd->add_flag("--quiet", a->quiet, "do not print the tables");
    return std::function<int()>([a] {
        std::vector<fs::path> dirs(a->dirs.begin(), a->dirs.end());
        const fs::path out = a->out.empty() ? default_merge_output(dirs) : fs::path(a->out);
        const auto summary = merge_shards(dirs, out);
        for (const auto& note : summary.notes) std::fprintf(stderr, "note: %s\n", note.c_str());
        publish(summary.output, !a->no_plots, a->quiet);
        std::fprintf(stderr, "Merged %zu trials from %zu directories into %s.\n", summary.records, dirs.size(),
                     summary.output.string().c_str());
        return exit_ok;
    });
});

}  // namespace
}  // namespace mhb::cli
