#include "softkin/learn/dataset.hpp"
#include "softkin/solver/common/text_format.hpp"
#include "softkin/solver/common/input_file.hpp"
#include "softkin/solver/common/output_file.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <algorithm>
#include <cassert>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <stdexcept>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

namespace softkin {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

constexpr long long kMaxSamples = 1LL << 40;
constexpr int kFormatVersion = 1;

/// SplitMix64 (Steele, Lea, Flood 2014): a counter-based generator, the same on every platform.
std::uint64_t Mix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

/// Uniform in [0, 1) from a 64-bit hash (53 random bits).
double Unit(std::uint64_t h) { return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0); }

std::string Num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string SidecarPath(const std::string& csv) { return csv + ".json"; }

const char* kCoord[3] = {"x", "y", "z"};

std::string HeaderLine(int m, const std::vector<std::string>& points, bool jacobian) {
  std::ostringstream h;
  h << "index,status";
  for (int a = 0; a < m; ++a) h << ",c" << a;
  for (const auto& p : points)
    for (int d = 0; d < 3; ++d) h << "," << p << "_" << kCoord[d];
  if (jacobian)
    for (const auto& p : points)
      for (int d = 0; d < 3; ++d)
        for (int a = 0; a < m; ++a) h << ",J_" << p << "_" << kCoord[d] << "_c" << a;
  h << ",message";
  return h.str();
}

std::string Sanitize(std::string s) {
  for (char& ch : s) {
    if (ch == ',') ch = ';';
    if (ch == '\n' || ch == '\r') ch = ' ';
  }
  return s.empty() ? "unspecified failure" : s;
}

std::string SampleLine(long long index, const Eigen::VectorXd& c, const KinematicsEval& ev,
                       int num_points, bool jacobian) {
  const int m = static_cast<int>(c.size());
  const bool inverted = ev.ok && ev.inverted_elements > 0;
  std::string line = std::to_string(index) + (!ev.ok ? ",failed" : inverted ? ",inverted" : ",ok");
  for (int a = 0; a < m; ++a) line += "," + Num(c[a]);
  const int np = 3 * num_points, nj = jacobian ? 3 * num_points * m : 0;
  if (ev.ok) {
    for (int q = 0; q < num_points; ++q)
      for (int d = 0; d < 3; ++d) line += "," + Num(ev.p(q, d));
    for (int r = 0; r < 3 * num_points && jacobian; ++r)
      for (int a = 0; a < m; ++a) line += "," + Num(ev.J(r, a));
    line += ",";
    if (inverted)
      line += std::to_string(ev.inverted_elements) +
              " inverted body elements (smallest volume ratio " + Num(ev.min_volume_ratio) + ")";
  } else {
    line.append(static_cast<size_t>(np + nj), ',');
    line += "," + Sanitize(ev.message);
  }
  return line;
}

std::vector<std::string> SplitFields(const std::string& line) {
  std::vector<std::string> f;
  size_t pos = 0;
  while (true) {
    const size_t comma = line.find(',', pos);
    f.push_back(line.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos));
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return f;
}

[[noreturn]] void Bad(const std::string& file, long long line, const std::string& what) {
  throw std::invalid_argument(file + ":" + std::to_string(line) + ": " + what);
}

double ParseNumber(const std::string& s, const std::string& file, long long line,
                   const std::string& column) {
  const char* b = s.c_str();
  char* e = nullptr;
  const double v = std::strtod(b, &e);
  if (s.empty() || e != b + s.size())
    Bad(file, line, "column " + column + ": expected a number, got '" + s + "'");
  if (!std::isfinite(v))
    Bad(file, line, "column " + column + ": expected a finite number, got '" + s + "'");
  return v;
}

