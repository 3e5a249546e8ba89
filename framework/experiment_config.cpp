#include "framework/experiment_config.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <functional>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "framework/input_error.hpp"
#include "framework/plugin_loader.hpp"
#include "framework/registry.hpp"

namespace mhb {
namespace {

namespace fs = std::filesystem;

long line_of(const toml::node& node) { return static_cast<long>(node.source().begin.line); }

class ConfigReader {
public:
    explicit ConfigReader(fs::path file) : file_(std::move(file)) {}

    [[noreturn]] void fail(long line, const std::string& field, const std::string& message) const {
        throw InputError(file_.string(), line, field, message);
    }

    ParameterValue scalar(const toml::node& node, const std::string& field) const {
        if (auto v = node.as_boolean()) return v->get();
        if (auto v = node.as_integer()) return std::int64_t{v->get()};
        if (auto v = node.as_floating_point()) return v->get();
        if (auto v = node.as_string()) return v->get();
        fail(line_of(node), field, "expects a boolean, number or string");
    }

    // An integer in [lo, hi]; `why_hi` says what the upper limit protects, for the message.
    std::int64_t integer(const toml::table& t, const char* key, const std::string& field, std::int64_t lo,
                         std::int64_t fallback, long table_line, bool required,
                         std::int64_t hi = std::numeric_limits<std::int64_t>::max(), const char* why_hi = "") const {
        const toml::node* n = t.get(key);
        if (!n) {
            if (required) fail(table_line, field, "is required");
            return fallback;
        }
        auto v = n->as_integer();
        if (!v) fail(line_of(*n), field, "expects an integer");
        if (v->get() < lo) fail(line_of(*n), field, fmt::format("must be >= {} (got {})", lo, v->get()));
        if (v->get() > hi) fail(line_of(*n), field, fmt::format("must be <= {} (got {}){}", hi, v->get(), why_hi));
        return v->get();
    }

    std::string text(const toml::table& t, const char* key, const std::string& field, long table_line,
                     bool required, std::string fallback = {}) const {
        const toml::node* n = t.get(key);
        if (!n) {
            if (required) fail(table_line, field, "is required");
            return fallback;
        }
        auto v = n->as_string();
        if (!v) fail(line_of(*n), field, "expects a string");
        return v->get();
    }

