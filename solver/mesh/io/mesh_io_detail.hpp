#pragma once
/// \file mesh_io_detail.hpp
/// Private, header-only helpers shared by the mesh readers and writers (not public API).
///
/// Scanner reads a whole file into memory and walks it with a cursor that always knows its 1-based
/// line number, so every parse error can name "<file>:<line>". Numbers are parsed with
/// std::from_chars (locale-independent, allocation-free); a number must be followed by a blank,
/// the end of the line, a comment or the end of the file, otherwise the token is reported as
/// non-numeric. The cursor never moves past the end of the buffer.
#include "softkin/solver/common/output_file.hpp"
#include "softkin/solver/common/input_file.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <climits>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/mesh/mesh.hpp"

namespace softkin {
namespace detail {

/// Throws std::runtime_error("<where>: <what>; expected <expected>").
[[noreturn]] inline void Fail(const std::string& where, const std::string& what,
                              const std::string& expected) {
  throw std::runtime_error(where + ": " + what + "; expected " + expected);
}

/// "<file>:<line>".
inline std::string At(const std::string& file, int line) {
  return file + ":" + std::to_string(line);
}

/// Quotes a token for an error message, shortened to 40 characters.
inline std::string Quote(std::string_view s) {
  if (s.size() > 40) return "'" + std::string(s.substr(0, 37)) + "...'";
  return "'" + std::string(s) + "'";
}

/// Cursor over a whole file held in memory.
class Scanner {
 public:
  /// Reads `path` (throws "<path>: cannot open ...; expected a readable file" on failure).
  /// `comment` (e.g. '#') starts a comment that runs to the end of the line; 0 disables.
  explicit Scanner(const std::string& path, char comment = 0) : path_(path), comment_(comment) {
    CheckInputFile(path, "a mesh file");
    std::ifstream in(path, std::ios::binary);
    if (!in) Fail(path, "cannot open file", "a readable mesh file");
    in.seekg(0, std::ios::end);
    const std::streamoff n = in.tellg();
    if (n < 0) Fail(path, "cannot determine the file size", "a regular file");
    in.seekg(0, std::ios::beg);
    data_.resize(static_cast<std::size_t>(n));
    if (n > 0 && !in.read(&data_[0], n)) Fail(path, "read error", "a readable mesh file");
    p_ = data_.data();
    end_ = p_ + data_.size();
    if (data_.size() >= 3 && static_cast<unsigned char>(p_[0]) == 0xEF &&
        static_cast<unsigned char>(p_[1]) == 0xBB && static_cast<unsigned char>(p_[2]) == 0xBF)
      p_ += 3;  // UTF-8 byte order mark
  }

  const std::string& path() const { return path_; }
  int line() const { return line_; }
  std::string Here() const { return At(path_, line_); }
  std::size_t size() const { return data_.size(); }

  /// Saved cursor position (for one-token look-ahead).
  struct Pos {
    const char* p;
    int line;
  };
  Pos Tell() const { return {p_, line_}; }
  void Seek(Pos pos) {
    p_ = pos.p;
    line_ = pos.line;
  }

  /// Raw access for binary parts: the file's bytes, the cursor, and a jump forward to `q` (lines
  /// are counted over the skipped bytes, so later messages still name the right line).
  const char* Begin() const { return data_.data(); }
  const char* End() const { return end_; }
  const char* Ptr() const { return p_; }
  long long Offset() const { return static_cast<long long>(p_ - data_.data()); }
  void JumpTo(const char* q) {
    for (; p_ < q && p_ < end_; ++p_)
      if (*p_ == '\n') ++line_;
  }

  /// True when the cursor is at the end of the file.
  bool Eof() const { return p_ >= end_; }

  /// Skips blanks on the current line; true if nothing (but a comment) is left on it.
  bool AtEol() {
    SkipBlanks();
    return p_ >= end_ || *p_ == '\n' || (comment_ && *p_ == comment_);
  }

  /// Moves to the start of the next line; false (and stays at the end) if there is none.
  bool NextLine() {
    while (p_ < end_ && *p_ != '\n') ++p_;
    if (p_ >= end_) return false;
    ++p_;
    ++line_;
    return p_ < end_;
  }

  /// Skips lines that are empty or comment-only; false if the file ends first.
  bool SkipBlankLines() {
    while (AtEol()) {
      if (!NextLine()) return false;
    }
    return true;
  }

  /// Skips whitespace including newlines and comments (token-stream mode); false at end of file.
  bool SkipWs() {
    for (;;) {
      if (AtEol()) {
        if (!NextLine()) return false;
      } else {
        return true;
      }
    }
  }

  /// Rest of the current line without surrounding blanks or a comment (cursor unchanged).
  std::string_view RestOfLine() {
    SkipBlanks();
    const char* e = p_;
    while (e < end_ && *e != '\n' && !(comment_ && *e == comment_)) ++e;
    while (e > p_ && IsBlank(e[-1])) --e;
    return std::string_view(p_, static_cast<std::size_t>(e - p_));
  }

