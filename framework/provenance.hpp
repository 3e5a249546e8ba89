#pragma once
// Where a result came from: which build of mhbench made it, when, on which machine and with how many
// threads. Experiments record it in experiment.json and the reports show it, so a surprising number
// can be traced to the build and machine that produced it.
#include <string>
#include <utility>
#include <vector>

namespace mhb {

struct Provenance {
    std::string version;  // mhbench's version (the CMake project version)
    std::string commit;   // the git commit the build was configured at; "unknown" outside a git checkout
    std::string date;     // when it started, UTC, ISO 8601
    std::string host;     // the machine's host name
    std::string system;   // operating system, its release and the processor architecture (uname)
    unsigned hardware_threads = 0;
    int threads = 0;      // worker threads used (per rank under MPI)
    int ranks = 1;        // MPI processes the trials were spread over
};

// This process, now, using `threads` worker threads.
Provenance current_provenance(int threads);

// The provenance as labelled lines for people ("mhbench", "commit", "started", "machine", "threads").
std::vector<std::pair<std::string, std::string>> provenance_lines(const Provenance& p);
// The same in one line, for a list of several runs.
std::string provenance_summary(const Provenance& p);

}  // namespace mhb
