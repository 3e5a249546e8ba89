// `mhbench list [optimizers|problems|effects]`: the registry with every parameter's type, default,
// range and description.
#include <cstdio>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "framework/cli/commands.hpp"
#include "framework/registry.hpp"

namespace mhb::cli {
namespace {

template <class Entries>
void print_entries(const char* heading, const Entries& entries, bool verbose) {
    fmt::print("{} ({})\n", heading, entries.size());
    for (const auto* e : entries) {
        fmt::print("  {:<24} {}\n", e->name, e->summary);
        if (!verbose) continue;
        for (const auto& p : e->parameters) {
            std::string range = p.range_text();
            if (!p.unit.empty()) range += " " + p.unit;
            fmt::print("      {:<22} {:<5} = {:<10} {:<22} {}\n", p.name, type_name(p.type), to_string(p.default_value),
                       range, p.description);
        }
    }
    fmt::print("\n");
}

const bool registered = register_command("list", [](CLI::App& app) {
    auto* cmd = app.add_subcommand("list", "List registered optimizers and problems with their parameters");
    auto what = std::make_shared<std::string>("all");
    auto brief = std::make_shared<bool>(false);
    cmd->add_option("what", *what, "optimizers, problems or all")
        ->check(CLI::IsMember({"all", "optimizers", "problems"}));
    cmd->add_flag("--brief", *brief, "names only, without parameters");
    return std::function<int()>([what, brief] {
        if (*what == "all" || *what == "optimizers")
            print_entries("Optimizers", OptimizerRegistry::instance().entries(), !*brief);
        if (*what == "all" || *what == "problems")
            print_entries("Problems", ProblemRegistry::instance().entries(), !*brief);
        return exit_ok;
    });
});

}  // namespace
}  // namespace mhb::cli
