#include "framework/report_tables.hpp"

#include <cmath>
#include <fstream>
#include <map>
#include <set>

#include <fmt/format.h>

#include "framework/input_error.hpp"
#include "framework/statistics.hpp"

namespace mhb {
namespace {

std::string num(double v) {
    if (std::isnan(v)) return "–";
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    return fmt::format("{:.4g}", v);
}
std::string pval(double p) { return std::isnan(p) ? "–" : fmt::format("{:.3g}", p); }

std::vector<double> errors_of(const ProblemInfo& problem, const std::vector<const TrialRecord*>& trials) {
    std::vector<double> out;
    out.reserve(trials.size());
    for (const auto* t : trials) out.push_back(final_error(problem, *t));
    return out;
}

std::size_t index_of(const ExperimentInfo& info, const std::string& label) {
    for (std::size_t i = 0; i < info.optimizers.size(); ++i)
        if (info.optimizers[i].label == label) return i;
    return info.optimizers.size();
}

// Which parameter values count as the truth for error %: the true parameters the data were made
// with, else the exact reference solution.
const std::optional<Vector>& accuracy_target(const ProblemInfo& p) {
    return p.truth.true_parameters ? p.truth.true_parameters : p.truth.reference_solution;
}

struct ParameterStats {
    std::vector<stats::Summary> per_parameter;
};
ParameterStats parameter_stats(const std::vector<const TrialRecord*>& trials, int dimension) {
    ParameterStats s;
    for (int j = 0; j < dimension; ++j) {
        std::vector<double> v;
        for (const auto* t : trials)
            if (t->best_position.size() == dimension) v.push_back(t->best_position[j]);
        s.per_parameter.push_back(stats::summarize(v));
    }
    return s;
}

double seconds_sum(const std::vector<const TrialRecord*>& trials) {
    double s = 0;
    for (const auto* t : trials) s += t->seconds;
    return s;
}
double evaluations_mean(const std::vector<const TrialRecord*>& trials) {
    double s = 0;
    for (const auto* t : trials) s += static_cast<double>(t->evaluations);
    return trials.empty() ? std::nan("") : s / static_cast<double>(trials.size());
}

}  // namespace

double final_error(const ProblemInfo& problem, const TrialRecord& record) {
    return problem.truth.optimum_value ? record.best_fitness - *problem.truth.optimum_value : record.best_fitness;
}

TrialGroups group_trials(const ExperimentInfo& info, const std::vector<TrialRecord>& records) {
    TrialGroups g;
    g.ok.assign(info.problems.size(), std::vector<std::vector<const TrialRecord*>>(info.optimizers.size()));
    g.failed.assign(info.problems.size(), std::vector<std::size_t>(info.optimizers.size(), 0));
    std::map<std::string, std::size_t> prob_index, opt_index;
    for (std::size_t i = 0; i < info.problems.size(); ++i) prob_index[info.problems[i].label] = i;
    for (std::size_t i = 0; i < info.optimizers.size(); ++i) opt_index[info.optimizers[i].label] = i;
    // A resumed run may hold a trial twice (an interrupted write followed by a rerun): keep the last.
    std::map<std::tuple<std::size_t, std::size_t, std::int64_t>, const TrialRecord*> unique;
    for (const auto& r : records) {
        auto p = prob_index.find(r.problem);
        auto o = opt_index.find(r.optimizer);
        if (p == prob_index.end() || o == opt_index.end()) continue;
        unique[{p->second, o->second, r.trial}] = &r;
    }
    for (const auto& [key, r] : unique) {
        const auto [p, o, t] = key;
        if (r->ok) g.ok[p][o].push_back(r);
        else ++g.failed[p][o];
    }
    return g;
}

std::string markdown_report(const ExperimentInfo& info, const std::vector<TrialRecord>& records) {
    const auto groups = group_trials(info, records);
    std::string md = fmt::format("# {}\n\n", info.name);
    if (!info.description.empty()) md += info.description + "\n\n";
    md += fmt::format("Config `{}`; {} trials per pair; master seed {}; budget: {}.\n\n",
                      std::filesystem::path(info.config_file).filename().string(), info.trials, info.seed,
                      info.budget.max_evaluations > 0
                          ? (info.budget.max_iterations > 0 ? fmt::format("{} iterations or {} evaluations, whichever first",
                                                                          info.budget.max_iterations, info.budget.max_evaluations)
                                                            : fmt::format("{} function evaluations", info.budget.max_evaluations))
                          : fmt::format("{} iterations", info.budget.max_iterations));
    md += "Columns: final fitness statistics over the successful trials (minus the known optimum f* where "
          "there is one), the mean number of function evaluations used, two-sided Wilcoxon rank-sum p-values and "
          "Vargha-Delaney A12 (probability that a run of the row's optimiser ends lower than one of the reference) "
          "against each reference optimiser, and run time.\n\n";

    for (std::size_t p = 0; p < info.problems.size(); ++p) {
        const auto& prob = info.problems[p];
        md += fmt::format("## {}\n\n", prob.label);
        if (!prob.description.empty()) md += prob.description + "\n\n";
        md += fmt::format("Dimension {}", prob.dimension);
        if (prob.truth.optimum_value) md += fmt::format("; known optimum f* = {}", num(*prob.truth.optimum_value));
        md += ".\n\n";
        const bool shifted = prob.truth.optimum_value.has_value();
        std::string header = "| Optimizer | runs | mean" + std::string(shifted ? " f−f*" : " f") +
                             " | std | median | best | worst | evaluations |";
        std::string rule = "|---|---|---|---|---|---|---|---|";
        for (const auto& ref : info.references) {
            header += fmt::format(" p vs {} | A12 vs {} |", ref, ref);
            rule += "---|---|";
        }
        header += " time/trial (s) |";
        rule += "---|";
        md += header + "\n" + rule + "\n";
        for (std::size_t o = 0; o < info.optimizers.size(); ++o) {
            const auto& trials = groups.ok[p][o];
            const auto errors = errors_of(prob, trials);
            const auto s = stats::summarize(errors);
            std::string runs = std::to_string(trials.size());
            if (groups.failed[p][o]) runs += fmt::format(" ({} failed)", groups.failed[p][o]);
            md += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} |", info.optimizers[o].label, runs,
                              s.n ? num(s.mean) : "–", s.n ? num(s.sd) : "–", s.n ? num(s.median) : "–",
                              s.n ? num(s.min) : "–", s.n ? num(s.max) : "–", num(evaluations_mean(trials)));
            for (const auto& ref : info.references) {
                const std::size_t r = index_of(info, ref);
                if (r == o || r >= info.optimizers.size() || trials.empty() || groups.ok[p][r].empty()) {
                    md += " – | – |";
                    continue;
                }
                const auto ref_errors = errors_of(prob, groups.ok[p][r]);
                const auto test = stats::wilcoxon_rank_sum(errors, ref_errors);
                const double a12 = stats::vargha_delaney_a12(errors, ref_errors);
                md += fmt::format(" {} | {} ({}) |", pval(test.p), fmt::format("{:.2f}", a12), stats::a12_magnitude(a12));
            }
            md += fmt::format(" {} |\n", trials.empty() ? "–" : num(seconds_sum(trials) / static_cast<double>(trials.size())));
        }
        md += "\n";

