#include "framework/distributed_launch.hpp"

#include <cstdlib>
#include <string>

namespace mhb {
namespace {

// The first of the variables that holds a whole number >= `least`; `fallback` when none does.
int first_count(std::initializer_list<const char*> names, int least = 1, int fallback = -1) {
    for (const char* name : names)
        if (const char* value = std::getenv(name)) {
            try {
                const int n = std::stoi(value);
                if (n >= least) return n;
            } catch (const std::exception&) {
            }
        }
    return fallback >= 0 ? fallback : least;
}

}  // namespace

int launched_ranks() { return first_count({"OMPI_COMM_WORLD_SIZE", "PMIX_SIZE", "PMI_SIZE"}); }

int launched_rank() { return first_count({"OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK"}, 0); }

int launched_ranks_on_this_machine() { return first_count({"OMPI_COMM_WORLD_LOCAL_SIZE", "MPI_LOCALNRANKS"}); }

}  // namespace mhb
