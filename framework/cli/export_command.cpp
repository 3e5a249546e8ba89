// `mhbench export --format iohprofiler DIR [--out OUT]`.
#include <cstdio>
#include <memory>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "framework/cli/commands.hpp"
#include "framework/input_error.hpp"
#include "framework/iohprofiler_export.hpp"

namespace mhb::cli {
namespace {

namespace fs = std::filesystem;

const bool export_registered = register_command("export", [](CLI::App& app) {
    auto* cmd = app.add_subcommand("export", "Write a results directory in another tool's data format (IOHprofiler, for IOHanalyzer)");
    struct Args {
        std::string format, dir, out;
    };
    auto a = std::make_shared<Args>();
    cmd->add_option("--format", a->format, "the format to write; known: iohprofiler (docs/campaigns.md)")->required();
    cmd->add_option("DIR", a->dir, "a directory written by `mhbench run` or `mhbench merge`")->required();
    cmd->add_option("--out", a->out, "a new or empty directory to write into (default: DIR/iohprofiler)");
    return std::function<int()>([a] {
        // Checked here rather than by CLI11, so that the refusal is one line naming the known formats.
        if (a->format != "iohprofiler")
            throw InputError("command line", 0, "--format", fmt::format("unknown format '{}'; known: iohprofiler", a->format));
        const fs::path out = a->out.empty() ? fs::path(a->dir) / "iohprofiler" : fs::path(a->out);
        const auto summary = export_iohprofiler(a->dir, out);
        for (const auto& note : summary.notes) std::fprintf(stderr, "note: %s\n", note.c_str());
        fmt::print("Exported {} runs of {} algorithm(s) on {} function(s) to {}: load that folder (or a zip of it) into "
                   "IOHanalyzer.\n",
                   summary.runs, summary.algorithms, summary.functions, summary.output.string());
        return exit_ok;
    });
});

}  // namespace
}  // namespace mhb::cli
