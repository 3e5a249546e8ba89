#include "framework/shard_merge.hpp"

#include <algorithm>
#include <map>
#include <tuple>

#include <fmt/format.h>

#include "framework/file_output.hpp"
#include "framework/input_error.hpp"

namespace mhb {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// The experiment as it decides the trials: everything but where and how the run went, and the config's
// text (a comment edited between two shards' runs changes no trial; the settings it gives are compared).
json experiment_identity(const ExperimentInfo& info) {
    json j = to_json(info);
    for (const char* key : {"config_file", "config_text", "runs", "shard"}) j.erase(key);
    return j;
}

// The first key whose value differs between two experiment.json objects, for the message.
std::string first_difference(const json& a, const json& b) {
    for (const auto& [key, value] : a.items())
        if (!b.contains(key) || b[key] != value) return key;
    for (const auto& [key, value] : b.items())
        if (!a.contains(key)) return key;
    return "";
}

std::string shard_text(const ExperimentInfo& info) {
    return info.shard ? fmt::format("shard {} of {}", info.shard->index, info.shard->count) : std::string("not a shard");
}

}  // namespace

fs::path default_merge_output(const std::vector<fs::path>& shards) {
    const fs::path parent = fs::absolute(shards.front()).lexically_normal().parent_path();
    for (const auto& s : shards)
        if (fs::absolute(s).lexically_normal().parent_path() != parent)
            throw InputError("command line", 0, "--out",
                             fmt::format("{} and {} are not in one directory, so there is no default output; give --out DIR",
                                         shards.front().string(), s.string()));
    return parent;
}

