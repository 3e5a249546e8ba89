#pragma once
// Starting external programs (gnuplot) without a shell: the program is looked up on PATH and
// receives its arguments as a vector, so no text from a config, a label or a path is ever
// interpreted by /bin/sh.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace mhb {

struct ProcessOutcome {
    bool started = false;   // false: the program could not be started (e.g. not installed); see `error`
    int exit_code = -1;     // the program's exit status; -1 when it was killed by a signal
    std::string error;      // why it could not be started or was killed
};

// Runs argv[0] (searched on PATH) with `argv`, standard input read from `input` (or /dev/null),
// standard output written to `output` (or discarded), and waits for it. Standard error goes to
// `error_output` when given, else wherever standard output goes: a program that prints its result
// (a browser's DOM) and chatters on standard error can keep the two apart.
ProcessOutcome run_program(const std::vector<std::string>& argv, const std::optional<std::filesystem::path>& input,
                           const std::optional<std::filesystem::path>& output,
                           const std::optional<std::filesystem::path>& error_output = std::nullopt);

}  // namespace mhb
