#include "softkin/ik/trajectory_io.hpp"
#include "softkin/solver/common/input_file.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace softkin {
namespace {

// Splits on whitespace and commas; empty fields between two commas count as fields ("").
std::vector<std::string> SplitFields(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  bool in_field = false, after_comma = false;
  for (char ch : line) {
    if (ch == ',') {
      if (in_field || after_comma) out.push_back(cur);
      cur.clear();
      in_field = false;
      after_comma = true;
    } else if (std::isspace(static_cast<unsigned char>(ch))) {
      if (in_field) {
        out.push_back(cur);
        cur.clear();
        in_field = false;
        after_comma = false;
      }
    } else {
      cur += ch;
      in_field = true;
    }
  }
  if (in_field || after_comma) out.push_back(cur);
  return out;
}

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

std::string Where(const std::string& path, int line) {
  return path + ":" + std::to_string(line) + ": ";
}

// Parses a whole field as a finite number or throws with file, line and column.
double ParseNumber(const std::string& tok, const std::string& path, int line, int column) {
  char* end = nullptr;
  errno = 0;
  const double v = tok.empty() ? 0.0 : std::strtod(tok.c_str(), &end);
  if (tok.empty() || end != tok.c_str() + tok.size())
    throw std::invalid_argument(Where(path, line) + "column " + std::to_string(column) + " '" +
                                tok + "' is not a number");
  if (!std::isfinite(v))
    throw std::invalid_argument(Where(path, line) + "column " + std::to_string(column) + " '" +
                                tok + "' is not finite (expected a finite coordinate in mm)");
  return v;
}

}  // namespace

Eigen::MatrixX3d ReadWaypoints(const std::string& path) {
  CheckInputFile(path, "a waypoint file (lines of x y z in mm)");
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(path + ": cannot open the waypoint file");
  std::vector<Eigen::Vector3d> pts;
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    const std::vector<std::string> f = SplitFields(line);
    if (f.empty()) continue;
    if (pts.empty() && f.size() == 3 && Lower(f[0]) == "x" && Lower(f[1]) == "y" &&
        Lower(f[2]) == "z")
      continue;  // header
    if (f.size() != 3)
      throw std::invalid_argument(Where(path, lineno) + "expected 3 values (x y z in mm), found " +
                                  std::to_string(f.size()));
    Eigen::Vector3d p;
    for (int d = 0; d < 3; ++d) p[d] = ParseNumber(f[d], path, lineno, d + 1);
    pts.push_back(p);
  }
  if (pts.empty())
    throw std::invalid_argument(path + ": no waypoints (expected lines of x y z in mm)");
  Eigen::MatrixX3d out(pts.size(), 3);
  for (size_t i = 0; i < pts.size(); ++i) out.row(i) = pts[i].transpose();
  return out;
}

std::string WaypointCsvHeader(int num_actuators) {
  std::ostringstream s;
  s << "index,target_x,target_y,target_z";
  for (int a = 0; a < num_actuators; ++a) s << ",c" << a;
  s << ",reached_x,reached_y,reached_z,error_mm,objective,converged,termination,iterations,"
       "evaluations,fk_solves,time_s,jump,inverted_elements";
  return s.str();
}

std::string WaypointCsvRow(const WaypointResult& w) {
  std::ostringstream s;
  s << std::setprecision(10) << w.index << "," << w.target.x() << "," << w.target.y() << ","
    << w.target.z();
  s << std::setprecision(17);
  for (int a = 0; a < w.c.size(); ++a) s << "," << w.c[a];
  s << std::setprecision(10) << "," << w.reached.x() << "," << w.reached.y() << "," << w.reached.z()
    << "," << w.error_mm << "," << w.objective << "," << (w.converged ? 1 : 0) << ","
    << IkTerminationToString(w.termination) << "," << w.iterations << "," << w.evaluations << ","
    << w.fk_solves << "," << w.time_s << "," << w.jump << "," << w.inverted_elements;
  return s.str();
}

WaypointCsvResume ReadWaypointCsvForResume(const std::string& path, int num_actuators) {
  CheckInputFile(path, "the waypoint CSV to resume");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path + ": cannot open the waypoint CSV");
  std::stringstream buf;
  buf << in.rdbuf();
  const std::string text = buf.str();
  WaypointCsvResume out;
  const std::string header = WaypointCsvHeader(num_actuators);
  size_t pos = 0;
  int lineno = 0;
  while (pos < text.size()) {
    const size_t nl = text.find('\n', pos);
    if (nl == std::string::npos) break;  // an unterminated last line: a killed run's partial row
    std::string line = text.substr(pos, nl - pos);
    pos = nl + 1;
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (lineno == 1) {
      if (line != header)
        throw std::invalid_argument(Where(path, 1) + "expected the header '" + header + "'");
      continue;
    }
    if (line.empty()) continue;
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string tok;
    while (std::getline(ss, tok, ',')) f.push_back(tok);
    const size_t expected = 4 + num_actuators + 13;
    if (f.size() != expected)
      throw std::invalid_argument(Where(path, lineno) + "expected " + std::to_string(expected) +
                                  " columns, found " + std::to_string(f.size()));
    const double idx = ParseNumber(f[0], path, lineno, 1);
    Eigen::VectorXd c(num_actuators);
    for (int a = 0; a < num_actuators; ++a) c[a] = ParseNumber(f[4 + a], path, lineno, 5 + a);
    out.next_index = static_cast<int>(idx) + 1;
    out.last_c = c;
  }
  if (lineno == 0)
    throw std::invalid_argument(path + ": empty (expected the header '" + header + "')");
  return out;
}

}  // namespace softkin
