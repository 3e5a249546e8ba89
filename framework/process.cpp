#include "framework/process.hpp"

#include <cerrno>
#include <cstring>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

extern char** environ;

namespace mhb {

namespace {
// Owns a posix_spawn_file_actions_t so every return path releases it.
class FileActions {
public:
    FileActions() { posix_spawn_file_actions_init(&actions_); }
    ~FileActions() { posix_spawn_file_actions_destroy(&actions_); }
    FileActions(const FileActions&) = delete;
    FileActions& operator=(const FileActions&) = delete;
    posix_spawn_file_actions_t* get() { return &actions_; }

private:
    posix_spawn_file_actions_t actions_;
};
}  // namespace

ProcessOutcome run_program(const std::vector<std::string>& argv, const std::optional<std::filesystem::path>& input,
                           const std::optional<std::filesystem::path>& output,
                           const std::optional<std::filesystem::path>& error_output) {
    ProcessOutcome outcome;
    if (argv.empty()) {
        outcome.error = "no program given";
        return outcome;
    }
    std::vector<char*> args;
    args.reserve(argv.size() + 1);
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);

    // The paths are kept alive here: posix_spawn_file_actions_addopen may keep the pointer.
    const std::string in_path = input ? input->string() : std::string("/dev/null");
    const std::string out_path = output ? output->string() : std::string("/dev/null");
    const std::string error_path = error_output ? error_output->string() : std::string();
    FileActions actions;
    posix_spawn_file_actions_addopen(actions.get(), 0, in_path.c_str(), O_RDONLY, 0);
    posix_spawn_file_actions_addopen(actions.get(), 1, out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (error_output) posix_spawn_file_actions_addopen(actions.get(), 2, error_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    else posix_spawn_file_actions_adddup2(actions.get(), 1, 2);

    pid_t pid = 0;
    const int spawn_error = posix_spawnp(&pid, argv[0].c_str(), actions.get(), nullptr, args.data(), environ);
    if (spawn_error != 0) {
        outcome.error = argv[0] + ": " + std::strerror(spawn_error);
        return outcome;
    }
    outcome.started = true;
    int status = 0;
    while (waitpid(pid, &status, 0) < 0) {
        if (errno != EINTR) {
            outcome.error = std::string("waiting for ") + argv[0] + ": " + std::strerror(errno);
            return outcome;
        }
    }
    if (WIFEXITED(status)) {
        outcome.exit_code = WEXITSTATUS(status);
    } else if (WIFSIGNALED(status)) {
        outcome.error = argv[0] + " was killed by signal " + std::to_string(WTERMSIG(status));
    }
    return outcome;
}

}  // namespace mhb