        const auto& target = accuracy_target(prob);
        if (prob.named_parameters && (target || prob.truth.reference_solution)) {
            md += fmt::format("### {}: identified parameters (mean over trials, error % against {}, std)\n\n", prob.label,
                              prob.truth.true_parameters ? "the true values" : prob.truth.reference_label);
            std::string h = "| |", r2 = "|---|";
            for (const auto& n : prob.parameter_names) {
                h += fmt::format(" {} mean | {} err % | {} std |", n, n, n);
                r2 += "---|---|---|";
            }
            h += " fitness mean | fitness std | time total (s) |";
            r2 += "---|---|---|";
            md += h + "\n" + r2 + "\n";
            auto fixed_row = [&](const std::string& label, const Vector& v, std::optional<double> fitness) {
                std::string row = "| " + label + " |";
                for (Eigen::Index j = 0; j < v.size(); ++j) {
                    const double err = target ? 100.0 * std::abs(v[j] - (*target)[j]) / std::abs((*target)[j]) : std::nan("");
                    row += fmt::format(" {} | {} | |", num(v[j]), fmt::format("{:.3g}", err));
                }
                row += fmt::format(" {} | | |\n", fitness ? num(*fitness) : "");
                return row;
            };
            if (prob.truth.true_parameters) md += fixed_row("truth", *prob.truth.true_parameters, std::nullopt);
            if (prob.truth.reference_solution)
                md += fixed_row(prob.truth.reference_label.empty() ? "reference" : prob.truth.reference_label,
                                *prob.truth.reference_solution, prob.truth.reference_fitness);
            for (std::size_t o = 0; o < info.optimizers.size(); ++o) {
                const auto& trials = groups.ok[p][o];
                if (trials.empty()) continue;
                const auto ps = parameter_stats(trials, prob.dimension);
                std::string row = "| " + info.optimizers[o].label + " |";
                for (int j = 0; j < prob.dimension; ++j) {
                    const auto& s = ps.per_parameter[static_cast<std::size_t>(j)];
                    const double err = target ? 100.0 * std::abs(s.mean - (*target)[j]) / std::abs((*target)[j]) : std::nan("");
                    row += fmt::format(" {} | {} | {} |", num(s.mean), fmt::format("{:.3g}", err), num(s.sd));
                }
                std::vector<double> fit;
                for (const auto* t : trials) fit.push_back(t->best_fitness);
                const auto fs = stats::summarize(fit);
                row += fmt::format(" {} | {} | {} |\n", num(fs.mean), num(fs.sd), num(seconds_sum(trials)));
                md += row;
            }
            for (const auto& pub : info.published) {
                if (pub.problem != prob.label) continue;
                std::string row = "| " + pub.label + " |";
                for (int j = 0; j < prob.dimension; ++j) {
                    const auto& n = prob.parameter_names[static_cast<std::size_t>(j)];
                    auto m = pub.mean.find(n);
                    auto d = pub.sd.find(n);
                    const double err = (m != pub.mean.end() && target) ? 100.0 * std::abs(m->second - (*target)[j]) / std::abs((*target)[j])
                                                                      : std::nan("");
                    row += fmt::format(" {} | {} | {} |", m != pub.mean.end() ? num(m->second) : "–", fmt::format("{:.3g}", err),
                                       d != pub.sd.end() ? num(d->second) : "–");
                }
                row += fmt::format(" {} | {} | {} |\n", pub.fitness_mean ? num(*pub.fitness_mean) : "–",
                                   pub.fitness_sd ? num(*pub.fitness_sd) : "–", pub.time_total ? fmt::format("{:.3f}", *pub.time_total) : "–");
                md += row;
            }
            std::set<std::string> sources;
            for (const auto& pub : info.published)
                if (pub.problem == prob.label) sources.insert(pub.source);
            for (const auto& src : sources)
                md += fmt::format("\nRows marked as published are quoted from {}, with the error % recomputed against the truth above; "
                                  "their fitness values come from the paper's own fitness function, which may differ from ours.\n", src);
            md += "\n";
            if (prob.truth.reference_fitness) {
                md += fmt::format("Gap to the {} (fitness {}): ", prob.truth.reference_label, num(*prob.truth.reference_fitness));
                std::vector<std::string> parts;
                for (std::size_t o = 0; o < info.optimizers.size(); ++o) {
                    const auto& trials = groups.ok[p][o];
                    if (trials.empty()) continue;
                    std::vector<double> gaps;
                    std::size_t reached = 0;
                    for (const auto* t : trials) {
                        const double gap = t->best_fitness - *prob.truth.reference_fitness;
                        gaps.push_back(gap);
                        if (gap <= 1e-6 * std::max(1e-300, std::abs(*prob.truth.reference_fitness))) ++reached;
                    }
                    parts.push_back(fmt::format("{} mean gap {}, {}/{} trials within 1e-6 relative", info.optimizers[o].label,
                                                num(stats::summarize(gaps).mean), reached, trials.size()));
                }
                for (std::size_t i = 0; i < parts.size(); ++i) md += (i ? "; " : "") + parts[i];
                md += ".\n\n";
            }
        }
    }

    if (info.problems.size() >= 2 && info.optimizers.size() >= 2) {
        std::vector<std::vector<double>> scores;
        for (std::size_t p = 0; p < info.problems.size(); ++p) {
            std::vector<double> row;
            bool complete = true;
            for (std::size_t o = 0; o < info.optimizers.size(); ++o) {
                const auto e = errors_of(info.problems[p], groups.ok[p][o]);
                if (e.empty()) complete = false;
                row.push_back(e.empty() ? 0.0 : stats::summarize(e).mean);
            }
            if (complete) scores.push_back(std::move(row));
        }
        if (scores.size() >= 2) {
            const auto f = stats::friedman(scores);
            md += fmt::format("## Friedman mean ranks over {} problems (by mean final fitness; 1 = best)\n\n", scores.size());
            md += "| Optimizer | mean rank |\n|---|---|\n";
            for (std::size_t o = 0; o < info.optimizers.size(); ++o)
                md += fmt::format("| {} | {:.2f} |\n", info.optimizers[o].label, f.mean_ranks[o]);
            md += fmt::format("\nFriedman chi-square = {:.3f}, {} degrees of freedom, p = {}.\n\n", f.chi_square,
                              info.optimizers.size() - 1, pval(f.p));
        }
    }

    double total = 0;
    std::size_t n = 0, failed = 0;
    for (std::size_t p = 0; p < info.problems.size(); ++p)
        for (std::size_t o = 0; o < info.optimizers.size(); ++o) {
            total += seconds_sum(groups.ok[p][o]);
            n += groups.ok[p][o].size();
            failed += groups.failed[p][o];
        }
    md += fmt::format("Total: {} successful trials, {} failed; {:.3f} s of trial time (summed over threads).\n", n, failed, total);
    return md;
}