MergeSummary merge_shards(const std::vector<fs::path>& shards, const fs::path& output) {
    if (shards.empty()) throw InputError("command line", 0, "DIR", "name the shard directories to merge");
    MergeSummary summary;
    summary.output = output;
    std::error_code ec;
    if (fs::file_size(output / "results.jsonl", ec) > 0 && !ec)
        throw InputError((output / "results.jsonl").string(), 0, "--out",
                         "already holds results; merge into an empty directory (another --out), so no run is overwritten");

    std::vector<ExperimentInfo> infos;
    for (const auto& dir : shards) infos.push_back(read_experiment_info(dir));
    const json identity = experiment_identity(infos.front());
    for (std::size_t i = 1; i < infos.size(); ++i) {
        const json other = experiment_identity(infos[i]);
        if (other != identity)
            throw InputError((shards[i] / "experiment.json").string(), 0, first_difference(identity, other),
                             fmt::format("differs from {}: these directories hold different experiments",
                                         (shards.front() / "experiment.json").string()));
        if (infos[i].config_text != infos.front().config_text)
            summary.notes.push_back(fmt::format("the config's text differs between {} and {} though every setting of the "
                                                "trials agrees; the merged experiment.json keeps the first",
                                                shards.front().string(), shards[i].string()));
    }
    // The same shard twice, or shards of different counts: said before the trials would show it.
    for (std::size_t i = 0; i < infos.size(); ++i)
        for (std::size_t j = i + 1; j < infos.size(); ++j) {
            if (fs::equivalent(shards[i], shards[j], ec))
                throw InputError("command line", 0, "DIR", fmt::format("{} is named twice", shards[j].string()));
            if (infos[i].shard && infos[i].shard == infos[j].shard)
                throw InputError("command line", 0, "DIR",
                                 fmt::format("{} and {} are both {}: the same share run twice; merge one of them",
                                             shards[i].string(), shards[j].string(), shard_text(infos[i])));
            if (infos[i].shard && infos[j].shard && infos[i].shard->count != infos[j].shard->count)
                throw InputError("command line", 0, "DIR",
                                 fmt::format("{} is {} but {} is {}: shards of different counts overlap and leave gaps; "
                                             "merge the shards of one --shard K/N division",
                                             shards[i].string(), shard_text(infos[i]), shards[j].string(), shard_text(infos[j])));
        }

    const ExperimentInfo& info = infos.front();
    std::map<std::string, std::size_t> optimizer_index, problem_index;
    for (std::size_t o = 0; o < info.optimizers.size(); ++o) optimizer_index[info.optimizers[o].label] = o;
    for (std::size_t p = 0; p < info.problems.size(); ++p) problem_index[info.problems[p].label] = p;
    const auto position = [&](std::size_t p, std::size_t o, std::int64_t t) {
        return (static_cast<std::int64_t>(p) * static_cast<std::int64_t>(info.optimizers.size()) + static_cast<std::int64_t>(o)) *
                   info.trials + t;
    };
    const std::int64_t total = position(info.problems.size(), 0, 0);
    std::vector<TrialRecord> records(static_cast<std::size_t>(total));
    std::vector<int> source(static_cast<std::size_t>(total), -1);  // which directory each trial came from

    for (std::size_t d = 0; d < shards.size(); ++d) {
        const fs::path path = shards[d] / "results.jsonl";
        auto loaded = read_results(path);
        for (const auto& note : loaded.notes) summary.notes.push_back(path.string() + ": " + note);
        for (auto& r : loaded.records) {
            const auto o = optimizer_index.find(r.optimizer), p = problem_index.find(r.problem);
            if (o == optimizer_index.end() || p == problem_index.end() || r.trial < 0 || r.trial >= info.trials)
                throw InputError(path.string(), 0, "",
                                 fmt::format("holds trial {} of '{}' on '{}', which the experiment does not have", r.trial,
                                             r.optimizer, r.problem));
            const auto k = static_cast<std::size_t>(position(p->second, o->second, r.trial));
            if (source[k] >= 0)
                throw InputError(path.string(), 0, "",
                                 fmt::format("trial {} of '{}' on '{}' is also in {}: the directories overlap (one shard "
                                             "named twice, or a directory that is not a shard)",
                                             r.trial, r.optimizer, r.problem, (shards[static_cast<std::size_t>(source[k])] / "results.jsonl").string()));
            source[k] = static_cast<int>(d);
            records[k] = std::move(r);
        }
    }

    std::vector<std::size_t> missing;
    for (std::size_t k = 0; k < source.size(); ++k)
        if (source[k] < 0) missing.push_back(k);
    if (!missing.empty()) {
        const auto k = static_cast<std::int64_t>(missing.front());
        const auto t = k % info.trials, o = (k / info.trials) % static_cast<std::int64_t>(info.optimizers.size()),
                   p = k / info.trials / static_cast<std::int64_t>(info.optimizers.size());
        std::string where;
        if (info.shard) where = fmt::format(" (it belongs to shard {} of {})", k % info.shard->count + 1, info.shard->count);
        throw InputError("command line", 0, "DIR",
                         fmt::format("{} of the experiment's {} trials are in none of the directories, the first: trial {} of "
                                     "'{}' on '{}'{}; run the missing shards (or finish one with --resume) and merge again",
                                     missing.size(), total, t, info.optimizers[static_cast<std::size_t>(o)].label,
                                     info.problems[static_cast<std::size_t>(p)].label, where));
    }

    summary.info = info;
    summary.info.shard.reset();
    summary.info.runs.clear();
    for (const auto& i : infos) summary.info.runs.insert(summary.info.runs.end(), i.runs.begin(), i.runs.end());
    fs::create_directories(output, ec);
    if (ec || !fs::is_directory(output))
        throw InputError(output.string(), 0, "--out", "cannot create the output directory: " + (ec ? ec.message() : std::string("not a directory")));
    // experiment.json first: a kill between the two leaves no results.jsonl, so merging again proceeds.
    // The results are one file written whole and renamed: all of them or none.
    write_experiment_info(output, summary.info);
    std::string text;
    for (const auto& r : records) text += to_json(r).dump() + "\n";
    replace_file(output / "results.jsonl", text);
    summary.records = records.size();
    return summary;
}

}  // namespace mhb
