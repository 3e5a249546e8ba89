#pragma once
// `mpirun -np N mhbench run FILE`: the trials spread over N processes, each running its share on its
// own TBB threads. Built only when Open MPI and Boost.MPI are installed (MHBENCH_WITH_MPI), as a
// library of its own.
//
// Rank 0 prepares the output as a single run would (resume checks, earlier runs kept aside,
// experiment.json with `ranks` and `threads`). Rank r runs share r+1 of N of the trials (the
// round robin of `--shard`) that results.jsonl does not hold yet, appending each record to its own
// results.rank-r.jsonl, flushed as it finishes, so a process that dies loses nothing that
// finished. At the end rank 0 appends the rank files to results.jsonl and removes them; a later
// `--resume`, with any number of ranks or none, joins whatever rank files a killed run left. A
// trial's seed does not depend on the rank, so the records are those of a single run bit for bit.
#include <exception>
#include <optional>

#include "framework/experiment_runner.hpp"

namespace mhb {

// Thrown on the ranks other than 0 when the run stopped: rank 0 says why.
class RunStoppedOnAnotherRank : public std::exception {
public:
    const char* what() const noexcept override { return "the run stopped; rank 0 reports why"; }
};

struct DistributedOutcome {
    int rank = 0;
    int ranks = 1;
    std::optional<RunSummary> summary;  // rank 0 only
};

// Call from every rank. Rank 0 rethrows what stopped the run (InputError: bad input, a failed
// write); the other ranks then return without a summary.
DistributedOutcome run_distributed(const ExperimentSpec& spec, RunOptions options);

// run_distributed is in libmhbench_mpi.so, which `mhbench run` loads only when mpirun started it
// (framework/optional_library.hpp): every other command starts without Open MPI.
using DistributedRun = DistributedOutcome (*)(const ExperimentSpec& spec, RunOptions options);

}  // namespace mhb
