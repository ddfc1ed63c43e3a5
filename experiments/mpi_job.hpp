#pragma once
/// \file mpi_job.hpp
/// The MPI job this process belongs to (docs/cluster.md). SoftKin never needs MPI: outside a
/// launcher, or in a build without MPI, a process is a job of one. Under `mpirun -n N` (or `srun`)
/// MPI starts on the first call of MpiJob() and is finalised at exit. The users of the job are
/// `softkin dataset` (experiments/dataset_mpi.hpp) and the sweeps of `softkin run`
/// (experiments/sweep.hpp).
#include <exception>
#include <string>

namespace softkin {

/// The number of processes of the MPI job this process was started in, read from the launcher's
/// environment before MPI is initialised (Open MPI's mpirun: OMPI_COMM_WORLD_SIZE; MPICH / PMI:
/// PMI_SIZE; Slurm's srun with PMIx: SLURM_NTASKS with PMIX_RANK); 1 outside a launcher.
int LaunchedMpiSize();

/// This process's rank in that job (OMPI_COMM_WORLD_RANK, PMI_RANK or PMIX_RANK); 0 outside one.
int LaunchedMpiRank();

/// Whether this build has MPI (CMake found it: SOFTKIN_HAVE_MPI).
bool HaveMpi();

/// One line for --help: whether this build can share work over MPI ranks, and how.
std::string MpiSupportNote();

/// Throws std::invalid_argument when this process was started by a launcher with several
/// processes but the build has no MPI: each process would compute everything and write the same
/// files. `what` names the command ("dataset", "run fig5_5_architecture") in the message.
void RequireMpiIfLaunched(const std::string& what);

/// This process's place in the job. The first call starts MPI if the launcher started more than
/// one process (RequireMpiIfLaunched first); later calls return the same.
struct MpiPlace {
  int rank = 0;
  int size = 1;
  bool active() const { return size > 1; }
  bool root() const { return rank == 0; }
};
const MpiPlace& MpiJob();

/// Whether MPI has been started in this process (by MpiJob()).
bool MpiStarted();

/// Waits for every rank (nothing outside an MPI job).
void MpiBarrier();

/// Prints "softkin: rank R: error: ..." and aborts the whole job (MPI_Abort with exit code 2 for
/// std::invalid_argument, else 1), so that no rank waits forever for one that failed. If MPI was
/// never started it prints "softkin: error: ..." and exits with that code.
[[noreturn]] void MpiAbortJob(const std::exception& e);

/// The sum over ranks of each of n values, on every rank (copies them outside a job).
void MpiSumOverRanks(const long long* in, long long* out, int n);

/// The maximum over ranks, on every rank.
double MpiMaxOverRanks(double v);

/// A counter shared by the ranks of the job: each Next() returns the next of 0, 1, 2, ..., and no
/// two calls on any ranks return the same value. It lives on rank 0 and is updated with one-sided
/// atomics (MPI_Fetch_and_op), which on one node (shared memory) and on RDMA networks need no
/// action from rank 0, so rank 0 can compute units too. Construction and destruction are
/// collective: every rank constructs and destroys it at the same point of the program.
class MpiSharedCounter {
 public:
  MpiSharedCounter();
  ~MpiSharedCounter();
  MpiSharedCounter(const MpiSharedCounter&) = delete;
  MpiSharedCounter& operator=(const MpiSharedCounter&) = delete;
  long long Next();

 private:
  long long local_ = 0;  ///< the counter outside an MPI job
  void* win_ = nullptr;  ///< MPI_Win, allocated by MPI
};

}  // namespace softkin
