/// \file sweep.cpp
/// Sweep::Run (sweep.hpp): the missing units, in order in one process, shared out under MPI.
#include "softkin/experiments/sweep.hpp"

#include "softkin/experiments/mpi_job.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <chrono>
#include <cstdio>
#include <stdexcept>

namespace softkin {

Sweep::Sweep(const std::string& journal_path, std::string label, bool verbose)
    : journal_(journal_path), label_(std::move(label)), verbose_(verbose) {}

bool Sweep::WritesResults() { return MpiJob().root(); }

void Sweep::Run(const std::vector<nlohmann::json>& keys,
                const std::function<nlohmann::json(std::size_t)>& compute) {
  const MpiPlace& job = MpiJob();
  std::vector<std::size_t> missing;
  for (std::size_t i = 0; i < keys.size(); ++i)
    if (!journal_.Reuse(keys[i])) missing.push_back(i);
  resumed_ = journal_.reused();
  if (verbose_ && job.root() && resumed_ > 0)
    std::fprintf(stderr, "  %s: %d of %zu units resumed from %s\n", label_.c_str(), resumed_,
                 keys.size(), journal_.path().c_str());
  if (verbose_ && job.root() && job.active())
    std::fprintf(stderr, "  %s: %zu units to compute on %d MPI ranks\n", label_.c_str(),
                 missing.size(), job.size);
  {
    MpiSharedCounter next;  // one process: 0, 1, 2, ...
    for (long long m = next.Next(); m < static_cast<long long>(missing.size()); m = next.Next()) {
      const std::size_t i = missing[static_cast<std::size_t>(m)];
      const auto t0 = std::chrono::steady_clock::now();
      nlohmann::json row;
      try {
        row = compute(i);
        journal_.Append(keys[i], row);
      } catch (const std::exception& e) {
        if (!job.active()) throw;
        MpiAbortJob(e);
      }
      if (job.active())
        std::fprintf(stderr, "  %s: rank %d: unit %zu of %zu done in %.1f s\n", label_.c_str(),
                     job.rank, i + 1, keys.size(), SecondsSince(t0));
    }
    MpiBarrier();  // every rank has journaled its units
  }
  journal_.Reload();
  rows_.clear();
  for (const auto& key : keys) {
    const nlohmann::json* row = journal_.Reuse(key);
    if (!row)
      throw std::runtime_error(journal_.path() + ": the row of unit " + key.dump() +
                               " is missing after the sweep (was the journal changed meanwhile?)");
    rows_.push_back(*row);
  }
}

nlohmann::json Sweep::WriteTable(const std::string& csv_path,
                                 const std::vector<std::string>& header) const {
  CsvWriter csv(csv_path, header);
  for (const auto& row : rows_) csv.RowJson(row);
  return nlohmann::json(rows_);
}

}  // namespace softkin
