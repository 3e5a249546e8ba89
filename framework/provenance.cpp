#include "framework/provenance.hpp"

#include <chrono>
#include <thread>

#include <fmt/chrono.h>
#include <fmt/format.h>
#include <sys/utsname.h>
#include <unistd.h>

// For this file alone (CMakeLists.txt), so a new commit or an edit recompiles only this file: CMake
// defines the version, and stamps the commit at every build into the header included here.
#include "mhbench_provenance_stamp.hpp"
#ifndef MHBENCH_VERSION
#error "MHBENCH_VERSION is defined by CMakeLists.txt"
#endif

namespace mhb {

Provenance current_provenance(int threads) {
    Provenance p;
    p.version = MHBENCH_VERSION;
    p.commit = MHBENCH_GIT_COMMIT;
    p.date = fmt::format("{:%Y-%m-%dT%H:%M:%SZ}", fmt::gmtime(std::chrono::system_clock::to_time_t(std::chrono::system_clock::now())));
    // POSIX bounds host names by HOST_NAME_MAX (64 on Linux); the buffer has room for a terminator.
    char host[256] = {};
    p.host = gethostname(host, sizeof host - 1) == 0 ? std::string(host) : std::string("unknown");
    struct utsname system {};
    p.system = uname(&system) == 0 ? fmt::format("{} {} {}", system.sysname, system.release, system.machine) : std::string("unknown");
    p.hardware_threads = std::thread::hardware_concurrency();
    p.threads = threads;
    return p;
}

std::vector<std::pair<std::string, std::string>> provenance_lines(const Provenance& p) {
    return {{"mhbench", p.version},
            {"commit", p.commit},
            {"date", p.date},
            {"machine", fmt::format("{} ({}, {} hardware threads)", p.host, p.system, p.hardware_threads)},
            {"threads", p.ranks > 1 ? fmt::format("{} per rank, {} MPI ranks", p.threads, p.ranks) : std::to_string(p.threads)}};
}

std::string provenance_summary(const Provenance& p) {
    return fmt::format("{} on {} ({}, {} hardware threads), {}{} threads, mhbench {} at commit {}", p.date, p.host, p.system,
                       p.hardware_threads, p.ranks > 1 ? fmt::format("{} MPI ranks x ", p.ranks) : std::string(), p.threads,
                       p.version, p.commit);
}

}  // namespace mhb
