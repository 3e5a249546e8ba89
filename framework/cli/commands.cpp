#include "framework/cli/commands.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <new>
#include <map>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "framework/closest_name.hpp"
#include "framework/input_error.hpp"
#include "framework/registry.hpp"

namespace mhb::cli {
namespace {
std::vector<std::pair<std::string, CommandSetup>>& commands() {
    static std::vector<std::pair<std::string, CommandSetup>> list;
    return list;
}
}  // namespace

bool register_command(std::string name, CommandSetup setup) {
    commands().emplace_back(std::move(name), std::move(setup));
    return true;
}

int run(int argc, char** argv) {
    CLI::App app{"mhbench: benchmark metaheuristic optimisers and identify physical models from measurements"};
    app.require_subcommand(1);
    app.set_version_flag("--version", "mhbench 0.1.0");
    std::map<CLI::App*, std::function<int()>> actions;
    for (auto& [name, setup] : commands()) {
        auto action = setup(app);
        actions[app.get_subcommand(name)] = std::move(action);
    }
    // CLI11 would answer a mistyped command with "A subcommand is required"; name it and the closest.
    if (argc >= 2 && argv[1][0] != '-') {
        std::vector<std::string> names;
        for (const auto& [name, setup] : commands()) names.push_back(name);
        std::sort(names.begin(), names.end());
        if (std::find(names.begin(), names.end(), argv[1]) == names.end()) {
            std::fprintf(stderr, "error: command line: %s\nRun 'mhbench --help' for usage.\n",
                         unknown_name_message("command", argv[1], names).c_str());
            return exit_bad_input;
        }
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        std::fprintf(stderr, "error: command line: %s\nRun 'mhbench --help' for usage.\n", e.what());
        return exit_bad_input;
    }
    bool conflicts = false;
    for (const auto& registry : listed_registries())
        for (const auto& name : registry.conflicts()) {
            std::fprintf(stderr, "error: two plugins among the %s register the name '%s'; rename one of them\n",
                         registry.kind.c_str(), name.c_str());
            conflicts = true;
        }
    if (conflicts) return exit_bad_input;
    for (auto* sub : app.get_subcommands()) {
        try {
            return actions.at(sub)();
        } catch (const InputError& e) {
            std::fprintf(stderr, "error: %s\n", e.what());
            return exit_bad_input;
        } catch (const UnknownPlugin& e) {
            std::fprintf(stderr, "error: %s\n", e.what());
            return exit_bad_input;
        } catch (const std::filesystem::filesystem_error& e) {
            // Its message already names the path(s).
            std::fprintf(stderr, "error: %s\n", e.what());
            return exit_bad_input;
        } catch (const std::bad_alloc&) {
            std::fprintf(stderr, "error: out of memory: the input asks for more than this machine has; use a smaller file, "
                                 "fewer samples or a smaller budget\n");
            return exit_bad_input;
        } catch (const std::exception& e) {
            // Last resort: whatever escaped is still a message and exit code 2, never an abort.
            std::fprintf(stderr, "error: %s\n", e.what());
            return exit_bad_input;
        }
    }
    return exit_bad_input;
}

}  // namespace mhb::cli
