#pragma once
/// \file results.hpp
/// Writing experiment results: results/<name>/{summary.json, config.json, run.json, *.csv}.
/// run.json records the git commit, the machine and the wall time so results are traceable.
#include <nlohmann/json.hpp>

#include <fstream>
#include <string>
#include <vector>

namespace softkin {

struct CollisionCheck;

/// Creates (if needed) and returns the result folder `root`/`name`.
std::string ResultDir(const std::string& root, const std::string& name);
/// The git commit of the source tree (or "unknown"), and a description of the machine.
std::string GitCommit();
nlohmann::json MachineInfo();
/// The exact collision check of a state as JSON: collision_free, self_contacts, obstacle_contacts,
/// max/self/obstacle_penetration_mm, inverted_elements, inverted_body_elements, tangled_contacts.
nlohmann::json CollisionCheckJson(const CollisionCheck& check);
/// Writes JSON with 2-space indentation; throws std::runtime_error naming the path on failure.
void WriteJson(const std::string& path, const nlohmann::json& j);

/// A CSV file written row by row and flushed after each row, so finished rows survive a crash.
class CsvWriter {
 public:
  CsvWriter(const std::string& path, const std::vector<std::string>& header);
  void Row(const std::vector<double>& values);
  void RowStrings(const std::vector<std::string>& values);
  /// One row from a JSON object: the value of each header name (numbers as by Row, strings as is,
  /// a missing key as empty).
  void RowJson(const nlohmann::json& row);
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::vector<std::string> header_;
  std::ofstream out_;
};

/// A journal of finished units of a long sweep, for resuming it: one JSON record per line,
/// {"key": ..., "row": ...}, appended and flushed as each unit finishes. The key holds every
/// setting that determines the row; a rerun reuses the rows whose key matches exactly and
/// recomputes the rest. A line that does not parse (a write cut by a crash) is reported on stderr
/// and skipped. The key does not identify the code: after changing the code, delete the journal to
/// recompute (summaries report how many rows were reused, as "resumed_rows").
///
/// Several processes may append to one journal (the ranks of an MPI sweep, experiments/sweep.hpp):
/// each record is written whole under an exclusive lock of the file (flock), after a newline if a
/// killed writer left its last line cut.
class ResumeJournal {
 public:
  /// Reads the records of `path` (if it exists); throws std::runtime_error if it cannot be
  /// written.
  explicit ResumeJournal(const std::string& path);
  /// The row recorded for `key` (the last one if several), or nullptr. A row that was in the file
  /// when it was opened counts as reused. The pointer is valid until the next Append or Reload.
  const nlohmann::json* Reuse(const nlohmann::json& key);
  void Append(const nlohmann::json& key, const nlohmann::json& row);
  /// Reads the file again, with the records other processes have appended since.
  void Reload();
  /// Rows returned by Reuse so far that were in the file when it was opened.
  int reused() const { return reused_; }
  const std::string& path() const { return path_; }

 private:
  void Read(bool report);
  std::string path_;
  std::vector<nlohmann::json> records_;
  std::size_t opened_ = 0;  ///< records in the file when it was opened
  int reused_ = 0;
};

}  // namespace softkin