long long ParseIndex(const std::string& s, const std::string& file, long long line) {
  size_t used = 0;
  long long v = -1;
  try {
    v = std::stoll(s, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != s.size() || s.empty() || v < 0)
    Bad(file, line, "column index: expected a non-negative integer, got '" + s + "'");
  return v;
}

enum class SampleStatus { kOk, kInverted, kFailed };

/// Checks the fields of one sample line against the header `head` (m actuation columns): the
/// field count, the status, finite numbers in an ok or inverted row, empty outputs in a failed
/// row. Throws with file:line.
SampleStatus CheckSampleFields(const std::vector<std::string>& f,
                               const std::vector<std::string>& head, int m, const std::string& path,
                               long long lineno) {
  const size_t nfields = head.size();
  if (f.size() != nfields)
    Bad(path, lineno,
        "expected " + std::to_string(nfields) + " fields, found " + std::to_string(f.size()));
  if (f[1] == "failed") {
    for (size_t j = 2 + m; j + 1 < nfields; ++j)
      if (!f[j].empty())
        Bad(path, lineno, "a failed sample must have empty position and Jacobian fields");
    return SampleStatus::kFailed;
  }
  if (f[1] != "ok" && f[1] != "inverted")
    Bad(path, lineno, "column status: expected ok, inverted or failed, got '" + f[1] + "'");
  for (size_t j = 2; j + 1 < nfields; ++j) ParseNumber(f[j], path, lineno, head[j]);
  return f[1] == "ok" ? SampleStatus::kOk : SampleStatus::kInverted;
}

/// The text of a file.
std::string ReadAll(const std::string& path) {
  CheckInputFile(path, "a dataset file (CSV or its .json sidecar)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path + ": cannot read");
  std::stringstream buf;
  buf << in.rdbuf();
  return buf.str();
}

/// An exclusive lock (flock) on a dataset file for the length of a run, taken before the file
/// is read or written; a file system without locks (ENOLCK, ENOSYS, EOPNOTSUPP) runs unlocked.
class WriterLock {
 public:
  explicit WriterLock(const std::string& path) {
    // Create it if missing (empty: "fresh" below), without truncating anything that exists.
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0 && errno == EWOULDBLOCK) {
      ::close(fd_);
      throw std::runtime_error(
          path +
          " is being written by another process (it holds the file's lock); wait for it "
          "to finish, or stop it, then run the same command again to resume; or choose "
          "another output");
    }
  }
  ~WriterLock() { ::close(fd_); }
  WriterLock(const WriterLock&) = delete;
  WriterLock& operator=(const WriterLock&) = delete;

 private:
  int fd_ = -1;
};

nlohmann::json ReadSidecar(const std::string& csv) {
  const std::string path = SidecarPath(csv);
  if (!fs::exists(path))
    throw std::invalid_argument(csv + ": its sidecar " + path +
                                " is missing (it says how the dataset was made)");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(ReadAll(path));
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(path + ": not valid JSON: " + e.what());
  }
  if (!j.is_object() || j.value("format", "") != "softkin-dataset" || !j.contains("config") ||
      !j.contains("shard"))
    throw std::invalid_argument(path +
                                ": expected a softkin-dataset sidecar with keys format, "
                                "version, config, shard");
  if (j.value("version", 0) != kFormatVersion)
    throw std::invalid_argument(path + ": version " + j["version"].dump() + ", expected " +
                                std::to_string(kFormatVersion));
  return j;
}

void WriteSidecar(const std::string& csv, const nlohmann::json& j) {
  WriteTextFile(SidecarPath(csv), j.dump(2) + "\n");
}

/// Key paths where a and b differ, comma-separated ("" if equal).
void Differences(const nlohmann::json& a, const nlohmann::json& b, const std::string& at,
                 std::vector<std::string>* out) {
  auto key = [&](const std::string& k) { return at.empty() ? k : at + "." + k; };
  if (a.is_object() && b.is_object()) {
    for (auto it = a.begin(); it != a.end(); ++it) {
      if (!b.contains(it.key()))
        out->push_back(key(it.key()));
      else
        Differences(it.value(), b[it.key()], key(it.key()), out);
    }
    for (auto it = b.begin(); it != b.end(); ++it)
      if (!a.contains(it.key())) out->push_back(key(it.key()));
  } else if (a != b) {
    out->push_back(at.empty() ? "(root)" : at);
  }
}
std::string KeyDifferences(const nlohmann::json& a, const nlohmann::json& b,
                           const std::string& at) {
  std::vector<std::string> d;
  Differences(a, b, at, &d);
  std::string s;
  for (const auto& k : d) s += (s.empty() ? "" : "', '") + k;
  return s;
}

