#pragma once
/// \file output_file.hpp
/// Output files that are never left half written, and output paths checked before any work.
///
///  - OutputFile writes into a temporary file beside the target ("<name>.tmp-<pid>") and renames
///    it over the target in Commit(), after a flush and a check of every write. A failed or
///    interrupted write leaves the old file (if any) untouched and removes the temporary.
///    Special files (a device such as /dev/stdout or /dev/full, a FIFO) are written in place,
///    and their write errors are reported the same way.
///  - CheckOutputPath says, before a long solve, why a path cannot be written: a missing folder,
///    a folder given as the file, no permission.
///  - CheckDistinctPaths refuses an output that is also an input or another output (compared as
///    canonical paths, so "./a.json" and "a.json" are the same file).
/// Every error names the path (and the option or key it came from) and says what was expected.
#include <fstream>
#include <string>
#include <vector>

namespace softkin {

class OutputFile {
 public:
  /// Opens the temporary (or the special file). Throws std::runtime_error naming `path`.
  explicit OutputFile(std::string path, std::ios::openmode mode = std::ios::out);
  ~OutputFile();  ///< without Commit(): removes the temporary, leaves `path` as it was
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  std::ostream& stream() { return out_; }
  const std::string& path() const { return path_; }
  /// Flushes, checks, closes and renames the temporary over `path`. Throws std::runtime_error
  /// naming `path` and the system's reason (for example "No space left on device").
  void Commit();

 private:
  std::string path_, tmp_;  ///< tmp_ empty: written in place (a special file)
  std::ofstream out_;
  bool committed_ = false;
};

/// Writes `text` to `path` through an OutputFile.
void WriteTextFile(const std::string& path, const std::string& text);

/// A path with the option or key that named it ("--json", "out"), for messages.
struct NamedPath {
  std::string what;
  std::string path;
};

/// Throws std::invalid_argument "<what> '<path>': <reason>; expected ..." if `path` cannot be
/// written: empty, an existing folder, a missing parent folder or a parent that is not a folder,
/// no permission to create or replace it. Special files that exist (devices, FIFOs) pass.
void CheckOutputPath(const NamedPath& out);

/// Throws std::invalid_argument if an output names the same file as an input or as another
/// output. Empty paths are skipped.
void CheckDistinctPaths(const std::vector<NamedPath>& inputs,
                        const std::vector<NamedPath>& outputs);

}  // namespace softkin
