// `mhbench study FILE [--out DIR] [--threads N] [--seeds N]`: the hidden-effect study
// (problems/pmsm/study/detection_study.hpp): simulated drives with known imperfections over many noise
// seeds, diagnosed blind; writes records.jsonl, table.md and table.csv.
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <tbb/global_control.h>

#include "framework/cli/commands.hpp"
#include "framework/input_error.hpp"
#include "problems/pmsm/study/detection_study.hpp"

namespace mhb::cli {
namespace {

struct StudyOptions {
    std::string file, out, keep_data, only;
    int threads = 0;
    std::int64_t seeds = 0;
    bool quiet = false;
};

// Written beside each other and then renamed, so that a reader never sees half a table.
void write_file(const std::filesystem::path& path, const std::string& text) {
    const auto temporary = std::filesystem::path(path.string() + ".tmp");
    {
        std::ofstream out(temporary);
        out << text;
        out.close();
        if (!out) throw InputError(temporary.string(), 0, "", "cannot write");
    }
    std::error_code ec;
    std::filesystem::rename(temporary, path, ec);
    if (ec) throw InputError(path.string(), 0, "", "cannot write: " + ec.message());
}

const bool registered = register_command("study", [](CLI::App& app) {
    auto* cmd = app.add_subcommand("study", "Run a hidden-effect detection study: simulated drives with known effects, diagnosed blind, rates over seeds");
    auto o = std::make_shared<StudyOptions>();
    cmd->add_option("file", o->file, "study file (TOML, e.g. experiments/pmsm/detection_study.toml)")->required();
    cmd->add_option("--out", o->out, "output directory (default: the study file's `output`)");
    cmd->add_option("--threads", o->threads, "worker threads (default: all cores)")->check(CLI::Range(1, 4096));
    cmd->add_option("--seeds", o->seeds, "use only the first N seeds of the study file")->check(CLI::Range(1, 100000));
    cmd->add_flag("--quiet", o->quiet, "do not print progress and the summary");
    cmd->add_option("--only", o->only, "run only the cases whose label contains this text (e.g. deadtime, clean)");
    cmd->add_option("--keep-data", o->keep_data, "write each drive's measurement CSV and sidecar into this directory, to diagnose a case by hand");
    return std::function<int()>([o] {
        auto spec = pmsm::read_study(o->file);
        if (o->seeds > 0 && static_cast<std::size_t>(o->seeds) < spec.seeds.size()) spec.seeds.resize(static_cast<std::size_t>(o->seeds));
        if (!o->out.empty()) spec.output = o->out;
        spec.only = o->only;
        spec.keep_data = o->keep_data;
        if (!spec.keep_data.empty()) {
            std::error_code created;
            std::filesystem::create_directories(spec.keep_data, created);
            if (created) throw InputError(spec.keep_data.string(), 0, "--keep-data", "cannot create the directory: " + created.message());
        }
        std::optional<tbb::global_control> limit;
        if (o->threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(o->threads));
        std::error_code ec;
        std::filesystem::create_directories(spec.output, ec);
        if (ec) throw InputError(spec.output.string(), 0, "output", "cannot create the directory: " + ec.message());
        const auto run = pmsm::run_study(spec, pmsm::study_cases(spec), pmsm::DiagnosisOptions{}, [&](std::size_t done, std::size_t total) {
            if (!o->quiet && (done % 10 == 0 || done == total)) std::fprintf(stderr, "\r%zu of %zu drives diagnosed", done, total);
            if (!o->quiet && done == total) std::fprintf(stderr, "\n");
        });
        std::string records;
        for (const auto& r : run.records) records += pmsm::study_record_json(run, r).dump() + "\n";
        write_file(spec.output / "records.jsonl", records);
        const std::string md = pmsm::study_markdown(spec, run);
        write_file(spec.output / "table.md", md);
        write_file(spec.output / "table.csv", pmsm::study_csv(run));
        if (!o->quiet) fmt::print("{}", md);
        fmt::print("\nresults: {}\n", (spec.output / "table.md").string());
        return exit_ok;
    });
});

}  // namespace
}  // namespace mhb::cli
