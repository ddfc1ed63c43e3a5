#include "softkin/experiments/cli_ik.hpp"

#include "softkin/experiments/cli_args.hpp"
#include "softkin/ik/ik_solver.hpp"
#include "softkin/ik/simulator_kinematics.hpp"
#include "softkin/ik/trajectory.hpp"
#include "softkin/ik/trajectory_io.hpp"
#include "softkin/learn/net_kinematics.hpp"
#include "softkin/solver/common/text_format.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/scene/scene_json.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace softkin {

namespace fs = std::filesystem;

CLI::App* AddIkCommand(CLI::App* app, IkCommandArgs* a) {
  auto* ik = app->add_subcommand(
      "ik",
      "Inverse kinematics with the simulator in the loop (thesis Ch. 4): find the actuation that "
      "brings a tracked point to a target, or along a waypoint file (Algorithm 4: the first "
      "waypoint starts from the closest of samples^#actuators configuration-space samples, each "
      "later one from the previous solution). Writes one CSV row per waypoint as soon as it is "
      "solved: index, target, actuation c0.., reached point, error_mm, objective (mm^2), "
      "converged, termination, iterations, evaluations, fk_solves, time_s, jump. Progress goes to "
      "stderr. Exit 0 when every waypoint was solved (converged or not: a target outside the "
      "workspace gives the closest point found), 1 when the simulator failed at a waypoint, 2 for "
      "bad input. Units: mm. See docs/ik.md");
  auto* o_robot = ik->add_option("--robot", a->robot, "Embedded robot name (see `softkin robots`)");
  auto* o_scene =
      ik->add_option("--scene", a->scene, "Scene JSON file (see `softkin scene --schema`)");
  o_robot->excludes(o_scene);
  ik->add_option("--res", a->res, "Robot resolution (default: the robot's own)")
      ->needs(o_robot)
      ->check(CLI::Range(1, 1 << 20));
  ik->add_option("--param", a->params,
                 "Robot design parameter NAME=VALUE (repeatable; see `softkin robots`)")
      ->needs(o_robot);
  auto* o_target = ik->add_option("--target", a->target, "One target point x,y,z (mm)");
  auto* o_traj = ik->add_option("--trajectory", a->trajectory,
                                "Waypoint file: one 'x y z' (mm) per line, separated by spaces, "
                                "tabs or commas; '#' comments, "
                                "blank lines and an 'x y z' header line are allowed");
  o_target->excludes(o_traj);
  ik->add_option(
      "--point", a->point,
      "Tracked point: a marker of the scene (its vertices' mean), or 'marker[i]' for its "
      "vertex i (default tip)");
  ik->add_option("--method", a->method,
                 "IK method: " + IkMethodNames() +
                     " (default softls, thesis Algorithm 3); with --nets also 'learned' "
                     "(gauss-newton on the networks, Eq. 5.4-5.6) and 'direct' (the direct-IK "
                     "network N_ik, Table 5.1's baseline)");
  ik->add_option("--jacobian", a->jacobian,
                 "How the simulator's Jacobian dp/dc is computed: fd (central differences, "
                 "Eq. 4.2), fd-warm (differences started from the converged state), implicit "
                 "(implicit differentiation of the equilibrium; default)");
  ik->add_option("--lambda", a->lambda_mm,
                 "Stop a waypoint when the point is within this distance of its target, mm "
                 "(default 0.2, thesis Sec. 4.3)");
  ik->add_option("--max-iterations", a->max_iterations,
                 "i_max: iterations per waypoint of softls / gauss-newton (default 30)");
  ik->add_option("--max-evaluations", a->max_evaluations,
                 "Kinematics evaluations per waypoint, every method (default 300)");
  ik->add_option("--max-time", a->max_time_s, "Wall-time limit per waypoint, s (default 600)");
  // --solver and --gradient-tolerance, in the option table's order.
  CLI::Option* gtol = AddFkOptionFlags(ik, &a->fk_options, {"solver", "gradient_tolerance"}).back();
  gtol->description(gtol->get_description() +
                    " 1e-4 saves about half the iterations but its error depends on the robot: "
                    "micrometres on cable_finger, ~0.1 mm on three_chamber, up to 4 mm on "
                    "finger_manipulator (a soft lateral mode); check yours against a tight solve "
                    "first.");
  ik->add_option("--samples", a->samples,
                 "Configuration-space samples per actuator for the first waypoint's initial guess "
                 "(default 5: 5^3 = 125 for three actuators); 0 starts from the rest actuation");
  ik->add_option("--first-starts", a->first_starts,
                 "The first waypoint is solved from up to this many of the closest samples, "
                 "closest first, until one converges (default 3; 1 is Algorithm 4 as written). A "
                 "sample on a corner of the actuation box can be a stationary point no method "
                 "leaves");
  ik->add_option("--cache", a->cache,
                 "CSV cache of the configuration-space samples: loaded if it was built for the "
                 "same robot, point, Jacobian mode and grid, else (re)built and written");
  ik->add_option("--out", a->out,
                 "Output CSV, one row per waypoint (required unless --interactive)");
  ik->add_option("--nets", a->nets,
                 "Network directory from `softkin train`: IK on the learned kinematics instead of "
                 "the simulator (no --robot/--scene; the reached point is the networks' "
                 "prediction)");
  ik->add_option("--jacobian-source", a->jacobian_source,
                 "With --nets: network (the learned Jacobian N_J, Eq. 5.3; default) or "
                 "fk-derivative (the analytic derivative of N_fk)");
  ik->add_flag("--s2r", a->s2r,
               "With --nets: use the sim-to-real layer, p = N_s2r(N_fk(c)) (Eq. 5.4)");
  ik->add_flag("--interactive", a->interactive,
               "With --nets: read targets 'x y z' (or x,y,z) from stdin, one per line, and print "
               "one CSV row per target to stdout (actuation and predicted point); each target "
               "starts from the previous answer; 'quit' or end of input stops (Fig. 5.13)");
  ik->add_flag("--resume", a->resume,
               "Continue an interrupted run: keep the complete rows already in --out (they must "
               "be for the same waypoints) and solve the rest, warm-started from the last row's "
               "actuation");
  ik->add_flag("--quiet", a->quiet, "No progress on stderr");
  ik->add_flag("--trace-fk", a->trace_fk,
               "One stderr line per forward solve (start: predicted, warm or probe; c; status; "
               "iterations; time), to see where a waypoint's time goes");
  return ik;
}

