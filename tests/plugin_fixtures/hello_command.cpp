// A plugin that brings a subcommand: `mhbench --plugin libhello_command.so hello --name X`.
#include <cstdio>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "framework/cli/commands.hpp"

namespace {

const bool registered = mhb::cli::register_command("hello", [](CLI::App& app) {
    auto* cmd = app.add_subcommand("hello", "Greets (a command brought by a plugin)");
    auto name = std::make_shared<std::string>("world");
    cmd->add_option("--name", *name, "whom to greet");
    return std::function<int()>([name] {
        std::printf("hello, %s\n", name->c_str());
        return mhb::cli::exit_ok;
    });
});

}  // namespace