std::string csv_table(const ExperimentInfo& info, const std::vector<TrialRecord>& records) {
    const auto groups = group_trials(info, records);
    std::vector<std::string> columns{"problem", "optimizer", "runs", "failed", "mean", "std", "median", "best", "worst",
                                     "mean_evaluations"};
    for (const auto& ref : info.references) {
        columns.push_back("p_vs_" + ref);
        columns.push_back("a12_vs_" + ref);
    }
    std::set<std::string> param_columns;
    std::vector<std::string> param_order;
    for (const auto& prob : info.problems)
        if (prob.named_parameters)
            for (const auto& n : prob.parameter_names)
                for (const char* suffix : {"_mean", "_err_pct", "_std"})
                    if (param_columns.insert(n + suffix).second) param_order.push_back(n + suffix);
    columns.insert(columns.end(), param_order.begin(), param_order.end());
    columns.push_back("mean_time_s");
    columns.push_back("total_time_s");

    auto quote = [](const std::string& s) {
        if (s.find_first_of(",\"\n") == std::string::npos) return s;
        std::string q = "\"";
        for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
        return q + "\"";
    };
    auto full = [](double v) { return std::isnan(v) ? std::string() : fmt::format("{:.17g}", v); };
    std::string out;
    for (std::size_t i = 0; i < columns.size(); ++i) out += (i ? "," : "") + columns[i];
    out += "\n";
    for (std::size_t p = 0; p < info.problems.size(); ++p) {
        const auto& prob = info.problems[p];
        const auto& target = accuracy_target(prob);
        for (std::size_t o = 0; o < info.optimizers.size(); ++o) {
            const auto& trials = groups.ok[p][o];
            std::map<std::string, std::string> row;
            row["problem"] = quote(prob.label);
            row["optimizer"] = quote(info.optimizers[o].label);
            row["runs"] = std::to_string(trials.size());
            row["failed"] = std::to_string(groups.failed[p][o]);
            const auto errors = errors_of(prob, trials);
            if (!errors.empty()) {
                const auto s = stats::summarize(errors);
                row["mean"] = full(s.mean);
                row["std"] = full(s.sd);
                row["median"] = full(s.median);
                row["best"] = full(s.min);
                row["worst"] = full(s.max);
                row["mean_evaluations"] = full(evaluations_mean(trials));
                row["mean_time_s"] = full(seconds_sum(trials) / static_cast<double>(trials.size()));
                row["total_time_s"] = full(seconds_sum(trials));
            }
            for (const auto& ref : info.references) {
                const std::size_t r = index_of(info, ref);
                if (r == o || r >= info.optimizers.size() || trials.empty() || groups.ok[p][r].empty()) continue;
                const auto ref_errors = errors_of(prob, groups.ok[p][r]);
                row["p_vs_" + ref] = full(stats::wilcoxon_rank_sum(errors, ref_errors).p);
                row["a12_vs_" + ref] = full(stats::vargha_delaney_a12(errors, ref_errors));
            }
            if (prob.named_parameters && !trials.empty()) {
                const auto ps = parameter_stats(trials, prob.dimension);
                for (int j = 0; j < prob.dimension; ++j) {
                    const auto& n = prob.parameter_names[static_cast<std::size_t>(j)];
                    const auto& s = ps.per_parameter[static_cast<std::size_t>(j)];
                    row[n + "_mean"] = full(s.mean);
                    row[n + "_std"] = full(s.sd);
                    if (target) row[n + "_err_pct"] = full(100.0 * std::abs(s.mean - (*target)[j]) / std::abs((*target)[j]));
                }
            }
            for (std::size_t i = 0; i < columns.size(); ++i) out += (i ? "," : "") + row[columns[i]];
            out += "\n";
        }
    }
    return out;
}

std::string write_tables(const std::filesystem::path& directory, const ExperimentInfo& info,
                         const std::vector<TrialRecord>& records) {
    std::string markdown = markdown_report(info, records);
    for (const auto& [name, text] : {std::pair{"table.md", markdown},
                                     std::pair{"table.csv", csv_table(info, records)}}) {
        std::ofstream out(directory / name);
        out << text;
        if (!out) throw InputError((directory / name).string(), 0, "output", "cannot write the table");
    }
    return markdown;
}

}  // namespace mhb
