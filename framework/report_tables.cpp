#include "framework/report_tables.hpp"

#include <cmath>
#include <fstream>
#include <map>
#include <set>

#include <fmt/format.h>

#include "framework/anytime_analysis.hpp"
#include "framework/file_output.hpp"
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

double error_percent(double value, const std::optional<Vector>& target, Eigen::Index j) {
    return target ? 100.0 * std::abs(value - (*target)[j]) / std::abs((*target)[j]) : std::nan("");
}

// Pairwise test of one group against a reference group.
struct Versus {
    double p = std::nan(""), a12 = std::nan("");
};

// Everything the tables say about one (problem, optimizer) group, computed once for both formats.
struct GroupSummary {
    std::size_t runs = 0, failed = 0;
    stats::Summary error;    // final f - f* (f when the optimum is unknown)
    stats::Summary fitness;  // final f
    double mean_evaluations = std::nan(""), total_seconds = 0;
    std::vector<std::optional<Versus>> versus;  // one per info.references; empty when not applicable
    std::vector<stats::Summary> parameters;     // for problems with named parameters
    double mean_seconds() const { return runs ? total_seconds / static_cast<double>(runs) : std::nan(""); }
};

// summaries[p][o], in the experiment's declaration order.
std::vector<std::vector<GroupSummary>> summarize_groups(const ExperimentInfo& info, const TrialGroups& groups) {
    std::vector<std::vector<GroupSummary>> out(info.problems.size(), std::vector<GroupSummary>(info.optimizers.size()));
    for (std::size_t p = 0; p < info.problems.size(); ++p) {
        const auto& prob = info.problems[p];
        std::vector<std::vector<double>> errors(info.optimizers.size());
        for (std::size_t o = 0; o < info.optimizers.size(); ++o) {
            const auto& trials = groups.ok[p][o];
            auto& g = out[p][o];
            g.runs = trials.size();
            g.failed = groups.failed[p][o];
            std::vector<double> fitness;
            double evaluations = 0;
            for (const auto* t : trials) {
                errors[o].push_back(final_error(info, prob, *t));
                fitness.push_back(t->best_fitness);
                evaluations += static_cast<double>(t->evaluations);
                g.total_seconds += t->seconds;
            }
            g.error = stats::summarize(errors[o]);
            g.fitness = stats::summarize(fitness);
            if (g.runs) g.mean_evaluations = evaluations / static_cast<double>(g.runs);
            if (prob.named_parameters && g.runs)
                for (int j = 0; j < prob.dimension; ++j) {
                    std::vector<double> v;
                    for (const auto* t : trials)
                        if (t->best_position.size() == prob.dimension) v.push_back(t->best_position[j]);
                    g.parameters.push_back(stats::summarize(v));
                }
        }
        for (std::size_t o = 0; o < info.optimizers.size(); ++o)
            for (const auto& ref : info.references) {
                const std::size_t r = index_of(info, ref);
                auto& slot = out[p][o].versus.emplace_back();
                if (r == o || r >= info.optimizers.size() || errors[o].empty() || errors[r].empty()) continue;
                slot = Versus{stats::wilcoxon_rank_sum(errors[o], errors[r]).p, stats::vargha_delaney_a12(errors[o], errors[r])};
            }
    }
    return out;
}

