#pragma once
/// \file sweep.hpp
/// A sweep of independent units whose rows are journaled (ResumeJournal, results.hpp): the
/// architecture grid of Fig. 5.5, the IK methods of ik_methods. One process computes the missing
/// units in order. Under `mpirun -n N softkin run CONFIG` the ranks share them: a counter on
/// rank 0 (MpiSharedCounter, mpi_job.hpp) hands the missing units out in order as ranks become
/// free, each rank appends its rows to the one journal, and then every rank reads the journal
/// again, so that rank 0 writes the tables and the summary from the rows in the sweep's order.
/// Each unit runs once; a killed job rerun with the same command computes only what is missing.
#include "softkin/experiments/results.hpp"

#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <vector>

namespace softkin {

class Sweep {
 public:
  /// The journal at `journal_path` (created if missing). `label` names the sweep in progress
  /// lines.
  Sweep(const std::string& journal_path, std::string label, bool verbose);

  /// Computes, with compute(i), the row of every keys[i] not in the journal, and journals it. All
  /// ranks of an MPI job call Run with the same keys; WriteTable then gives the rows. An
  /// exception from compute aborts an MPI job (MpiAbortJob) and is rethrown in one process.
  void Run(const std::vector<nlohmann::json>& keys,
           const std::function<nlohmann::json(std::size_t)>& compute);

  /// After Run: writes the rows, in the order of the keys, as a CSV of the columns `header`
  /// (CsvWriter::RowJson) and returns them as a JSON array.
  nlohmann::json WriteTable(const std::string& csv_path,
                            const std::vector<std::string>& header) const;
  /// After Run: the rows, in the order of the keys.
  const std::vector<nlohmann::json>& rows() const { return rows_; }
  /// Units whose rows were in the journal before this run (resumed).
  int resumed() const { return resumed_; }
  /// Whether this process writes the experiment's results: rank 0 of an MPI job, or the only one.
  /// The other ranks return from the experiment after Run.
  static bool WritesResults();

 private:
  ResumeJournal journal_;
  std::string label_;
  bool verbose_;
  std::vector<nlohmann::json> rows_;
  int resumed_ = 0;
};

}  // namespace softkin
