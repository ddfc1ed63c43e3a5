/// \file mpi_job.cpp
/// The process's MPI job (mpi_job.hpp): the launcher's environment, MPI's start and end, and the
/// few collective operations the dataset and sweep jobs use.
#include "softkin/experiments/mpi_job.hpp"

#include <algorithm>
#include <cstdlib>
#include <iostream>
#include <stdexcept>

#ifdef SOFTKIN_HAVE_MPI
#include <mpi.h>
#endif

namespace softkin {

int LaunchedMpiRank() {
  for (const char* var : {"OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"})
    if (const char* v = std::getenv(var)) return std::max(0, std::atoi(v));
  return 0;
}

int LaunchedMpiSize() {
  for (const char* var : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
    if (const char* v = std::getenv(var)) return std::max(1, std::atoi(v));
  if (std::getenv("PMIX_RANK"))
    if (const char* v = std::getenv("SLURM_NTASKS")) return std::max(1, std::atoi(v));
  return 1;
}

std::string MpiSupportNote() {
  return HaveMpi() ? "MPI: this build has MPI; under mpirun -n N (or srun) the ranks share the "
                     "work (docs/cluster.md)"
                   : "MPI: unavailable, this build has no MPI (install libopenmpi-dev and "
                     "openmpi-bin, then rebuild; docs/cluster.md)";
}

void RequireMpiIfLaunched(const std::string& what) {
  const int n = LaunchedMpiSize();
  if (n > 1 && !HaveMpi())
    throw std::invalid_argument(
        what + ": started by an MPI launcher with " + std::to_string(n) +
        " processes, but MPI is unavailable: this softkin was built without MPI (install "
        "libopenmpi-dev and openmpi-bin, then rebuild); the processes would each compute "
        "everything and write the same files");
}

#ifndef SOFTKIN_HAVE_MPI

bool HaveMpi() { return false; }

const MpiPlace& MpiJob() {
  static const MpiPlace place;
  return place;
}
bool MpiStarted() { return false; }
void MpiBarrier() {}
void MpiAbortJob(const std::exception& e) {
  std::cerr << "softkin: error: " << e.what() << "\n";
  std::exit(dynamic_cast<const std::invalid_argument*>(&e) ? 2 : 1);
}
void MpiSumOverRanks(const long long* in, long long* out, int n) { std::copy(in, in + n, out); }
double MpiMaxOverRanks(double v) { return v; }
MpiSharedCounter::MpiSharedCounter() = default;
MpiSharedCounter::~MpiSharedCounter() = default;
long long MpiSharedCounter::Next() { return local_++; }

#else

bool HaveMpi() { return true; }

namespace {

// Ipopt's sequential MUMPS (libdmumps_seq, linked before Open MPI) exports dummy MPI_Init,
// MPI_Comm_rank, MPI_Finalize and MPI_Wtime, which would shadow Open MPI's (every rank would be
// rank 0). Those four are called by their profiling-interface names (PMPI_*), which only the
// real MPI library defines.

bool started = false;

/// Finalises MPI at exit, after everything that used it (a static object's destructor).
struct MpiFinalizer {
  ~MpiFinalizer() {
    int done = 0;
    if (started && MPI_Finalized(&done) == MPI_SUCCESS && !done) PMPI_Finalize();
  }
};

}  // namespace

const MpiPlace& MpiJob() {
  static const MpiPlace place = [] {
    MpiPlace p;
    if (LaunchedMpiSize() <= 1) return p;
    static MpiFinalizer finalizer;
    int provided = 0;
    // FUNNELED: the forward solves use OpenMP, and only the main thread calls MPI.
    PMPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    started = true;
    PMPI_Comm_rank(MPI_COMM_WORLD, &p.rank);
    MPI_Comm_size(MPI_COMM_WORLD, &p.size);
    return p;
  }();
  return place;
}

bool MpiStarted() { return started; }

void MpiBarrier() {
  if (MpiJob().active()) MPI_Barrier(MPI_COMM_WORLD);
}

void MpiAbortJob(const std::exception& e) {
  const int code = dynamic_cast<const std::invalid_argument*>(&e) ? 2 : 1;
  if (!started) {
    std::cerr << "softkin: error: " << e.what() << "\n";
    std::exit(code);
  }
  std::cerr << "softkin: rank " << MpiJob().rank << ": error: " << e.what()
            << " (aborting the MPI job; finished units stay for a rerun)\n";
  std::cerr.flush();
  MPI_Abort(MPI_COMM_WORLD, code);
  std::abort();
}

void MpiSumOverRanks(const long long* in, long long* out, int n) {
  if (!MpiJob().active()) {
    std::copy(in, in + n, out);
    return;
  }
  MPI_Allreduce(in, out, n, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
}

double MpiMaxOverRanks(double v) {
  if (!MpiJob().active()) return v;
  double m = v;
  MPI_Allreduce(&v, &m, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return m;
}

MpiSharedCounter::MpiSharedCounter() {
  const MpiPlace& job = MpiJob();
  if (!job.active()) return;
  long long* base = nullptr;
  MPI_Win win;
  MPI_Win_allocate(job.root() ? sizeof(long long) : 0, sizeof(long long), MPI_INFO_NULL,
                   MPI_COMM_WORLD, &base, &win);
  if (job.root()) {
    MPI_Win_lock(MPI_LOCK_EXCLUSIVE, 0, 0, win);
    *base = 0;
    MPI_Win_unlock(0, win);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  MPI_Win_lock_all(0, win);
  win_ = new MPI_Win(win);
}

MpiSharedCounter::~MpiSharedCounter() {
  if (!win_) return;
  auto* win = static_cast<MPI_Win*>(win_);
  MPI_Win_unlock_all(*win);
  MPI_Win_free(win);
  delete win;
}

long long MpiSharedCounter::Next() {
  if (!win_) return local_++;
  auto* win = static_cast<MPI_Win*>(win_);
  const long long one = 1;
  long long old = -1;
  MPI_Fetch_and_op(&one, &old, MPI_LONG_LONG, 0, 0, MPI_SUM, *win);
  MPI_Win_flush(0, *win);
  return old;
}

#endif

}  // namespace softkin
