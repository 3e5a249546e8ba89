// `mhbench compare DIR --optimizer LABEL --samples FILE [--name NAME] [--values fitness|error]`: one
// optimiser's runs in a results directory against runs of another program (the organisers' code of
// the same algorithm, a paper's raw results), problem by problem: two-sided Wilcoxon rank-sum p,
// Holm's adjustment over the problems compared, and A12. The other program's values get the same
// f* and error threshold as the directory's, so both sides are errors by one rule.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "framework/cli/commands.hpp"
#include "framework/input_error.hpp"
#include "framework/report_tables.hpp"
#include "framework/results_store.hpp"
#include "framework/statistics.hpp"

namespace mhb::cli {
namespace {

namespace fs = std::filesystem;

// Lines "PROBLEM VALUE" (blank or tab separated; '#' starts a comment), VALUE a number; grouped by
// problem label in the order they first appear.
std::map<std::string, std::vector<double>> read_samples(const fs::path& file, const ExperimentInfo& info) {
    std::ifstream in(file);
    if (!in) throw InputError(file.string(), 0, "", "cannot open the samples file");
    std::map<std::string, std::vector<double>> out;
    std::string line;
    for (long number = 1; std::getline(in, line); ++number) {
        if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
        std::istringstream fields(line);
        std::string problem, value, extra;
        if (!(fields >> problem)) continue;
        if (!(fields >> value) || (fields >> extra))
            throw InputError(file.string(), number, "", "expects two fields, a problem label and a value");
        bool known = false;
        for (const auto& p : info.problems) known = known || p.label == problem;
        if (!known) throw InputError(file.string(), number, "problem", fmt::format("'{}' is not a problem label of the results directory", problem));
        std::size_t used = 0;
        double v = 0;
        try {
            v = std::stod(value, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used != value.size() || !std::isfinite(v)) throw InputError(file.string(), number, "value", fmt::format("'{}' is not a finite number", value));
        out[problem].push_back(v);
    }
    if (out.empty()) throw InputError(file.string(), 0, "", "no samples (expected lines 'PROBLEM VALUE')");
    return out;
}

std::string number(double v) { return std::isnan(v) ? "–" : fmt::format("{:.4g}", v); }

const bool compare_registered = register_command("compare", [](CLI::App& app) {
    auto* cmd = app.add_subcommand("compare",
                                   "One optimizer's runs in a results directory against another program's runs of the same problems: "
                                   "rank-sum p per problem, Holm-adjusted over the problems, A12");
    struct Args {
        std::string dir, optimizer, samples, name = "other", values = "fitness";
    };
    auto a = std::make_shared<Args>();
    cmd->add_option("DIR", a->dir, "a directory written by `mhbench run`")->required();
    cmd->add_option("--optimizer", a->optimizer, "the optimizer label in DIR to compare")->required();
    cmd->add_option("--samples", a->samples, "the other program's runs: lines 'PROBLEM VALUE', PROBLEM a problem label of DIR")->required();
    cmd->add_option("--name", a->name, "what the other program is called in the table (default: other)");
    cmd->add_option("--values", a->values, "fitness: the values are f, made errors with DIR's f* and threshold; error: already f - f*")
        ->check(CLI::IsMember({"fitness", "error"}));
    return std::function<int()>([a] {
        const fs::path dir(a->dir);
        const auto info = read_experiment_info(dir);
        std::size_t optimizer = info.optimizers.size();
        for (std::size_t o = 0; o < info.optimizers.size(); ++o)
            if (info.optimizers[o].label == a->optimizer) optimizer = o;
        if (optimizer == info.optimizers.size()) {
            std::string labels;
            for (const auto& o : info.optimizers) labels += (labels.empty() ? "" : ", ") + o.label;
            throw InputError("command line", 0, "--optimizer", fmt::format("'{}' is not an optimizer label of {}; labels: {}", a->optimizer, a->dir, labels));
        }
        const auto samples = read_samples(a->samples, info);
        const auto loaded = read_results(dir / "results.jsonl");
        const auto groups = group_trials(info, loaded.records);

        struct Row {
            std::string problem;
            stats::Summary ours, theirs;
            double p = std::nan(""), a12 = std::nan("");
        };
        std::vector<Row> rows;
        std::vector<double> p_values;
        for (std::size_t p = 0; p < info.problems.size(); ++p) {
            const auto& problem = info.problems[p];
            const auto found = samples.find(problem.label);
            if (found == samples.end()) continue;
            std::vector<double> ours, theirs;
            for (const auto* t : groups.ok[p][optimizer]) ours.push_back(final_error(info, problem, *t));
            for (double v : found->second) theirs.push_back(a->values == "fitness" ? reported_error(info, problem, v) : v);
            if (ours.empty()) throw InputError(a->dir, 0, a->optimizer, fmt::format("has no successful run of {}", problem.label));
            Row row{problem.label, stats::summarize(ours), stats::summarize(theirs)};
            row.p = stats::wilcoxon_rank_sum(ours, theirs).p;
            row.a12 = stats::vargha_delaney_a12(ours, theirs);
            p_values.push_back(row.p);
            rows.push_back(std::move(row));
        }
        const auto adjusted = stats::holm_adjusted(p_values);
        fmt::print("{} in {} against {}: errors f - f*{}; two-sided Wilcoxon rank-sum p per problem, Holm-adjusted over the {} "
                   "problems; A12 = P({} ends lower) + P(tie)/2.\n\n",
                   a->optimizer, a->dir, a->name,
                   info.error_threshold > 0 ? fmt::format(", those below {:g} counted as 0", info.error_threshold) : std::string(),
                   rows.size(), a->optimizer);
        fmt::print("| problem | runs | {0} mean | {0} median | {1} runs | {1} mean | {1} median | p | p (Holm) | A12 |\n"
                   "|---|---|---|---|---|---|---|---|---|---|\n",
                   a->optimizer, a->name);
        std::size_t below_001 = 0;
        for (std::size_t i = 0; i < rows.size(); ++i) {
            const auto& r = rows[i];
            if (adjusted[i] < 0.01) ++below_001;
            fmt::print("| {} | {} | {} | {} | {} | {} | {} | {:.3g} | {:.3g} | {:.2f} |\n", r.problem, r.ours.n, number(r.ours.mean),
                       number(r.ours.median), r.theirs.n, number(r.theirs.mean), number(r.theirs.median), r.p, adjusted[i], r.a12);
        }
        fmt::print("\n{} of {} problems differ at p < 0.01 after Holm's adjustment.\n", below_001, rows.size());
        return exit_ok;
    });
});

}  // namespace
}  // namespace mhb::cli
