#include "framework/iohprofiler_export.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <string_view>

#include <fmt/format.h>

#include "framework/file_output.hpp"
#include "framework/input_error.hpp"
#include "framework/report_tables.hpp"
#include "framework/results_store.hpp"

namespace mhb {
namespace {

namespace fs = std::filesystem;

// IOHanalyzer recognises the data of .info files by the first line of the .dat: a header that starts
// with "function (its check_format); two columns make its TWO_COL format, evaluations and the
// best-so-far value. The `evaluations raw_y` header of IOHexperimenter's JSON logger is refused there.
constexpr const char* dat_header = "\"function evaluation\" \"best-so-far f(x)\"";

// Letters, digits and . + - stay; '=' becomes '-' so that "batch=4" reads as batch-4; anything else
// becomes one '_'. No leading '.', so that no name is hidden or a relative path.
std::string file_name_safe(const std::string& text) {
    std::string out;
    for (char c : text) {
        const bool kept = std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '+' || c == '-';
        const char mapped = kept ? c : (c == '=' ? '-' : '_');
        if (mapped == '_' && (out.empty() || out.back() == '_')) continue;
        out += mapped;
    }
    while (!out.empty() && out.back() == '_') out.pop_back();
    if (!out.empty() && out.front() == '.') out.front() = '_';
    return out;
}

// `base`, or base_2, base_3, ... when an earlier name took it: two labels that differ only in
// characters a file name cannot hold must still get folders (and function files) of their own.
std::string unique_name(std::string base, std::set<std::string>& taken) {
    if (base.empty()) base = "unnamed";
    std::string name = base;
    for (int k = 2; !taken.insert(name).second; ++k) name = fmt::format("{}_{}", base, k);
    return name;
}

// A double quote would end the .info field it stands in.
std::string info_text(std::string text) {
    std::replace(text.begin(), text.end(), '"', '\'');
    return text;
}

struct Function {
    std::string name;  // the problem name
    int id = 0;
    std::string file_name;  // funcName: the problem name, plus a suffix when one name has several functions
};

// How each problem of the experiment maps onto IOHprofiler's (function, dimension, instance).
struct ProblemPlace {
    std::size_t function = 0;
    int dimension = 0;
    std::int64_t instance = 1;
};

struct Layout {
    std::vector<Function> functions;
    std::vector<ProblemPlace> places;  // per experiment problem
};

std::optional<int> bbob_number(const std::string& name) {
    constexpr std::string_view prefix = "bbob_f";
    if (!name.starts_with(prefix) || name.size() == prefix.size() || name.size() > prefix.size() + 6) return std::nullopt;
    const std::string digits = name.substr(prefix.size());
    if (!std::all_of(digits.begin(), digits.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); }))
        return std::nullopt;
    const int n = std::stoi(digits);
    return n > 0 ? std::optional<int>(n) : std::nullopt;
}

std::int64_t instance_of(const ProblemInfo& problem, const fs::path& experiment_file) {
    const auto it = problem.parameters.find("instance");
    if (it == problem.parameters.end()) return 1;
    if (const auto* i = std::get_if<std::int64_t>(&it->second)) return *i;
    if (const auto* d = std::get_if<double>(&it->second); d && std::isfinite(*d) && *d == std::round(*d) && std::abs(*d) < 1e15)
        return static_cast<std::int64_t>(*d);
    throw InputError(experiment_file.string(), 0, "problem " + problem.label + " instance",
                     fmt::format("is {}, not a whole number: IOHprofiler numbers its instances", to_string(it->second)));
}

// The settings that make a problem another function: its parameters other than instance and
// dimension, and a box the config gave. Numbers in full (shortest exact form), so that two settings
// that differ in the seventh digit are still two functions.
std::string settings_text(const ProblemInfo& problem) {
    std::vector<std::string> settings;
    for (const auto& [key, value] : problem.parameters) {
        if (key == "instance" || key == "dimension") continue;
        const auto* real = std::get_if<double>(&value);
        settings.push_back(fmt::format("{}={}", key, real ? fmt::format("{}", *real) : to_string(value)));
    }
    if (!problem.lower.empty()) settings.push_back(fmt::format("lower={}", fmt::join(problem.lower, ";")));
    if (!problem.upper.empty()) settings.push_back(fmt::format("upper={}", fmt::join(problem.upper, ";")));
    return fmt::format("{}", fmt::join(settings, ","));
}

