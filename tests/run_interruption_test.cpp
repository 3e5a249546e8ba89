// `mhbench run` killed with SIGKILL at several moments, then `--resume`: the records and tables must
// be those of a run that was never interrupted (README: results that finished are never lost).
#include <catch2/catch.hpp>

#include <chrono>
#include <functional>
#include <map>
#include <thread>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include "framework/results_store.hpp"
#include "tests/mhbench_cli.hpp"
#include "tests/table_comparison.hpp"
#include "tests/temporary_directory.hpp"

extern char** environ;

using namespace mhb;
namespace fs = std::filesystem;

namespace {

// Two optimizers x two problems x 8 trials, each trial tens of milliseconds, so that the run lasts
// long enough for every kill point below to land while it is still going.
const char* experiment = R"(name = "interrupted"
trials = 8
seed = 5
[budget]
evaluations = 30000
[[optimizer]]
name = "cmaes"
[[optimizer]]
name = "random_search"
batch = 50
[[problem]]
name = "bbob_f10"
dimension = 20
[[problem]]
name = "F1"
dimension = 20
)";

// Starts mhbench without a shell (as framework/process.cpp does), output to `log`.
pid_t start_mhbench(const std::vector<std::string>& arguments, const fs::path& log) {
    std::vector<std::string> argv{MHBENCH_CLI};
    argv.insert(argv.end(), arguments.begin(), arguments.end());
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    const std::string log_path = log.string();
    posix_spawn_file_actions_addopen(&actions, 1, log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    pid_t pid = 0;
    const int error = posix_spawn(&pid, argv[0].c_str(), &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    REQUIRE(error == 0);
    return pid;
}

std::size_t complete_records(const fs::path& results) {
    const std::string text = testing::read_file(results);
    return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

// Runs mhbench and kills it with SIGKILL as soon as `moment` holds; fails if the run ended first
// (then nothing would have been tested).
void kill_when(const std::vector<std::string>& arguments, const fs::path& log, const std::function<bool()>& moment) {
    const pid_t pid = start_mhbench(arguments, log);
    int status = 0;
    while (true) {
        if (waitpid(pid, &status, WNOHANG) == pid) break;
        if (moment()) {
            ::kill(pid, SIGKILL);
            waitpid(pid, &status, 0);
            break;
        }
        std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    INFO(testing::read_file(log));
    REQUIRE(WIFSIGNALED(status));
    REQUIRE(WTERMSIG(status) == SIGKILL);
}

using Key = std::tuple<std::string, std::string, std::int64_t>;
std::map<Key, TrialRecord> records_by_key(const fs::path& results) {
    std::map<Key, TrialRecord> out;
    for (auto& r : read_results(results).records) {
        const Key key{r.optimizer, r.problem, r.trial};
        REQUIRE(out.count(key) == 0);  // no trial twice
        out[key] = std::move(r);
    }
    return out;
}

void require_same_as_uninterrupted(const fs::path& resumed, const fs::path& reference) {
    const auto got = records_by_key(resumed / "results.jsonl"), want = records_by_key(reference / "results.jsonl");
    REQUIRE(got.size() == want.size());
    for (const auto& [key, w] : want) {
        const auto& g = got.at(key);
        REQUIRE(g.ok);
        REQUIRE(g.seed == w.seed);
        REQUIRE(g.best_fitness == w.best_fitness);  // bitwise
        REQUIRE(g.best_position == w.best_position);
        REQUIRE(g.trace_evaluations == w.trace_evaluations);
        REQUIRE(g.trace_best == w.trace_best);
    }
    REQUIRE(testing::without_times(testing::read_file(resumed / "table.csv")) ==
            testing::without_times(testing::read_file(reference / "table.csv")));
}

}  // namespace

TEST_CASE("a run killed at any moment and resumed gives the records and tables of an uninterrupted run", "[cli][resume]") {
    const testing::TemporaryDirectory dir;
    const auto config = dir.write("interrupted.toml", experiment).string();
    // Catch runs the case once per section; the uninterrupted run is made once and shared.
    static const testing::TemporaryDirectory reference_directory;
    const auto reference = reference_directory.path() / "reference";
    if (!fs::exists(reference / "table.csv")) {
        const auto reference_config = reference_directory.write("interrupted.toml", experiment).string();
        REQUIRE(testing::run_mhbench({"run", reference_config, "--threads", "1", "--quiet", "--no-plots", "--out", reference.string()},
                                     reference_directory.path() / "reference.log").exit_code == 0);
    }
    REQUIRE(records_by_key(reference / "results.jsonl").size() == 32);

    auto resume = [&](const fs::path& out) {
        const auto run = testing::run_mhbench({"run", config, "--threads", "1", "--quiet", "--resume", "--out", out.string()},
                                              dir.path() / "resume.log");
        INFO(run.output);
        REQUIRE(run.exit_code == 0);
    };
    auto run_arguments = [&](const fs::path& out) {
        return std::vector<std::string>{"run", config, "--threads", "1", "--quiet", "--out", out.string()};
    };

    SECTION("during the first trial, before any record") {
        const auto out = dir.path() / "first";
        kill_when(run_arguments(out), dir.path() / "kill.log", [&] { return fs::exists(out / "experiment.json"); });
        resume(out);
        require_same_as_uninterrupted(out, reference);
    }
    SECTION("during trials, twice, after 3 and after 20 records") {
        const auto out = dir.path() / "middle";
        kill_when(run_arguments(out), dir.path() / "kill.log", [&] { return complete_records(out / "results.jsonl") >= 3; });
        kill_when(run_arguments(out), dir.path() / "kill.log", [&] { return complete_records(out / "results.jsonl") >= 20; });
        // The second run was started without --resume: the first run's records were kept aside.
        REQUIRE(complete_records(out / "previous" / "1" / "results.jsonl") >= 3);
        resume(out);
        require_same_as_uninterrupted(out, reference);
    }
    SECTION("while writing the tables and plots") {
        const auto out = dir.path() / "publishing";
        kill_when(run_arguments(out), dir.path() / "kill.log", [&] { return fs::exists(out / "plot-data"); });
        resume(out);
        require_same_as_uninterrupted(out, reference);
    }
    SECTION("while a record is written: the torn last line a kill leaves is cut off and rerun") {
        const auto out = dir.path() / "torn";
        kill_when(run_arguments(out), dir.path() / "kill.log", [&] { return complete_records(out / "results.jsonl") >= 5; });
        // What a kill inside the write leaves: the record's first half, without its newline.
        const auto results = out / "results.jsonl";
        std::string text = testing::read_file(results);
        text.erase(text.rfind('\n') + 1);  // the kill may itself have cut a record short
        const std::string last = text.substr(text.rfind('\n', text.size() - 2) + 1);
        text += last.substr(0, last.size() / 2);
        std::ofstream(results, std::ios::trunc) << text;
        resume(out);
        require_same_as_uninterrupted(out, reference);
    }
    SECTION("while experiment.json or a table is written: the temporary files left behind change nothing") {
        const auto out = dir.path() / "replacing";
        kill_when(run_arguments(out), dir.path() / "kill.log", [&] { return complete_records(out / "results.jsonl") >= 5; });
        // A kill between writing a temporary file and renaming it leaves the temporary file, cut short.
        const std::string info = testing::read_file(out / "experiment.json");
        std::ofstream(out / "experiment.json.tmp-99999") << info.substr(0, info.size() / 3);
        std::ofstream(out / "table.csv.tmp-99999") << "optimizer,prob";
        resume(out);
        require_same_as_uninterrupted(out, reference);
        REQUIRE(read_experiment_info(out).optimizers.size() == 2);
    }
}
