/// \file dataset_mpi.cpp
/// The MPI dataset job of dataset_mpi.hpp: rank 0's work queue of units, the units as shard
/// files, and the merge.
#include "softkin/experiments/dataset_mpi.hpp"

#include "softkin/experiments/mpi_job.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#ifdef SOFTKIN_HAVE_MPI
#include <mpi.h>
#endif

namespace softkin {

namespace fs = std::filesystem;

namespace {

/// The whole dataset in this process.
DatasetRunSummary GenerateWhole(Kinematics& kin, const DatasetSampling& sampling,
                                const DatasetRunOptions& run) {
  DatasetRunOptions o = run;
  o.shard = 0;
  o.shards = 1;
  return GenerateDataset(kin, sampling, o);
}

}  // namespace

#ifndef SOFTKIN_HAVE_MPI

DatasetRunSummary GenerateDatasetMpi(Kinematics& kin, const DatasetSampling& sampling,
                                     const DatasetRunOptions& run) {
  return GenerateWhole(kin, sampling, run);
}

#else

namespace {

constexpr int kTagRequest = 1;  // a rank asks rank 0 for a unit
constexpr int kTagUnit = 2;     // rank 0's answer: a unit index, or -1 when none is left

/// Rank 0's queue of units: it hands them out in order, to itself and to the ranks that ask.
class UnitQueue {
 public:
  UnitQueue(int rank, int size, long long units) : rank_(rank), size_(size), units_(units) {}

