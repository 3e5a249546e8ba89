// `mhbench list [KIND]`: every registry (optimizers, problems, and plugin families such as the PMSM
// effects) with each parameter's type, default, range, unit and description.
#include <algorithm>
#include <cstdio>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "framework/cli/commands.hpp"
#include "framework/registry.hpp"

namespace mhb::cli {
namespace {

void print_registry(const ListedRegistry& r, bool verbose) {
    const auto names = r.names_and_summaries();
    const auto params = r.parameters();
    std::string heading = r.kind;
    heading[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(heading[0])));
    fmt::print("{} ({})\n", heading, names.size());
    for (std::size_t i = 0; i < names.size(); ++i) {
        fmt::print("  {:<24} {}\n", names[i].first, names[i].second);
        if (!verbose) continue;
        for (const auto& p : params[i]) {
            std::string range = p.range_text();
            if (!p.unit.empty()) range += " " + p.unit;
            fmt::print("      {:<22} {:<5} = {:<10} {:<22} {}\n", p.name, type_name(p.type), to_string(p.default_value), range,
                       p.description);
        }
    }
    fmt::print("\n");
}

const bool registered = register_command("list", [](CLI::App& app) {
    auto* cmd = app.add_subcommand("list", "List registered plugins (optimizers, problems, effects) with their parameters");
    auto what = std::make_shared<std::string>("all");
    auto brief = std::make_shared<bool>(false);
    cmd->add_option("what", *what, "all, or one kind: optimizers, problems, effects");
    cmd->add_flag("--brief", *brief, "names only, without parameters");
    return std::function<int()>([what, brief] {
        bool shown = false;
        auto registries = listed_registries();  // static-initialisation order varies: sort by kind
        std::sort(registries.begin(), registries.end(), [](const auto& a, const auto& b) { return a.kind < b.kind; });
        for (const auto& r : registries)
            if (*what == "all" || *what == r.kind) {
                print_registry(r, !*brief);
                shown = true;
            }
        if (!shown) {
            std::string kinds;
            for (const auto& r : registries) kinds += ", " + r.kind;
            std::fprintf(stderr, "error: command line: list: unknown kind '%s'; expected all%s\n", what->c_str(), kinds.c_str());
            return exit_bad_input;
        }
        return exit_ok;
    });
});

}  // namespace
}  // namespace mhb::cli
