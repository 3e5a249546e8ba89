#include "framework/anytime_analysis.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>

#include <fmt/format.h>

#include "framework/plots.hpp"
#include "framework/random.hpp"

namespace mhb {
namespace {

namespace fs = std::filesystem;
constexpr double infinity = std::numeric_limits<double>::infinity();

// The p-quantile of sorted values by nearest rank: +inf stays +inf instead of becoming NaN in an
// interpolation between a finite value and +inf.
double nearest_rank(const std::vector<double>& sorted, double p) {
    const auto rank = static_cast<std::size_t>(std::ceil(p * static_cast<double>(sorted.size())));
    return sorted[std::clamp<std::size_t>(rank, 1, sorted.size()) - 1];
}

std::string function_key(const ProblemInfo& p) {
    std::string settings;
    for (const auto& [k, v] : p.parameters)
        if (k != "instance" && k != "dimension") settings += (settings.empty() ? "" : ", ") + k + "=" + to_string(v);
    // A box of the config's makes another function, as in the IOHprofiler export.
    if (!p.lower.empty()) settings += fmt::format("{}lower=[{}]", settings.empty() ? "" : ", ", fmt::join(p.lower, ", "));
    if (!p.upper.empty()) settings += fmt::format("{}upper=[{}]", settings.empty() ? "" : ", ", fmt::join(p.upper, ", "));
    return settings.empty() ? p.name : p.name + "(" + settings + ")";
}

// The successful trials that carry anytime records, by (optimizer label, problem label).
std::map<std::pair<std::string, std::string>, std::vector<const TrialRecord*>> anytime_runs(const std::vector<TrialRecord>& records,
                                                                                           std::size_t targets) {
    std::map<std::pair<std::string, std::string>, std::vector<const TrialRecord*>> out;
    for (const auto& r : records)
        if (r.ok && r.anytime.hits.size() == targets) out[{r.optimizer, r.problem}].push_back(&r);
    return out;
}

// The runs of each function for one optimiser: hits per target, in the functions' order.
std::vector<std::vector<std::vector<std::int64_t>>> hits_by_function(
    const ExperimentInfo& info, const std::vector<const AnytimeFunction*>& functions, const std::string& optimizer,
    const std::map<std::pair<std::string, std::string>, std::vector<const TrialRecord*>>& runs) {
    std::vector<std::vector<std::vector<std::int64_t>>> out;
    for (const auto* f : functions) {
        std::vector<std::vector<std::int64_t>> of_function;
        for (std::size_t p : f->problems)
            if (auto it = runs.find({optimizer, info.problems[p].label}); it != runs.end())
                for (const auto* r : it->second) of_function.push_back(r->anytime.hits);
        out.push_back(std::move(of_function));
    }
    return out;
}

// 10^(k/10) evaluations per dimension, from the first evaluation to past the longest run.
std::vector<double> budget_grid(int dimension, std::int64_t max_evaluations) {
    std::vector<double> out;
    const double d = dimension;
    for (int k = static_cast<int>(std::floor(-10.0 * std::log10(d)));; ++k) {
        const double b = std::pow(10.0, k / 10.0);
        out.push_back(b);
        if (b * d >= static_cast<double>(max_evaluations)) break;
    }
    return out;
}

std::vector<int> dimensions_of(const std::vector<AnytimeFunction>& functions) {
    std::vector<int> out;
    for (const auto& f : functions) out.push_back(f.dimension);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

std::string evaluations_text(double v) {
    if (!std::isfinite(v)) return "inf";
    return v < 1e5 ? fmt::format("{:.0f}", v) : fmt::format("{:.2e}", v);
}

std::string target_text(double t) { return fmt::format("{:.0e}", t); }

}  // namespace

std::vector<AnytimeFunction> anytime_functions(const ExperimentInfo& info) {
    std::vector<AnytimeFunction> out;
    for (std::size_t p = 0; p < info.problems.size(); ++p) {
        const auto key = function_key(info.problems[p]);
        const int dimension = info.problems[p].dimension;
        auto it = std::find_if(out.begin(), out.end(), [&](const auto& f) { return f.label == key && f.dimension == dimension; });
        if (it == out.end()) {
            out.push_back({key, dimension, {}});
            it = out.end() - 1;
        }
        it->problems.push_back(p);
    }
    return out;
}

Ert expected_running_time(const std::vector<RunToTarget>& runs, int bootstrap, std::uint64_t seed) {
    auto estimate = [](double used, std::size_t successes) { return successes ? used / static_cast<double>(successes) : infinity; };
    Ert ert;
    ert.runs = runs.size();
    double used = 0.0;
    for (const auto& r : runs) {
        used += static_cast<double>(r.hit > 0 ? r.hit : r.evaluations);
        ert.successes += r.hit > 0;
    }
    ert.value = ert.low = ert.high = estimate(used, ert.successes);
    if (bootstrap <= 0 || runs.empty()) return ert;
    Rng rng(seed);
    std::vector<double> resampled(static_cast<std::size_t>(bootstrap));
    for (auto& value : resampled) {
        double sum = 0.0;
        std::size_t successes = 0;
        for (std::size_t i = 0; i < runs.size(); ++i) {
            const auto& r = runs[rng.below(runs.size())];
            sum += static_cast<double>(r.hit > 0 ? r.hit : r.evaluations);
            successes += r.hit > 0;
        }
        value = estimate(sum, successes);
    }
    std::sort(resampled.begin(), resampled.end());
    ert.low = nearest_rank(resampled, 0.025);
    ert.high = nearest_rank(resampled, 0.975);
    return ert;
}

Ecdf runtime_ecdf(const std::vector<std::vector<std::vector<std::int64_t>>>& runs, int dimension, const std::vector<double>& budgets,
                  int bootstrap, std::uint64_t seed) {
    Ecdf ecdf;
    ecdf.budgets = budgets;
    const std::size_t grid = budgets.size();
    // Per run, the targets reached within each budget: a step function computed once, so that a
    // resample only adds rows.
    std::vector<std::vector<std::vector<double>>> reached(runs.size());
    std::vector<double> pairs(runs.size(), 0.0);
    for (std::size_t f = 0; f < runs.size(); ++f)
        for (const auto& hits : runs[f]) {
            std::vector<std::int64_t> sorted;
            for (auto h : hits)
                if (h > 0) sorted.push_back(h);
            std::sort(sorted.begin(), sorted.end());
            std::vector<double> counts(grid);
            std::size_t k = 0;
            for (std::size_t g = 0; g < grid; ++g) {
                while (k < sorted.size() && static_cast<double>(sorted[k]) <= budgets[g] * dimension) ++k;
                counts[g] = static_cast<double>(k);
            }
            reached[f].push_back(std::move(counts));
            pairs[f] = static_cast<double>(runs[f].size() * hits.size());
        }
    auto aggregate = [&](const std::vector<std::vector<double>>& sums, std::vector<double>& out) {
        out.assign(grid, 0.0);
        std::size_t functions = 0;
        for (std::size_t f = 0; f < runs.size(); ++f) {
            if (pairs[f] <= 0) continue;
            ++functions;
            for (std::size_t g = 0; g < grid; ++g) out[g] += sums[f][g] / pairs[f];
        }
        for (auto& v : out) v = functions ? v / static_cast<double>(functions) : 0.0;
    };
    std::vector<std::vector<double>> sums(runs.size(), std::vector<double>(grid, 0.0));
    for (std::size_t f = 0; f < runs.size(); ++f)
        for (const auto& counts : reached[f])
            for (std::size_t g = 0; g < grid; ++g) sums[f][g] += counts[g];
    aggregate(sums, ecdf.value);
    ecdf.low = ecdf.high = ecdf.value;
    if (bootstrap <= 0) return ecdf;

    Rng rng(seed);
    std::vector<std::vector<double>> curves(static_cast<std::size_t>(bootstrap));
    for (auto& curve : curves) {
        for (std::size_t f = 0; f < runs.size(); ++f) {
            std::fill(sums[f].begin(), sums[f].end(), 0.0);
            for (std::size_t i = 0; i < reached[f].size(); ++i) {
                const auto& counts = reached[f][rng.below(reached[f].size())];
                for (std::size_t g = 0; g < grid; ++g) sums[f][g] += counts[g];
            }
        }
        aggregate(sums, curve);
    }
    std::vector<double> at(curves.size());
    for (std::size_t g = 0; g < grid; ++g) {
        for (std::size_t b = 0; b < curves.size(); ++b) at[b] = curves[b][g];
        std::sort(at.begin(), at.end());
        ecdf.low[g] = nearest_rank(at, 0.025);
        ecdf.high[g] = nearest_rank(at, 0.975);
    }
    return ecdf;
}

Document anytime_section(const ExperimentInfo& info, const std::vector<TrialRecord>& records) {
    Document doc;
    if (!info.anytime) return doc;
    const auto& spec = *info.anytime;
    const auto functions = anytime_functions(info);
    const auto runs = anytime_runs(records, spec.targets.size());
    const auto dimensions = dimensions_of(functions);

    doc.add(Heading{2, "Runtime to targets"});
    doc.add(Paragraph{fmt::format("Targets are precisions f - f*; a run reaches one at the first evaluation whose best-so-far is within it. "
                                  "ERT: the evaluations of all runs until they reached the target (all their evaluations when they did not), "
                                  "divided by the runs that reached it, pooled over a function's instances; in brackets the 2.5 and 97.5 "
                                  "percentiles of {} bootstrap resamples of the runs; then runs that reached it / runs (docs/config-reference.md, \"Anytime analysis\").",
                                  spec.bootstrap)});
    for (int d : dimensions) {
        doc.add(Heading{3, fmt::format("ERT, dimension {}", d)});
        std::vector<Column> columns{"function", "optimizer"};
        for (double t : spec.ert_targets) columns.emplace_back("ERT to " + target_text(t));
        Table ert_table(fmt::format("ERT, dimension {}", d), std::move(columns));
        for (const auto& f : functions) {
            if (f.dimension != d) continue;
            for (const auto& o : info.optimizers) {
                std::vector<Cell> row{f.label, o.label};
                for (double t : spec.ert_targets) {
                    const auto index = static_cast<std::size_t>(std::find(spec.targets.begin(), spec.targets.end(), t) - spec.targets.begin());
                    std::vector<RunToTarget> to_target;
                    for (std::size_t p : f.problems)
                        if (auto it = runs.find({o.label, info.problems[p].label}); it != runs.end())
                            for (const auto* r : it->second) to_target.push_back({r->anytime.hits[index], r->evaluations});
                    if (to_target.empty()) {
                        row.emplace_back("–");
                        continue;
                    }
                    const auto ert = expected_running_time(to_target, spec.bootstrap,
                                                           derive_seed(info.seed, o.label, f.label + "/D" + std::to_string(d), index));
                    row.emplace_back(ert.successes == 0 ? fmt::format("inf (0/{})", ert.runs)
                                                        : fmt::format("{} [{}, {}] ({}/{})", evaluations_text(ert.value), evaluations_text(ert.low),
                                                                      evaluations_text(ert.high), ert.successes, ert.runs));
                }
                ert_table.add_row(std::move(row));
            }
        }
        doc.add(std::move(ert_table));
    }

    doc.add(Heading{3, "Runtime ECDF at the end of the budget"});
    doc.add(Paragraph{fmt::format("The fraction of (run, target) pairs reached over the {} "
                                  "targets ({} to {}), averaged over the functions of a dimension, with the 2.5 and 97.5 bootstrap "
                                  "percentiles; the ecdf_D* plots show it against the budget.",
                                  spec.targets.size(), target_text(spec.targets.front()), target_text(spec.targets.back()))});
    Table ecdf_table("runtime ECDF at the end of the budget", {"dimension", "optimizer", "functions", "reached", "95 % interval"});
    for (int d : dimensions) {
        std::vector<const AnytimeFunction*> of_dimension;
        for (const auto& f : functions)
            if (f.dimension == d) of_dimension.push_back(&f);
        for (const auto& o : info.optimizers) {
            const auto hits = hits_by_function(info, of_dimension, o.label, runs);
            std::size_t with_runs = 0;
            for (const auto& h : hits) with_runs += !h.empty();
            if (with_runs == 0) continue;
            // One budget past every run: the fraction reached at the end.
            const auto ecdf = runtime_ecdf(hits, d, {infinity}, spec.bootstrap, derive_seed(info.seed, o.label, "ecdf/D" + std::to_string(d), 0));
            ecdf_table.add_row({std::to_string(d), o.label, std::to_string(with_runs), fmt::format("{:.3f}", ecdf.value[0]),
                                fmt::format("[{:.3f}, {:.3f}]", ecdf.low[0], ecdf.high[0])});
        }
    }
    doc.add(std::move(ecdf_table));
    return doc;
}

void write_ecdf_plots(const fs::path& directory, const fs::path& data_dir, const ExperimentInfo& info,
                      const std::vector<TrialRecord>& records,
                      const std::function<bool(const fs::path&, const std::string&, int, int)>& render) {
    if (!info.anytime) return;
    const auto& spec = *info.anytime;
    const auto functions = anytime_functions(info);
    const auto runs = anytime_runs(records, spec.targets.size());
    const auto dimensions = dimensions_of(functions);
    for (int d : dimensions) {
        std::vector<const AnytimeFunction*> of_dimension;
        std::int64_t longest = 1;  // of this dimension's runs: budgets may scale with the dimension
        for (const auto& f : functions)
            if (f.dimension == d) {
                of_dimension.push_back(&f);
                for (std::size_t p : f.problems)
                    for (const auto& o : info.optimizers)
                        if (auto it = runs.find({o.label, info.problems[p].label}); it != runs.end())
                            for (const auto* r : it->second) longest = std::max(longest, r->evaluations);
            }
        const auto budgets = budget_grid(d, longest);
        const fs::path data = data_dir / fmt::format("ecdf_D{}.dat", d);
        std::ofstream out(data);
        std::string plots;
        for (std::size_t o = 0; o < info.optimizers.size(); ++o) {
            const auto& label = info.optimizers[o].label;
            const auto hits = hits_by_function(info, of_dimension, label, runs);
            out << "# " << label << "\n# evaluations/dimension fraction low high\n";
            bool any = false;
            for (const auto& h : hits) any = any || !h.empty();
            if (any) {
                const auto ecdf = runtime_ecdf(hits, d, budgets, spec.bootstrap, derive_seed(info.seed, label, "ecdf/D" + std::to_string(d), 1));
                for (std::size_t g = 0; g < budgets.size(); ++g)
                    out << fmt::format("{:.6g} {:.6g} {:.6g} {:.6g}\n", budgets[g], ecdf.value[g], ecdf.low[g], ecdf.high[g]);
                plots += fmt::format("{}{} index {} using 1:3:4 with filledcurves fs transparent solid 0.15 noborder {} notitle, "
                                     "'' index {} using 1:2 with lines lw 2 {} title {} noenhanced",
                                     plots.empty() ? "" : ", ", gnuplot_quote(data.string()), o, plot_line_style(o), o, plot_line_style(o),
                                     gnuplot_quote(label));
            }
            out << "\n\n";
        }
        out.close();
        if (plots.empty()) continue;
        std::string body = fmt::format(
            "set title {} noenhanced\nset xlabel 'function evaluations / dimension'\nset ylabel 'fraction of (run, target) pairs'\n",
            gnuplot_quote(fmt::format("Runtime ECDF, dimension {}: {} function(s), {} targets f - f* from {} to {}", d,
                                      of_dimension.size(), spec.targets.size(), target_text(spec.targets.front()),
                                      target_text(spec.targets.back()))));
        body += fmt::format("set xrange [{:.6g}:{:.6g}]\n", budgets.front(), budgets.back());
        body += "set logscale x\nset format x '10^{%L}'\nset yrange [0:1]\nset key outside right top\nset grid\nplot " + plots + "\n";
        render(directory / fmt::format("ecdf_D{}", d), body, 1000, 600);
    }
}

}  // namespace mhb
