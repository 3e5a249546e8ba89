// Job arrays without MPI: `run --shard K/N` runs one share of the trials, `merge` joins the shares into
// what a single run gives.
#include <catch2/catch.hpp>

#include <fstream>
#include <sstream>

#include "framework/experiment_runner.hpp"
#include "framework/input_error.hpp"
#include "framework/report_tables.hpp"
#include "framework/shard_merge.hpp"
#include "tests/mhbench_cli.hpp"
#include "tests/same_results.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
using mhb::testing::require_same_results;
using mhb::testing::TemporaryDirectory;
namespace fs = std::filesystem;

namespace {

// 2 optimisers x 2 problems x 7 trials: 28 trials, which no shard count below divides evenly.
// `problem`: the CLI has the built-in problems only, the test program its fixtures too.
std::string config(std::uint64_t seed = 99, const std::string& top = "", const std::string& problem = "test_sphere") {
    return "name = \"sharded\"\ntrials = 7\nseed = " + std::to_string(seed) + "\n" + top +
           "[budget]\niterations = 12\n"
           "[[optimizer]]\nname = \"random_search\"\nbatch = [4, 16]\n"
           "[[problem]]\nname = \"" + problem + "\"\ndimension = [2, 5]\n";
}

RunSummary run_share(const ExperimentSpec& spec, const fs::path& out, std::optional<Shard> shard, int threads) {
    RunOptions options;
    options.output = out;
    options.shard = shard;
    options.threads = threads;
    options.progress = false;
    return run_experiment(spec, options);
}

// The tables remade from the directory's records, without the time columns.
std::string table_without_time(const fs::path& directory) {
    write_tables(directory, read_experiment_info(directory), read_results(directory / "results.jsonl").records);
    return testing::table_csv_without_time(directory);
}

std::string merge_error(const std::vector<fs::path>& dirs, const fs::path& out) {
    try {
        merge_shards(dirs, out);
    } catch (const InputError& e) {
        return e.what();
    }
    return "(merged)";
}

}  // namespace

TEST_CASE("shards of any count, on any thread count, merge into the records and tables of a single run", "[shard]") {
    TemporaryDirectory dir;
    const auto spec = load_experiment(dir.write("e.toml", config()));
    run_share(spec, dir.path() / "single", std::nullopt, 2);
    const auto single = read_results(dir.path() / "single" / "results.jsonl").records;
    REQUIRE(single.size() == 28);
    const std::string single_table = table_without_time(dir.path() / "single");

    for (const std::int64_t count : {1, 3, 5}) {
        INFO("N = " << count);
        std::vector<fs::path> shards;
        std::size_t smallest = 1000, largest = 0;
        for (std::int64_t k = 1; k <= count; ++k) {
            shards.push_back(dir.path() / ("n" + std::to_string(count)) / shard_directory_name({k, count}));
            const auto summary = run_share(spec, shards.back(), Shard{k, count}, static_cast<int>(k % 2 + 1));
            smallest = std::min(smallest, summary.ran);
            largest = std::max(largest, summary.ran);
            REQUIRE(read_experiment_info(shards.back()).shard == Shard{k, count});
        }
        CHECK(largest - smallest <= 1);  // round robin: the shares differ by one trial at most
        const fs::path merged = default_merge_output(shards);
        REQUIRE(merged == dir.path() / ("n" + std::to_string(count)));
        const auto summary = merge_shards(shards, merged);
        REQUIRE(summary.records == 28);
        const auto records = read_results(merged / "results.jsonl").records;
        require_same_results(records, single);
        // In the fixed order (problem, optimizer, trial), so the file is the same whoever merged it.
        for (std::size_t i = 0; i < records.size(); ++i) {
            CHECK(records[i].trial == static_cast<std::int64_t>(i % 7));
            CHECK(records[i].optimizer == (i / 7 % 2 == 0 ? "random_search(batch=4)" : "random_search(batch=16)"));
        }
        const auto info = read_experiment_info(merged);
        CHECK_FALSE(info.shard.has_value());
        CHECK(info.runs.size() == static_cast<std::size_t>(count));  // every shard's provenance
        CHECK(table_without_time(merged) == single_table);
    }
}

