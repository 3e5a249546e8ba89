#pragma once
// `mhbench merge`: joins the directories of an experiment's shards (`mhbench run --shard K/N`, e.g. the
// tasks of a scheduler's job array) into one results directory that holds what a single run would:
// every trial exactly once, in the fixed trial order.
#include <filesystem>
#include <string>
#include <vector>

#include "framework/results_store.hpp"

namespace mhb {

struct MergeSummary {
    std::filesystem::path output;
    ExperimentInfo info;       // the experiment, no longer a shard; `runs` lists every shard's runs
    std::size_t records = 0;   // trials written
    std::vector<std::string> notes;
};

// Reads every directory's experiment.json and results.jsonl and writes output/experiment.json and
// output/results.jsonl. InputError, naming the directories, when they hold different experiments, when
// a trial is in two of them (shards of different N, or one shard twice), when one is not a trial of
// the experiment, or when trials are missing (a shard not run or not finished): nothing is written then.
// `output` must not hold results yet.
MergeSummary merge_shards(const std::vector<std::filesystem::path>& shards, const std::filesystem::path& output);

// Where merge writes by default: the directory the shards share (the experiment's output when they
// were written to shard-K-of-N under it). InputError when they have no common parent.
std::filesystem::path default_merge_output(const std::vector<std::filesystem::path>& shards);

}  // namespace mhb