/// The complete sample lines of a dataset CSV whose header must be `header`; their indices must
/// be first, first + 1, ... Returns the lines and the byte length of the header plus them.
struct RawLines {
  std::vector<std::string> lines;
  size_t complete_bytes = 0;
  bool truncated = false;  ///< the file ends with a partial line
};
RawLines ReadRawLines(const std::string& path, const std::string& header, long long first) {
  const std::string text = ReadAll(path);
  const std::vector<std::string> head = SplitFields(header);
  int m = 0;  // actuation columns c0, c1, ... after index and status
  while (2 + m < static_cast<int>(head.size()) && head[2 + m] == "c" + std::to_string(m)) ++m;
  RawLines r;
  size_t pos = 0;
  long long lineno = 0;
  while (pos < text.size()) {
    const size_t nl = text.find('\n', pos);
    if (nl == std::string::npos) {
      r.truncated = true;
      break;
    }
    const std::string line = text.substr(pos, nl - pos);
    ++lineno;
    if (lineno == 1) {
      if (line != header)
        Bad(path, 1,
            "the header differs from the one this dataset's config gives:\n  found    " + line +
                "\n  expected " + header);
    } else {
      const std::vector<std::string> f = SplitFields(line);
      const long long idx = ParseIndex(f[0], path, lineno);
      const long long want = first + static_cast<long long>(r.lines.size());
      if (idx != want)
        Bad(path, lineno,
            "sample index " + std::to_string(idx) + ", expected " + std::to_string(want));
      // A complete line is kept only if it is a valid sample: a resume must not carry a corrupt
      // row into a dataset it reports as complete.
      CheckSampleFields(f, head, m, path, lineno);
      r.lines.push_back(line);
    }
    pos = nl + 1;
    r.complete_bytes = pos;
  }
  if (lineno == 0) r.complete_bytes = 0;  // not even a complete header
  return r;
}

/// Progress bar on stderr: samples done/total, rate, ETA; redrawn at most 5 times a second.
class Progress {
 public:
  Progress(bool on, long long total, long long done) : on_(on), total_(total), start_done_(done) {
    t0_ = last_ = Clock::now();
  }
  void Update(long long done, bool force = false) {
    if (!on_) return;
    const auto now = Clock::now();
    if (!force && Seconds(last_, now) < 0.2) return;
    last_ = now;
    const double el = Seconds(t0_, now);
    const double rate = el > 0 ? (done - start_done_) / el : 0.0;
    const double eta = rate > 0 ? (total_ - done) / rate : 0.0;
    const int width = 30;
    const int fill = total_ > 0 ? static_cast<int>(width * done / total_) : width;
    char buf[200];
    std::snprintf(buf, sizeof buf, "\r[%s%s] %lld/%lld  %.2f samples/s  ETA %d:%02d:%02d ",
                  std::string(fill, '#').c_str(), std::string(width - fill, ' ').c_str(), done,
                  total_, rate, static_cast<int>(eta / 3600), static_cast<int>(eta / 60) % 60,
                  static_cast<int>(eta) % 60);
    std::cerr << buf << std::flush;
  }
  void Finish(long long done) {
    if (!on_) return;
    Update(done, true);
    std::cerr << "\n";
  }

 private:
  bool on_;
  long long total_, start_done_;
  Clock::time_point t0_, last_;
};

}  // namespace

// ---- sampling ----

bool DatasetSampling::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (kind == Kind::kGrid && grid < 2) return bad("grid: expected N >= 2 values per actuator");
  if (kind == Kind::kRandom && random < 1) return bad("random: expected >= 1 samples");
  if (block < 1) return bad("block: expected >= 1 samples per warm-start block");
  return true;
}

nlohmann::json DatasetSampling::ToJson() const {
  if (kind == Kind::kGrid) return {{"kind", "grid"}, {"grid", grid}, {"block", block}};
  return {{"kind", "random"}, {"samples", random}, {"seed", seed}, {"block", block}};
}