namespace {

std::string Vec3(const Eigen::Vector3d& v) {
  std::ostringstream s;
  s << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return s.str();
}

/// The complete rows of a waypoint CSV must be for the given waypoints, in order: checks their
/// index and target columns. Returns the byte length of the complete lines (a partial last line,
/// from a killed run, is cut off before appending).
size_t CheckResumeRows(const std::string& out, const Eigen::MatrixX3d& waypoints,
                       const std::string& source) {
  std::ifstream in(out, std::ios::binary);
  std::stringstream buf;
  buf << in.rdbuf();
  const std::string text = buf.str();
  size_t pos = 0;
  int lineno = 0, expected = 0;
  while (pos < text.size()) {
    const size_t nl = text.find('\n', pos);
    if (nl == std::string::npos) break;
    std::string line = text.substr(pos, nl - pos);
    pos = nl + 1;
    if (++lineno == 1 || line.empty()) continue;
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string tok;
    while (std::getline(ss, tok, ',') && f.size() < 4) f.push_back(tok);
    const std::string where = out + ":" + std::to_string(lineno) + ": ";
    const int index = std::stoi(f[0]);
    if (index != expected)
      throw std::invalid_argument("--resume: " + where + "row for waypoint " + f[0] +
                                  ", expected waypoint " + std::to_string(expected));
    if (index >= waypoints.rows())
      throw std::invalid_argument("--resume: " + where + "waypoint " + f[0] + ", but " + source +
                                  " has only " + std::to_string(waypoints.rows()) + " waypoint(s)");
    const Eigen::Vector3d t(std::stod(f[1]), std::stod(f[2]), std::stod(f[3]));
    const Eigen::Vector3d w = waypoints.row(index).transpose();
    if ((t - w).norm() > 1e-6 * (1.0 + w.norm()))
      throw std::invalid_argument("--resume: " + where + "target " + Vec3(t) +
                                  " differs from waypoint " + std::to_string(index) + " " +
                                  Vec3(w) + " of " + source +
                                  " (was the file written for another path?)");
    ++expected;
  }
  return pos;
}

/// The per-waypoint IK options shared by the simulator and the learned kinematics.
IkOptions ParseIkOptions(const IkCommandArgs& a, const std::string& method) {
  IkOptions ik;
  if (!StringToIkMethod(method, &ik.method))
    throw std::invalid_argument("--method: unknown method '" + method + "' (expected one of " +
                                IkMethodNames() + (a.nets.empty() ? "" : ", learned, direct") +
                                ")");
  if (!(a.lambda_mm >= 0) || !std::isfinite(a.lambda_mm))
    throw std::invalid_argument("--lambda: expected a distance >= 0 mm, got " +
                                std::to_string(a.lambda_mm));
  if (a.max_iterations < 1)
    throw std::invalid_argument("--max-iterations: expected an integer >= 1, got " +
                                std::to_string(a.max_iterations));
  if (a.max_evaluations < 1)
    throw std::invalid_argument("--max-evaluations: expected an integer >= 1, got " +
                                std::to_string(a.max_evaluations));
  if (a.samples != 0 && (a.samples < 2 || a.samples > 50))
    throw std::invalid_argument(
        "--samples: expected 0 (start at rest) or an integer in [2, 50], got " +
        std::to_string(a.samples));
  if (a.first_starts < 1 || a.first_starts > 1000)
    throw std::invalid_argument("--first-starts: expected an integer in [1, 1000], got " +
                                std::to_string(a.first_starts));
  if (!(a.max_time_s > 0) || !std::isfinite(a.max_time_s))
    throw std::invalid_argument("--max-time: expected a time > 0 s, got " +
                                std::to_string(a.max_time_s));
  ik.max_time_s = a.max_time_s;
  ik.lambda = a.lambda_mm * a.lambda_mm;
  ik.max_iterations = a.max_iterations;
  ik.max_evaluations = a.max_evaluations;
  return ik;
}

/// The waypoints of --target or --trajectory; *source names them in messages.
Eigen::MatrixX3d ReadTargets(const IkCommandArgs& a, std::string* source) {
  if (!a.target.empty()) {
    const Eigen::VectorXd t = ParseNumberList(a.target, "--target");
    if (t.size() != 3)
      throw std::invalid_argument("--target: expected x,y,z (3 numbers, mm), got " +
                                  std::to_string(t.size()) + " number(s) in '" + a.target + "'");
    *source = "--target";
    return t.transpose();
  }
  *source = a.trajectory;
  return ReadWaypoints(a.trajectory);
}

// ---- IK with the simulator in the loop ----

/// Checks which of the options the simulator IK needs are given.
void CheckSimulatorArgs(const IkCommandArgs& a) {
  if (a.interactive)
    throw std::invalid_argument("--interactive: needs --nets DIR (learned kinematics)");
  if (a.s2r) throw std::invalid_argument("--s2r: needs --nets DIR (learned kinematics)");
  if (a.out.empty()) throw std::invalid_argument("--out: required (the output CSV)");
  if (a.robot.empty() == a.scene.empty())
    throw std::invalid_argument("ik: give exactly one of --robot NAME or --scene FILE");
  if (a.target.empty() == a.trajectory.empty())
    throw std::invalid_argument("ik: give exactly one of --target x,y,z or --trajectory FILE");
  if (a.res < 0) throw std::invalid_argument("--res: expected a positive integer");
}

/// The simulator of `scene` tracking --point, with --gradient-tolerance applied.
std::unique_ptr<SimulatorKinematics> MakeSimulatorKinematics(const IkCommandArgs& a,
                                                             const Scene& scene,
                                                             SimulatorKinematicsOptions ko) {
  const std::string marker = a.point.substr(0, a.point.find('['));
  if (scene.marker_index(marker) < 0) {
    std::string names;
    for (const auto& m : scene.markers) names += (names.empty() ? "" : ", ") + m.name;
    throw std::invalid_argument("--point: '" + marker + "' is not a marker of " +
                                (a.robot.empty() ? "scene " + a.scene : "robot '" + a.robot + "'") +
                                " (its markers: " + names + ")");
  }
  ko.points = {a.point};
  FkOptions fk = ApplyFkOptionFlags(a.fk_options, scene.solver);
  try {
    return std::make_unique<SimulatorKinematics>(scene, ko, &fk);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("--point " + a.point + ": " + e.what());
  }
}

/// Algorithm 4's options: the first waypoint's sampling (and its cache key) or the rest start.
TrajectoryOptions SimulatorTrajectoryOptions(const IkCommandArgs& a, const SimulatorKinematics& kin,
                                             const IkOptions& ik) {
  TrajectoryOptions to;
  to.point = kin.point_names().front();
  to.ik = ik;
  to.sampling.samples_per_axis = a.samples == 0 ? 2 : a.samples;
  to.first_waypoint_starts = a.first_starts;
  to.sampling.cache_file = a.cache;
  std::ostringstream key;
  if (a.robot.empty())
    key << "scene=" << fs::absolute(a.scene).string();
  else
    key << "robot=" << a.robot << " res=" << a.res;
  for (const auto& p : a.params) key << " " << p;
  key << " fk=" << ToString(kin.fk_options().solver);
  to.sampling.cache_key = key.str();
  if (a.samples == 0) to.warm_start = kin.rest();
  return to;
}

/// Opens --out for the rows: a new file with its header or, with --resume, after the complete rows
/// of an interrupted run (the waypoints continue from there: sets to->first_waypoint and
/// to->warm_start). Returns false when the file already holds every waypoint.
bool OpenWaypointCsv(const IkCommandArgs& a, const Eigen::MatrixX3d& waypoints,
                     const std::string& source, int n, TrajectoryOptions* to, std::ofstream* csv) {
  std::ios::openmode mode = std::ios::out | std::ios::trunc;
  bool write_header = true;
  if (a.resume && fs::exists(a.out)) {
    const WaypointCsvResume r = ReadWaypointCsvForResume(a.out, n);
    const size_t keep = CheckResumeRows(a.out, waypoints, source);
    fs::resize_file(a.out, keep);  // drop a partial last line
    if (r.next_index >= waypoints.rows()) {
      if (!a.quiet)
        std::cerr << "softkin ik: " << a.out << " already holds all " << waypoints.rows()
                  << " waypoint(s); nothing to do\n";
      return false;
    }
    if (r.next_index > 0) {
      to->first_waypoint = r.next_index;
      to->warm_start = r.last_c;
    }
    mode = std::ios::out | std::ios::app;
    write_header = false;
    if (!a.quiet)
      std::cerr << "softkin ik: resuming " << a.out << " at waypoint " << r.next_index << " of "
                << waypoints.rows() << "\n";
  } else if (a.resume && !a.quiet) {
    std::cerr << "softkin ik: --resume: " << a.out
              << " does not exist yet; starting at waypoint 0\n";
  }
  csv->open(a.out, mode);
  if (!*csv) throw std::runtime_error("cannot write " + a.out);
  if (write_header) *csv << WaypointCsvHeader(n) << "\n" << std::flush;
  return true;
}

void ReportSimulatorStart(const IkCommandArgs& a, const Scene& scene, int n,
                          const Eigen::MatrixX3d& waypoints, const TrajectoryOptions& to) {
  std::cerr << "softkin ik: " << (a.robot.empty() ? a.scene : a.robot) << " ("
            << scene.mesh.num_vertices() << " vertices, " << n << " actuators), point " << a.point
            << ", " << a.method << ", jacobian " << a.jacobian << ", lambda " << a.lambda_mm
            << " mm, " << waypoints.rows() << " waypoint(s)\n";
  if (to.warm_start.size() == 0) {
    long long total = 1;
    for (int i = 0; i < n; ++i) total *= to.sampling.samples_per_axis;
    std::cerr << "softkin ik: sampling the configuration space (" << total << " samples"
              << (a.cache.empty() ? "" : ", cache " + a.cache) << ")\n";
  }
}

void ReportSimulatorEnd(const IkCommandArgs& a, const TrajectoryResult& r) {
  if (!r.samples.cache_status.empty())
    std::cerr << "softkin ik: samples " << r.samples.cache_status << " (" << r.samples.c.rows()
              << " samples, " << r.samples.time_s << " s)\n";
  std::cerr << "softkin ik: " << r.converged << " of " << r.waypoints.size()
            << " waypoint(s) within lambda; error mean " << r.mean_error_mm << " mm, max "
            << r.max_error_mm << " mm; largest actuation jump " << r.max_jump << " ("
            << 100.0 * r.max_jump_fraction << " % of the range); " << r.total_time_s << " s; wrote "
            << a.out << "\n";
  if (r.inverted > 0)
    std::cerr << "softkin ik: WARNING: " << r.inverted << " of " << r.waypoints.size()
              << " waypoint(s) reached with inverted body elements (column inverted_elements)\n";
}

/// `softkin ik` on the simulator (no --nets).
int RunSimulatorIk(const IkCommandArgs& a) {
  CheckSimulatorArgs(a);
  const IkOptions ik = ParseIkOptions(a, a.method);
  SimulatorKinematicsOptions ko;
  ko.trace = a.trace_fk;
  if (!JacobianModeFromString(a.jacobian, &ko.jacobian))
    throw std::invalid_argument("--jacobian: unknown mode '" + a.jacobian + "' (expected one of " +
                                JacobianModeNames() + ")");
  if (a.point.find("[*]") != std::string::npos)
    throw std::invalid_argument(
        "--point: expected one point (a marker or 'marker[i]'), got the group '" + a.point + "'");
  std::string source;
  const Eigen::MatrixX3d waypoints = ReadTargets(a, &source);
  const Scene scene = a.robot.empty() ? LoadSceneJson(a.scene)
                                      : MakeRobot(a.robot, a.res, ParseRobotParams(a.params));
  const std::unique_ptr<SimulatorKinematics> kin = MakeSimulatorKinematics(a, scene, ko);
  const int n = kin->num_actuators();
  TrajectoryOptions to = SimulatorTrajectoryOptions(a, *kin, ik);
  std::ofstream csv;
  if (!OpenWaypointCsv(a, waypoints, source, n, &to, &csv)) return 0;
  if (!a.quiet) ReportSimulatorStart(a, scene, n, waypoints, to);

  int failed = 0;
  const int total = static_cast<int>(waypoints.rows());
  auto on_waypoint = [&](const WaypointResult& w) {
    csv << WaypointCsvRow(w) << "\n" << std::flush;
    if (!csv) throw std::runtime_error("error while writing " + a.out);
    if (w.error_mm < 0) ++failed;
    if (!a.quiet) {
      char line[256];
      std::snprintf(line, sizeof(line),
                    "  [%d/%d] error %.3f mm, %s, %d iterations, %lld FK solves, %.2f s",
                    w.index + 1, total, w.error_mm, IkTerminationToString(w.termination).c_str(),
                    w.iterations, w.fk_solves, w.time_s);
      std::cerr << line << (w.error_mm < 0 ? " (" + w.message + ")" : std::string()) << "\n";
    }
    if (w.inverted_elements > 0)  // a warning even with --quiet: the reached point is not physical
      std::cerr << "softkin ik: WARNING: waypoint " << w.index << ": " << w.inverted_elements
                << " inverted body element(s) in the solved state (smallest volume ratio "
                << w.min_volume_ratio << "); its reached point is not a physical answer\n";
  };
  const TrajectoryResult r = FollowTrajectory(*kin, waypoints, to, on_waypoint);
  if (!a.quiet) ReportSimulatorEnd(a, r);
  return failed > 0 ? 1 : 0;
}

// ---- IK on the learned kinematics (--nets) ----

/// One target with the direct-IK network: c = N_ik(t), the point predicted by the kinematics.
/// Converged (as for the iterative methods) only if that point is within lambda (`lambda_sq`,
/// mm^2, as IkOptions::lambda) of the target; else "no-progress", with the distance in the message.
WaypointResult DirectWaypoint(const LearnedNets& nets, NetKinematics& kin, int index,
                              const Eigen::Vector3d& target, const Eigen::VectorXd& previous,
                              const Eigen::VectorXd& range, double lambda_sq) {
  const auto t0 = std::chrono::steady_clock::now();
  WaypointResult w;
  w.index = index;
  w.target = target;
  w.c = DirectIk(nets, target);
  const KinematicsEval e = kin.Evaluate(w.c, false);
  w.reached = e.p.row(0).transpose();
  w.error_mm = (w.reached - target).norm();
  w.objective = w.error_mm * w.error_mm;
  w.converged = std::isfinite(w.objective) && w.objective <= lambda_sq;
  w.termination = w.converged ? IkTermination::kConverged : IkTermination::kNoProgress;
  w.message = w.converged ? "direct"
                          : "direct: N_ik's answer is " + FormatNumber(w.error_mm) +
                                " mm from the target, beyond lambda";
  w.evaluations = 1;
  w.time_s = SecondsSince(t0);
  if (previous.size() == w.c.size()) {
    w.jump = (w.c - previous).cwiseAbs().maxCoeff();
    w.jump_fraction = (w.c - previous).cwiseAbs().cwiseQuotient(range).maxCoeff();
  }
  return w;
}

/// Checks the learned IK's own options; returns --jacobian-source.
JacobianSource CheckLearnedArgs(const IkCommandArgs& a) {
  if (a.nets.empty())
    throw std::invalid_argument("--method " + a.method +
                                ": needs --nets DIR (from `softkin train`)");
  if (!a.robot.empty() || !a.scene.empty())
    throw std::invalid_argument("--nets: the networks replace the simulator; drop --robot/--scene");
  const int given = !a.target.empty() + !a.trajectory.empty() + a.interactive;
  if (given != 1)
    throw std::invalid_argument(
        "ik --nets: give exactly one of --target x,y,z, --trajectory FILE or --interactive");
  if (!a.interactive && a.out.empty())
    throw std::invalid_argument("--out: required (the output CSV)");
  if (a.resume)
    throw std::invalid_argument(
        "--resume: not supported with --nets (learned IK takes milliseconds)");
  JacobianSource source;
  if (!JacobianSourceFromString(a.jacobian_source, &source))
    throw std::invalid_argument("--jacobian-source: unknown source '" + a.jacobian_source +
                                "' (expected network or fk-derivative)");
  return source;
}

/// The networks of --nets, checked to have what the method, Jacobian source and --s2r need.
LearnedNets LoadCheckedNets(const IkCommandArgs& a, bool direct, JacobianSource source) {
  LearnedNets nets;
  try {
    nets = LearnedNets::Load(a.nets);
  } catch (const std::runtime_error& e) {
    throw std::invalid_argument(std::string("--nets: ") + e.what());
  }
  if (direct && !nets.has_ik())
    throw std::invalid_argument("--method direct: " + a.nets +
                                " has no ik network (train it with --what fk,ik)");
  if (!direct && source == JacobianSource::kNetwork && !nets.has_jac())
    throw std::invalid_argument("--jacobian-source network: " + a.nets +
                                " has no jac network; train one (--what fk,jac) or use "
                                "--jacobian-source fk-derivative");
  if (a.s2r && !nets.has_s2r())
    throw std::invalid_argument("--s2r: " + a.nets +
                                " has no s2r network (train it with `softkin train --s2r`)");
  if (a.point != "tip" && a.point != nets.points.front())
    throw std::invalid_argument("--point: the networks track '" + nets.points.front() +
                                "' first; got '" + a.point + "'");
  return nets;
}

/// --interactive: targets from stdin, one CSV row per target to stdout (Fig. 5.13).
int RunInteractiveIk(const IkCommandArgs& a, const LearnedNets& nets, NetKinematics& kin,
                     const TrajectoryOptions& to, bool direct) {
  const int n = kin.num_actuators();
  const Eigen::VectorXd range = kin.upper() - kin.lower();
  std::cout << WaypointCsvHeader(n) << "\n" << std::flush;
  if (!a.quiet)
    std::cerr << "softkin ik: " << kin.name() << " from " << a.nets
              << "; type a target 'x y z' (mm) per line, 'quit' to stop\n";
  Eigen::VectorXd previous;
  std::string line;
  int index = 0, lineno = 0;
  while (std::getline(std::cin, line)) {
    ++lineno;
    const size_t b = line.find_first_not_of(" \t\r");
    if (b == std::string::npos || line[b] == '#') continue;
    if (line.compare(b, 4, "quit") == 0 || line.compare(b, 4, "exit") == 0) break;
    std::string norm = line;
    for (char& ch : norm)
      if (ch == ',' || ch == '\t') ch = ' ';
    std::istringstream ss(norm);
    Eigen::Vector3d t;
    std::string extra;
    if (!(ss >> t.x() >> t.y() >> t.z()) || (ss >> extra) || !t.allFinite()) {
      std::cerr << "softkin ik: stdin:" << lineno
                << ": expected a target 'x y z' (3 finite numbers, mm), got '" << line << "'\n";
      continue;
    }
    WaypointResult w;
    if (direct) {
      w = DirectWaypoint(nets, kin, index, t, previous, range, to.ik.lambda);
    } else {
      TrajectoryOptions one = to;
      if (previous.size() == n) one.warm_start = previous;
      const TrajectoryResult r = FollowTrajectory(kin, t.transpose(), one);
      w = r.waypoints.front();
      w.index = index;
      if (previous.size() == n) {
        w.jump = (w.c - previous).cwiseAbs().maxCoeff();
        w.jump_fraction = (w.c - previous).cwiseAbs().cwiseQuotient(range).maxCoeff();
      }
    }
    previous = w.c;
    ++index;
    std::cout << WaypointCsvRow(w) << "\n" << std::flush;
  }
  return 0;
}

/// --target or --trajectory on the learned kinematics, rows into --out.
int RunLearnedWaypoints(const IkCommandArgs& a, const LearnedNets& nets, NetKinematics& kin,
                        const TrajectoryOptions& to, bool direct, const std::string& method) {
  const Eigen::VectorXd range = kin.upper() - kin.lower();
  std::string source_name;
  const Eigen::MatrixX3d waypoints = ReadTargets(a, &source_name);
  std::ofstream csv(a.out);
  if (!csv) throw std::runtime_error("cannot write " + a.out);
  csv << WaypointCsvHeader(kin.num_actuators()) << "\n";
  if (!a.quiet)
    std::cerr << "softkin ik: " << kin.name() << " from " << a.nets << ", "
              << (direct ? std::string("direct") : method) << ", " << waypoints.rows()
              << " waypoint(s) from " << source_name << "\n";
  double sum = 0, worst = 0, total_time = 0, max_jump = 0;
  int converged = 0;
  if (direct) {
    Eigen::VectorXd previous;
    for (int i = 0; i < waypoints.rows(); ++i) {
      const WaypointResult w =
          DirectWaypoint(nets, kin, i, waypoints.row(i).transpose(), previous, range, to.ik.lambda);
      previous = w.c;
      csv << WaypointCsvRow(w) << "\n";
      sum += w.error_mm;
      worst = std::max(worst, w.error_mm);
      total_time += w.time_s;
      max_jump = std::max(max_jump, w.jump);
      converged += w.converged;
    }
  } else {
    const TrajectoryResult r = FollowTrajectory(
        kin, waypoints, to, [&](const WaypointResult& w) { csv << WaypointCsvRow(w) << "\n"; });
    for (const auto& w : r.waypoints) sum += std::max(0.0, w.error_mm);
    worst = r.max_error_mm;
    total_time = r.total_time_s;
    max_jump = r.max_jump;
    converged = r.converged;
  }
  csv.flush();
  if (!csv) throw std::runtime_error("error while writing " + a.out);
  if (!a.quiet) {
    const double N = static_cast<double>(waypoints.rows());
    std::cerr << "softkin ik: " << converged << " of " << waypoints.rows()
              << " waypoint(s) within lambda (predicted); error mean " << sum / N << " mm, max "
              << worst << " mm; largest actuation jump " << max_jump << "; " << 1e3 * total_time / N
              << " ms per waypoint; wrote " << a.out << "\n";
  }
  return 0;
}

/// `softkin ik --nets DIR` (thesis Ch. 5): learned Jacobian IK, or the direct-IK network.
int RunLearnedIk(const IkCommandArgs& a) {
  const JacobianSource source = CheckLearnedArgs(a);
  const bool direct = a.method == "direct";
  const std::string method = a.method == "learned" || direct ? "gauss-newton" : a.method;
  const IkOptions ik = ParseIkOptions(a, method);
  const LearnedNets nets = LoadCheckedNets(a, direct, source);
  NetKinematics kin(nets, source, a.s2r);
  TrajectoryOptions to;
  to.point = nets.points.front();
  to.ik = ik;
  to.sampling.samples_per_axis = a.samples == 0 ? 2 : a.samples;
  to.first_waypoint_starts = a.first_starts;
  if (a.samples == 0) to.warm_start = kin.rest();
  if (a.interactive) return RunInteractiveIk(a, nets, kin, to, direct);
  return RunLearnedWaypoints(a, nets, kin, to, direct, method);
}

}  // namespace

int RunIkCommand(const IkCommandArgs& a) {
  // Before any work: no output overwrites an input or another output, and each can be written.
  std::vector<NamedPath> inputs = SceneInputs(a.scene);
  inputs.push_back({"--trajectory", a.trajectory});
  if (!a.nets.empty())
    for (const std::string& f : LearnedNets::Files(a.nets)) inputs.push_back({"--nets", f});
  CheckCommandPaths(inputs, {{"--out", a.out}, {"--cache", a.cache}});
  if (!a.nets.empty() || a.method == "learned" || a.method == "direct") return RunLearnedIk(a);
  return RunSimulatorIk(a);
}

}  // namespace softkin
