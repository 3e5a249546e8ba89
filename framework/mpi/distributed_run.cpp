#include "framework/mpi/distributed_run.hpp"

#include <algorithm>
#include <exception>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include <boost/mpi/collectives.hpp>
#include <boost/mpi/communicator.hpp>
#include <boost/mpi/environment.hpp>
#include <boost/serialization/string.hpp>
#include <boost/serialization/vector.hpp>

#include "framework/distributed_launch.hpp"
#include "framework/input_error.hpp"

namespace mhb {
namespace {

namespace mpi = boost::mpi;

// The exception of the first rank that had one, on every rank: a rank that throws alone would
// leave the others waiting in a collective forever.
void agree_on_failure(const mpi::communicator& world, std::exception_ptr failure, const std::string& message) {
    const int failed = failure ? 1 : 0;
    int any = 0;
    mpi::all_reduce(world, failed, any, mpi::maximum<int>());
    if (!any) return;
    std::vector<std::string> messages;
    mpi::all_gather(world, message, messages);
    if (world.rank() == 0) {
        if (failure) std::rethrow_exception(failure);
        for (const auto& m : messages)
            if (!m.empty()) throw InputError("", 0, "", m);
    }
    throw RunStoppedOnAnotherRank();
}

}  // namespace

DistributedOutcome run_distributed(const ExperimentSpec& spec, RunOptions options) {
    // Initialised once per process and finalised at exit; MPI is only ever entered from this thread.
    static mpi::environment environment(mpi::threading::funneled);
    mpi::communicator world;
    DistributedOutcome outcome;
    outcome.rank = world.rank();
    outcome.ranks = world.size();
    if (options.shard)
        throw InputError("command line", 0, "--shard",
                         "a run is either spread over MPI ranks or one --shard of the trials, not both; drop --shard under mpirun");
    if (options.threads <= 0)  // the ranks on one machine share its cores
        options.threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()) / launched_ranks_on_this_machine());
    options.progress = options.progress && outcome.rank == 0;

    PreparedRun prepared;
    std::exception_ptr failure;
    std::string message;
    auto attempt = [&](const std::function<void()>& step) {
        try {
            step();
        } catch (const std::exception& e) {
            failure = std::current_exception();
            message = e.what();
        }
    };
    if (outcome.rank == 0) attempt([&] { prepared = prepare_run(spec, options, outcome.ranks); });
    agree_on_failure(world, failure, message);
    if (outcome.rank != 0) attempt([&] { prepared = attach_to_run(spec, options); });
    agree_on_failure(world, failure, message);

    RunSummary summary;
    attempt([&] {
        summary = run_prepared(spec, options, prepared, Shard{outcome.rank + 1, outcome.ranks},
                               prepared.output / rank_results_name(outcome.rank));
    });
    // Every rank's records are flushed to its file before anyone goes on.
    std::vector<std::size_t> counts{summary.total, summary.ran, summary.skipped, summary.failed};
    std::vector<std::vector<std::size_t>> all_counts;
    std::vector<std::vector<std::string>> all_failures;
    mpi::gather(world, counts, all_counts, 0);
    mpi::gather(world, summary.failures, all_failures, 0);
    agree_on_failure(world, failure, message);
    if (outcome.rank != 0) return outcome;

    summary.total = summary.ran = summary.skipped = summary.failed = 0;
    summary.failures.clear();
    for (std::size_t r = 0; r < all_counts.size(); ++r) {
        summary.total += all_counts[r][0];
        summary.ran += all_counts[r][1];
        summary.skipped += all_counts[r][2];
        summary.failed += all_counts[r][3];
        for (const auto& f : all_failures[r])
            if (summary.failures.size() < 5) summary.failures.push_back(f);
    }
    for (auto& note : fold_rank_results(prepared.output))
        if (!note.starts_with("joined")) summary.notes.push_back(std::move(note));
    outcome.summary = std::move(summary);
    return outcome;
}

}  // namespace mhb

// This file is the library libmhbench_mpi.so (CMakeLists.txt); `mhbench run` finds the run here.
extern "C" [[gnu::visibility("default")]] mhb::DistributedRun mhbench_mpi_run() {
    return &mhb::run_distributed;
}