long long DatasetSize(const DatasetSampling& s, int m) {
  if (s.kind == DatasetSampling::Kind::kRandom) return s.random;
  long long n = 1;
  for (int a = 0; a < m; ++a) {
    n *= s.grid;
    if (n > kMaxSamples)
      throw std::invalid_argument("grid: " + std::to_string(s.grid) + "^" + std::to_string(m) +
                                  " samples is more than 2^40");
  }
  return n;
}

std::vector<int> SerpentineDigits(long long i, int grid, int m) {
  assert(grid >= 2 && m >= 1 && i >= 0);
  std::vector<int> d(m);
  for (int a = 0; a < m; ++a) {  // plain mixed-radix digits, actuator 0 least significant
    d[a] = static_cast<int>(i % grid);
    i /= grid;
  }
  // Reflect each digit when the (reflected) digits above it sum to an odd number.
  long long above = 0;
  for (int a = m - 1; a >= 0; --a) {
    if (above % 2 == 1) d[a] = grid - 1 - d[a];
    above += d[a];
  }
  return d;
}

Eigen::VectorXd DatasetActuation(const DatasetSampling& s, const Eigen::VectorXd& lower,
                                 const Eigen::VectorXd& upper, long long i) {
  const int m = static_cast<int>(lower.size());
  Eigen::VectorXd c(m);
  if (s.kind == DatasetSampling::Kind::kGrid) {
    const std::vector<int> d = SerpentineDigits(i, s.grid, m);
    for (int a = 0; a < m; ++a) {
      // Exact at both ends of the range.
      const double t = static_cast<double>(d[a]) / (s.grid - 1);
      c[a] = d[a] == s.grid - 1 ? upper[a] : lower[a] + (upper[a] - lower[a]) * t;
    }
  } else {
    for (int a = 0; a < m; ++a) {
      const std::uint64_t h = Mix(Mix(s.seed) ^ Mix(static_cast<std::uint64_t>(i) * 64 + a));
      c[a] = lower[a] + (upper[a] - lower[a]) * Unit(h);
    }
  }
  return c;
}

ShardRange DatasetShard(long long total, int block, int k, int n) {
  assert(n >= 1 && k >= 0 && k < n && block >= 1);
  const long long blocks = (total + block - 1) / block;
  const long long b0 = blocks * k / n, b1 = blocks * (k + 1) / n;
  ShardRange r;
  r.first = std::min(total, b0 * block);
  r.count = std::min(total, b1 * block) - r.first;
  return r;
}

// ---- generation ----