    // [[optimizer]] or [[problem]] entries, each expanded into its grid of variants.
    template <class RegistryT>
    std::vector<PluginVariant> variants(const toml::table& root, const char* key, const char* kind,
                                        const RegistryT& registry) const {
        std::vector<PluginVariant> out;
        const toml::node* node = root.get(key);
        if (!node) fail(0, key, fmt::format("at least one [[{}]] table is required", key));
        const toml::array* list = node->as_array();
        if (!list) fail(line_of(*node), key, fmt::format("must be an array of tables, written [[{}]]", key));
        std::size_t index = 0;
        for (const auto& element : *list) {
            const auto* table = element.as_table();
            const std::string where = fmt::format("{}[{}]", key, index++);
            if (!table) fail(line_of(element), where, "must be a table");
            const long line = line_of(element);
            const std::string name = text(*table, "name", where + ".name", line, true);
            const typename RegistryT::Entry* found = nullptr;
            try {
                found = &registry.at(name, kind);
            } catch (const UnknownPlugin& e) {  // its message lists the registered names
                fail(line_of(*table->get("name")), where + ".name", e.what());
            }
            const auto& entry = *found;
            const std::string label = text(*table, "label", where + ".label", line, false);

            std::vector<std::pair<std::string, std::vector<ParameterValue>>> axes;
            std::vector<double> box_lower, box_upper;
            long box_line = line;
            std::map<std::string, long> key_lines;
            std::vector<std::string> grid_keys;
            for (const auto& [k, v] : *table) {
                const std::string param(k.str());
                if (param == "name" || param == "label") continue;
                const std::string field = where + "." + param;
                if (std::string(kind) == "problem" && (param == "lower" || param == "upper")) {
                    auto& target = param == "lower" ? box_lower : box_upper;
                    box_line = line_of(v);
                    if (const auto* arr = v.as_array()) {
                        for (const auto& item : *arr) {
                            auto d = item.template value<double>();
                            if (!d) fail(line_of(item), field, "expects numbers");
                            target.push_back(*d);
                        }
                    } else if (auto d = v.template value<double>()) {
                        target.push_back(*d);
                    } else {
                        fail(line_of(v), field, "expects a number or a list of numbers");
                    }
                    continue;
                }
                key_lines[param] = line_of(v);
                std::vector<ParameterValue> values;
                if (const auto* arr = v.as_array()) {
                    if (arr->empty()) fail(line_of(v), field, "an empty list gives no variant");
                    for (const auto& item : *arr) values.push_back(scalar(item, field));
                    grid_keys.push_back(param);
                } else {
                    values.push_back(scalar(v, field));
                }
                axes.emplace_back(param, std::move(values));
            }
            std::int64_t grid_size = 1;
            for (const auto& [param, values] : axes) {
                grid_size *= static_cast<std::int64_t>(values.size());
                if (grid_size > max_grid_variants)  // checked per factor, so the product cannot overflow
                    fail(line, where, fmt::format("the lists up to '{}' already expand into {} variants; the limit is {} "
                                                  "per entry (split the entry or shorten the lists)",
                                                  param, grid_size, max_grid_variants));
            }
            for (auto& given : expand_grid(axes)) {
                std::string non_default;
                try {
                    non_default = ParameterSet(entry.parameters, given).non_default_text();
                } catch (const ParameterError& e) {
                    auto it = key_lines.find(e.field());
                    fail(it != key_lines.end() ? it->second : line, where + "." + e.field(), e.message());
                }
                PluginVariant variant;
                variant.name = entry.name;
                variant.line = line;
                std::string suffix;
                for (const auto& g : grid_keys) suffix += (suffix.empty() ? "" : ",") + g + "=" + to_string(given.at(g));
                const std::string base = label.empty() ? entry.name : label;
                if (label.empty() && grid_keys.empty()) {
                    // Without a label, non-default parameters name the variant so two entries of
                    // one optimiser with different settings stay apart.
                    variant.label = non_default.empty() ? base : base + "(" + non_default + ")";
                } else {
                    variant.label = suffix.empty() ? base : base + "(" + suffix + ")";
                }
                variant.values = std::move(given);
                variant.lower = box_lower;
                variant.upper = box_upper;
                variant.bounds_line = box_line;
                out.push_back(std::move(variant));
            }
        }
        std::set<std::string> seen;
        for (const auto& v : out)
            if (!seen.insert(v.label).second)
                fail(v.line, std::string(key) + ".label",
                     fmt::format("two {} variants are both labelled '{}'; give them distinct labels", kind, v.label));
        return out;
    }

