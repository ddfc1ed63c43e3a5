#include "softkin/ik/trajectory.hpp"

#include "softkin/ik/objectives.hpp"
#include "softkin/solver/common/output_file.hpp"
#include "softkin/solver/common/text_format.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>
#include <stdexcept>

namespace softkin {
namespace {

std::string JoinNumbers(const Eigen::VectorXd& v) {
  std::ostringstream s;
  s << std::setprecision(17);
  for (int i = 0; i < v.size(); ++i) s << (i ? "," : "") << v[i];
  return s.str();
}

// The header lines a cache must carry to be reused, in file order.
std::vector<std::pair<std::string, std::string>> CacheHeader(const Kinematics& kin,
                                                             const std::string& point,
                                                             const SamplingOptions& o) {
  return {{"format", "softkin configuration-space samples v1"},
          {"kinematics", kin.name()},
          {"key", o.cache_key},
          {"point", point},
          {"actuators", std::to_string(kin.num_actuators())},
          {"samples_per_axis", std::to_string(o.samples_per_axis)},
          {"lower", JoinNumbers(kin.lower())},
          {"upper", JoinNumbers(kin.upper())}};
}

// Loads the cache; "" on success, else why it cannot be used.
std::string LoadCache(const std::string& path,
                      const std::vector<std::pair<std::string, std::string>>& header, int n,
                      const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                      ConfigurationSamples* out) {
  std::ifstream in(path);
  if (!in) return "cannot read " + path;
  std::map<std::string, std::string> got;
  std::string line;
  std::vector<std::vector<double>> rows;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.empty()) continue;
    if (line[0] == '#') {
      const size_t eq = line.find('=');
      if (eq != std::string::npos) got[line.substr(2, eq - 2)] = line.substr(eq + 1);
      continue;
    }
    if (line.rfind("c0", 0) == 0) continue;  // the column header
    std::vector<double> row;
    std::stringstream ss(line);
    std::string tok;
    while (std::getline(ss, tok, ',')) {
      char* end = nullptr;
      const double v = std::strtod(tok.c_str(), &end);
      if (end == tok.c_str() || *end != '\0' || !std::isfinite(v))
        return path + ":" + std::to_string(lineno) + ": '" + tok + "' is not a finite number";
      row.push_back(v);
    }
    if (static_cast<int>(row.size()) != n + 3)
      return path + ":" + std::to_string(lineno) + ": expected " + std::to_string(n + 3) +
             " columns, found " + std::to_string(row.size());
    for (int a = 0; a < n; ++a)
      if (row[a] < lower[a] || row[a] > upper[a])
        return path + ":" + std::to_string(lineno) + ": c" + std::to_string(a) + " = " +
               FormatNumber(row[a], 10) + " is outside the actuator's range [" +
               FormatNumber(lower[a], 10) + ", " + FormatNumber(upper[a], 10) + "]";
    rows.push_back(std::move(row));
  }
  for (const auto& [k, v] : header) {
    auto it = got.find(k);
    if (it == got.end()) return "the cache has no '" + k + "' line";
    if (it->second != v) return "the cache was built for " + k + "=" + it->second + ", not " + v;
  }
  if (rows.empty()) return "the cache has no samples";
  out->c.resize(rows.size(), n);
  out->p.resize(rows.size(), 3);
  for (size_t i = 0; i < rows.size(); ++i) {
    for (int a = 0; a < n; ++a) out->c(i, a) = rows[i][a];
    for (int d = 0; d < 3; ++d) out->p(i, d) = rows[i][n + d];
  }
  out->failed = std::stoi(got.count("failed") ? got["failed"] : "0");
  return "";
}

}  // namespace

bool SamplingOptions::IsValid(std::string* why) const {
  std::string s;
  if (samples_per_axis < 2)
    s = "samples_per_axis must be >= 2, got " + std::to_string(samples_per_axis);
  if (why) *why = s;
  return s.empty();
}

bool TrajectoryOptions::IsValid(std::string* why) const {
  std::string s;
  if (point.empty())
    s = "point must be named";
  else if (!ik.IsValid(&s))
    s = "ik." + s;
  else if (!sampling.IsValid(&s))
    s = "sampling." + s;
  else if (first_waypoint < 0)
    s = "first_waypoint must be >= 0";
  else if (first_waypoint_starts < 1)
    s = "first_waypoint_starts must be >= 1, got " + std::to_string(first_waypoint_starts);
  if (why) *why = s;
  return s.empty();
}