  /// Next whitespace-separated word on the current line ("" if the line is exhausted).
  std::string_view Word() {
    if (AtEol()) return {};
    const char* b = p_;
    while (p_ < end_ && !IsSpace(*p_) && !(comment_ && *p_ == comment_)) ++p_;
    return std::string_view(b, static_cast<std::size_t>(p_ - b));
  }

  /// Next word across lines ("" at end of file).
  std::string_view StreamWord() {
    if (!SkipWs()) return {};
    return Word();
  }

  // ---- line mode: the value must be on the current line; `what` names it for the message ----
  double Double(const char* what) {
    if (AtEol())
      FailHere(std::string("line ends before ") + what, std::string(what) + " (a number)");
    return ParseDouble(what);
  }
  long long Integer(const char* what) {
    if (AtEol())
      FailHere(std::string("line ends before ") + what, std::string(what) + " (an integer)");
    return ParseInteger(what);
  }
  int Int(const char* what) { return ToInt(Integer(what), what); }

  /// Fails if anything but blanks/comment is left on the current line.
  void ExpectEol(const char* expected) {
    if (!AtEol()) FailHere("unexpected extra token " + Quote(PeekToken()), std::string(expected));
  }

  // ---- token-stream mode: values may span lines ----
  double StreamDouble(const char* what) {
    if (!SkipWs())
      FailHere(std::string("file ends before ") + what, std::string(what) + " (a number)");
    return ParseDouble(what);
  }
  long long StreamInteger(const char* what) {
    if (!SkipWs())
      FailHere(std::string("file ends before ") + what, std::string(what) + " (an integer)");
    return ParseInteger(what);
  }
  int StreamInt(const char* what) { return ToInt(StreamInteger(what), what); }

  [[noreturn]] void FailHere(const std::string& what, const std::string& expected) const {
    Fail(Here(), what, expected);
  }

 private:
  static bool IsBlank(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
  }
  static bool IsSpace(char c) { return IsBlank(c) || c == '\n'; }

  void SkipBlanks() {
    while (p_ < end_ && IsBlank(*p_)) ++p_;
  }
  bool AtTokenEnd(const char* q) const {
    return q >= end_ || IsSpace(*q) || (comment_ && *q == comment_);
  }
  std::string_view PeekToken() const {
    const char* e = p_;
    while (e < end_ && !IsSpace(*e)) ++e;
    return std::string_view(p_, static_cast<std::size_t>(e - p_));
  }
  [[noreturn]] void FailToken(const char* what, const char* kind) const {
    FailHere("non-numeric token " + Quote(PeekToken()) + " for " + what,
             std::string(what) + " (" + kind + ")");
  }
  // Precondition: p_ < end_ and at a non-blank character of the current line.
  double ParseDouble(const char* what) {
    const char* b = p_;
    if (*b == '+' && b + 1 < end_ && *(b + 1) != '-' && *(b + 1) != '+') ++b;
    double v = 0.0;
    const auto r = std::from_chars(b, end_, v);
    if (r.ec == std::errc::result_out_of_range) {
      // Overflow/underflow: report as a non-finite value (overflow) or accept 0 (underflow).
      FailHere("number " + Quote(PeekToken()) + " for " + std::string(what) + " is out of range",
               "a finite number");
    }
    if (r.ec != std::errc() || !AtTokenEnd(r.ptr)) FailToken(what, "a number");
    p_ = r.ptr;
    return v;
  }
  long long ParseInteger(const char* what) {
    const char* b = p_;
    if (*b == '+' && b + 1 < end_ && *(b + 1) != '-' && *(b + 1) != '+') ++b;
    long long v = 0;
    const auto r = std::from_chars(b, end_, v);
    if (r.ec == std::errc::result_out_of_range)
      FailHere("integer " + Quote(PeekToken()) + " for " + std::string(what) + " is out of range",
               std::string(what) + " (an integer that fits in 64 bits)");
    if (r.ec != std::errc() || !AtTokenEnd(r.ptr)) FailToken(what, "an integer");
    p_ = r.ptr;
    return v;
  }
  int ToInt(long long v, const char* what) const {
    if (v < INT_MIN || v > INT_MAX)
      FailHere(std::string(what) + " " + std::to_string(v) + " is out of range",
               std::string(what) + " (a 32-bit integer)");
    return static_cast<int>(v);
  }

