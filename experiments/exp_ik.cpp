// Thesis Chapter 4 with the simulator in the loop: the initial guess (Fig. 4.1), trajectory
// following (Algorithm 4; Fig. 4.2, 4.3, 4.5) and every IK method x Jacobian mode on one path.
#include "softkin/experiments/ik_config.hpp"
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/experiments/sweep.hpp"
#include "softkin/ik/trajectory_io.hpp"

#include <cstdio>
#include <fstream>
#include <memory>
#include <stdexcept>

namespace softkin {

namespace {

nlohmann::json Vec(const Eigen::VectorXd& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}
nlohmann::json Vec3J(const Eigen::Vector3d& v) { return {v[0], v[1], v[2]}; }

/// Writes the configuration-space samples (c0.., x, y, z) for the figures.
void WriteSamples(const std::string& path, const ConfigurationSamples& s) {
  std::vector<std::string> head;
  for (int a = 0; a < s.c.cols(); ++a) head.push_back("c" + std::to_string(a));
  for (const char* h : {"x", "y", "z"}) head.push_back(h);
  CsvWriter csv(path, head);
  for (int i = 0; i < s.c.rows(); ++i) {
    std::vector<double> row;
    for (int a = 0; a < s.c.cols(); ++a) row.push_back(s.c(i, a));
    for (int d = 0; d < 3; ++d) row.push_back(s.p(i, d));
    csv.Row(row);
  }
}

nlohmann::json SamplesJson(const ConfigurationSamples& s) {
  nlohmann::json j = {{"n", s.c.rows()}, {"failed", s.failed}, {"time_s", s.time_s}};
  if (s.p.rows() > 0) {
    j["min"] = Vec3J(s.p.colwise().minCoeff().transpose());
    j["max"] = Vec3J(s.p.colwise().maxCoeff().transpose());
  }
  return j;
}

/// What a followed path reports: errors, times, counts and continuity.
struct PathStats {
  int n = 0, converged = 0, failed = 0, outside = 0;
  int inverted = 0;  ///< waypoints reached with inverted body elements (not physical)
  double mean_err = 0, max_err = 0, time_s = 0, mean_iter = 0;
  long long fk = 0, evals = 0;
  double max_jump = 0, max_jump_fraction = 0, max_reached_step = 0, max_target_step = 0;
  int max_jump_index = -1;
};

PathStats Stats(const std::vector<WaypointResult>& w, const Kinematics& kin, double lambda_mm) {
  PathStats s;
  s.n = static_cast<int>(w.size());
  const Eigen::VectorXd range = (kin.upper() - kin.lower()).cwiseMax(1e-300);
  int with_err = 0;
  for (size_t i = 0; i < w.size(); ++i) {
    s.converged += w[i].converged;
    s.inverted += w[i].inverted_elements > 0;
    s.time_s += w[i].time_s;
    s.fk += w[i].fk_solves;
    s.evals += w[i].evaluations;
    s.mean_iter += w[i].iterations;
    if (w[i].error_mm < 0) {
      ++s.failed;
      continue;
    }
    ++with_err;
    s.mean_err += w[i].error_mm;
    s.max_err = std::max(s.max_err, w[i].error_mm);
    if (w[i].error_mm > lambda_mm * (1 + 1e-9)) ++s.outside;
    if (i > 0 && w[i - 1].error_mm >= 0) {
      const double jump = (w[i].c - w[i - 1].c).cwiseAbs().maxCoeff();
      if (jump > s.max_jump) {
        s.max_jump = jump;
        s.max_jump_index = static_cast<int>(i);
      }
      s.max_jump_fraction = std::max(
          s.max_jump_fraction, (w[i].c - w[i - 1].c).cwiseAbs().cwiseQuotient(range).maxCoeff());
      s.max_reached_step = std::max(s.max_reached_step, (w[i].reached - w[i - 1].reached).norm());
      s.max_target_step = std::max(s.max_target_step, (w[i].target - w[i - 1].target).norm());
    }
  }
  if (with_err) s.mean_err /= with_err;
  if (s.n) s.mean_iter /= s.n;
  return s;
}

nlohmann::json StatsJson(const PathStats& s) {
  return {{"waypoints", s.n},
          {"converged", s.converged},
          {"inverted_waypoints", s.inverted},
          {"kinematics_failures", s.failed},
          {"beyond_lambda", s.outside},
          {"mean_error_mm", s.mean_err},
          {"max_error_mm", s.max_err},
          {"ik_time_s", s.time_s},
          {"s_per_waypoint", s.n ? s.time_s / s.n : 0.0},
          {"mean_iterations", s.mean_iter},
          {"fk_solves", s.fk},
          {"evaluations", s.evals},
          {"max_jump", s.max_jump},
          {"max_jump_fraction", s.max_jump_fraction},
          {"max_jump_index", s.max_jump_index},
          {"max_reached_step_mm", s.max_reached_step},
          {"max_target_step_mm", s.max_target_step}};
}

/// Follows `waypoints` from the closest of `samples` (up to s.first_waypoint_starts of them for
/// the first waypoint), streaming rows into `csv_path` and progress to stderr.
TrajectoryResult Follow(SimulatorKinematics& kin, const Eigen::MatrixX3d& waypoints,
                        const ConfigurationSamples& samples, const IkExperimentSetup& s,
                        const IkOptions& ik, const std::string& csv_path, const std::string& label,
                        bool verbose) {
  std::ofstream csv(csv_path);
  if (!csv) throw std::runtime_error("cannot write " + csv_path);
  csv << WaypointCsvHeader(kin.num_actuators()) << "\n";
  TrajectoryOptions to;
  to.point = kin.point_names().front();
  to.ik = ik;
  to.samples = &samples;
  to.first_waypoint_starts = s.first_waypoint_starts;
  kin.Reset();
  const int total = static_cast<int>(waypoints.rows());
  auto cb = [&](const WaypointResult& w) {
    csv << WaypointCsvRow(w) << "\n" << std::flush;
    if (verbose)
      std::fprintf(stderr, "  [%s %d/%d] error %.3f mm, %s, %d it, %lld FK, %.2f s%s%s\n",
                   label.c_str(), w.index + 1, total, w.error_mm,
                   IkTerminationToString(w.termination).c_str(), w.iterations, w.fk_solves,
                   w.time_s, w.message.empty() ? "" : ": ", w.message.c_str());
  };
  return FollowTrajectory(kin, waypoints, to, cb);
}

ConfigurationSamples Sample(SimulatorKinematics& kin, const IkExperimentSetup& s, bool verbose) {
  SamplingOptions so;
  so.samples_per_axis = s.samples_per_axis;
  if (verbose) std::fprintf(stderr, "  sampling %d per actuator\n", s.samples_per_axis);
  kin.Reset();
  ConfigurationSamples samples = SampleConfigurationSpace(kin, kin.point_names().front(), so);
  if (samples.c.rows() == 0) throw std::runtime_error("every configuration-space sample failed");
  return samples;
}

// ---- Fig. 4.1: the objective against iteration from rest and from the sampled initial guess ----

/// The keys of an ik_initial_guess config.
struct InitialGuessParams {
  IkExperimentSetup s;
  std::vector<double> target_actuation;  ///< the target is the point it reaches
};

InitialGuessParams ReadInitialGuessParams(const Config& cfg) {
  InitialGuessParams p;
  p.s = ReadIkSetup(cfg, "cable_finger");
  p.target_actuation = cfg.NumberList("target_actuation", {});
  cfg.CheckNoUnknownKeys();
  return p;
}

/// The target: the point that target_actuation reaches (checked against the kinematics).
Eigen::Vector3d TargetPoint(const Config& cfg, const std::vector<double>& ta,
                            SimulatorKinematics& kin, Eigen::VectorXd* c_target) {
  if (static_cast<int>(ta.size()) != kin.num_actuators())
    cfg.Fail("target_actuation", std::to_string(kin.num_actuators()) +
                                     " actuation values (the target is the point they reach)");
  *c_target = Eigen::Map<const Eigen::VectorXd>(ta.data(), ta.size());
  const std::string why = CheckKinematicsInput(kin, *c_target);
  if (!why.empty()) cfg.Fail("target_actuation", "values inside the box (" + why + ")");
  kin.Reset();
  const KinematicsEval te = kin.Evaluate(*c_target, false);
  if (!te.ok)
    throw std::runtime_error("the forward solve at target_actuation failed: " + te.message);
  return te.p.row(0).transpose();
}

// ---- Fig. 4.2, 4.3, 4.5: trajectory following (Algorithm 4) ----

/// The keys of an ik_trajectory config.
struct TrajectoryParams {
  IkExperimentSetup s;
  nlohmann::json paths;  ///< a non-empty array of path objects (ik_config.hpp)
};

TrajectoryParams ReadTrajectoryParams(const Config& cfg) {
  TrajectoryParams p;
  p.s = ReadIkSetup(cfg, "cable_finger");
  p.paths = cfg.Raw("paths");
  cfg.CheckNoUnknownKeys();
  if (!p.paths.is_array() || p.paths.empty())
    cfg.Fail("paths", "a non-empty array of path objects");
  return p;
}

// ---- every IK method x Jacobian mode on the same waypoints ----

/// The keys of an ik_methods config.
struct IkMethodsParams {
  IkExperimentSetup s;
  nlohmann::json path_spec;
  std::vector<IkMethod> methods;
  std::vector<JacobianMode> jmodes;
  /// The config but its method and Jacobian lists: what a journaled row was computed with.
  nlohmann::json settings;
};

IkMethodsParams ReadIkMethodsParams(const Config& cfg) {
  IkMethodsParams p;
  p.s = ReadIkSetup(cfg, "cable_finger");
  p.path_spec = cfg.Raw("path");
  std::vector<std::string> method_names;
  for (IkMethod m : AllIkMethods()) method_names.push_back(IkMethodToString(m));
  method_names = cfg.StringList("methods", method_names);
  const std::vector<std::string> modes = cfg.StringList("jacobians", {"fd", "fd-warm", "implicit"});
  cfg.CheckNoUnknownKeys();
  for (const auto& m : method_names) {
    IkMethod x;
    if (!StringToIkMethod(m, &x))
      cfg.Fail("methods", "names out of " + IkMethodNames() + " ('" + m + "' is not)");
    p.methods.push_back(x);
  }
  for (const auto& m : modes) {
    JacobianMode x;
    if (!JacobianModeFromString(m, &x))
      cfg.Fail("jacobians", "names out of " + JacobianModeNames() + " ('" + m + "' is not)");
    p.jmodes.push_back(x);
  }
  p.settings = cfg.json();
  for (const char* k : {"methods", "jacobians", "description", "name"}) p.settings.erase(k);
  p.settings["quick"] = cfg.quick();
  return p;
}

/// One method with one Jacobian mode on the path; returns its row of methods.csv.
nlohmann::json MethodRow(const IkMethodsParams& p, const std::shared_ptr<const Model>& model,
                         IkMethod m, JacobianMode jmode, const std::string& jname,
                         const IkPath& path, const ConfigurationSamples& samples,
                         const std::string& dir, bool verbose) {
  const IkExperimentSetup& s = p.s;
  SimulatorKinematicsOptions ko = s.KinematicsFor({s.point});
  ko.jacobian = jmode;
  SimulatorKinematics kin(model, ko, &s.fk);
  IkOptions ik = s.ik;
  ik.method = m;
  const std::string label = IkMethodToString(m) + "/" + jname;
  const TrajectoryResult r =
      Follow(kin, path.waypoints, samples, s, ik,
             dir + "/path_" + IkMethodToString(m) + "_" + jname + ".csv", label, verbose);
  const PathStats st = Stats(r.waypoints, kin, s.lambda_mm);
  const double ms = st.n ? 1e3 * st.time_s / st.n : 0.0;
  if (verbose)
    std::fprintf(stderr,
                 "  %s: %d/%d converged, %.1f ms/waypoint, mean %.3f mm, max %.3f mm, %lld FK\n",
                 label.c_str(), st.converged, st.n, ms, st.mean_err, st.max_err, st.fk);
  return {{"method", IkMethodToString(m)},
          {"jacobian", jname},
          {"waypoints", st.n},
          {"converged", st.converged},
          {"inverted_waypoints", st.inverted},
          {"ms_per_waypoint", ms},
          {"mean_err_mm", st.mean_err},
          {"max_err_mm", st.max_err},
          {"fk_calls", st.fk},
          {"fk_calls_per_waypoint", st.n ? double(st.fk) / st.n : 0.0},
          {"evaluations", st.evals},
          {"mean_iterations", st.mean_iter},
          {"failures", st.failed},
          {"initial_sample", r.initial_sample},
          {"initial_starts_tried", r.initial_starts_tried}};
}

}  // namespace

nlohmann::json RunIkInitialGuess(const Config& cfg, const std::string& dir, bool verbose) {
  const InitialGuessParams p = ReadInitialGuessParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  const IkExperimentSetup& s = p.s;
  SimulatorKinematics kin(s.scene, s.KinematicsFor({s.point}), &s.fk);
  Eigen::VectorXd c_target;
  const Eigen::Vector3d target = TargetPoint(cfg, p.target_actuation, kin, &c_target);

  const ConfigurationSamples samples = Sample(kin, s, verbose);
  WriteSamples(dir + "/samples.csv", samples);
  const int closest = ClosestSample(samples, target);

  CsvWriter hist(dir + "/history.csv", {"start", "iteration", "objective"});
  nlohmann::json runs = nlohmann::json::array();
  const PointTrackingObjective obj(kin.point_names(), kin.point_names().front(), target);
  for (const std::string start : {"rest", "sampled"}) {
    const Eigen::VectorXd c0 =
        start == "rest" ? kin.rest() : Eigen::VectorXd(samples.c.row(closest).transpose());
    kin.Reset();
    const IkResult r = SolveIk(kin, obj, c0, s.ik);
    for (size_t i = 0; i < r.summary.history.size(); ++i)
      hist.RowStrings({start, std::to_string(i), std::to_string(r.summary.history[i])});
    if (verbose)
      std::fprintf(stderr, "  [%s] %s\n", start.c_str(), r.summary.BriefReport().c_str());
    const double err = r.p.rows() ? (r.p.row(0).transpose() - target).norm() : -1.0;
    runs.push_back({{"start", start},
                    {"c0", Vec(c0)},
                    {"c", Vec(r.c)},
                    {"termination", IkTerminationToString(r.summary.termination)},
                    {"initial_objective", r.summary.initial_objective},
                    {"final_objective", r.summary.final_objective},
                    {"error_mm", err},
                    {"iterations", r.summary.iterations},
                    {"evaluations", r.summary.evaluations},
                    {"fk_solves", r.summary.fk_solves},
                    {"time_s", r.summary.time_s}});
  }
  nlohmann::json j = s.Json();
  j["target_actuation"] = Vec(c_target);
  j["target"] = Vec3J(target);
  j["closest_sample"] = {{"index", closest},
                         {"c", Vec(samples.c.row(closest).transpose())},
                         {"point", Vec3J(samples.p.row(closest).transpose())}};
  j["samples"] = SamplesJson(samples);
  j["runs"] = runs;
  j["thesis"] = {{"samples", 125}, {"sampling_time_s", 8.3}};
  return j;
}

nlohmann::json RunIkTrajectory(const Config& cfg, const std::string& dir, bool verbose) {
  const TrajectoryParams p = ReadTrajectoryParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  const IkExperimentSetup& s = p.s;
  const nlohmann::json& paths = p.paths;
  SimulatorKinematics kin(s.scene, s.KinematicsFor({s.point}), &s.fk);
  const ConfigurationSamples samples = Sample(kin, s, verbose);
  WriteSamples(dir + "/samples.csv", samples);

  nlohmann::json out = nlohmann::json::array();
  double total = 0;
  for (size_t i = 0; i < paths.size(); ++i) {
    kin.Reset();
    const IkPath path =
        MakeIkPath(paths[i], cfg.path() + ": paths[" + std::to_string(i) + "]", kin, samples);
    const TrajectoryResult r = Follow(kin, path.waypoints, samples, s, s.ik,
                                      dir + "/path_" + path.name + ".csv", path.name, verbose);
    const PathStats st = Stats(r.waypoints, kin, s.lambda_mm);
    nlohmann::json pj = StatsJson(st);
    pj["name"] = path.name;
    pj["spec"] = path.info;
    pj["initial_sample"] = r.initial_sample;
    pj["initial_guess"] = Vec(r.initial_guess);
    pj["initial_starts_tried"] = r.initial_starts_tried;
    pj["total_time_s"] = r.total_time_s;
    pj["total_time_with_sampling_s"] = r.total_time_s + samples.time_s;
    pj["thesis"] = path.thesis;
    total += r.total_time_s;
    out.push_back(pj);
    if (verbose)
      std::fprintf(stderr, "  %s: %d/%d within %.2f mm, mean %.3f mm, max %.3f mm, %.1f s\n",
                   path.name.c_str(), st.converged, st.n, s.lambda_mm, st.mean_err, st.max_err,
                   r.total_time_s);
  }
  nlohmann::json j = s.Json();
  j["samples"] = SamplesJson(samples);
  j["paths"] = out;
  j["total_time_s"] = total;
  return j;
}

nlohmann::json RunIkMethods(const Config& cfg, const std::string& dir, bool verbose) {
  const IkMethodsParams p = ReadIkMethodsParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  const IkExperimentSetup& s = p.s;
  auto model = std::make_shared<const Model>(s.scene);
  SimulatorKinematics probe(model, s.KinematicsFor({s.point}), &s.fk);
  const ConfigurationSamples samples = Sample(probe, s, verbose);
  probe.Reset();
  const IkPath path = MakeIkPath(p.path_spec, cfg.path() + ": path", probe, samples);
  const Eigen::VectorXd closest =
      samples.c.row(ClosestSample(samples, path.waypoints.row(0).transpose())).transpose();

  // Resume: each finished method x Jacobian row is journaled with every setting that produced it
  // (the config but its method and Jacobian lists); a rerun reuses matching rows. Under mpirun the
  // ranks share the rows (experiments/sweep.hpp).
  Sweep sweep(dir + "/methods.jsonl", "ik_methods", verbose);
  struct Unit {
    IkMethod method;
    JacobianMode jmode;
    std::string jname;
  };
  std::vector<Unit> units;
  std::vector<nlohmann::json> keys;
  for (IkMethod m : p.methods) {
    // BOBYQA never asks for J: one run, whatever the mode.
    const bool derivative_free = m == IkMethod::kNloptBobyqa;
    for (size_t k = 0; k < p.jmodes.size(); ++k) {
      if (derivative_free && k > 0) break;
      const std::string jname = derivative_free ? "none" : JacobianModeToString(p.jmodes[k]);
      units.push_back({m, p.jmodes[k], jname});
      keys.push_back(
          {{"settings", p.settings}, {"method", IkMethodToString(m)}, {"jacobian", jname}});
    }
  }
  sweep.Run(keys, [&](size_t i) {
    const Unit& u = units[i];
    return MethodRow(p, model, u.method, u.jmode, u.jname, path, samples, dir, verbose);
  });
  if (!Sweep::WritesResults()) return {};
  const nlohmann::json rows = sweep.WriteTable(
      dir + "/methods.csv",
      {"method", "jacobian", "waypoints", "converged", "ms_per_waypoint", "mean_err_mm",
       "max_err_mm", "fk_calls", "fk_calls_per_waypoint", "evaluations", "mean_iterations",
       "failures", "initial_sample", "initial_starts_tried"});
  nlohmann::json j = s.Json();
  j.erase("method");
  j.erase("jacobian");
  j["path"] = path.info;
  j["waypoints"] = path.waypoints.rows();
  j["closest_sample"] = Vec(closest);
  j["samples"] = SamplesJson(samples);
  j["rows"] = rows;
  j["resumed_rows"] = sweep.resumed();
  return j;
}

}  // namespace softkin
