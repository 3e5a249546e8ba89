#include "framework/results_store.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <optional>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "framework/file_output.hpp"
#include "framework/input_error.hpp"

namespace mhb {
namespace {

using nlohmann::json;

// JSON has no infinity or NaN; they are written as strings so that nothing is lost.
json number(double v) {
    if (std::isfinite(v)) return v;
    if (std::isnan(v)) return "nan";
    return v > 0 ? "inf" : "-inf";
}
double number_from(const json& j) {
    if (j.is_number()) return j.get<double>();
    const auto s = j.get<std::string>();
    if (s == "inf") return std::numeric_limits<double>::infinity();
    if (s == "-inf") return -std::numeric_limits<double>::infinity();
    return std::nan("");
}
json vector_json(const Vector& v) {
    json a = json::array();
    for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(number(v[i]));
    return a;
}
Vector vector_from(const json& j) {
    Vector v(static_cast<Eigen::Index>(j.size()));
    for (std::size_t i = 0; i < j.size(); ++i) v[static_cast<Eigen::Index>(i)] = number_from(j[i]);
    return v;
}
json value_json(const ParameterValue& v) {
    return std::visit([](const auto& x) -> json { return x; }, v);
}
ParameterValue value_from(const json& j) {
    if (j.is_boolean()) return j.get<bool>();
    if (j.is_number_integer()) return j.get<std::int64_t>();
    if (j.is_number()) return j.get<double>();
    return j.get<std::string>();
}
json parameters_json(const std::map<std::string, ParameterValue>& values) {
    json params = json::object();
    for (const auto& [k, x] : values) params[k] = value_json(x);
    return params;
}
std::map<std::string, ParameterValue> parameters_from(const json& j) {
    std::map<std::string, ParameterValue> values;
    for (const auto& [k, x] : j.items()) values[k] = value_from(x);
    return values;
}
json variant_json(const PluginVariant& v) {
    return {{"label", v.label}, {"name", v.name}, {"parameters", parameters_json(v.values)}};
}
PluginVariant variant_from(const json& j) {
    PluginVariant v;
    v.label = j.at("label");
    v.name = j.at("name");
    v.values = parameters_from(j.at("parameters"));
    return v;
}
template <class T>
json optional_json(const std::optional<T>& o) {
    if (!o) return nullptr;
    if constexpr (std::is_same_v<T, Vector>) return vector_json(*o);
    else return number(*o);
}

json published_json(const std::vector<PublishedResult>& published) {
    json out = json::array();
    for (const auto& p : published) {
        json o{{"label", p.label}, {"problem", p.problem}, {"source", p.source}, {"mean", p.mean}, {"std", p.sd}};
        o["fitness_mean"] = p.fitness_mean ? json(*p.fitness_mean) : json(nullptr);
        o["fitness_std"] = p.fitness_sd ? json(*p.fitness_sd) : json(nullptr);
        o["time_total"] = p.time_total ? json(*p.time_total) : json(nullptr);
        out.push_back(std::move(o));
    }
    return out;
}
std::vector<PublishedResult> published_from(const json& j) {
    std::vector<PublishedResult> out;
    for (const auto& o : j) {
        PublishedResult p;
        p.label = o.at("label");
        p.problem = o.at("problem");
        p.source = o.at("source");
        p.mean = o.at("mean").get<std::map<std::string, double>>();
        p.sd = o.at("std").get<std::map<std::string, double>>();
        if (!o.at("fitness_mean").is_null()) p.fitness_mean = o["fitness_mean"].get<double>();
        if (!o.at("fitness_std").is_null()) p.fitness_sd = o["fitness_std"].get<double>();
        if (!o.at("time_total").is_null()) p.time_total = o["time_total"].get<double>();
        out.push_back(std::move(p));
    }
    return out;
}

json provenance_json(const Provenance& p) {
    return {{"mhbench_version", p.version}, {"commit", p.commit},
            {"started", p.date},            {"host", p.host},
            {"system", p.system},           {"hardware_threads", p.hardware_threads},
            {"threads", p.threads},         {"ranks", p.ranks}};
}
Provenance provenance_from(const json& j) {
    Provenance p;
    p.version = j.at("mhbench_version");
    p.commit = j.at("commit");
    p.date = j.at("started");
    p.host = j.at("host");
    p.system = j.at("system");
    p.hardware_threads = j.at("hardware_threads");
    p.threads = j.at("threads");
    p.ranks = j.value("ranks", 1);
    return p;
}

}  // namespace

json to_json(const TrialRecord& r) {
    json j{{"optimizer", r.optimizer},
           {"problem", r.problem},
           {"trial", r.trial},
           {"seed", r.seed},
           {"status", r.ok ? "ok" : "failed"},
           {"best_fitness", number(r.best_fitness)},
           {"best_position", vector_json(r.best_position)},
           {"evaluations", r.evaluations},
           {"iterations", r.iterations},
           {"seconds", r.seconds}};
    if (!r.ok) j["error"] = r.error;
    json trace{{"evaluations", r.trace_evaluations}, {"best", json::array()}};
    for (double b : r.trace_best) trace["best"].push_back(number(b));
    if (!r.trace_position.empty()) {
        json positions = json::array();
        for (const auto& p : r.trace_position) positions.push_back(vector_json(p));
        trace["position"] = std::move(positions);
    }
    j["trace"] = std::move(trace);
    if (!r.anytime.empty()) {
        json best = json::array(), hit_best = json::array();
        for (double b : r.anytime.best) best.push_back(number(b));
        for (double b : r.anytime.hit_best) hit_best.push_back(number(b));
        j["anytime"] = {{"evaluations", r.anytime.evaluations}, {"best", best}, {"hits", r.anytime.hits}, {"hit_best", hit_best}};
        if (!r.anytime.checkpoint_evaluations.empty()) {
            json checkpoint_best = json::array();
            for (double b : r.anytime.checkpoint_best) checkpoint_best.push_back(number(b));
            j["anytime"]["checkpoints"] = {{"evaluations", r.anytime.checkpoint_evaluations}, {"best", checkpoint_best}};
        }
    }
    return j;
}

TrialRecord trial_from_json(const json& j) {
    TrialRecord r;
    r.optimizer = j.at("optimizer");
    r.problem = j.at("problem");
    r.trial = j.at("trial");
    r.seed = j.at("seed");
    r.ok = j.at("status") == "ok";
    if (j.contains("error")) r.error = j["error"];
    r.best_fitness = number_from(j.at("best_fitness"));
    r.best_position = vector_from(j.at("best_position"));
    r.evaluations = j.at("evaluations");
    r.iterations = j.at("iterations");
    r.seconds = j.at("seconds");
    const auto& t = j.at("trace");
    r.trace_evaluations = t.at("evaluations").get<std::vector<std::int64_t>>();
    for (const auto& b : t.at("best")) r.trace_best.push_back(number_from(b));
    if (t.contains("position"))
        for (const auto& p : t["position"]) r.trace_position.push_back(vector_from(p));
    if (j.contains("anytime")) {
        const auto& a = j["anytime"];
        r.anytime.evaluations = a.at("evaluations").get<std::vector<std::int64_t>>();
        for (const auto& b : a.at("best")) r.anytime.best.push_back(number_from(b));
        r.anytime.hits = a.at("hits").get<std::vector<std::int64_t>>();
        for (const auto& b : a.at("hit_best")) r.anytime.hit_best.push_back(number_from(b));
        if (a.contains("checkpoints")) {
            r.anytime.checkpoint_evaluations = a["checkpoints"].at("evaluations").get<std::vector<std::int64_t>>();
            for (const auto& b : a["checkpoints"].at("best")) r.anytime.checkpoint_best.push_back(number_from(b));
            if (r.anytime.checkpoint_best.size() != r.anytime.checkpoint_evaluations.size())
                throw std::invalid_argument("anytime: the checkpoints' evaluations and best differ in length");
        }
        if (r.anytime.best.size() != r.anytime.evaluations.size() || r.anytime.hit_best.size() != r.anytime.hits.size())
            throw std::invalid_argument("anytime: evaluations and best, or hits and hit_best, differ in length");
    }
    return r;
}

json to_json(const ExperimentInfo& info) {
    json optimizers = json::array(), problems = json::array();
    for (const auto& o : info.optimizers) optimizers.push_back(variant_json(o));
    for (const auto& p : info.problems) {
        problems.push_back({{"label", p.label},
                            {"name", p.name},
                            {"dimension", p.dimension},
                            {"parameter_names", p.parameter_names},
                            {"named_parameters", p.named_parameters},
                            {"description", p.description},
                            {"optimum_value", optional_json(p.truth.optimum_value)},
                            {"true_parameters", optional_json(p.truth.true_parameters)},
                            {"reference_solution", optional_json(p.truth.reference_solution)},
                            {"reference_fitness", optional_json(p.truth.reference_fitness)},
                            {"reference_label", p.truth.reference_label},
                            {"parameters", parameters_json(p.parameters)},
                            {"lower", p.lower},
                            {"upper", p.upper}});
    }
    json runs = json::array();
    for (const auto& r : info.runs) runs.push_back(provenance_json(r));
    json out = {{"name", info.name},
            {"description", info.description},
            {"config_file", info.config_file},
            {"config_text", info.config_text},
            {"runs", runs},
            {"trials", info.trials},
            {"seed", info.seed},
            {"budget", {{"iterations", info.budget.max_iterations}, {"evaluations", info.budget.max_evaluations}}},
            {"optimizers", optimizers},
            {"problems", problems},
            {"baseline", info.baseline},
            {"references", info.references},
            {"plots", info.plots},
            {"per_problem", info.per_problem},
            {"published", published_json(info.published)}};
    if (info.shard) out["shard"] = {{"index", info.shard->index}, {"count", info.shard->count}};
    if (info.evaluations_per_dimension > 0) out["budget"]["evaluations_per_dimension"] = info.evaluations_per_dimension;
    if (!info.evaluations_by_dimension.empty()) {
        json by_dimension = json::object();
        for (const auto& [d, e] : info.evaluations_by_dimension) by_dimension[std::to_string(d)] = e;
        out["budget"]["evaluations_by_dimension"] = by_dimension;
    }
    if (info.error_threshold > 0) out["error_threshold"] = info.error_threshold;
    if (info.selected_dimension > 0) out["selected_dimension"] = info.selected_dimension;
    if (info.anytime)
        out["anytime"] = {{"targets", info.anytime->targets},
                          {"ert_targets", info.anytime->ert_targets},
                          {"points_per_decade", info.anytime->points_per_decade},
                          {"bootstrap", info.anytime->bootstrap},
                          {"iteration_trace", info.anytime->iteration_trace}};
    if (info.anytime && (!info.anytime->checkpoints.empty() || !info.anytime->checkpoint_exponents.empty()))
        out["anytime"]["checkpoints"] = {{"fractions", info.anytime->checkpoints},
                                         {"rule", info.anytime->checkpoints_rule},
                                         {"dimension_exponents", info.anytime->checkpoint_exponents}};
    return out;
}

ExperimentInfo experiment_from_json(const json& j) {
    ExperimentInfo info;
    info.name = j.at("name");
    info.description = j.value("description", "");
    info.config_file = j.value("config_file", "");
    info.config_text = j.value("config_text", "");
    if (j.contains("runs"))
        for (const auto& r : j["runs"]) info.runs.push_back(provenance_from(r));
    if (j.contains("shard")) {
        info.shard = Shard{j["shard"].at("index").get<std::int64_t>(), j["shard"].at("count").get<std::int64_t>()};
        if (info.shard->count < 1 || info.shard->index < 1 || info.shard->index > info.shard->count)
            throw std::invalid_argument(fmt::format("shard: index {} of count {} is not a share (1 <= index <= count)",
                                                    info.shard->index, info.shard->count));
    }
    if (j.contains("anytime")) {
        const auto& a = j["anytime"];
        AnytimeSpec spec;
        spec.targets = a.at("targets").get<std::vector<double>>();
        spec.ert_targets = a.at("ert_targets").get<std::vector<double>>();
        spec.points_per_decade = a.at("points_per_decade").get<int>();
        spec.bootstrap = a.at("bootstrap").get<int>();
        spec.iteration_trace = a.value("iteration_trace", true);
        info.anytime = std::move(spec);
        if (a.contains("checkpoints")) {
            const auto& c = a["checkpoints"];
            info.anytime->checkpoints = c.at("fractions").get<std::vector<double>>();
            info.anytime->checkpoints_rule = c.value("rule", "");
            info.anytime->checkpoint_exponents = c.value("dimension_exponents", std::vector<double>{});
        }
    }
    info.trials = j.at("trials");
    info.seed = j.at("seed");
    info.budget.max_iterations = j.at("budget").at("iterations");
    info.budget.max_evaluations = j.at("budget").at("evaluations");
    info.evaluations_per_dimension = j.at("budget").value("evaluations_per_dimension", std::int64_t{0});
    if (j.at("budget").contains("evaluations_by_dimension"))
        for (const auto& [d, e] : j["budget"]["evaluations_by_dimension"].items()) info.evaluations_by_dimension[std::stoi(d)] = e.get<std::int64_t>();
    info.error_threshold = j.value("error_threshold", 0.0);
    info.selected_dimension = j.value("selected_dimension", 0);
    for (const auto& o : j.at("optimizers")) info.optimizers.push_back(variant_from(o));
    for (const auto& p : j.at("problems")) {
        ProblemInfo pi;
        pi.label = p.at("label");
        pi.name = p.at("name");
        pi.dimension = p.at("dimension");
        pi.parameter_names = p.at("parameter_names").get<std::vector<std::string>>();
        pi.named_parameters = p.value("named_parameters", false);
        pi.description = p.value("description", "");
        if (!p.at("optimum_value").is_null()) pi.truth.optimum_value = number_from(p["optimum_value"]);
        if (!p.at("true_parameters").is_null()) pi.truth.true_parameters = vector_from(p["true_parameters"]);
        if (!p.at("reference_solution").is_null()) pi.truth.reference_solution = vector_from(p["reference_solution"]);
        if (!p.at("reference_fitness").is_null()) pi.truth.reference_fitness = number_from(p["reference_fitness"]);
        pi.truth.reference_label = p.value("reference_label", "");
        pi.settings_recorded = p.contains("parameters");
        if (pi.settings_recorded) {
            pi.parameters = parameters_from(p["parameters"]);
            pi.lower = p.value("lower", std::vector<double>{});
            pi.upper = p.value("upper", std::vector<double>{});
        }
        info.problems.push_back(std::move(pi));
    }
    info.baseline = j.at("baseline");
    info.references = j.at("references").get<std::vector<std::string>>();
    info.plots = j.value("plots", true);
    info.per_problem = j.value("per_problem", true);
    if (j.contains("published")) info.published = published_from(j["published"]);
    return info;
}

ResultsWriter::ResultsWriter(const std::filesystem::path& path) : path_(path) {
    std::error_code ec;
    std::filesystem::create_directories(path.parent_path(), ec);
    out_.open(path, std::ios::app);
    if (!out_)
        throw InputError(path.parent_path().string(), 0, "output",
                         "cannot write here (" + (ec ? ec.message() : std::string("permission denied or not a directory")) +
                             "); choose another directory with --out");
}

void ResultsWriter::append(const TrialRecord& record, std::vector<TrialRecord>* kept) {
    const std::string line = to_json(record).dump() + "\n";
    std::lock_guard lock(mutex_);
    if (!out_) throw InputError(path_.string(), 0, "", failure_.empty() ? std::string("an earlier write to this file failed") : failure_);
    errno = 0;
    out_ << line;
    out_.flush();
    if (!out_) {
        failure_ = fmt::format("writing a trial record failed ({}); the records before it are kept: make room, then run again with --resume",
                               errno ? std::strerror(errno) : "disk full?");
        throw InputError(path_.string(), 0, "", failure_);
    }
    if (kept) kept->push_back(record);
}

LoadedResults read_results(const std::filesystem::path& path) {
    LoadedResults out;
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) {
        if (ec) throw InputError(path.string(), 0, "", "cannot read the results: " + ec.message());
        return out;
    }
    std::ifstream in(path);
    if (!in) throw InputError(path.string(), 0, "", std::string("cannot read the results: ") + std::strerror(errno));
    std::string line;
    long number = 0;
    std::vector<std::pair<long, std::string>> lines;
    while (std::getline(in, line)) {
        ++number;
        if (!line.empty()) lines.emplace_back(number, line);
    }
    // Lines are independent records, so they are parsed in parallel (parsing is most of the time of
    // `run`'s tables on small experiments); what a bad line means is decided afterwards, in file order.
    std::vector<std::optional<TrialRecord>> parsed(lines.size());
    std::vector<std::string> errors(lines.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lines.size()), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            try {
                parsed[i] = trial_from_json(json::parse(lines[i].second));
            } catch (const std::exception& e) {
                errors[i] = e.what();
            }
        }
    });
    out.records.reserve(lines.size());
    for (std::size_t i = 0; i < lines.size(); ++i) {
        if (parsed[i]) {
            out.records.push_back(std::move(*parsed[i]));
            continue;
        }
        if (i + 1 == lines.size()) {
            out.notes.push_back(fmt::format("{}:{}: ignored an incomplete last line (an interrupted write)",
                                            path.string(), lines[i].first));
            continue;
        }
        throw InputError(path.string(), lines[i].first, "", std::string("not a trial record: ") + errors[i]);
    }
    return out;
}

ExperimentInfo read_experiment_info(const std::filesystem::path& directory) {
    const auto path = directory / "experiment.json";
    std::ifstream in(path);
    if (!in) throw InputError(path.string(), 0, "", "missing: is this an mhbench results directory?");
    try {
        return experiment_from_json(json::parse(in));
    } catch (const json::exception& e) {
        throw InputError(path.string(), 0, "", std::string("unreadable: ") + e.what());
    } catch (const std::invalid_argument& e) {
        throw InputError(path.string(), 0, "", std::string("unreadable: ") + e.what());
    }
}

void write_experiment_info(const std::filesystem::path& directory, const ExperimentInfo& info) {
    replace_file(directory / "experiment.json", to_json(info).dump(2) + "\n");
}

}  // namespace mhb
