#pragma once
// The `mhbench` command line. Each subcommand lives in its own file and registers itself here.
#include <functional>
#include <string>

namespace CLI {
class App;
}

namespace mhb::cli {

// Exit codes: 0 success, 1 some trials failed (results are still written), 2 bad input.
constexpr int exit_ok = 0;
constexpr int exit_trial_failures = 1;
constexpr int exit_bad_input = 2;

// A subcommand adds itself to the app and returns the action to run when it is chosen.
using CommandSetup = std::function<std::function<int()>(CLI::App&)>;
bool register_command(std::string name, CommandSetup setup);

int run(int argc, char** argv);

}  // namespace mhb::cli
