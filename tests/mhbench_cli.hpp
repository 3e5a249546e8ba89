#pragma once
// Runs the `mhbench` binary as a user does and collects its exit code and output.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <sys/wait.h>

namespace mhb::testing {

struct CliRun {
    int exit_code;
    std::string output;  // stdout and stderr
};

// `arguments` go to a shell: quote what it must not split. The output passes through `log`.
inline CliRun run_mhbench(const std::string& arguments, const std::filesystem::path& log) {
    const std::string command = std::string(MHBENCH_CLI) + " " + arguments + " > " + log.string() + " 2>&1";
    const int status = std::system(command.c_str());
    std::ifstream in(log);
    std::stringstream text;
    text << in.rdbuf();
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text.str()};
}

}  // namespace mhb::testing
