#pragma once
// Whether this process was started as one of several by mpirun/mpiexec, read from the launcher's
// environment (Open MPI, MPICH/Hydra, PMIx), so that a normal run never initialises MPI.
namespace mhb {

// The number of processes the launcher started (1 when not started by one).
int launched_ranks();
// This process's index among them (0 when not started by a launcher).
int launched_rank();
// How many of them run on this machine (1 when not known).
int launched_ranks_on_this_machine();

}  // namespace mhb
