#include "framework/cli/commands.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <new>
#include <string_view>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "framework/closest_name.hpp"
#include "framework/input_error.hpp"
#include "framework/plugin_loader.hpp"
#include "framework/provenance.hpp"
#include "framework/registry.hpp"

namespace mhb::cli {
namespace {

struct Command {
    std::string name;
    CommandSetup setup;
    std::string origin;
};

std::vector<Command>& commands() {
    static std::vector<Command> list;
    return list;
}

std::vector<RegistrationClash>& command_clashes() {
    static std::vector<RegistrationClash> clashes;
    return clashes;
}

const bool clashes_reported = [] {
    add_clash_source([] {
        std::vector<std::string> out;
        for (const auto& clash : command_clashes()) out.push_back(clash_message("command", clash));
        return out;
    });
    return true;
}();

// The libraries named by --plugin, loaded before the command line is parsed because they may add
// commands. Options of the main program come before the command, so the scan stops at the first word
// that is not an option or an option's value.
void load_plugins_of_arguments(int argc, char** argv) {
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        std::string path;
        if (arg == "--plugin") {
            if (i + 1 >= argc) return;  // CLI11 reports the missing value
            path = argv[++i];
        } else if (arg.starts_with("--plugin=")) {
            path = arg.substr(9);
        } else {
            return;
        }
        try {
            load_plugin(path);
        } catch (const PluginLoadError& e) {
            throw InputError("command line", 0, "--plugin", e.what());
        }
    }
}

}  // namespace

bool register_command(std::string name, CommandSetup setup) {
    for (const auto& command : commands())
        if (command.name == name) {
            command_clashes().push_back({name, command.origin, registration_origin()});
            return false;
        }
    commands().push_back({std::move(name), std::move(setup), registration_origin()});
    return true;
}

int run(int argc, char** argv) {
    try {
        load_plugins_of_arguments(argc, argv);
    } catch (const InputError& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return exit_bad_input;
    }
    CLI::App app{"mhbench: benchmark metaheuristic optimisers and identify physical models from measurements"};
    app.require_subcommand(1);
    const auto build = current_provenance(0);
    app.set_version_flag("--version", fmt::format("mhbench {} (commit {}, plugin interface version {})", build.version,
                                                   build.commit, plugin_interface_version()));
    std::vector<std::string> plugins;  // loaded above; declared so that --help lists it
    app.add_option("--plugin", plugins,
                   "load a plugin library (optimizers, problems, effects, commands) built against the installed "
                   "mhbench; may be repeated; goes before the command (docs/plugins.md)");
    std::map<CLI::App*, std::function<int()>> actions;
    for (auto& command : commands()) {
        auto action = command.setup(app);
        actions[app.get_subcommand(command.name)] = std::move(action);
    }
    // CLI11 would answer a mistyped command with "A subcommand is required"; name it and the closest.
    int first_word = 1;
    while (first_word < argc && std::string_view(argv[first_word]).starts_with("--plugin"))
        first_word += std::string_view(argv[first_word]) == "--plugin" ? 2 : 1;
    if (first_word < argc && argv[first_word][0] != '-') {
        std::vector<std::string> names;
        for (const auto& command : commands()) names.push_back(command.name);
        std::sort(names.begin(), names.end());
        if (std::find(names.begin(), names.end(), argv[first_word]) == names.end()) {
            std::fprintf(stderr, "error: command line: %s\nRun 'mhbench --help' for usage.\n",
                         unknown_name_message("command", argv[first_word], names).c_str());
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
    const auto clashes = registration_clashes();
    for (const auto& clash : clashes) std::fprintf(stderr, "error: %s\n", clash.c_str());
    if (!clashes.empty()) return exit_bad_input;
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