Layout lay_out(const ExperimentInfo& info, const fs::path& experiment_file) {
    Layout layout;
    std::map<std::pair<std::string, std::string>, std::size_t> function_of;  // (name, settings) -> function
    std::vector<std::string> settings_of_function;
    for (const auto& problem : info.problems) {
        const std::string settings = settings_text(problem);
        auto [it, added] = function_of.try_emplace({problem.name, settings}, layout.functions.size());
        if (added) {
            layout.functions.push_back({problem.name, 0, ""});
            settings_of_function.push_back(settings);
        }
        layout.places.push_back({it->second, problem.dimension, instance_of(problem, experiment_file)});
    }

    // bbob_f<N> keeps N so that the data line up with other BBOB data; a second function of that name
    // (another box) and every other name take the free numbers from 1 on, in order of appearance.
    std::set<int> used;
    for (auto& f : layout.functions)
        if (const auto n = bbob_number(f.name); n && used.insert(*n).second) f.id = *n;
    int next = 1;
    for (auto& f : layout.functions) {
        if (f.id != 0) continue;
        while (used.count(next)) ++next;
        f.id = next;
        used.insert(next);
    }

    std::map<std::string, std::size_t> functions_per_name;
    for (const auto& f : layout.functions) ++functions_per_name[f.name];
    std::set<std::string> taken;
    for (std::size_t k = 0; k < layout.functions.size(); ++k) {
        auto& f = layout.functions[k];
        std::string name = file_name_safe(f.name);
        // Long settings (a box of one bound per coordinate) would make unwieldy file names: the
        // numbered fallback of unique_name tells those apart.
        const std::string suffix = file_name_safe(settings_of_function[k]);
        if (functions_per_name[f.name] > 1 && !suffix.empty() && suffix.size() <= 40) name += "_" + suffix;
        f.file_name = unique_name(name, taken);
    }
    return layout;
}

// The value IOHanalyzer gets: f - f* when the optimum is known (targets then read as precisions, as
// in COCO), the raw f otherwise. report_tables' final_error uses the same rule for a trial's end.
double exported_value(const ProblemInfo& problem, double f) {
    return problem.truth.optimum_value ? f - *problem.truth.optimum_value : f;
}

struct Row {
    std::int64_t evaluations;
    double value;
};

// The run as IOHanalyzer's .dat holds it: the rows where the best-so-far improved, from every exact
// (evaluation, best-so-far) pair the record has (per-iteration trace, anytime checkpoints, target hits,
// the budget's checkpoints),
// closed by a row at the run's last evaluation. Fixed-target runtimes read off these rows are exact
// for the recorded targets, because each hit is a row of its own.
std::vector<Row> run_rows(const ProblemInfo& problem, const TrialRecord& record) {
    std::vector<Row> events;
    events.reserve(record.trace_evaluations.size() + record.anytime.evaluations.size() + record.anytime.hits.size() + 1);
    for (std::size_t k = 0; k < record.trace_evaluations.size() && k < record.trace_best.size(); ++k)
        events.push_back({record.trace_evaluations[k], exported_value(problem, record.trace_best[k])});
    for (std::size_t c = 0; c < record.anytime.evaluations.size(); ++c)
        events.push_back({record.anytime.evaluations[c], exported_value(problem, record.anytime.best[c])});
    for (std::size_t t = 0; t < record.anytime.hits.size(); ++t)
        if (record.anytime.hits[t] > 0) events.push_back({record.anytime.hits[t], exported_value(problem, record.anytime.hit_best[t])});
    for (std::size_t c = 0; c < record.anytime.checkpoint_evaluations.size() && c < record.anytime.checkpoint_best.size(); ++c)
        events.push_back({record.anytime.checkpoint_evaluations[c], exported_value(problem, record.anytime.checkpoint_best[c])});
    events.push_back({record.evaluations, exported_value(problem, record.best_fitness)});
    std::sort(events.begin(), events.end(), [](const Row& a, const Row& b) {
        return a.evaluations != b.evaluations ? a.evaluations < b.evaluations : a.value < b.value;
    });

    std::vector<Row> rows;
    for (const auto& e : events) {
        // Before the first evaluation there is no best-so-far to report (IOH counts from 1).
        if (e.evaluations < 1 || e.evaluations > record.evaluations || std::isnan(e.value)) continue;
        if (rows.empty() || e.value < rows.back().value) rows.push_back(e);
    }
    if (rows.empty() || rows.back().evaluations != record.evaluations)
        rows.push_back({record.evaluations, rows.empty() ? exported_value(problem, record.best_fitness) : rows.back().value});
    return rows;
}

struct Run {
    const TrialRecord* record;
    const ProblemInfo* problem;
    std::int64_t instance;
};

void require_writable(const std::ofstream& out, const fs::path& path) {
    if (!out)
        throw InputError(path.string(), 0, "", fmt::format("cannot write the export here ({})", errno ? std::strerror(errno) : "disk full?"));
}

// Writes one (algorithm, function, dimension) .dat and returns its .info record line:
// "<dat path>, <instance>:<evals>|<best>, ...".
std::string write_dat(const fs::path& folder, const std::string& relative_dat, const std::vector<Run>& runs) {
    const fs::path path = folder / relative_dat;
    fs::create_directories(path.parent_path());
    errno = 0;
    std::ofstream out(path);
    require_writable(out, path);
    std::string record_line = relative_dat;
    for (const auto& run : runs) {
        const auto rows = run_rows(*run.problem, *run.record);
        out << dat_header << '\n';
        for (const auto& row : rows) out << fmt::format("{} {}\n", row.evaluations, row.value);
        record_line += fmt::format(", {}:{}|{}", run.instance, rows.back().evaluations, rows.back().value);
    }
    out.flush();
    require_writable(out, path);
    return record_line;
}