DatasetRunSummary GenerateDataset(Kinematics& kin, const DatasetSampling& sampling,
                                  const DatasetRunOptions& opt) {
  const auto t0 = Clock::now();
  std::string why;
  if (!sampling.IsValid(&why)) throw std::invalid_argument(why);
  if (opt.out.empty()) throw std::invalid_argument("out: expected a CSV path");
  if (opt.shards < 1 || opt.shard < 0 || opt.shard >= opt.shards)
    throw std::invalid_argument("shard: expected k/n with 0 <= k < n, got " +
                                std::to_string(opt.shard) + "/" + std::to_string(opt.shards));
  const int m = kin.num_actuators();
  const long long total = DatasetSize(sampling, m);
  if (opt.shards > total)
    throw std::invalid_argument("shard: " + std::to_string(opt.shards) + " shards for " +
                                std::to_string(total) + " samples");
  const ShardRange range = DatasetShard(total, sampling.block, opt.shard, opt.shards);
  const Eigen::VectorXd lower = kin.lower(), upper = kin.upper();
  const std::vector<std::string>& points = kin.point_names();
  const int np = kin.num_points();

  nlohmann::json actuators = nlohmann::json::array();
  for (int a = 0; a < m; ++a) actuators.push_back({lower[a], upper[a]});
  nlohmann::json config = {{"source", opt.source.is_null() ? nlohmann::json::object() : opt.source},
                           {"kinematics", kin.name()},
                           {"points", points},
                           {"actuator_bounds", actuators},
                           {"sampling", sampling.ToJson()},
                           {"samples", total},
                           {"jacobian", opt.jacobian}};
  nlohmann::json shard = {
      {"k", opt.shard}, {"n", opt.shards}, {"first", range.first}, {"count", range.count}};
  const std::string header = HeaderLine(m, points, opt.jacobian);

  DatasetRunSummary sum;
  sum.first = range.first;
  sum.count = range.count;

  // One writer per file: a second process started on the same output (a duplicated job, two
  // shells) stops here instead of interleaving lines with the first.
  const bool existed = fs::exists(opt.out);
  const WriterLock lock(opt.out);
  // Resume or start (an empty file without a sidecar, from a run killed right after creating it,
  // holds nothing).
  bool fresh = true;
  if (fs::exists(opt.out) && (fs::file_size(opt.out) > 0 || fs::exists(SidecarPath(opt.out)))) {
    // A refusal leaves no empty file behind where the lock created one.
    try {
      const nlohmann::json side = ReadSidecar(opt.out);
      std::string d = KeyDifferences(config, side["config"], "config");
      if (d.empty()) d = KeyDifferences(shard, side["shard"], "shard");
      if (!d.empty())
        throw std::invalid_argument(opt.out +
                                    " exists and was made with another configuration (its "
                                    "sidecar " +
                                    SidecarPath(opt.out) + " differs at '" + d +
                                    "'); refusing to overwrite it: remove it "
                                    "or choose another output");
    } catch (...) {
      if (!existed) fs::remove(opt.out);
      throw;
    }
    const RawLines raw = ReadRawLines(opt.out, header, range.first);
    if (static_cast<long long>(raw.lines.size()) > range.count)
      Bad(opt.out, static_cast<long long>(range.count) + 2,
          "more samples than the shard's " + std::to_string(range.count));
    // A kept row must be the sample of its index: the actuation this run would write there.
    for (size_t j = 0; j < raw.lines.size(); ++j) {
      const long long idx = range.first + static_cast<long long>(j);
      const std::vector<std::string> f = SplitFields(raw.lines[j]);
      const Eigen::VectorXd c = DatasetActuation(sampling, lower, upper, idx);
      for (int a = 0; a < m; ++a)
        if (f[2 + a] != Num(c[a]))
          Bad(opt.out, static_cast<long long>(j) + 2,
              "c" + std::to_string(a) + " = " + f[2 + a] + ", expected " + Num(c[a]) + " (sample " +
                  std::to_string(idx) + " of this dataset's sampling)");
    }
    fs::resize_file(opt.out, raw.complete_bytes);  // drop a truncated last line
    sum.already = static_cast<long long>(raw.lines.size());
    fresh = raw.complete_bytes == 0;
  }
  if (fresh) {
    nlohmann::json side = {
        {"format", "softkin-dataset"},
        {"version", kFormatVersion},
        {"config", config},
        {"shard", shard},
        {"provenance", opt.provenance.is_null() ? nlohmann::json::object() : opt.provenance}};
    WriteSidecar(opt.out, side);
  }
  std::ofstream csv(opt.out, std::ios::binary | (fresh ? std::ios::trunc : std::ios::app));
  if (!csv) throw std::runtime_error("cannot write " + opt.out);
  if (fresh) csv << header << "\n" << std::flush;

  const long long start = range.first + sum.already, end = range.first + range.count;
  if (start >= end) return sum;
  // Recompute (not rewrite) the samples of start's block that are already in the file, so the
  // warm-start state at `start` is the one an uninterrupted run has.
  const long long block_start = std::max(range.first, (start / sampling.block) * sampling.block);
  const long long solves0 = kin.total_fk_solves();
  Progress bar(opt.progress, range.count, sum.already);
  for (long long i = block_start; i < end; ++i) {
    if (opt.stop_after >= 0 && sum.written >= opt.stop_after) break;
    if (i % sampling.block == 0 && opt.reset) opt.reset();
    const Eigen::VectorXd c = DatasetActuation(sampling, lower, upper, i);
    KinematicsEval ev = kin.Evaluate(c, opt.jacobian);
    if (ev.ok) {
      // Never write NaN: a kinematics that claims ok with bad numbers is recorded as failed.
      const bool shape =
          ev.p.rows() == np && (!opt.jacobian || (ev.J.rows() == 3 * np && ev.J.cols() == m));
      if (!shape || !ev.p.allFinite() || (opt.jacobian && !ev.J.allFinite())) {
        ev.ok = false;
        ev.message = shape ? "non-finite positions or Jacobian" : "wrong output shape";
      }
    }
    if (opt.after_sample) opt.after_sample();
    if (i < start) continue;
    csv << SampleLine(i, c, ev, np, opt.jacobian) << "\n" << std::flush;
    if (!csv) throw std::runtime_error("error while writing " + opt.out);
    ++sum.written;
    if (!ev.ok) ++sum.failed;
    if (ev.ok && ev.inverted_elements > 0) ++sum.inverted;
    bar.Update(sum.already + sum.written);
  }
  bar.Finish(sum.already + sum.written);
  sum.fk_solves = kin.total_fk_solves() - solves0;
  sum.time_s = SecondsSince(t0);
  return sum;
}

