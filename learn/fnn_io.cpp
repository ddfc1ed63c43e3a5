// The "softkin-fnn v1" file format of Fnn (documented in learn/fnn.hpp): writer and checking
// reader.
#include "softkin/learn/fnn.hpp"
#include "softkin/solver/common/input_file.hpp"

#include "softkin/solver/common/output_file.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <istream>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace softkin {

namespace {

constexpr const char* kMagic = "softkin-fnn";
constexpr int kVersion = 1;
constexpr int kMaxLayerSize = 1 << 20;  // guards against absurd allocations from a corrupt file

std::string FormatDouble(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

// Line-oriented reader that knows where it is, for error messages.
class Reader {
 public:
  Reader(std::istream& in, std::string source) : in_(in), source_(std::move(source)) {}

  [[noreturn]] void Fail(const std::string& field, const std::string& what) const {
    throw std::runtime_error(source_ + ":" + std::to_string(line_no_) + ": softkin-fnn field '" +
                             field + "': " + what);
  }

  // Next non-empty, non-comment line split into tokens; fails with "unexpected end of file".
  std::vector<std::string> NextLine(const std::string& field) {
    std::string line;
    while (std::getline(in_, line)) {
      ++line_no_;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      std::istringstream ss(line);
      std::vector<std::string> tokens;
      std::string t;
      while (ss >> t) tokens.push_back(t);
      if (tokens.empty() || tokens[0][0] == '#') continue;
      return tokens;
    }
    ++line_no_;
    Fail(field, "unexpected end of file (truncated?)");
  }

  // A line "<key> <v_1> ... <v_count>" (count < 0: any count >= 0) as its value tokens.
  std::vector<std::string> KeyLine(const std::string& key, int count) {
    std::vector<std::string> t = NextLine(key);
    if (t[0] != key) Fail(key, "expected a line starting with '" + key + "', found '" + t[0] + "'");
    t.erase(t.begin());
    if (count >= 0 && static_cast<int>(t.size()) != count)
      Fail(key,
           "expected " + std::to_string(count) + " value(s), found " + std::to_string(t.size()));
    return t;
  }

  double ParseDouble(const std::string& field, const std::string& token) const {
    errno = 0;
    char* end = nullptr;
    const double v = std::strtod(token.c_str(), &end);
    if (end == token.c_str() || *end != '\0') Fail(field, "'" + token + "' is not a number");
    if (!std::isfinite(v)) Fail(field, "'" + token + "' is not finite");
    return v;
  }

  int ParseInt(const std::string& field, const std::string& token, int lo, int hi) const {
    errno = 0;
    char* end = nullptr;
    const long v = std::strtol(token.c_str(), &end, 10);
    if (end == token.c_str() || *end != '\0' || errno == ERANGE)
      Fail(field, "'" + token + "' is not an integer");
    if (v < lo || v > hi)
      Fail(field,
           token + " is out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return static_cast<int>(v);
  }

  Eigen::VectorXd Vector(const std::string& key, int n) {
    const std::vector<std::string> t = KeyLine(key, n);
    Eigen::VectorXd v(n);
    for (int i = 0; i < n; ++i) v(i) = ParseDouble(key + "[" + std::to_string(i) + "]", t[i]);
    return v;
  }

  const std::string& source() const { return source_; }

 private:
  std::istream& in_;
  std::string source_;
  int line_no_ = 0;
};

MinMaxMap ReadMap(Reader& r, const std::string& prefix, int n) {
  const Eigen::VectorXd lo = r.Vector(prefix + "_min", n);
  const Eigen::VectorXd hi = r.Vector(prefix + "_max", n);
  for (int i = 0; i < n; ++i)
    if (lo(i) > hi(i))
      r.Fail(prefix + "_max[" + std::to_string(i) + "]",
             "max " + FormatDouble(hi(i)) + " is below min " + FormatDouble(lo(i)));
  return MinMaxMap(lo, hi);
}

}  // namespace

void Fnn::Write(std::ostream& out) const {
  if (num_layers() == 0) throw std::runtime_error("Fnn::Write: the network is empty");
  out << kMagic << " v" << kVersion << "\n";
  out << "activation tansig\n";
  out << "layers " << sizes_.size() << "\n";
  out << "sizes";
  for (int n : sizes_) out << " " << n;
  out << "\n";
  auto vec = [&](const char* key, const Eigen::VectorXd& v) {
    out << key;
    for (Eigen::Index i = 0; i < v.size(); ++i) out << " " << FormatDouble(v(i));
    out << "\n";
  };
  vec("input_min", in_map_.xmin());
  vec("input_max", in_map_.xmax());
  vec("output_min", out_map_.xmin());
  vec("output_max", out_map_.xmax());
  const Eigen::VectorXd w = parameters();
  out << "parameters " << w.size() << "\n";
  for (Eigen::Index i = 0; i < w.size(); ++i) out << FormatDouble(w(i)) << "\n";
  out << "end\n";
}

void Fnn::Save(const std::string& path) const {
  if (num_layers() == 0) throw std::runtime_error("Fnn::Save(" + path + "): the network is empty");
  OutputFile f(path, std::ios::binary);  // atomic: a failed write leaves the old network
  Write(f.stream());
  f.Commit();
}

Fnn Fnn::Read(std::istream& in, const std::string& source) {
  Reader r(in, source);
  {
    const std::vector<std::string> t = r.NextLine("magic");
    if (t[0] != kMagic)
      r.Fail("magic",
             "expected '" + std::string(kMagic) + "', found '" + t[0] + "' (not a network file?)");
    if (t.size() != 2)
      r.Fail("version", "expected '" + std::string(kMagic) + " v" + std::to_string(kVersion) + "'");
    if (t[1] != "v" + std::to_string(kVersion))
      r.Fail("version",
             "unsupported version '" + t[1] + "', this reader knows v" + std::to_string(kVersion));
  }
  {
    const std::vector<std::string> t = r.KeyLine("activation", 1);
    if (t[0] != "tansig")
      r.Fail("activation", "unknown activation '" + t[0] + "', expected 'tansig'");
  }
  const int n_sizes = r.ParseInt("layers", r.KeyLine("layers", 1)[0], 2, 1000);
  std::vector<int> sizes(n_sizes);
  {
    const std::vector<std::string> t = r.KeyLine("sizes", n_sizes);
    for (int i = 0; i < n_sizes; ++i)
      sizes[i] = r.ParseInt("sizes[" + std::to_string(i) + "]", t[i], 1, kMaxLayerSize);
  }
  long long expected = 0;
  for (int l = 1; l < n_sizes; ++l)
    expected += static_cast<long long>(sizes[l]) * (sizes[l - 1] + 1);
  if (expected > (1LL << 31) - 1)
    r.Fail("sizes", "the network would have " + std::to_string(expected) + " parameters");
  Fnn net(sizes);
  net.in_map_ = ReadMap(r, "input", sizes.front());
  net.out_map_ = ReadMap(r, "output", sizes.back());
  const int count = r.ParseInt("parameters", r.KeyLine("parameters", 1)[0], 0, 1 << 30);
  if (count != net.num_parameters())
    r.Fail("parameters", "count " + std::to_string(count) + " does not match the sizes (" +
                             net.Describe() + " has " + std::to_string(net.num_parameters()) + ")");
  Eigen::VectorXd w(count);
  for (int i = 0; i < count; ++i) {
    const std::string field = "parameters[" + std::to_string(i) + "]";
    const std::vector<std::string> t = r.NextLine(field);
    if (t.size() != 1)
      r.Fail(field, "expected one number per line, found " + std::to_string(t.size()) + " tokens");
    w(i) = r.ParseDouble(field, t[0]);
  }
  net.set_parameters(w);
  {
    const std::vector<std::string> t = r.NextLine("end");
    if (t.size() != 1 || t[0] != "end")
      r.Fail("end", "expected 'end' after the parameters, found '" + t[0] + "'");
  }
  return net;
}

Fnn Fnn::Load(const std::string& path) {
  CheckInputFile(path, "a network file (.fnn)");
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error("Fnn::Load: cannot open '" + path + "'");
  return Read(f, path);
}

}  // namespace softkin