    fs::path file_;
};

// A list of target precisions: positive numbers, or "bbob" for COCO's 51.
std::vector<double> read_targets(const ConfigReader& reader, const toml::node& node, const std::string& field) {
    if (const auto* s = node.as_string()) {
        if (s->get() == "bbob") return bbob_targets();
        reader.fail(line_of(node), field, "expects \"bbob\" or a list of f - f* precisions, e.g. [1e1, 1e-1, 1e-3]");
    }
    const auto* list = node.as_array();
    if (!list || list->empty()) reader.fail(line_of(node), field, "expects \"bbob\" or a non-empty list of f - f* precisions");
    std::vector<double> out;
    for (const auto& item : *list) {
        const auto value = item.value<double>();
        if (!value || !(*value > 0) || !std::isfinite(*value))
            reader.fail(line_of(item), field, "expects positive finite numbers (precisions f - f*)");
        out.push_back(*value);
    }
    return out;
}

AnytimeSpec read_anytime(const ConfigReader& reader, const toml::node& node) {
    const auto* table = node.as_table();
    if (!table) reader.fail(line_of(node), "anytime", "must be a table, written [anytime]");
    const long line = line_of(node);
    for (const auto& [k, v] : *table) {
        const std::string key(k.str());
        if (key != "targets" && key != "ert_targets" && key != "points_per_decade" && key != "bootstrap" && key != "iteration_trace" &&
            key != "checkpoints")
            reader.fail(line_of(v), "anytime." + key,
                        "unknown key; expected targets, ert_targets, points_per_decade, bootstrap, iteration_trace or checkpoints");
    }
    AnytimeSpec spec;
    spec.targets = table->get("targets") ? read_targets(reader, *table->get("targets"), "anytime.targets") : bbob_targets();
    std::sort(spec.targets.begin(), spec.targets.end(), std::greater<>());
    spec.targets.erase(std::unique(spec.targets.begin(), spec.targets.end()), spec.targets.end());
    const long targets_line = table->get("targets") ? line_of(*table->get("targets")) : line;
    if (spec.targets.size() > 1000)
        reader.fail(targets_line, "anytime.targets", fmt::format("at most 1000 targets (got {}): each trial records one hit per target", spec.targets.size()));
    // The ERT table's targets are recorded targets, so that each has its hits: matched to within a
    // rounding error (1e-3 in a config against 10^(-15/5) computed).
    const std::vector<double> ert = table->get("ert_targets") ? read_targets(reader, *table->get("ert_targets"), "anytime.ert_targets")
                                                               : std::vector<double>{1e1, 1e-1, 1e-3, 1e-5, 1e-7};
    for (double e : ert) {
        const auto match = std::find_if(spec.targets.begin(), spec.targets.end(),
                                        [e](double t) { return std::abs(t - e) <= 1e-9 * e; });
        if (match == spec.targets.end())
            reader.fail(table->get("ert_targets") ? line_of(*table->get("ert_targets")) : targets_line, "anytime.ert_targets",
                        fmt::format("{:g} is not among anytime.targets; the ERT table shows targets whose hits are recorded", e));
        spec.ert_targets.push_back(*match);
    }
    spec.points_per_decade = static_cast<int>(reader.integer(*table, "points_per_decade", "anytime.points_per_decade", 0, 5, line, false, 100));
    spec.bootstrap = static_cast<int>(reader.integer(*table, "bootstrap", "anytime.bootstrap", 0, 1000, line, false, 100'000,
                                                     ": each resample recomputes every ERT and ECDF"));
    if (const auto* trace = table->get("iteration_trace")) {
        const auto b = trace->as_boolean();
        if (!b) reader.fail(line_of(*trace), "anytime.iteration_trace", "expects true or false");
        spec.iteration_trace = b->get();
    }
    if (const auto* node = table->get("checkpoints")) {
        const char* expected = "expects \"cec2017\", \"cec2022\" or a list of fractions of the evaluation budget in (0, 1], e.g. [0.1, 0.5, 1]";
        if (const auto* name = node->as_string()) {
            if (!set_named_checkpoints(spec, name->get())) reader.fail(line_of(*node), "anytime.checkpoints", expected);
        } else if (const auto* list = node->as_array(); list && !list->empty()) {
            for (const auto& item : *list) {
                const auto value = item.value<double>();
                if (!value || !(*value > 0) || !(*value <= 1)) reader.fail(line_of(item), "anytime.checkpoints", expected);
                spec.checkpoints.push_back(*value);
            }
            if (spec.checkpoints.size() > 1000)
                reader.fail(line_of(*node), "anytime.checkpoints", fmt::format("at most 1000 checkpoints (got {})", spec.checkpoints.size()));
            std::sort(spec.checkpoints.begin(), spec.checkpoints.end());
            spec.checkpoints.erase(std::unique(spec.checkpoints.begin(), spec.checkpoints.end()), spec.checkpoints.end());
        } else {
            reader.fail(line_of(*node), "anytime.checkpoints", expected);
        }
    }
    return spec;
}

}  // namespace

std::int64_t evaluation_budget(const Budget& budget, std::int64_t evaluations_per_dimension,
                               const std::map<int, std::int64_t>& evaluations_by_dimension, int dimension) {
    if (!evaluations_by_dimension.empty()) {
        const auto it = evaluations_by_dimension.find(dimension);
        return it == evaluations_by_dimension.end() ? 0 : it->second;
    }
    if (evaluations_per_dimension > 0) return evaluations_per_dimension * dimension;
    return budget.max_evaluations;
}

std::vector<std::map<std::string, ParameterValue>> expand_grid(
    const std::vector<std::pair<std::string, std::vector<ParameterValue>>>& axes) {
    std::vector<std::map<std::string, ParameterValue>> out{{}};
    for (const auto& [name, values] : axes) {
        std::vector<std::map<std::string, ParameterValue>> next;
        for (const auto& partial : out)
            for (const auto& v : values) {
                auto m = partial;
                m[name] = v;
                next.push_back(std::move(m));
            }
        out = std::move(next);
    }
    return out;
}

ExperimentSpec load_experiment(const fs::path& file, PluginLoading plugins) {
    ConfigReader reader(file);
    std::error_code ec;
    if (fs::is_directory(file, ec)) reader.fail(0, "", "is a directory; expected an experiment TOML file");
    std::ifstream in(file, std::ios::binary);
    if (!in) reader.fail(0, "", std::string("cannot open the experiment file: ") + std::strerror(errno));
    const std::string text((std::istreambuf_iterator<char>(in)), {});
    return parse_experiment(text, file, plugins);
}

ExperimentSpec parse_experiment(const std::string& text, const fs::path& file, PluginLoading plugins) {
    ExperimentSpec spec;
    spec.file = file;
    spec.text = text;
    ConfigReader reader(file);
    if (text.find_first_not_of(" \t\r\n") == std::string::npos)
        reader.fail(0, "", "empty file; an experiment needs trials, seed, [budget], [[optimizer]] and [[problem]] "
                           "(docs/config-reference.md)");
    toml::table root;
    try {
        root = toml::parse(text, file.string());
    } catch (const toml::parse_error& e) {
        reader.fail(static_cast<long>(e.source().begin.line), "", std::string("TOML syntax: ") + std::string(e.description()));
    }
    static const std::set<std::string> known{"name",     "description", "trials",  "seed",  "output",    "budget",  "analysis",
                                             "optimizer", "problem",     "plots",   "published", "plugins", "anytime"};
    for (const auto& [k, v] : root)
        if (!known.count(std::string(k.str())))
            reader.fail(line_of(v), std::string(k.str()),
                        "unknown key; expected one of name, description, trials, seed, output, plots, plugins, "
                        "[budget], [analysis], [anytime], [[optimizer]], [[problem]], [[published]]");
    const fs::path base = fs::absolute(file).parent_path();

    // Before the names are resolved: a plugin may register the optimisers and problems named below.
    if (const auto* list = root.get("plugins")) {
        const auto* array = list->as_array();
        if (!array) reader.fail(line_of(*list), "plugins", "expects a list of plugin library paths, e.g. [\"build/libmy_optimizer.so\"]");
        for (std::size_t i = 0; i < array->size(); ++i) {
            const auto& item = *array->get(i);
            const std::string field = "plugins[" + std::to_string(i) + "]";
            const auto* path = item.as_string();
            if (!path || path->get().empty()) reader.fail(line_of(item), field, "expects a plugin library path (a non-empty string)");
            // Relative to the config, like `output`: the experiment and its plugins travel together.
            const fs::path library = (base / path->get()).lexically_normal();
            spec.plugins.push_back(library);
            if (plugins == PluginLoading::load) {
                try {
                    load_plugin(library);
                } catch (const PluginLoadError& e) {
                    reader.fail(line_of(item), field, e.what());
                }
            }
        }
    }

    spec.name = reader.text(root, "name", "name", 1, false, file.stem().string());
    spec.description = reader.text(root, "description", "description", 1, false);
    spec.trials = reader.integer(root, "trials", "trials", 1, 0, 1, true, max_trials,
                                 ": every trial is a line in results.jsonl and a row in memory for the tables");
    spec.seed = static_cast<std::uint64_t>(reader.integer(root, "seed", "seed", 0, 0, 1, true));
    spec.output = base / reader.text(root, "output", "output", 1, false, "../results/" + spec.name);
    spec.output = spec.output.lexically_normal();
    if (const auto* p = root.get("plots")) {
        auto b = p->as_boolean();
        if (!b) reader.fail(line_of(*p), "plots", "expects true or false");
        spec.plots = b->get();
    }

    const toml::node* budget = root.get("budget");
    if (!budget || !budget->as_table()) reader.fail(budget ? line_of(*budget) : 0, "budget",
                                                    "a [budget] table with iterations and/or evaluations is required");
    const auto& bt = *budget->as_table();
    for (const auto& [k, v] : bt)
        if (k.str() != "iterations" && k.str() != "evaluations" && k.str() != "evaluations_per_dimension" &&
            k.str() != "evaluations_by_dimension")
            reader.fail(line_of(v), "budget." + std::string(k.str()),
                        "unknown key; expected iterations, evaluations, evaluations_per_dimension or evaluations_by_dimension");
    const char* trace_cost = ": each iteration adds an entry to the trial's convergence trace, held in memory and written "
                             "to results.jsonl";
    spec.budget.max_iterations =
        reader.integer(bt, "iterations", "budget.iterations", 1, 0, line_of(*budget), false, max_budget_iterations, trace_cost);
    spec.budget.max_evaluations = reader.integer(bt, "evaluations", "budget.evaluations", 1, 0, line_of(*budget), false,
                                                 max_budget_evaluations, trace_cost);
    spec.evaluations_per_dimension = reader.integer(bt, "evaluations_per_dimension", "budget.evaluations_per_dimension", 1, 0,
                                                    line_of(*budget), false, max_budget_evaluations / 100,
                                                    ": times a dimension of up to 100 it must stay within the evaluation limit");
    if (spec.evaluations_per_dimension > 0 && spec.budget.max_evaluations > 0)
        reader.fail(line_of(*bt.get("evaluations_per_dimension")), "budget.evaluations_per_dimension",
                    "set evaluations or evaluations_per_dimension, not both");
    if (const auto* node = bt.get("evaluations_by_dimension")) {
        const std::string field = "budget.evaluations_by_dimension";
        spec.evaluations_by_dimension_line = line_of(*node);
        const auto* table = node->as_table();
        if (!table || table->empty())
            reader.fail(line_of(*node), field, "expects a table of dimension = evaluations, e.g. { 10 = 200000, 20 = 1000000 }");
        if (spec.budget.max_evaluations > 0 || spec.evaluations_per_dimension > 0)
            reader.fail(line_of(*node), field, "set one of evaluations, evaluations_per_dimension and evaluations_by_dimension");
        for (const auto& [k, v] : *table) {
            const std::string key(k.str());
            int dimension = 0;
            const auto parsed = std::from_chars(key.data(), key.data() + key.size(), dimension);
            if (parsed.ec != std::errc() || parsed.ptr != key.data() + key.size() || dimension < 1)
                reader.fail(line_of(v), field + "." + key, "a key must be a dimension (a whole number >= 1)");
            const auto value = v.as_integer();
            if (!value || value->get() < 1 || value->get() > max_budget_evaluations)
                reader.fail(line_of(v), field + "." + key, fmt::format("expects a whole number of evaluations from 1 to {}", max_budget_evaluations));
            spec.evaluations_by_dimension[dimension] = value->get();
        }
    }
    if (spec.budget.max_iterations == 0 && spec.budget.max_evaluations == 0 && spec.evaluations_per_dimension == 0 &&
        spec.evaluations_by_dimension.empty())
        reader.fail(line_of(*budget), "budget",
                    "set iterations, evaluations or both (evaluations_per_dimension or evaluations_by_dimension in place of evaluations)");

    spec.optimizers = reader.variants(root, "optimizer", "optimizer", OptimizerRegistry::instance());
    spec.problems = reader.variants(root, "problem", "problem", ProblemRegistry::instance());

    if (const auto* node = root.get("anytime")) {
        spec.anytime = read_anytime(reader, *node);
        const bool evaluation_budget_given =
            spec.budget.max_evaluations > 0 || spec.evaluations_per_dimension > 0 || !spec.evaluations_by_dimension.empty();
        if ((!spec.anytime->checkpoints.empty() || !spec.anytime->checkpoint_exponents.empty()) && !evaluation_budget_given)
            reader.fail(line_of(*node->as_table()->get("checkpoints")), "anytime.checkpoints",
                        "are fractions of the evaluation budget: set budget.evaluations, evaluations_per_dimension or evaluations_by_dimension");
    }

    spec.baseline = spec.optimizers.front().label;
    spec.references.clear();
    if (const auto* analysis = root.get("analysis")) {
        const auto* at = analysis->as_table();
        if (!at) reader.fail(line_of(*analysis), "analysis", "must be a table");
        auto known_label = [&](const std::string& label, const toml::node& where, const std::string& field) {
            for (const auto& o : spec.optimizers)
                if (o.label == label) return;
            std::string labels;
            for (const auto& o : spec.optimizers) labels += (labels.empty() ? "" : ", ") + o.label;
            reader.fail(line_of(where), field, fmt::format("'{}' is not an optimizer label here; labels: {}", label, labels));
        };
        for (const auto& [k, v] : *at) {
            const std::string key(k.str());
            if (key == "baseline") {
                auto s = v.as_string();
                if (!s) reader.fail(line_of(v), "analysis.baseline", "expects a string");
                known_label(s->get(), v, "analysis.baseline");
                spec.baseline = s->get();
            } else if (key == "references") {
                auto arr = v.as_array();
                if (!arr) reader.fail(line_of(v), "analysis.references", "expects a list of optimizer labels");
                for (const auto& item : *arr) {
                    auto s = item.as_string();
                    if (!s) reader.fail(line_of(item), "analysis.references", "expects strings");
                    known_label(s->get(), item, "analysis.references");
                    spec.references.push_back(s->get());
                }
            } else if (key == "error_threshold") {
                const auto d = v.value<double>();
                if (!d || !(*d >= 0) || !std::isfinite(*d))
                    reader.fail(line_of(v), "analysis.error_threshold",
                                "expects a number >= 0: errors f - f* below it are reported as 0 (the CEC rule is 1e-8)");
                spec.error_threshold = *d;
                spec.error_threshold_line = line_of(v);
            } else if (key == "per_problem") {
                auto b = v.as_boolean();
                if (!b) reader.fail(line_of(v), "analysis.per_problem", "expects true or false");
                spec.per_problem = b->get();
            } else {
                reader.fail(line_of(v), "analysis." + key, "unknown key; expected baseline, references, error_threshold or per_problem");
            }
        }
    }
    if (spec.references.empty()) spec.references.push_back(spec.baseline);

    if (const auto* node = root.get("published")) {
        const auto* arr = node->as_array();
        if (!arr) reader.fail(line_of(*node), "published", "must be an array of tables, written [[published]]");
        std::size_t index = 0;
        for (const auto& el : *arr) {
            const std::string where = fmt::format("published[{}]", index++);
            const auto* t = el.as_table();
            if (!t) reader.fail(line_of(el), where, "must be a table");
            PublishedResult r;
            r.line = line_of(el);
            r.label = reader.text(*t, "label", where + ".label", r.line, true);
            r.problem = reader.text(*t, "problem", where + ".problem", r.line, true);
            r.source = reader.text(*t, "source", where + ".source", r.line, true);
            bool known_problem = false;
            for (const auto& p : spec.problems) known_problem = known_problem || p.label == r.problem;
            if (!known_problem) reader.fail(r.line, where + ".problem", "'" + r.problem + "' is not a problem label of this experiment");
            for (const auto& [k, v] : *t) {
                const std::string key(k.str()), field = where + "." + key;
                if (key == "label" || key == "problem" || key == "source") continue;
                if (key == "mean" || key == "std") {
                    const auto* values = v.as_table();
                    if (!values) reader.fail(line_of(v), field, "expects a table of parameter = number");
                    for (const auto& [pk, pv] : *values) {
                        auto d = pv.value<double>();
                        if (!d) reader.fail(line_of(pv), field + "." + std::string(pk.str()), "expects a number");
                        (key == "mean" ? r.mean : r.sd)[std::string(pk.str())] = *d;
                    }
                } else if (key == "fitness_mean" || key == "fitness_std" || key == "time_total") {
                    auto d = v.value<double>();
                    if (!d) reader.fail(line_of(v), field, "expects a number");
                    (key == "fitness_mean" ? r.fitness_mean : key == "fitness_std" ? r.fitness_sd : r.time_total) = *d;
                } else {
                    reader.fail(line_of(v), field, "unknown key; expected label, problem, source, mean, std, fitness_mean, fitness_std, time_total");
                }
            }
            spec.published.push_back(std::move(r));
        }
    }
    return spec;
}

}  // namespace mhb