// ---- merge ----

long long MergeDatasets(const std::vector<std::string>& shards, const std::string& out) {
  if (shards.empty()) throw std::invalid_argument("merge: expected at least one shard file");
  std::map<int, std::string> by_k;
  nlohmann::json config;
  int n = -1;
  for (const auto& f : shards) {
    if (fs::exists(out) && fs::equivalent(f, out))
      throw std::invalid_argument("merge: the output " + out + " is also an input");
    const nlohmann::json side = ReadSidecar(f);
    if (n < 0) {
      config = side["config"];
      n = side["shard"].value("n", 0);
    } else {
      const std::string d = KeyDifferences(config, side["config"], "config");
      if (!d.empty())
        throw std::invalid_argument("merge: " + f + " has another configuration than " +
                                    shards.front() + " (sidecars differ at '" + d + "')");
      if (side["shard"].value("n", 0) != n)
        throw std::invalid_argument("merge: " + f + " is a shard of " + side["shard"]["n"].dump() +
                                    ", " + shards.front() + " of " + std::to_string(n));
    }
    const int k = side["shard"].value("k", -1);
    if (by_k.count(k))
      throw std::invalid_argument("merge: shard " + std::to_string(k) + " given twice (" + by_k[k] +
                                  " and " + f + ")");
    by_k[k] = f;
  }
  for (int k = 0; k < n; ++k)
    if (!by_k.count(k))
      throw std::invalid_argument("merge: shard " + std::to_string(k) + "/" + std::to_string(n) +
                                  " is missing");
  const long long total = config.value("samples", 0LL);
  long long written = 0;
  std::string header;
  // Written beside `out` and renamed in only once every shard is in (OutputFile).
  OutputFile file(out, std::ios::binary);
  std::ostream& o = file.stream();
  for (const auto& [k, f] : by_k) {
    const nlohmann::json side = ReadSidecar(f);
    const long long first = side["shard"].value("first", 0LL),
                    count = side["shard"].value("count", 0LL);
    const std::string text = ReadAll(f);
    const std::string h = text.substr(0, text.find('\n'));
    if (header.empty()) {
      header = h;
      o << header << "\n";
    }
    const RawLines raw = ReadRawLines(f, header, first);
    if (raw.truncated || static_cast<long long>(raw.lines.size()) != count)
      throw std::invalid_argument(
          "merge: shard " + f + " is incomplete: " + std::to_string(raw.lines.size()) + " of " +
          std::to_string(count) + " samples" + (raw.truncated ? " and a truncated last line" : "") +
          " (run its generation again to finish it)");
    if (first != written)
      throw std::invalid_argument("merge: shard " + f + " starts at sample " +
                                  std::to_string(first) + ", expected " + std::to_string(written));
    for (const auto& l : raw.lines) o << l << "\n";
    written += count;
  }
  if (written != total)
    throw std::invalid_argument("merge: the shards hold " + std::to_string(written) + " of " +
                                std::to_string(total) + " samples");
  nlohmann::json side = ReadSidecar(by_k.begin()->second);
  side["shard"] = {{"k", 0}, {"n", 1}, {"first", 0}, {"count", total}};
  side["provenance"]["merged_from"] = shards;
  file.Commit();
  WriteSidecar(out, side);
  return written;
}