  std::string path_;
  std::string data_;
  const char* p_ = nullptr;
  const char* end_ = nullptr;
  int line_ = 1;
  char comment_ = 0;
};

/// Moves `src` into `*dst` when dst is set, otherwise prints it to std::cerr (PrintMeshReport).
inline void Deliver(MeshReport& src, MeshReport* dst) {
  if (dst) {
    *dst = std::move(src);
    return;
  }
  PrintMeshReport(src, std::cerr);
}

/// The note for `n` higher-order elements read by their corner nodes, put first in `rep`.
inline void NoteCornersOnly(const std::string& path, int n, MeshReport* rep) {
  if (n <= 0) return;
  rep->notes.insert(rep->notes.begin(),
                    path + ": read " + std::to_string(n) +
                        " higher-order elements by their corner nodes (SoftKin's elements are "
                        "linear; the mid-edge nodes are dropped as unused)");
}

/// Converts a VTK wedge (base normal pointing away from the top) to SoftKin/Gmsh prism order and
/// back: the same permutation both ways (swap 1<->2 and 4<->5).
inline void VtkWedgeSwap(std::array<int, 6>& v) {
  std::swap(v[1], v[2]);
  std::swap(v[4], v[5]);
}

/// Maps integer tags (e.g. Gmsh node tags, possibly non-contiguous) to dense 0-based indices:
/// a dense table when the tags are compact, otherwise a sorted table with binary search.
class TagIndex {
 public:
  /// `tags[i]` is the tag of index i. Returns the index of the first duplicated tag, or -1.
  int Build(const std::vector<long long>& tags) {
    dense_.clear();
    sorted_.clear();
    if (tags.empty()) {
      use_dense_ = true;
      return -1;
    }
    const auto mm = std::minmax_element(tags.begin(), tags.end());
    min_ = *mm.first;
    // Unsigned difference: well defined for any pair of 64-bit tags.
    const unsigned long long span =
        static_cast<unsigned long long>(*mm.second) - static_cast<unsigned long long>(*mm.first);
    use_dense_ = span <= 4ULL * tags.size() + 1024;
    if (use_dense_) {
      dense_.assign(static_cast<std::size_t>(span + 1), -1);
      for (std::size_t i = 0; i < tags.size(); ++i) {
        int& slot = dense_[Offset(tags[i])];
        if (slot >= 0) return static_cast<int>(i);
        slot = static_cast<int>(i);
      }
      return -1;
    }
    sorted_.resize(tags.size());
    for (std::size_t i = 0; i < tags.size(); ++i) sorted_[i] = {tags[i], static_cast<int>(i)};
    std::sort(sorted_.begin(), sorted_.end());
    for (std::size_t i = 1; i < sorted_.size(); ++i)
      if (sorted_[i].first == sorted_[i - 1].first)
        return std::max(sorted_[i].second, sorted_[i - 1].second);
    return -1;
  }

  /// Index of `tag`, or -1.
  int Find(long long tag) const {
    if (use_dense_) {
      if (tag < min_ || Offset(tag) >= dense_.size()) return -1;
      return dense_[Offset(tag)];
    }
    const auto it = std::lower_bound(sorted_.begin(), sorted_.end(), std::make_pair(tag, INT_MIN));
    return (it != sorted_.end() && it->first == tag) ? it->second : -1;
  }

 private:
  std::size_t Offset(long long tag) const {
    return static_cast<std::size_t>(static_cast<unsigned long long>(tag) -
                                    static_cast<unsigned long long>(min_));
  }

  long long min_ = 0;
  std::vector<int> dense_;
  std::vector<std::pair<long long, int>> sorted_;
  bool use_dense_ = true;
};

/// Lower-case extension including the dot ("" if none).
inline std::string LowerExtension(const std::string& path) {
  const auto slash = path.find_last_of("/\\");
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string e = path.substr(dot);
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

/// A row count to pre-allocate for `declared` items in a file of `bytes` bytes: a corrupt header
/// cannot make us allocate more than the file could possibly hold (>= 2 bytes per line).
inline long long SafeReserve(long long declared, std::size_t bytes) {
  return std::max(0LL, std::min(declared, static_cast<long long>(bytes / 2 + 1)));
}

/// Writes a double in the shortest form that reads back to the same value (std::to_chars), e.g.
/// 0.1 -> "0.1", 1/3 -> "0.3333333333333333"; "nan"/"inf" for non-finite values.
struct Num {
  double x;
};
inline std::ostream& operator<<(std::ostream& o, Num n) {
  char buf[40];
  const auto r = std::to_chars(buf, buf + sizeof buf, n.x);
  return o.write(buf, r.ptr - buf);
}

/// Writes "x y z" of row j of a #V x 3 matrix.
template <typename M>
inline std::ostream& WriteRow(std::ostream& o, const M& X, int j) {
  return o << Num{X(j, 0)} << ' ' << Num{X(j, 1)} << ' ' << Num{X(j, 2)};
}

/// The stream of an output file, set to full double precision for any value not written through
/// Num. (OutputFile, solver/common/output_file.hpp, writes beside the target and renames it in
/// Commit(), after checking every write.)
inline std::ostream& ForWrite(OutputFile& file) {
  file.stream().precision(17);
  return file.stream();
}

}  // namespace detail
}  // namespace softkin
