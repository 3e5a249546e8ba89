#pragma once
// Runs the `mhbench` binary as a user does and collects its exit code and output. No shell runs in
// between: each argument reaches mhbench as written, which the injection tests rely on.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "framework/process.hpp"

namespace mhb::testing {

struct CliRun {
    int exit_code;
    std::string output;  // stdout and stderr
};

// Any program (cmake, mpirun, an installed mhbench), `argv[0]` searched on PATH.
inline CliRun run_command(const std::vector<std::string>& argv, const std::filesystem::path& log) {
    const auto outcome = run_program(argv, std::nullopt, log);
    std::ifstream in(log);
    std::stringstream text;
    text << in.rdbuf();
    return {outcome.started ? outcome.exit_code : -1, text.str()};
}

inline CliRun run_mhbench(const std::vector<std::string>& arguments, const std::filesystem::path& log) {
    std::vector<std::string> argv{MHBENCH_CLI};
    argv.insert(argv.end(), arguments.begin(), arguments.end());
    return run_command(argv, log);
}

// `arguments` split at blanks; single quotes keep a blank inside one argument (as in a shell, but
// nothing else of a shell's syntax means anything).
inline CliRun run_mhbench(const std::string& arguments, const std::filesystem::path& log) {
    std::vector<std::string> argv;
    std::string current;
    bool quoted = false, any = false;
    for (char c : arguments) {
        if (c == '\'') {
            quoted = !quoted;
            any = true;
        } else if (c == ' ' && !quoted) {
            if (any) argv.push_back(current);
            current.clear();
            any = false;
        } else {
            current += c;
            any = true;
        }
    }
    if (any) argv.push_back(current);
    return run_mhbench(argv, log);
}

}  // namespace mhb::testing