// ---- loading ----

void CheckSidecarMatches(const Dataset& d, const std::string& csv_path) {
  const std::string side = SidecarPath(csv_path);
  if (!d.meta.is_object())
    throw std::invalid_argument(side +
                                ": not found; expected the sidecar that `softkin dataset` "
                                "writes beside the CSV (its actuator bounds and source)");
  auto fail = [&](const std::string& key, const std::string& what) {
    throw std::invalid_argument(side + ": config." + key + ": " + what);
  };
  const nlohmann::json& cfg = d.meta["config"];
  if (!cfg.contains("points") || cfg["points"] != nlohmann::json(d.point_names))
    fail("points", "expected the CSV's points " + nlohmann::json(d.point_names).dump() + ", got " +
                       (cfg.contains("points") ? cfg["points"].dump() : "none") +
                       " (a sidecar of another dataset?)");
  const nlohmann::json& b =
      cfg.contains("actuator_bounds") ? cfg["actuator_bounds"] : nlohmann::json();
  if (!b.is_array() || static_cast<int>(b.size()) != d.num_actuators)
    fail("actuator_bounds", "expected " + std::to_string(d.num_actuators) +
                                " [lower, upper] pairs, one per actuator column of the CSV");
  for (int a = 0; a < d.num_actuators; ++a) {
    if (!b[a].is_array() || b[a].size() != 2 || !b[a][0].is_number() || !b[a][1].is_number() ||
        !(b[a][0].get<double>() < b[a][1].get<double>()))
      fail("actuator_bounds[" + std::to_string(a) + "]", "expected [lower, upper], lower < upper");
    const double lo = b[a][0].get<double>(), hi = b[a][1].get<double>(), tol = 1e-9 * (hi - lo);
    for (Eigen::Index i = 0; i < d.inputs.rows(); ++i)
      if (d.inputs(i, a) < lo - tol || d.inputs(i, a) > hi + tol)
        fail("actuator_bounds[" + std::to_string(a) + "]",
             "[" + FormatNumber(lo) + ", " + FormatNumber(hi) + "] does not hold sample " +
                 std::to_string(d.index[i]) + " (actuation " + FormatNumber(d.inputs(i, a)) +
                 "): the sidecar is not this CSV's");
  }
}

