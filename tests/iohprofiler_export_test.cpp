// `mhbench export --format iohprofiler`: the exported files, read back with a parser of this test's
// own, against the trial records they come from.
#include <catch2/catch.hpp>

#include <algorithm>
#include <fstream>
#include <limits>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "framework/experiment_runner.hpp"
#include "framework/input_error.hpp"
#include "framework/iohprofiler_export.hpp"
#include "tests/mhbench_cli.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
using mhb::testing::TemporaryDirectory;
namespace fs = std::filesystem;

namespace {

// One section of a .info file: its header fields, its data file and one (instance, evals, best) per run.
struct InfoEntry {
    std::int64_t instance, evaluations;
    double best;
};
struct InfoSection {
    std::map<std::string, std::string> fields;  // values without their quotes
    std::string dat;
    std::vector<InfoEntry> runs;
};

std::vector<InfoSection> parse_info(const fs::path& file) {
    std::ifstream in(file);
    std::vector<InfoSection> sections;
    std::string header, percent, records;
    const std::regex field(R"re(\s*(\w+) = ("([^"]*)"|[^,]*)(,|$))re");
    while (std::getline(in, header)) {
        REQUIRE(std::getline(in, percent));
        REQUIRE(std::getline(in, records));
        CHECK(percent == "%");
        InfoSection s;
        for (std::sregex_iterator m(header.begin(), header.end(), field), end; m != end; ++m)
            s.fields[(*m)[1]] = (*m)[3].matched ? (*m)[3].str() : (*m)[2].str();
        std::stringstream parts(records);
        std::string part;
        std::getline(parts, s.dat, ',');
        while (std::getline(parts, part, ',')) {
            InfoEntry e{};
            char colon = 0, bar = 0;
            std::stringstream entry(part);
            entry >> e.instance >> colon >> e.evaluations >> bar;
            std::string best;
            entry >> best;
            REQUIRE(colon == ':');
            REQUIRE(bar == '|');
            e.best = std::stod(best);
            s.runs.push_back(e);
        }
        sections.push_back(std::move(s));
    }
    return sections;
}

struct Row {
    std::int64_t evaluations;
    double value;
};
struct Block {
    std::string header;
    std::vector<Row> rows;
};

std::vector<Block> parse_dat(const fs::path& file) {
    std::ifstream in(file);
    REQUIRE(in);
    std::vector<Block> blocks;
    std::string line;
    while (std::getline(in, line)) {
        if (!line.empty() && !std::isdigit(static_cast<unsigned char>(line[0]))) {
            blocks.push_back({line, {}});
            continue;
        }
        REQUIRE_FALSE(blocks.empty());
        std::stringstream fields(line);
        std::string evaluations, value, extra;
        fields >> evaluations >> value >> extra;
        CHECK(extra.empty());
        blocks.back().rows.push_back({std::stoll(evaluations), std::stod(value)});
    }
    return blocks;
}

// The exported best-so-far after `evaluations`: the last row at or before it.
double value_at(const Block& block, std::int64_t evaluations) {
    double value = std::numeric_limits<double>::quiet_NaN();
    for (const auto& row : block.rows)
        if (row.evaluations <= evaluations) value = row.value;
    return value;
}

std::int64_t integer_parameter(const ProblemInfo& p, const std::string& name, std::int64_t fallback) {
    const auto it = p.parameters.find(name);
    return it == p.parameters.end() ? fallback : std::get<std::int64_t>(it->second);
}

// Where a trial's run must be, worked out from the experiment here rather than by the exporter.
struct Expected {
    std::string folder, info_file, function_name, dat;
    int function_id = 0;
    std::int64_t instance = 1;
};

// Every exported block against its trial: ends at the trial's evaluations with its final f - f*,
// improves strictly but for the closing row, and reads the record's exact best-so-far at every
// evaluation count the record holds, so that fixed-target and fixed-budget views are exact.
void check_block(const Block& block, const TrialRecord& trial, double optimum, const AnytimeSpec* anytime) {
    INFO(trial.optimizer << " on " << trial.problem << ", trial " << trial.trial);
    CHECK(block.header == "\"function evaluation\" \"best-so-far f(x)\"");
    REQUIRE_FALSE(block.rows.empty());
    CHECK(block.rows.front().evaluations >= 1);
    for (std::size_t k = 1; k < block.rows.size(); ++k) {
        CHECK(block.rows[k].evaluations > block.rows[k - 1].evaluations);
        if (k + 1 < block.rows.size()) CHECK(block.rows[k].value < block.rows[k - 1].value);
        else CHECK(block.rows[k].value <= block.rows[k - 1].value);
    }
    CHECK(block.rows.back().evaluations == trial.evaluations);
    CHECK(block.rows.back().value == trial.best_fitness - optimum);
    for (std::size_t k = 0; k < trial.trace_evaluations.size(); ++k)
        CHECK(value_at(block, trial.trace_evaluations[k]) == trial.trace_best[k] - optimum);
    if (!anytime) return;
    for (std::size_t c = 0; c < trial.anytime.evaluations.size(); ++c)
        CHECK(value_at(block, trial.anytime.evaluations[c]) == trial.anytime.best[c] - optimum);
    for (std::size_t c = 0; c < trial.anytime.checkpoint_evaluations.size(); ++c)
        CHECK(value_at(block, trial.anytime.checkpoint_evaluations[c]) == trial.anytime.checkpoint_best[c] - optimum);
    REQUIRE(trial.anytime.hits.size() == anytime->targets.size());
    for (std::size_t t = 0; t < anytime->targets.size(); ++t) {
        INFO("target " << anytime->targets[t]);
        const auto first = std::find_if(block.rows.begin(), block.rows.end(),
                                        [&](const Row& r) { return r.value <= anytime->targets[t]; });
        if (trial.anytime.hits[t] == 0) {
            CHECK(first == block.rows.end());
        } else {
            REQUIRE(first != block.rows.end());
            CHECK(first->evaluations == trial.anytime.hits[t]);
        }
    }
}

RunSummary run(const fs::path& config, const fs::path& out) {
    RunOptions options;
    options.output = out;
    options.progress = false;
    return run_experiment(load_experiment(config), options);
}

std::set<std::string> listing(const fs::path& folder) {
    std::set<std::string> names;
    for (const auto& entry : fs::directory_iterator(folder)) names.insert(entry.path().filename().string());
    return names;
}

}  // namespace

TEST_CASE("an anytime experiment on BBOB instances exports one exact run block per trial, indexed by the .info files",
          "[iohprofiler]") {
    TemporaryDirectory dir;
    // Batches of 16 put most target hits between two trace points: only the anytime hits make the
    // exported runtimes exact there.
    const auto config = dir.write("e.toml",
                                  "name = \"ioh\"\ntrials = 3\nseed = 5\n[budget]\nevaluations = 400\n[anytime]\ncheckpoints = [0.0125, 0.015, 0.0225, 0.0275, 0.0325, 0.035, 0.0375, 0.0425, 0.045, 0.0475, 0.0525, 0.055, 0.0575, 0.0625]\n"
                                  "[[optimizer]]\nname = \"random_search\"\nbatch = [4, 16]\n"
                                  "[[problem]]\nname = \"bbob_f1\"\ndimension = [2, 3]\ninstance = [1, 2]\n"
                                  "[[problem]]\nname = \"test_sphere\"\ndimension = 2\nshift = [1.5, 2.5]\n"
                                  "[[problem]]\nname = \"bbob_f8\"\ndimension = [2, 3]\ninstance = [1, 2]\n");
    const auto summary_of_run = run(config, dir.path() / "results");
    REQUIRE(summary_of_run.failed == 0);
    const auto info = read_experiment_info(dir.path() / "results");
    const auto records = read_results(dir.path() / "results" / "results.jsonl").records;
    REQUIRE(records.size() == 2 * 10 * 3);
    // Early checkpoints off the trace's and the log-spaced points, where random search still improves often:
    // only the checkpoints' own rows make the export exact there.
    for (const auto& r : records)
        REQUIRE(r.anytime.checkpoint_evaluations == std::vector<std::int64_t>{5, 6, 9, 11, 13, 14, 15, 17, 18, 19, 21, 22, 23, 25});

    const fs::path out = dir.path() / "ioh";
    const auto summary = export_iohprofiler(dir.path() / "results", out);
    CHECK(summary.output == out);
    CHECK(summary.algorithms == 2);
    CHECK(summary.functions == 4);
    CHECK(summary.runs == 60);
    CHECK(summary.notes.empty());

    // bbob_f<N> keeps N; the two test_sphere variants (shift differs) are two functions, numbered from
    // the first id no BBOB function holds.
    const std::map<std::string, std::string> folder_of{{"random_search(batch=4)", "random_search_batch-4"},
                                                       {"random_search(batch=16)", "random_search_batch-16"}};
    const std::set<std::string> files{"IOHprofiler_f1_bbob_f1.info",
                                      "IOHprofiler_f8_bbob_f8.info",
                                      "IOHprofiler_f2_test_sphere_shift-1.5.info",
                                      "IOHprofiler_f3_test_sphere_shift-2.5.info",
                                      "data_f1_bbob_f1",
                                      "data_f8_bbob_f8",
                                      "data_f2_test_sphere_shift-1.5",
                                      "data_f3_test_sphere_shift-2.5"};
    CHECK(listing(out) == std::set<std::string>{"random_search_batch-4", "random_search_batch-16"});
    for (const auto& [label, folder] : folder_of) CHECK(listing(out / folder) == files);

    std::map<std::string, const ProblemInfo*> problem_of;
    for (const auto& p : info.problems) problem_of[p.label] = &p;
    const auto expected_place = [&](const TrialRecord& r) {
        const ProblemInfo& p = *problem_of.at(r.problem);
        Expected e;
        e.folder = folder_of.at(r.optimizer);
        if (p.name == "test_sphere") {
            const bool second = std::get<double>(p.parameters.at("shift")) == 2.5;
            e.function_id = second ? 3 : 2;
            e.function_name = second ? "test_sphere_shift-2.5" : "test_sphere_shift-1.5";
        } else {
            e.function_id = p.name == "bbob_f1" ? 1 : 8;
            e.function_name = p.name;
        }
        e.instance = integer_parameter(p, "instance", 1);
        e.info_file = "IOHprofiler_f" + std::to_string(e.function_id) + "_" + e.function_name + ".info";
        e.dat = "data_f" + std::to_string(e.function_id) + "_" + e.function_name + "/IOHprofiler_f" +
                std::to_string(e.function_id) + "_DIM" + std::to_string(p.dimension) + ".dat";
        return e;
    };

    // Per data file, the trials it must hold, in the documented order: instance, then trial.
    std::map<std::pair<std::string, std::string>, std::vector<const TrialRecord*>> trials_of_dat;
    for (const auto& r : records) {
        const auto e = expected_place(r);
        trials_of_dat[{e.folder, e.dat}].push_back(&r);
    }
    for (auto& [key, trials] : trials_of_dat)
        std::sort(trials.begin(), trials.end(), [&](const TrialRecord* a, const TrialRecord* b) {
            return std::pair(expected_place(*a).instance, a->trial) < std::pair(expected_place(*b).instance, b->trial);
        });

    std::size_t sections = 0, hits_between_trace_points = 0;
    for (const auto& [label, folder] : folder_of)
        for (const auto& file : files) {
            if (!file.ends_with(".info")) continue;
            INFO(folder << "/" << file);
            const auto parsed = parse_info(out / folder / file);
            // Dimensions 2 and 3 of the BBOB functions, one section each; test_sphere has dimension 2 only.
            REQUIRE(parsed.size() == (file.find("bbob") != std::string::npos ? 2u : 1u));
            for (const auto& section : parsed) {
                ++sections;
                INFO(section.dat);
                const auto trials_it = trials_of_dat.find({folder, section.dat});
                REQUIRE(trials_it != trials_of_dat.end());
                const auto& trials = trials_it->second;
                const auto place = expected_place(*trials.front());
                const ProblemInfo& problem = *problem_of.at(trials.front()->problem);
                CHECK(place.info_file == file);
                CHECK(section.fields.at("suite") == "mhbench");
                CHECK(section.fields.at("funcId") == std::to_string(place.function_id));
                CHECK(section.fields.at("funcName") == place.function_name);
                CHECK(section.fields.at("DIM") == std::to_string(problem.dimension));
                CHECK(section.fields.at("maximization") == "F");
                CHECK(section.fields.at("algId") == label);
                CHECK_THAT(section.fields.at("algInfo"), Catch::StartsWith("random_search") && Catch::Contains("batch="));

                const auto blocks = parse_dat(out / folder / section.dat);
                REQUIRE(blocks.size() == trials.size());
                REQUIRE(section.runs.size() == trials.size());
                for (std::size_t k = 0; k < trials.size(); ++k) {
                    const TrialRecord& trial = *trials[k];
                    const ProblemInfo& p = *problem_of.at(trial.problem);
                    REQUIRE(p.truth.optimum_value);
                    check_block(blocks[k], trial, *p.truth.optimum_value, &*info.anytime);
                    CHECK(section.runs[k].instance == expected_place(trial).instance);
                    CHECK(section.runs[k].evaluations == blocks[k].rows.back().evaluations);
                    CHECK(section.runs[k].best == blocks[k].rows.back().value);
                    for (std::int64_t hit : trial.anytime.hits)
                        if (hit > 0 && std::find(trial.trace_evaluations.begin(), trial.trace_evaluations.end(), hit) ==
                                           trial.trace_evaluations.end())
                            ++hits_between_trace_points;
                }
            }
        }
    CHECK(sections == 2 * (2 + 2 + 1 + 1));
    CHECK(hits_between_trace_points > 20);

    // A second export into the same place is refused and leaves the first alone.
    const auto before = parse_dat(out / "random_search_batch-4" / "data_f1_bbob_f1" / "IOHprofiler_f1_DIM2.dat").size();
    try {
        export_iohprofiler(dir.path() / "results", out);
        FAIL("exported over an earlier export");
    } catch (const InputError& e) {
        CHECK_THAT(e.what(), Catch::Contains(out.string()) && Catch::Contains("already holds files"));
    }
    CHECK(parse_dat(out / "random_search_batch-4" / "data_f1_bbob_f1" / "IOHprofiler_f1_DIM2.dat").size() == before);
}

TEST_CASE("without a known optimum the column is the raw f, another box is another function, and failed trials are "
          "skipped with a note",
          "[iohprofiler]") {
    TemporaryDirectory dir;
    // test_nan knows no optimum; its box is cut below the region where it returns NaN. bbob_f1 in a
    // box of its own is another function than bbob_f1 in its standard box.
    const auto config = dir.write("e.toml",
                                  "name = \"raw\"\ntrials = 2\nseed = 3\n[budget]\niterations = 10\n"
                                  "[[optimizer]]\nname = \"random_search\"\n"
                                  "[[optimizer]]\nname = \"test_throwing\"\n"
                                  "[[problem]]\nname = \"test_nan\"\nupper = 0.5\n"
                                  "[[problem]]\nname = \"bbob_f1\"\ndimension = 2\n"
                                  "[[problem]]\nname = \"bbob_f1\"\nlabel = \"narrow\"\ndimension = 2\nupper = 2\n");
    const auto ran = run(config, dir.path() / "results");
    REQUIRE(ran.failed == 6);
    const auto info = read_experiment_info(dir.path() / "results");
    REQUIRE_FALSE(info.problems[0].truth.optimum_value);
    REQUIRE(info.problems[1].truth.optimum_value);
    REQUIRE(*info.problems[1].truth.optimum_value != 0.0);  // so that f and f - f* differ

    const auto summary = export_iohprofiler(dir.path() / "results", dir.path() / "out");
    CHECK(summary.algorithms == 1);
    CHECK(summary.functions == 3);
    CHECK(summary.runs == 6);
    REQUIRE(summary.notes.size() == 1);
    CHECK_THAT(summary.notes.front(), Catch::Contains("skipped 6 failed trial(s)"));
    CHECK(listing(dir.path() / "out") == std::set<std::string>{"random_search"});
    CHECK(listing(dir.path() / "out" / "random_search") ==
          std::set<std::string>{"IOHprofiler_f1_bbob_f1.info", "data_f1_bbob_f1", "IOHprofiler_f2_test_nan.info",
                                "data_f2_test_nan", "IOHprofiler_f3_bbob_f1_upper-2.info", "data_f3_bbob_f1_upper-2"});

    const auto records = read_results(dir.path() / "results" / "results.jsonl").records;
    const std::vector<std::tuple<std::string, std::size_t, double>> functions{
        {"f2_test_nan", 0, 0.0}, {"f1_bbob_f1", 1, *info.problems[1].truth.optimum_value},
        {"f3_bbob_f1_upper-2", 2, *info.problems[1].truth.optimum_value}};
    for (const auto& [function, problem, optimum] : functions) {
        INFO(function);
        const auto blocks = parse_dat(dir.path() / "out" / "random_search" / ("data_" + function) /
                                      ("IOHprofiler_" + function.substr(0, 2) + "_DIM2.dat"));
        const std::string& label = info.problems[problem].label;
        std::vector<const TrialRecord*> trials;
        for (const auto& r : records)
            if (r.ok && r.problem == label) trials.push_back(&r);
        REQUIRE(trials.size() == 2);
        std::sort(trials.begin(), trials.end(), [](const auto* a, const auto* b) { return a->trial < b->trial; });
        REQUIRE(blocks.size() == trials.size());
        for (std::size_t k = 0; k < trials.size(); ++k) check_block(blocks[k], *trials[k], optimum, nullptr);
    }
}

TEST_CASE("an export of a directory without a successful trial is refused", "[iohprofiler]") {
    TemporaryDirectory dir;
    const auto config = dir.write("e.toml", "name = \"failing\"\ntrials = 2\nseed = 3\n[budget]\niterations = 10\n"
                                            "[[optimizer]]\nname = \"test_throwing\"\n[[problem]]\nname = \"test_sphere\"\n");
    run(config, dir.path() / "results");
    try {
        export_iohprofiler(dir.path() / "results", dir.path() / "out");
        FAIL("exported nothing as a success");
    } catch (const InputError& e) {
        CHECK_THAT(e.what(), Catch::Contains("results.jsonl") && Catch::Contains("holds no successful trial"));
    }
    CHECK_FALSE(fs::exists(dir.path() / "out"));
}

TEST_CASE("mhbench export from the command line: the default folder, and refusals with exit code 2", "[iohprofiler][cli]") {
    TemporaryDirectory dir;
    const auto config = dir.write("e.toml", "name = \"cli\"\ntrials = 2\nseed = 3\noutput = \"results\"\n[budget]\n"
                                            "evaluations = 200\n[anytime]\n[[optimizer]]\nname = \"random_search\"\n"
                                            "[[problem]]\nname = \"F1\"\ndimension = [2, 4]\n");
    const auto ran = testing::run_mhbench({"run", config.string(), "--quiet", "--no-plots"}, dir.path() / "run.log");
    INFO(ran.output);
    REQUIRE(ran.exit_code == 0);
    const fs::path results = dir.path() / "results";

    const auto exported = testing::run_mhbench({"export", "--format", "iohprofiler", results.string()}, dir.path() / "export.log");
    INFO(exported.output);
    CHECK(exported.exit_code == 0);
    CHECK_THAT(exported.output, Catch::Contains("Exported 4 runs of 1 algorithm(s) on 1 function(s) to " +
                                                (results / "iohprofiler").string()));
    CHECK(fs::exists(results / "iohprofiler" / "random_search" / "IOHprofiler_f1_F1.info"));
    CHECK(parse_info(results / "iohprofiler" / "random_search" / "IOHprofiler_f1_F1.info").size() == 2);

    const auto again = testing::run_mhbench({"export", "--format", "iohprofiler", results.string()}, dir.path() / "again.log");
    CHECK(again.exit_code == 2);
    CHECK_THAT(again.output, Catch::Contains("error: " + (results / "iohprofiler").string() + ": --out: already holds files"));

    const auto elsewhere = testing::run_mhbench({"export", "--format", "iohprofiler", results.string(), "--out",
                                                 (dir.path() / "new" / "ioh").string()},
                                                dir.path() / "elsewhere.log");
    CHECK(elsewhere.exit_code == 0);
    CHECK(fs::exists(dir.path() / "new" / "ioh" / "random_search" / "data_f1_F1" / "IOHprofiler_f1_DIM4.dat"));

    fs::create_directories(dir.path() / "empty");
    const auto into_empty = testing::run_mhbench({"export", "--format", "iohprofiler", results.string(), "--out",
                                                  (dir.path() / "empty").string()},
                                                 dir.path() / "empty.log");
    CHECK(into_empty.exit_code == 0);

    const auto format = testing::run_mhbench({"export", "--format", "coco", results.string()}, dir.path() / "format.log");
    CHECK(format.exit_code == 2);
    CHECK_THAT(format.output, Catch::Contains("error: command line: --format: unknown format 'coco'; known: iohprofiler"));

    const auto no_format = testing::run_mhbench({"export", results.string()}, dir.path() / "no_format.log");
    CHECK(no_format.exit_code == 2);
    CHECK_THAT(no_format.output, Catch::Contains("--format is required"));

    const auto not_results = testing::run_mhbench({"export", "--format", "iohprofiler", dir.path().string()}, dir.path() / "not.log");
    CHECK(not_results.exit_code == 2);
    CHECK_THAT(not_results.output, Catch::Contains("error: " + (dir.path() / "experiment.json").string() +
                                                   ": missing: is this an mhbench results directory?"));
    CHECK_FALSE(fs::exists(dir.path() / "iohprofiler"));
}