ConfigurationSamples SampleConfigurationSpace(Kinematics& kin, const std::string& point,
                                              const SamplingOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("SamplingOptions: " + why);
  const int k = ResolvePoint(kin.point_names(), point, "configuration-space sampling");
  const int n = kin.num_actuators(), m = options.samples_per_axis;
  const double total = std::pow(static_cast<double>(m), n);
  if (total > 1e6)
    throw std::invalid_argument("configuration-space sampling: " + std::to_string(m) + "^" +
                                std::to_string(n) + " samples is more than 10^6");
  const auto header = CacheHeader(kin, point, options);
  ConfigurationSamples out;
  std::string rejected;
  if (!options.cache_file.empty() && std::ifstream(options.cache_file).good()) {
    rejected = LoadCache(options.cache_file, header, n, kin.lower(), kin.upper(), &out);
    if (rejected.empty()) {
      out.cache_status = "loaded";
      out.time_s = SecondsSince(t0);
      return out;
    }
  }
  // The grid, first actuator fastest.
  const int count = static_cast<int>(total);
  std::vector<Eigen::VectorXd> cs;
  std::vector<Eigen::Vector3d> ps;
  Eigen::VectorXi digit = Eigen::VectorXi::Zero(n);
  for (int s = 0; s < count; ++s) {
    Eigen::VectorXd c(n);
    for (int a = 0; a < n; ++a)
      c[a] = digit[a] == m - 1
                 ? kin.upper()[a]
                 : kin.lower()[a] + (kin.upper()[a] - kin.lower()[a]) * digit[a] / (m - 1);
    const KinematicsEval e = kin.Evaluate(c, false);
    if (e.ok && e.p.rows() > k && e.p.row(k).allFinite()) {
      cs.push_back(c);
      ps.push_back(e.p.row(k).transpose());
    } else {
      ++out.failed;
    }
    for (int a = 0; a < n && ++digit[a] == m; ++a) digit[a] = 0;
  }
  out.c.resize(cs.size(), n);
  out.p.resize(ps.size(), 3);
  for (size_t i = 0; i < cs.size(); ++i) {
    out.c.row(i) = cs[i].transpose();
    out.p.row(i) = ps[i].transpose();
  }
  if (options.cache_file.empty()) {
    out.cache_status = "built";
  } else {
    OutputFile file(options.cache_file);  // written whole or not at all
    std::ostream& f = file.stream();
    for (const auto& [key, v] : header) f << "# " << key << "=" << v << "\n";
    f << "# failed=" << out.failed << "\n";
    for (int a = 0; a < n; ++a) f << "c" << a << ",";
    f << "x,y,z\n" << std::setprecision(17);
    for (int i = 0; i < out.c.rows(); ++i) {
      for (int a = 0; a < n; ++a) f << out.c(i, a) << ",";
      f << out.p(i, 0) << "," << out.p(i, 1) << "," << out.p(i, 2) << "\n";
    }
    file.Commit();
    out.cache_status = rejected.empty() ? "written" : "rebuilt: " + rejected;
  }
  out.time_s = SecondsSince(t0);
  return out;
}

int ClosestSample(const ConfigurationSamples& samples, const Eigen::Vector3d& target) {
  int best = -1;
  double best_d = 0.0;
  for (int i = 0; i < samples.p.rows(); ++i) {
    const double d = (samples.p.row(i).transpose() - target).squaredNorm();
    if (best < 0 || d < best_d) {
      best = i;
      best_d = d;
    }
  }
  return best;
}

std::vector<int> ClosestSamples(const ConfigurationSamples& samples, const Eigen::Vector3d& target,
                                int count) {
  std::vector<std::pair<double, int>> d;
  d.reserve(samples.p.rows());
  for (int i = 0; i < samples.p.rows(); ++i)
    d.emplace_back((samples.p.row(i).transpose() - target).squaredNorm(), i);
  const size_t n = std::min(d.size(), static_cast<size_t>(std::max(count, 0)));
  std::partial_sort(d.begin(), d.begin() + n, d.end());
  std::vector<int> out;
  for (size_t i = 0; i < n; ++i) out.push_back(d[i].second);
  return out;
}