// The error at each of the budget's checkpoints ([anytime] checkpoints), mean and median over the
// trials, as the CEC reports' convergence records; nothing when the trials did not record them.
void add_checkpoint_table(Document& doc, const ExperimentInfo& info, const ProblemInfo& prob,
                          const std::vector<std::vector<const TrialRecord*>>& trials) {
    std::vector<std::int64_t> evaluations;
    for (const auto& group : trials)
        for (const auto* t : group)
            if (t->anytime.checkpoint_evaluations.size() > evaluations.size()) evaluations = t->anytime.checkpoint_evaluations;
    if (evaluations.empty()) return;
    std::vector<Column> columns{"Optimizer", "statistic"};
    for (auto e : evaluations) columns.emplace_back(fmt::format("{}", e));
    const std::string title = prob.label + ": error f − f* at the budget's checkpoints (evaluations)";
    doc.add(Heading{3, title});
    Table table(title, std::move(columns));
    for (std::size_t o = 0; o < info.optimizers.size(); ++o) {
        if (trials[o].empty()) continue;
        std::vector<stats::Summary> at(evaluations.size());
        for (std::size_t k = 0; k < evaluations.size(); ++k) {
            std::vector<double> errors;
            for (const auto* t : trials[o])
                if (k < t->anytime.checkpoint_best.size()) errors.push_back(reported_error(info, prob, t->anytime.checkpoint_best[k]));
            at[k] = stats::summarize(errors);
        }
        for (const char* statistic : {"mean", "median"}) {
            std::vector<Cell> row{info.optimizers[o].label, statistic};
            for (const auto& s : at) row.emplace_back(s.n ? num(std::string_view(statistic) == "mean" ? s.mean : s.median) : "–");
            table.add_row(std::move(row));
        }
    }
    table.add_note("Over the trials that reached each checkpoint (a trial ended by an iteration limit may stop short of the last).");
    doc.add(std::move(table));
}

}  // namespace

double reported_error(const ExperimentInfo& info, const ProblemInfo& problem, double f) {
    if (!problem.truth.optimum_value) return f;
    const double error = f - *problem.truth.optimum_value;
    return info.error_threshold > 0 && error < info.error_threshold ? 0.0 : error;
}