Dataset LoadDataset(const std::string& path) {
  const std::string text = ReadAll(path);
  Dataset ds;
  if (fs::exists(SidecarPath(path))) ds.meta = ReadSidecar(path);
  size_t pos = text.find('\n');
  if (pos == std::string::npos) Bad(path, 1, "expected a header line ending in a line break");
  // Lines may end in CRLF (a file saved on Windows or by a spreadsheet): the CR is not data.
  auto chomp = [](std::string line) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return line;
  };
  const std::vector<std::string> head = SplitFields(chomp(text.substr(0, pos)));
  // index,status,c0..c{m-1},<point>_x,_y,_z ...,J_... ,message
  if (head.size() < 3 || head[0] != "index" || head[1] != "status" || head.back() != "message")
    Bad(path, 1, "expected a header 'index,status,c0,...,message'");
  size_t col = 2;
  while (col < head.size() && head[col] == "c" + std::to_string(ds.num_actuators)) {
    ++ds.num_actuators;
    ++col;
  }
  if (ds.num_actuators == 0) Bad(path, 1, "expected actuation columns c0, c1, ... after status");
  while (col + 2 < head.size() && head[col].size() > 2 &&
         head[col].compare(head[col].size() - 2, 2, "_x") == 0) {
    const std::string p = head[col].substr(0, head[col].size() - 2);
    if (head[col + 1] != p + "_y" || head[col + 2] != p + "_z")
      Bad(path, 1,
          "column " + std::to_string(col + 1) + ": expected " + p + "_y and " + p + "_z after " +
              head[col]);
    ds.point_names.push_back(p);
    col += 3;
  }
  const int m = ds.num_actuators, P = static_cast<int>(ds.point_names.size());
  if (P == 0) Bad(path, 1, "expected position columns <point>_x,<point>_y,<point>_z");
  const size_t nj = head.size() - 1 - col;
  if (nj != 0 && nj != static_cast<size_t>(3 * P * m))
    Bad(path, 1,
        "expected 0 or " + std::to_string(3 * P * m) + " Jacobian columns, found " +
            std::to_string(nj));
  for (size_t j = 0; j < nj; ++j) {
    const int r = static_cast<int>(j) / m, a = static_cast<int>(j) % m;
    const std::string want =
        "J_" + ds.point_names[r / 3] + "_" + kCoord[r % 3] + "_c" + std::to_string(a);
    if (head[col + j] != want)
      Bad(path, 1,
          "column " + std::to_string(col + j + 1) + ": expected " + want + ", got " +
              head[col + j]);
  }
  const size_t nfields = head.size();

  std::vector<double> in, pos_v, jac;
  long long lineno = 1, last_index = -1;
  ++pos;
  while (pos < text.size()) {
    const size_t nl = text.find('\n', pos);
    ++lineno;
    if (nl == std::string::npos)
      Bad(path, lineno,
          "the last line has no line break (an interrupted run? run the generation "
          "again to resume it)");
    const std::string line = chomp(text.substr(pos, nl - pos));
    pos = nl + 1;
    const std::vector<std::string> f = SplitFields(line);
    if (f.size() != nfields)
      Bad(path, lineno,
          "expected " + std::to_string(nfields) + " fields, found " + std::to_string(f.size()));
    const long long idx = ParseIndex(f[0], path, lineno);
    if (idx <= last_index)
      Bad(path, lineno,
          "sample index " + std::to_string(idx) + " after " + std::to_string(last_index) +
              " (indices must increase)");
    last_index = idx;
    const SampleStatus status = CheckSampleFields(f, head, m, path, lineno);
    if (status != SampleStatus::kOk) {
      ++(status == SampleStatus::kFailed ? ds.failed : ds.inverted);
      continue;
    }
    for (int a = 0; a < m; ++a) in.push_back(ParseNumber(f[2 + a], path, lineno, head[2 + a]));
    for (int j = 0; j < 3 * P; ++j)
      pos_v.push_back(ParseNumber(f[2 + m + j], path, lineno, head[2 + m + j]));
    for (size_t j = 0; j < nj; ++j)
      jac.push_back(ParseNumber(f[col + j], path, lineno, head[col + j]));
    ds.index.push_back(idx);
  }
  const Eigen::Index n = static_cast<Eigen::Index>(ds.index.size());
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  ds.inputs = Eigen::Map<RowMajor>(in.data(), n, m);
  ds.positions = Eigen::Map<RowMajor>(pos_v.data(), n, 3 * P);
  ds.jacobians = Eigen::Map<RowMajor>(jac.data(), n, static_cast<Eigen::Index>(nj));
  return ds;
}

// ---- samples and split ----

SampleSet PositionSamples(const Dataset& d) { return SampleSet{d.inputs, d.positions}; }

SampleSet JacobianSamples(const Dataset& d) {
  if (d.jacobians.cols() == 0)
    throw std::invalid_argument("dataset has no Jacobian columns (generate it with --jacobian)");
  return SampleSet{d.inputs, d.jacobians};
}

TrainTestSets SplitTrainTest(const SampleSet& s, std::uint64_t seed, double train_fraction) {
  const SplitIndices idx = RandomSplit(s.size(), train_fraction, seed);
  TrainTestSets t;
  t.train_rows = idx.first;
  t.test_rows = idx.second;
  t.train = SelectRows(s, idx.first);
  t.test = SelectRows(s, idx.second);
  return t;
}

}  // namespace softkin