  /// The next unit for this rank, or -1.
  long long Take() {
    if (rank_ == 0) {
      Serve(false);
      return next_ < units_ ? next_++ : -1;
    }
    int ask = 0;
    long long u = -1;
    MPI_Send(&ask, 1, MPI_INT, 0, kTagRequest, MPI_COMM_WORLD);
    MPI_Recv(&u, 1, MPI_LONG_LONG, 0, kTagUnit, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    return u;
  }

  /// Rank 0: answers the requests waiting (block: until every other rank has been told there is
  /// no work left).
  void Serve(bool block) {
    if (rank_ != 0) return;
    while (finished_ < size_ - 1) {
      int flag = 1;
      MPI_Status st;
      if (block)
        MPI_Probe(MPI_ANY_SOURCE, kTagRequest, MPI_COMM_WORLD, &st);
      else
        MPI_Iprobe(MPI_ANY_SOURCE, kTagRequest, MPI_COMM_WORLD, &flag, &st);
      if (!flag) return;
      int ask = 0;
      MPI_Recv(&ask, 1, MPI_INT, st.MPI_SOURCE, kTagRequest, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      long long u = next_ < units_ ? next_++ : -1;
      if (u < 0) ++finished_;
      MPI_Send(&u, 1, MPI_LONG_LONG, st.MPI_SOURCE, kTagUnit, MPI_COMM_WORLD);
    }
  }

 private:
  int rank_, size_;
  long long units_, next_ = 0;
  int finished_ = 0;
};

std::string UnitPath(const std::string& parts, long long u, long long units) {
  return parts + "/unit-" + std::to_string(u) + "-of-" + std::to_string(units) + ".csv";
}

/// The job's totals (sums over ranks) on every rank.
DatasetRunSummary SumOverRanks(const DatasetRunSummary& mine) {
  const long long v[5] = {mine.already, mine.written, mine.failed, mine.inverted, mine.fk_solves};
  long long s[5] = {0, 0, 0, 0, 0};
  MpiSumOverRanks(v, s, 5);
  DatasetRunSummary out;
  out.already = s[0];
  out.written = s[1];
  out.failed = s[2];
  out.inverted = s[3];
  out.fk_solves = s[4];
  out.time_s = MpiMaxOverRanks(mine.time_s);
  return out;
}

/// Rank 0 prints each rank's busy time (its units' time) and the busiest over the mean.
void ReportBalance(int rank, int size, const DatasetRunSummary& mine, bool print) {
  std::vector<double> busy(static_cast<std::size_t>(size), 0.0);
  std::vector<long long> samples(static_cast<std::size_t>(size), 0);
  MPI_Gather(&mine.time_s, 1, MPI_DOUBLE, busy.data(), 1, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  MPI_Gather(&mine.written, 1, MPI_LONG_LONG, samples.data(), 1, MPI_LONG_LONG, 0, MPI_COMM_WORLD);
  if (rank != 0 || !print) return;
  double sum = 0, top = 0;
  std::cerr << "softkin dataset: busy time per rank:";
  for (int r = 0; r < size; ++r) {
    std::cerr << (r ? ", " : " ") << busy[r] << " s (" << samples[r] << " samples)";
    sum += busy[r];
    top = std::max(top, busy[r]);
  }
  std::cerr << "; busiest / mean " << (sum > 0 ? top / (sum / size) : 1.0) << "\n";
}

}  // namespace

DatasetRunSummary GenerateDatasetMpi(Kinematics& kin, const DatasetSampling& sampling,
                                     const DatasetRunOptions& run) {
  if (!MpiJob().active()) return GenerateWhole(kin, sampling, run);
  const int rank = MpiJob().rank, size = MpiJob().size;
  const long long total = DatasetSize(sampling, kin.num_actuators());
  const long long units = (total + sampling.block - 1) / sampling.block;
  const std::string parts = run.out + ".parts";
  DatasetRunSummary mine;

  // A dataset file already there: finished, or from one process. Rank 0 resumes or checks it.
  const bool single = fs::exists(run.out) && !fs::exists(parts);
  if (single) {
    if (rank == 0) {
      if (run.progress)
        std::cerr << "softkin dataset: " << run.out << " exists (no " << parts
                  << "): rank 0 resumes or checks it alone\n";
      try {
        mine = GenerateWhole(kin, sampling, run);
      } catch (const std::exception& e) {
        MpiAbortJob(e);
      }
    }
  } else {
    try {
      if (rank == 0) fs::create_directories(parts);
    } catch (const std::exception& e) {
      MpiAbortJob(e);
    }
    MPI_Barrier(MPI_COMM_WORLD);
    if (rank == 0 && run.progress)
      std::cerr << "softkin dataset: " << size << " ranks, " << units << " units of "
                << sampling.block << " samples, in " << parts << "\n";
    UnitQueue queue(rank, size, units);
    try {
      DatasetRunOptions o = run;
      o.progress = false;
      o.shards = static_cast<int>(units);
      o.after_sample = [&queue, &run] {
        queue.Serve(false);
        if (run.after_sample) run.after_sample();
      };
      for (long long u = queue.Take(); u >= 0; u = queue.Take()) {
        o.out = UnitPath(parts, u, units);
        o.shard = static_cast<int>(u);
        const DatasetRunSummary s = GenerateDataset(kin, sampling, o);
        mine.already += s.already;
        mine.written += s.written;
        mine.failed += s.failed;
        mine.inverted += s.inverted;
        mine.fk_solves += s.fk_solves;
        mine.time_s += s.time_s;
        if (run.progress && s.written > 0)
          std::cerr << "softkin dataset: rank " << rank << ": unit " << u + 1 << "/" << units
                    << ", samples [" << s.first << ", " << s.first + s.count << "), " << s.written
                    << " written in " << s.time_s << " s\n";
      }
      queue.Serve(true);
    } catch (const std::exception& e) {
      MpiAbortJob(e);
    }
  }
  DatasetRunSummary job = SumOverRanks(mine);
  job.first = 0;
  job.count = total;
  if (!single) ReportBalance(rank, size, mine, run.progress);
  MPI_Barrier(MPI_COMM_WORLD);
  if (!single && rank == 0) {
    try {
      std::vector<std::string> files;
      for (long long u = 0; u < units; ++u) files.push_back(UnitPath(parts, u, units));
      MergeDatasets(files, run.out);
      fs::remove_all(parts);
      if (run.progress)
        std::cerr << "softkin dataset: merged " << units << " units into " << run.out << "\n";
    } catch (const std::exception& e) {
      MpiAbortJob(e);
    }
  }
  MPI_Barrier(MPI_COMM_WORLD);
  return job;
}

#endif

}  // namespace softkin