double final_error(const ExperimentInfo& info, const ProblemInfo& problem, const TrialRecord& record) {
    return reported_error(info, problem, record.best_fitness);
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

Document tables_document(const ExperimentInfo& info, const std::vector<TrialRecord>& records) {
    const auto groups = group_trials(info, records);
    const auto summaries = summarize_groups(info, groups);
    Document doc;
    doc.add(Heading{1, info.name});
    if (!info.description.empty()) doc.add(Paragraph{info.description});
    std::string evaluations = info.evaluations_per_dimension > 0 ? fmt::format("{} x dimension", info.evaluations_per_dimension)
                                                                  : fmt::format("{}", info.budget.max_evaluations);
    if (!info.evaluations_by_dimension.empty()) {
        evaluations.clear();
        for (const auto& [d, e] : info.evaluations_by_dimension)
            evaluations += fmt::format("{}{} at D = {}", evaluations.empty() ? "" : ", ", e, d);
    }
    const bool evaluation_limit = info.budget.max_evaluations > 0 || info.evaluations_per_dimension > 0 ||
                                  !info.evaluations_by_dimension.empty();
    doc.add(Paragraph{fmt::format("Config `{}`; {} trial{} per pair; master seed {}; budget: {}.",
                                  std::filesystem::path(info.config_file).filename().string(), info.trials, info.trials == 1 ? "" : "s", info.seed,
                                  evaluation_limit ? (info.budget.max_iterations > 0 ? fmt::format("{} iterations or {} evaluations, whichever first",
                                                                                                   info.budget.max_iterations, evaluations)
                                                                                     : fmt::format("{} function evaluations", evaluations))
                                                   : fmt::format("{} iterations", info.budget.max_iterations))});
    if (info.selected_dimension > 0)
        doc.add(Paragraph{fmt::format("Only the config's problems of dimension {} were run (`mhbench run --dimension {}`).",
                                      info.selected_dimension, info.selected_dimension)});
    if (info.error_threshold > 0)
        doc.add(Paragraph{fmt::format("Errors f − f* below {:g} are counted as 0 (analysis.error_threshold), in every table, rank and plot.",
                                      info.error_threshold)});
    doc.add(Paragraph{"Columns: final fitness statistics over the successful trials (minus the known optimum f* where "
                      "there is one), the mean number of function evaluations used, two-sided Wilcoxon rank-sum p-values and "
                      "Vargha-Delaney A12 (probability that a run of the row's optimiser ends lower than one of the reference) "
                      "against each reference optimiser, and run time."});

    if (!info.per_problem)
        doc.add(Paragraph{fmt::format("Per-problem tables are off (analysis.per_problem = false): table.csv has a row for each of the {} "
                                      "problems and each optimiser.",
                                      info.problems.size())});
    for (std::size_t p = 0; p < (info.per_problem ? info.problems.size() : 0); ++p) {
        const auto& prob = info.problems[p];
        doc.add(Heading{2, prob.label});
        if (!prob.description.empty()) doc.add(Paragraph{prob.description});
        doc.add(Paragraph{fmt::format("Dimension {}{}.", prob.dimension,
                                      prob.truth.optimum_value ? fmt::format("; known optimum f* = {}", num(*prob.truth.optimum_value)) : "")});
        const bool shifted = prob.truth.optimum_value.has_value();
        std::vector<Column> columns{"Optimizer", "runs", shifted ? "mean f−f*" : "mean f", "std", "median", "best", "worst", "evaluations"};
        for (const auto& ref : info.references) {
            columns.emplace_back("p vs " + ref);
            columns.emplace_back("A12 vs " + ref);
        }
        columns.emplace_back("time/trial", "s");
        Table results(prob.label + ": final error per optimiser", std::move(columns));
        for (std::size_t o = 0; o < info.optimizers.size(); ++o) {
            const auto& g = summaries[p][o];
            const auto& s = g.error;
            std::string runs = std::to_string(g.runs);
            if (g.failed) runs += fmt::format(" ({} failed)", g.failed);
            std::vector<Cell> row{info.optimizers[o].label, runs, s.n ? num(s.mean) : "–", s.n ? num(s.sd) : "–", s.n ? num(s.median) : "–",
                                  s.n ? num(s.min) : "–", s.n ? num(s.max) : "–", num(g.mean_evaluations)};
            for (const auto& v : g.versus) {
                row.emplace_back(v ? pval(v->p) : "–");
                row.emplace_back(v ? fmt::format("{:.2f} ({})", v->a12, stats::a12_magnitude(v->a12)) : "–");
            }
            row.emplace_back(num(g.mean_seconds()));
            results.add_row(std::move(row));
        }
        doc.add(std::move(results));
        add_checkpoint_table(doc, info, prob, groups.ok[p]);

        const auto& target = accuracy_target(prob);
        if (prob.named_parameters && (target || prob.truth.reference_solution)) {
            const std::string title = fmt::format("{}: identified parameters (mean over trials, error % against {}, std)", prob.label,
                                                  prob.truth.true_parameters ? "the true values" : prob.truth.reference_label);
            doc.add(Heading{3, title});
            std::vector<Column> parameter_columns{""};
            for (const auto& n : prob.parameter_names)
                for (const char* what : {" mean", " err %", " std"}) parameter_columns.emplace_back(n + what);
            parameter_columns.emplace_back("fitness mean");
            parameter_columns.emplace_back("fitness std");
            parameter_columns.emplace_back("time total", "s");
            Table parameters(title, std::move(parameter_columns));
            // Truth and reference are single values: no spread, no time.
            auto add_fixed_row = [&](const std::string& label, const Vector& v, std::optional<double> fitness) {
                std::vector<Cell> row{label};
                for (Eigen::Index j = 0; j < v.size(); ++j) {
                    row.emplace_back(num(v[j]));
                    row.emplace_back(fmt::format("{:.3g}", error_percent(v[j], target, j)));
                    row.push_back(Cell::none());
                }
                row.emplace_back(fitness ? num(*fitness) : "");
                row.push_back(Cell::none());
                row.push_back(Cell::none());
                parameters.add_row(std::move(row));
            };
            if (prob.truth.true_parameters) add_fixed_row("truth", *prob.truth.true_parameters, std::nullopt);
            if (prob.truth.reference_solution)
                add_fixed_row(prob.truth.reference_label.empty() ? "reference" : prob.truth.reference_label, *prob.truth.reference_solution,
                              prob.truth.reference_fitness);
            for (std::size_t o = 0; o < info.optimizers.size(); ++o) {
                const auto& g = summaries[p][o];
                if (!g.runs) continue;
                std::vector<Cell> row{info.optimizers[o].label};
                for (int j = 0; j < prob.dimension; ++j) {
                    const auto& s = g.parameters[static_cast<std::size_t>(j)];
                    row.emplace_back(num(s.mean));
                    row.emplace_back(fmt::format("{:.3g}", error_percent(s.mean, target, j)));
                    row.emplace_back(num(s.sd));
                }
                row.emplace_back(num(g.fitness.mean));
                row.emplace_back(num(g.fitness.sd));
                row.emplace_back(num(g.total_seconds));
                parameters.add_row(std::move(row));
            }
            for (const auto& pub : info.published) {
                if (pub.problem != prob.label) continue;
                std::vector<Cell> row{pub.label};
                for (int j = 0; j < prob.dimension; ++j) {
                    const auto& n = prob.parameter_names[static_cast<std::size_t>(j)];
                    auto m = pub.mean.find(n);
                    auto d = pub.sd.find(n);
                    const double err = m != pub.mean.end() ? error_percent(m->second, target, j) : std::nan("");
                    row.emplace_back(m != pub.mean.end() ? num(m->second) : "–");
                    row.emplace_back(fmt::format("{:.3g}", err));
                    row.emplace_back(d != pub.sd.end() ? num(d->second) : "–");
                }
                row.emplace_back(pub.fitness_mean ? num(*pub.fitness_mean) : "–");
                row.emplace_back(pub.fitness_sd ? num(*pub.fitness_sd) : "–");
                row.emplace_back(pub.time_total ? fmt::format("{:.3f}", *pub.time_total) : "–");
                parameters.add_row(std::move(row));
            }
            std::set<std::string> sources;
            for (const auto& pub : info.published)
                if (pub.problem == prob.label) sources.insert(pub.source);
            for (const auto& src : sources)
                parameters.add_note(fmt::format("Rows marked as published are quoted from {}, with the error % recomputed against the truth above; "
                                                "their fitness values come from the paper's own fitness function, which may differ from ours.",
                                                src));
            doc.add(std::move(parameters));
            if (prob.truth.reference_fitness) {
                std::string gap = fmt::format("Gap to the {} (fitness {}): ", prob.truth.reference_label, num(*prob.truth.reference_fitness));
                std::vector<std::string> parts;
                for (std::size_t o = 0; o < info.optimizers.size(); ++o) {
                    const auto& trials = groups.ok[p][o];
                    if (trials.empty()) continue;
                    std::vector<double> gaps;
                    std::size_t reached = 0;
                    for (const auto* t : trials) {
                        const double difference = t->best_fitness - *prob.truth.reference_fitness;
                        gaps.push_back(difference);
                        if (difference <= 1e-6 * std::max(1e-300, std::abs(*prob.truth.reference_fitness))) ++reached;
                    }
                    parts.push_back(fmt::format("{} mean gap {}, {}/{} trials within 1e-6 relative", info.optimizers[o].label,
                                                num(stats::summarize(gaps).mean), reached, trials.size()));
                }
                for (std::size_t i = 0; i < parts.size(); ++i) gap += (i ? "; " : "") + parts[i];
                doc.add(Paragraph{gap + "."});
            }
        }
    }

    if (info.problems.size() >= 2 && info.optimizers.size() >= 2) {
        std::vector<std::vector<double>> scores;
        for (std::size_t p = 0; p < info.problems.size(); ++p) {
            std::vector<double> row;
            bool complete = true;
            for (const auto& g : summaries[p]) {
                complete = complete && g.runs > 0;
                row.push_back(g.runs ? g.error.mean : 0.0);
            }
            if (complete) scores.push_back(std::move(row));
        }
        if (scores.size() >= 2) {
            const auto f = stats::friedman(scores);
            doc.add(Heading{2, fmt::format("Friedman mean ranks over {} problems (by mean final fitness; 1 = best)", scores.size())});
            Table ranks("Friedman mean ranks", {"Optimizer", "mean rank"});
            for (std::size_t o = 0; o < info.optimizers.size(); ++o) ranks.add_row({info.optimizers[o].label, fmt::format("{:.2f}", f.mean_ranks[o])});
            doc.add(std::move(ranks));
            doc.add(Paragraph{fmt::format("Friedman chi-square = {:.3f}, {} degrees of freedom, p = {}.", f.chi_square, info.optimizers.size() - 1,
                                          pval(f.p))});
        }
    }

    doc.append(anytime_section(info, records));

    double total = 0;
    std::size_t n = 0, failed = 0;
    for (const auto& row : summaries)
        for (const auto& g : row) {
            total += g.total_seconds;
            n += g.runs;
            failed += g.failed;
        }
    doc.add(Paragraph{fmt::format("Total: {} successful trials, {} failed; {:.3f} s of trial time (summed over threads).", n, failed, total)});
    return doc;
}

std::string markdown_report(const ExperimentInfo& info, const std::vector<TrialRecord>& records) {
    return markdown(tables_document(info, records));
}

Table results_table(const ExperimentInfo& info, const std::vector<TrialRecord>& records) {
    const auto summaries = summarize_groups(info, group_trials(info, records));
    std::vector<std::string> names{"problem", "optimizer", "runs", "failed", "mean", "std", "median", "best", "worst", "mean_evaluations"};
    for (const auto& ref : info.references) {
        names.push_back("p_vs_" + ref);
        names.push_back("a12_vs_" + ref);
    }
    std::set<std::string> param_columns;
    for (const auto& prob : info.problems)
        if (prob.named_parameters)
            for (const auto& n : prob.parameter_names)
                for (const char* suffix : {"_mean", "_err_pct", "_std"})
                    if (param_columns.insert(n + suffix).second) names.push_back(n + suffix);
    names.push_back("mean_time_s");
    names.push_back("total_time_s");

    auto full = [](double v) { return std::isnan(v) ? std::string() : fmt::format("{:.17g}", v); };
    Table table("results per problem and optimiser", std::vector<Column>(names.begin(), names.end()));
    for (std::size_t p = 0; p < info.problems.size(); ++p) {
        const auto& prob = info.problems[p];
        const auto& target = accuracy_target(prob);
        for (std::size_t o = 0; o < info.optimizers.size(); ++o) {
            const auto& g = summaries[p][o];
            std::map<std::string, std::string> row;
            row["problem"] = prob.label;
            row["optimizer"] = info.optimizers[o].label;
            row["runs"] = std::to_string(g.runs);
            row["failed"] = std::to_string(g.failed);
            if (g.runs) {
                row["mean"] = full(g.error.mean);
                row["std"] = full(g.error.sd);
                row["median"] = full(g.error.median);
                row["best"] = full(g.error.min);
                row["worst"] = full(g.error.max);
                row["mean_evaluations"] = full(g.mean_evaluations);
                row["mean_time_s"] = full(g.mean_seconds());
                row["total_time_s"] = full(g.total_seconds);
            }
            for (std::size_t k = 0; k < info.references.size(); ++k)
                if (const auto& v = g.versus[k]) {
                    row["p_vs_" + info.references[k]] = full(v->p);
                    row["a12_vs_" + info.references[k]] = full(v->a12);
                }
            for (std::size_t j = 0; j < g.parameters.size(); ++j) {
                const auto& n = prob.parameter_names[j];
                row[n + "_mean"] = full(g.parameters[j].mean);
                row[n + "_std"] = full(g.parameters[j].sd);
                if (target) row[n + "_err_pct"] = full(error_percent(g.parameters[j].mean, target, static_cast<Eigen::Index>(j)));
            }
            std::vector<Cell> cells;
            for (const auto& name : names) cells.emplace_back(row[name]);
            table.add_row(std::move(cells));
        }
    }
    return table;
}

std::string csv_table(const ExperimentInfo& info, const std::vector<TrialRecord>& records) { return csv(results_table(info, records)); }

Document write_tables(const std::filesystem::path& directory, const ExperimentInfo& info, const std::vector<TrialRecord>& records) {
    Document document = tables_document(info, records);
    replace_file(directory / "table.md", markdown(document));
    replace_file(directory / "table.csv", csv(results_table(info, records)));
    return document;
}

}  // namespace mhb