std::string algorithm_info(const PluginVariant& optimizer) {
    std::string text = optimizer.name;
    for (const auto& [key, value] : optimizer.values) text += fmt::format(" {}={}", key, to_string(value));
    return info_text(text);
}

void refuse_used_output(const fs::path& out) {
    std::error_code ec;
    const auto status = fs::status(out, ec);
    if (!fs::exists(status)) return;
    if (!fs::is_directory(status))
        throw InputError(out.string(), 0, "--out", "is a file, not a directory; export into a new or empty directory");
    const bool empty = fs::is_empty(out, ec);
    if (ec) throw InputError(out.string(), 0, "--out", "cannot be read: " + ec.message());
    if (!empty)
        throw InputError(out.string(), 0, "--out",
                         "already holds files (an earlier export?); export into a new or empty directory (another --out), "
                         "so nothing is overwritten");
}

}  // namespace

ExportSummary export_iohprofiler(const fs::path& results_dir, const fs::path& out) {
    const ExperimentInfo info = read_experiment_info(results_dir);
    const fs::path results_file = results_dir / "results.jsonl";
    auto loaded = read_results(results_file);
    const Layout layout = lay_out(info, results_dir / "experiment.json");
    const TrialGroups groups = group_trials(info, loaded.records);

    ExportSummary summary;
    summary.output = out;
    summary.notes = std::move(loaded.notes);
    std::size_t failed = 0, without_evaluations = 0;
    for (const auto& per_problem : groups.failed)
        for (std::size_t n : per_problem) failed += n;

    // runs[o][function][dimension], in the experiment's problem order and then by trial.
    std::vector<std::map<std::size_t, std::map<int, std::vector<Run>>>> runs(info.optimizers.size());
    for (std::size_t p = 0; p < info.problems.size(); ++p)
        for (std::size_t o = 0; o < info.optimizers.size(); ++o)
            for (const TrialRecord* record : groups.ok[p][o]) {
                // IOHanalyzer drops a run without evaluations (its maxRT would be 0), as IOHexperimenter does.
                if (record->evaluations < 1) {
                    ++without_evaluations;
                    continue;
                }
                const auto& place = layout.places[p];
                runs[o][place.function][place.dimension].push_back({record, &info.problems[p], place.instance});
            }
    std::set<std::size_t> functions_with_runs;
    for (const auto& per_optimizer : runs)
        for (const auto& [function, per_dimension] : per_optimizer) {
            functions_with_runs.insert(function);
            for (const auto& [dimension, list] : per_dimension) summary.runs += list.size();
        }
    if (summary.runs == 0)
        throw InputError(results_file.string(), 0, "",
                         failed > 0 ? "holds no successful trial (all failed): there is nothing to export"
                                    : "holds no finished trial yet: there is nothing to export");
    refuse_used_output(out);

    if (failed > 0)
        summary.notes.push_back(fmt::format("skipped {} failed trial(s): IOHprofiler data have no failed runs; their "
                                            "reasons are in {}",
                                            failed, results_file.string()));
    if (without_evaluations > 0)
        summary.notes.push_back(fmt::format("skipped {} trial(s) that made no evaluation", without_evaluations));

    std::set<std::string> taken_folders;
    for (std::size_t o = 0; o < info.optimizers.size(); ++o) {
        if (runs[o].empty()) continue;
        const auto& optimizer = info.optimizers[o];
        const fs::path folder = out / unique_name(file_name_safe(optimizer.label), taken_folders);
        ++summary.algorithms;
        for (auto& [f, per_dimension] : runs[o]) {
            const Function& function = layout.functions[f];
            std::string info_file;
            for (auto& [dimension, list] : per_dimension) {
                // Instances in increasing order, as IOHexperimenter runs them; stable, so trials of one
                // instance stay in trial order.
                std::stable_sort(list.begin(), list.end(), [](const Run& a, const Run& b) { return a.instance < b.instance; });
                const std::string relative_dat = fmt::format("data_f{}_{}/IOHprofiler_f{}_DIM{}.dat", function.id,
                                                             function.file_name, function.id, dimension);
                info_file += fmt::format(
                    "suite = \"mhbench\", funcId = {}, funcName = \"{}\", DIM = {}, maximization = \"F\", algId = \"{}\", "
                    "algInfo = \"{}\"\n%\n{}\n",
                    function.id, function.file_name, dimension, info_text(optimizer.label), algorithm_info(optimizer),
                    write_dat(folder, relative_dat, list));
            }
            replace_file(folder / fmt::format("IOHprofiler_f{}_{}.info", function.id, function.file_name), info_file);
        }
    }
    summary.functions = functions_with_runs.size();
    return summary;
}

}  // namespace mhb