TrajectoryResult FollowTrajectory(Kinematics& kin,
                                  const Eigen::Ref<const Eigen::MatrixX3d>& waypoints,
                                  const TrajectoryOptions& options,
                                  const WaypointCallback& on_waypoint) {
  const auto t0 = std::chrono::steady_clock::now();
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("TrajectoryOptions: " + why);
  const int k = ResolvePoint(kin.point_names(), options.point, "trajectory");
  for (int w = 0; w < waypoints.rows(); ++w)
    if (!waypoints.row(w).allFinite())
      throw std::invalid_argument("trajectory: waypoint " + std::to_string(w) + " is not finite");
  TrajectoryResult res;
  Eigen::VectorXd c_prev;
  if (options.warm_start.size() > 0) {
    why = CheckKinematicsInput(kin, options.warm_start);
    if (!why.empty()) throw std::invalid_argument("trajectory warm start: " + why);
    c_prev = options.warm_start;
  }
  auto sample_set = [&]() { return options.samples ? options.samples : &res.samples; };
  std::vector<int> starts;  // samples to try for the first waypoint, closest first
  if (options.warm_start.size() == 0 && options.first_waypoint < waypoints.rows()) {
    if (!options.samples)
      res.samples = SampleConfigurationSpace(kin, options.point, options.sampling);
    else if (options.samples->c.cols() != kin.num_actuators() ||
             options.samples->p.rows() != options.samples->c.rows())
      throw std::invalid_argument("trajectory samples: expected #samples x " +
                                  std::to_string(kin.num_actuators()) +
                                  " actuations and as many points");
    starts = ClosestSamples(*sample_set(), waypoints.row(options.first_waypoint).transpose(),
                            options.first_waypoint_starts);
    res.initial_sample = starts.empty() ? -1 : starts.front();
    c_prev = starts.empty() ? kin.rest()
                            : Eigen::VectorXd(sample_set()->c.row(starts.front()).transpose());
  }
  res.initial_guess = c_prev;
  const Eigen::VectorXd range = (kin.upper() - kin.lower()).cwiseMax(1e-300);
  double err_sum = 0.0;
  int err_count = 0;
  Eigen::MatrixXd j_prev;
  for (int w = options.first_waypoint; w < waypoints.rows(); ++w) {
    WaypointResult wr;
    wr.index = w;
    wr.target = waypoints.row(w).transpose();
    const PointTrackingObjective objective(kin.point_names(), options.point, wr.target);
    // broyden: hand the last waypoint's J over (it was taken or updated at c_prev).
    IkOptions io = options.ik;
    if (io.method == IkMethod::kBroyden && io.initial_jacobian.size() == 0)
      io.initial_jacobian = j_prev;
    IkResult ik = SolveIk(kin, objective, c_prev, io);
    if (w == options.first_waypoint && starts.size() > 1) {
      // Further closest samples until one converges; keep the best, add up the cost.
      res.initial_starts_tried = 1;
      IkSummary total = ik.summary;
      for (size_t t = 1; t < starts.size() && !ik.summary.converged(); ++t) {
        const Eigen::VectorXd c_try = sample_set()->c.row(starts[t]).transpose();
        IkOptions it = options.ik;
        const IkResult again = SolveIk(kin, objective, c_try, it);
        ++res.initial_starts_tried;
        total.iterations += again.summary.iterations;
        total.evaluations += again.summary.evaluations;
        total.jacobian_evaluations += again.summary.jacobian_evaluations;
        total.fk_solves += again.summary.fk_solves;
        total.time_s += again.summary.time_s;
        const bool better =
            again.p.rows() > k && (ik.p.rows() <= k || again.objective < ik.objective);
        if (better) {
          ik = again;
          res.initial_sample = starts[t];
          res.initial_guess = c_try;
          c_prev = c_try;
        }
      }
      const std::string tried = "; first waypoint solved from " +
                                std::to_string(res.initial_starts_tried) +
                                " sample(s), kept sample " + std::to_string(res.initial_sample);
      total.termination = ik.summary.termination;
      total.message = ik.summary.message + (res.initial_starts_tried > 1 ? tried : "");
      ik.summary = total;
    } else if (w == options.first_waypoint && !starts.empty()) {
      res.initial_starts_tried = 1;
    }
    j_prev = ik.J;
    wr.c = ik.c;
    wr.termination = ik.summary.termination;
    wr.message = ik.summary.message;
    wr.iterations = ik.summary.iterations;
    wr.evaluations = ik.summary.evaluations;
    wr.fk_solves = ik.summary.fk_solves;
    wr.time_s = ik.summary.time_s;
    if (ik.p.rows() > k) {
      wr.reached = ik.p.row(k).transpose();
      wr.error_mm = (wr.reached - wr.target).norm();
      wr.objective = ik.objective;
      // A reached point in a state with inverted body elements is not a physical answer.
      wr.converged = ik.summary.converged() && ik.inverted_elements == 0;
      wr.inverted_elements = ik.inverted_elements;
      wr.min_volume_ratio = ik.min_volume_ratio;
    } else {  // not even c_prev could be evaluated: no point to report
      wr.reached = Eigen::Vector3d::Zero();
      wr.error_mm = -1.0;
      wr.objective = -1.0;
    }
    const Eigen::VectorXd dc = (wr.c - c_prev).cwiseAbs();
    wr.jump = dc.maxCoeff();
    wr.jump_fraction = dc.cwiseQuotient(range).maxCoeff();
    if (w > options.first_waypoint || options.warm_start.size() > 0) {
      if (res.max_jump_index < 0 || wr.jump > res.max_jump) {
        res.max_jump = wr.jump;
        res.max_jump_index = w;
      }
      res.max_jump_fraction = std::max(res.max_jump_fraction, wr.jump_fraction);
    }
    c_prev = wr.c;
    if (wr.converged) ++res.converged;
    if (wr.inverted_elements > 0) ++res.inverted;
    if (wr.error_mm >= 0) {
      err_sum += wr.error_mm;
      ++err_count;
      res.max_error_mm = std::max(res.max_error_mm, wr.error_mm);
    }
    res.waypoints.push_back(wr);
    if (on_waypoint) on_waypoint(res.waypoints.back());
  }
  if (err_count > 0) res.mean_error_mm = err_sum / err_count;
  res.total_time_s = SecondsSince(t0);
  return res;
}

}  // namespace softkin