TEST_CASE("merge refuses missing, overlapping, foreign or different shards, naming them, and writes nothing", "[shard]") {
    TemporaryDirectory dir;
    const auto spec = load_experiment(dir.write("e.toml", config()));
    std::vector<fs::path> thirds, halves;
    for (std::int64_t k = 1; k <= 3; ++k) {
        thirds.push_back(dir.path() / ("third" + std::to_string(k)));
        run_share(spec, thirds.back(), Shard{k, 3}, 1);
    }
    for (std::int64_t k = 1; k <= 2; ++k) {
        halves.push_back(dir.path() / ("half" + std::to_string(k)));
        run_share(spec, halves.back(), Shard{k, 2}, 1);
    }
    const fs::path out = dir.path() / "merged";

    const auto missing = merge_error({thirds[0], thirds[2]}, out);
    CHECK_THAT(missing, Catch::Contains("9 of the experiment's 28 trials are in none of the directories"));
    CHECK_THAT(missing, Catch::Contains("(it belongs to shard 2 of 3)"));

    CHECK_THAT(merge_error({thirds[0], thirds[1], thirds[1], thirds[2]}, out), Catch::Contains("is named twice"));
    fs::copy(thirds[1], dir.path() / "copy", fs::copy_options::recursive);
    CHECK_THAT(merge_error({thirds[0], thirds[1], dir.path() / "copy", thirds[2]}, out),
               Catch::Contains("are both shard 2 of 3: the same share run twice"));
    CHECK_THAT(merge_error({thirds[0], thirds[1], thirds[2], halves[0]}, out), Catch::Contains("shards of different counts"));

    // A directory of the whole experiment beside its shards: every trial twice.
    run_share(spec, dir.path() / "whole", std::nullopt, 2);
    CHECK_THAT(merge_error({thirds[0], dir.path() / "whole"}, out), Catch::Contains("the directories overlap"));

    // Another experiment (another seed) is named by the field that differs.
    const auto other = load_experiment(dir.write("other.toml", config(100)));
    run_share(other, dir.path() / "other", Shard{3, 3}, 1);
    const auto different = merge_error({thirds[0], thirds[1], dir.path() / "other"}, out);
    CHECK_THAT(different, Catch::Contains("other/experiment.json: seed: differs from"));

    // A record of a trial the experiment does not have.
    {
        std::ofstream extra(thirds[2] / "results.jsonl", std::ios::app);
        std::ifstream first(thirds[2] / "results.jsonl");
        std::string line;
        std::getline(first, line);
        const auto at = line.find("\"trial\":");
        REQUIRE(at != std::string::npos);
        extra << line.substr(0, at) << "\"trial\":7" << line.substr(line.find_first_of(",}", at)) << "\n";
    }
    CHECK_THAT(merge_error(thirds, out), Catch::Contains("holds trial 7 of"));
    CHECK_FALSE(fs::exists(out / "results.jsonl"));

    // Nothing is merged over results already there.
    CHECK_THAT(merge_error(halves, dir.path() / "whole"), Catch::Contains("already holds results"));
    CHECK(merge_error(halves, out) == "(merged)");
}

TEST_CASE("a shard resumes as that shard only", "[shard]") {
    TemporaryDirectory dir;
    const auto spec = load_experiment(dir.write("e.toml", config()));
    run_share(spec, dir.path() / "s", Shard{2, 3}, 1);
    RunOptions options;
    options.output = dir.path() / "s";
    options.resume = true;
    options.progress = false;
    options.shard = Shard{1, 3};
    CHECK_THROWS_WITH(run_experiment(spec, options), Catch::Contains("this run is shard 1 of 3 but the run being resumed in"));
    options.shard.reset();
    CHECK_THROWS_WITH(run_experiment(spec, options), Catch::Contains("this run is all trials but the run being resumed"));
    options.shard = Shard{2, 3};
    const auto resumed = run_experiment(spec, options);
    CHECK(resumed.ran == 0);
    CHECK(resumed.skipped == 9);
}

TEST_CASE("mhbench run --shard and mhbench merge from the command line", "[shard][cli]") {
    TemporaryDirectory dir;
    const auto file = dir.write("e.toml", config(99, "output = \"out\"\n", "F1"));
    for (const char* bad : {"0/3", "4/3", "3", "1/0", "a/b", "1/3/2", "1/3x"}) {
        const auto run = testing::run_mhbench({"run", file.string(), "--shard", bad}, dir.path() / "bad.log");
        INFO(run.output);
        CHECK(run.exit_code == 2);
        CHECK_THAT(run.output, Catch::Contains("--shard: expects K/N"));
    }
    for (const char* k : {"1", "2"}) {
        const auto run = testing::run_mhbench({"run", file.string(), "--shard", std::string(k) + "/2", "--quiet"}, dir.path() / "run.log");
        INFO(run.output);
        REQUIRE(run.exit_code == 0);
        CHECK(fs::exists(dir.path() / "out" / ("shard-" + std::string(k) + "-of-2") / "results.jsonl"));
    }
    const auto merged = testing::run_mhbench({"merge", (dir.path() / "out" / "shard-1-of-2").string(),
                                              (dir.path() / "out" / "shard-2-of-2").string(), "--quiet", "--no-plots"},
                                             dir.path() / "merge.log");
    INFO(merged.output);
    REQUIRE(merged.exit_code == 0);
    CHECK_THAT(merged.output, Catch::Contains("Merged 28 trials from 2 directories into " + (dir.path() / "out").string()));
    CHECK(fs::exists(dir.path() / "out" / "report.html"));
    const auto again = testing::run_mhbench({"merge", (dir.path() / "out" / "shard-1-of-2").string(),
                                             (dir.path() / "out" / "shard-2-of-2").string()},
                                            dir.path() / "again.log");
    CHECK(again.exit_code == 2);
    CHECK_THAT(again.output, Catch::Contains("already holds results"));
}
