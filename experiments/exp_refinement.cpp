// Convergence under mesh refinement, robot by robot (issue #35): each case is an embedded robot
// with its design parameters and one actuation, solved at four or more resolutions; the tip's
// change from one resolution to the next says whether the answer converges. (The tracked point
// is the marker `tip` unless the case names another.) A pneumatic case may instead prescribe the
// chambers' volume ratios: then each resolution is solved at the actuation that reaches them
// (matched_volume.hpp), so that the robots are compared at equal chamber volume. A case solves
// with its robot's own solver options (the contact robots' self-collision response), with the
// config's solver object and the case's solver on top. Each
// resolution of each case is a unit of a journaled sweep (sweep.hpp): rerun, a killed run solves
// only what is missing, and under mpirun the ranks share the units.
#include "softkin/experiments/matched_volume.hpp"
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/experiments/sweep.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/robots/robot_twisting.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/scene/solver_options_json.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace softkin {

namespace {

struct RefinementCase {
  std::string key;  ///< its place in the config, cases[i], for errors
  std::string label, robot, marker = "tip";
  RobotParams params;
  std::vector<double> actuation;  ///< one value per actuator
  std::vector<double> volume;     ///< instead of actuation: the chambers' volume ratios
  std::vector<int> resolutions;   ///< increasing, at least 4
  /// If set (non-zero), each row also records the marker's twist about this axis (degrees,
  /// TwistAboutAxisDegrees of its rest and deformed vertices): what a twisting robot does.
  Eigen::Vector3d twist_axis = Eigen::Vector3d::Zero();
  std::string solver;  ///< "": the config's solver.solver
  FkOptions opts;      ///< the robot's own solver options (collision response), the config's on top
};

std::string CaseKeys() {
  return "label (string), robot (string), solver (a solver name, instead of the config's), marker "
         "(the tracked marker's name; default tip), "
         "robot_params (object of numbers), actuation (array of "
         "numbers, one per actuator) or volume_ratio (array of positive numbers, the chamber "
         "volume ratios to reach, one per actuator, all unsigned pneumatic; 1 leaves a chamber at "
         "rest), "
         "resolutions (array of at least "
         "4 increasing integers), twist_axis (3 numbers, not all 0: also record the marker's "
         "twist about this axis, degrees; the marker needs 3 or more vertices)";
}

RefinementCase ReadCase(const Config& cfg, const nlohmann::json& c, const std::string& key) {
  if (!c.is_object()) cfg.Fail(key, "an object with " + CaseKeys());
  RefinementCase rc;
  rc.key = key;
  for (const auto& [k, v] : c.items()) {
    if (k == "label" && v.is_string()) {
      rc.label = v.get<std::string>();
    } else if (k == "robot" && v.is_string()) {
      rc.robot = v.get<std::string>();
    } else if (k == "solver" && v.is_string()) {
      rc.solver = v.get<std::string>();
      const auto names = FkSolverTypeNames();
      if (std::find(names.begin(), names.end(), rc.solver) == names.end()) {
        std::string list;
        for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
        cfg.Fail(key + ".solver", "one of " + list);
      }
    } else if (k == "marker" && v.is_string()) {
      rc.marker = v.get<std::string>();
    } else if (k == "robot_params") {
      rc.params = cfg.NumberObject(v, key + ".robot_params");
    } else if (k == "actuation" && v.is_array() && !v.empty()) {
      for (const auto& x : v) {
        if (!x.is_number()) cfg.Fail(key + ".actuation", "an array of numbers");
        rc.actuation.push_back(x.get<double>());
      }
    } else if (k == "volume_ratio" && v.is_array() && !v.empty()) {
      for (const auto& x : v) {
        if (!x.is_number() || !(x.get<double>() > 0))
          cfg.Fail(key + ".volume_ratio", "an array of positive numbers");
        rc.volume.push_back(x.get<double>());
      }
    } else if (k == "twist_axis") {
      const std::string expected = "an array of 3 numbers, not all zero";
      if (!v.is_array() || v.size() != 3) cfg.Fail(key + ".twist_axis", expected);
      for (int i = 0; i < 3; ++i) {
        if (!v[i].is_number()) cfg.Fail(key + ".twist_axis", expected);
        rc.twist_axis[i] = v[i].get<double>();
      }
      if (!(rc.twist_axis.norm() > 0) || !rc.twist_axis.allFinite())
        cfg.Fail(key + ".twist_axis", expected);
    } else if (k == "resolutions" && v.is_array()) {
      for (const auto& x : v) {
        if (!x.is_number_integer() || x.get<int>() < 1)
          cfg.Fail(key + ".resolutions", "an array of positive integers");
        rc.resolutions.push_back(x.get<int>());
      }
    } else {
      cfg.Fail(key + "." + k, "one of " + CaseKeys());
    }
  }
  if (rc.label.empty() || rc.label.find_first_of(",\"\n\r") != std::string::npos)
    cfg.Fail(key + ".label",
             "a name for the case without commas, quotes or line breaks (it is "
             "a field of refinement.csv)");
  if (rc.robot.empty()) cfg.Fail(key + ".robot", "an embedded robot's name (softkin robots)");
  if (rc.actuation.empty() == rc.volume.empty())
    cfg.Fail(key + ".actuation",
             "exactly one of actuation and volume_ratio (one value per actuator each)");
  if (rc.resolutions.size() < 4)
    cfg.Fail(key + ".resolutions", "at least 4 resolutions (convergence needs three changes)");
  for (size_t i = 1; i < rc.resolutions.size(); ++i)
    if (rc.resolutions[i] <= rc.resolutions[i - 1])
      cfg.Fail(key + ".resolutions", "strictly increasing resolutions");
  return rc;
}

std::vector<RefinementCase> ReadCases(const Config& cfg) {
  const nlohmann::json cases = cfg.Raw("cases");
  if (!cases.is_array() || cases.empty())
    cfg.Fail("cases", "a non-empty array of objects with " + CaseKeys());
  std::vector<RefinementCase> out;
  for (size_t i = 0; i < cases.size(); ++i) {
    out.push_back(ReadCase(cfg, cases[i], "cases[" + std::to_string(i) + "]"));
    for (size_t j = 0; j + 1 < out.size(); ++j)
      if (out[j].label == out.back().label)
        cfg.Fail("cases[" + std::to_string(i) + "].label", "a label no other case has");
  }
  return out;
}

/// The robot at `res` with the case's parameters; errors name the case.
Scene CaseRobot(const Config& cfg, const RefinementCase& rc, int res) {
  try {
    return MakeRobot(rc.robot, res, rc.params);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(cfg.path() + ": " + rc.key + " ('" + rc.label + "'): " + e.what());
  }
}

/// The case's robot at its first resolution takes its actuation and has its marker (checked
/// for every case before any runs); sets the case's solver options from the robot's.
void CheckCase(const Config& cfg, RefinementCase* c) {
  const RefinementCase& rc = *c;
  const Scene scene = CaseRobot(cfg, rc, rc.resolutions.front());
  c->opts = cfg.Solver(scene.solver);
  if (!rc.solver.empty()) c->opts.solver = FkSolverTypeFromString(rc.solver);
  const bool by_volume = !rc.volume.empty();
  const std::string key = rc.key + (by_volume ? ".volume_ratio" : ".actuation");
  const size_t n = by_volume ? rc.volume.size() : rc.actuation.size();
  if (static_cast<Eigen::Index>(n) != scene.num_actuators())
    cfg.Fail(key, std::to_string(scene.num_actuators()) + " value(s), one per actuator of '" +
                      rc.robot + "'");
  // A volume target is one chamber's ratio; a signed actuator drives two chambers.
  if (by_volume)
    for (const auto& a : scene.actuators)
      if (a.type != ActuatorType::Pneumatic || a.is_signed())
        cfg.Fail(key, "a robot whose actuators are all unsigned pneumatic ones ('" + rc.robot +
                          "' has " + (a.is_signed() ? "signed " : "") +
                          ActuatorTypeToString(a.type) + " actuator '" + a.name + "')");
  const int mi = scene.marker_index(rc.marker);
  if (mi < 0) cfg.Fail(rc.key + ".marker", "a marker of '" + rc.robot + "' (softkin robots)");
  if (rc.twist_axis.norm() > 0 && scene.markers[mi].vertices.size() < 3)
    cfg.Fail(rc.key + ".twist_axis", "a marker of 3 or more vertices to measure a twist ('" +
                                         rc.marker + "' has " +
                                         std::to_string(scene.markers[mi].vertices.size()) + ")");
}

/// The values joined by spaces (one CSV field).
std::string Joined(const Eigen::VectorXd& v) {
  std::string s;
  char buf[32];
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%.6g", v[i]);
    s += (i ? " " : "") + std::string(buf);
  }
  return s;
}

/// The journal key of one resolution of a case: every setting that determines its row.
nlohmann::json UnitKey(const RefinementCase& rc, int res) {
  nlohmann::json key = {{"label", rc.label},
                        {"robot", rc.robot},
                        {"robot_params", rc.params},
                        {"marker", rc.marker},
                        {"actuation", rc.actuation},
                        {"volume_ratio", rc.volume},
                        {"res", res},
                        {"solver", SolverOptionsToJson(rc.opts)}};
  if (rc.twist_axis.norm() > 0)
    key["twist_axis"] = {rc.twist_axis[0], rc.twist_axis[1], rc.twist_axis[2]};
  return key;
}

/// The twist (degrees) of marker `mi`'s vertices from the rest positions to X, about `axis`.
double MarkerTwist(const Scene& scene, int mi, const Eigen::MatrixX3d& X,
                   const Eigen::Vector3d& axis) {
  const std::vector<int>& v = scene.markers[mi].vertices;
  Eigen::MatrixX3d P(v.size(), 3), Q(v.size(), 3);
  for (size_t i = 0; i < v.size(); ++i) {
    P.row(i) = scene.mesh.vertices.row(v[i]);
    Q.row(i) = X.row(v[i]);
  }
  return TwistAboutAxisDegrees(P, Q, axis);
}

/// One resolution of a case, solved: its row (without the columns that compare resolutions).
nlohmann::json SolveUnit(const Config& cfg, const RefinementCase& rc, int res, bool verbose) {
  // A volume ratio of 1 leaves that chamber at rest (its volume then follows its neighbours').
  std::vector<bool> loaded;
  for (double v : rc.volume) loaded.push_back(v != 1.0);
  const Scene scene = CaseRobot(cfg, rc, res);
  const int tip = scene.marker_index(rc.marker);
  const Eigen::RowVector3d lo = scene.mesh.vertices.colwise().minCoeff();
  const Eigen::RowVector3d hi = scene.mesh.vertices.colwise().maxCoeff();
  auto model = std::make_shared<const Model>(scene);
  auto solver = MakeFkSolver(model, rc.opts);
  FkResult r;
  Eigen::VectorXd c;
  bool matched = true;
  const auto t0 = std::chrono::steady_clock::now();
  if (rc.volume.empty()) {
    c = Eigen::Map<const Eigen::VectorXd>(rc.actuation.data(), rc.actuation.size());
    r = solver->Solve(c);
  } else {
    MatchedVolume m = SolveAtVolume(solver.get(), scene, rc.volume, loaded);
    r = std::move(m.r);
    c = m.c;
    matched = m.matched;
  }
  // Wall time to the answer (with a volume target, every secant solve).
  const double solve_s = SecondsSince(t0);
  if (r.status == FkStatus::InvalidInput)
    throw std::invalid_argument(cfg.path() + ": " + rc.key + " ('" + rc.label + "'): " + r.message);
  const Eigen::VectorXd ratios =
      Eigen::Map<const Eigen::VectorXd>(r.volume_ratios.data(), r.volume_ratios.size());
  const Eigen::RowVector3d p = scene.marker_positions(r.positions).row(tip);
  if (verbose)
    std::fprintf(stderr, "  %s res %d: %d elements, %s\n", rc.label.c_str(), res,
                 scene.mesh.num_elements(), r.BriefReport().c_str());
  nlohmann::json row = {{"case", rc.label},
                        {"res", res},
                        {"n_vertices", scene.mesh.num_vertices()},
                        {"n_elements", scene.mesh.num_elements()},
                        {"length_mm", (hi - lo).maxCoeff()},
                        {"tip_x", p[0]},
                        {"tip_y", p[1]},
                        {"tip_z", p[2]},
                        {"energy", r.energy},
                        {"iterations", r.iterations},
                        {"solve_s", solve_s},
                        {"inverted", r.inverted_elements},
                        {"status", FkStatusToString(r.status)},
                        {"actuation", Joined(c)},
                        {"volume_ratio", Joined(ratios)},
                        {"volume_matched", matched}};
  if (rc.twist_axis.norm() > 0)
    row["twist_deg"] = MarkerTwist(scene, tip, r.positions, rc.twist_axis);
  return row;
}

/// One case from the rows of its resolutions, in order: the change from the previous resolution
/// (left empty on the first) and the distance to the finest mesh's point, per row, written to
/// the CSV; the summary entry, with whether the changes shrink.
nlohmann::json FinishCase(const RefinementCase& rc, std::vector<nlohmann::json> rows,
                          CsvWriter* csv) {
  auto tip = [&](size_t i) {
    return Eigen::Vector3d(rows[i]["tip_x"].get<double>(), rows[i]["tip_y"].get<double>(),
                           rows[i]["tip_z"].get<double>());
  };
  std::vector<double> changes, to_finest, twists;
  bool shrink = true, all_converged = true;
  for (size_t i = 0; i < rows.size(); ++i) {
    to_finest.push_back((tip(i) - tip(rows.size() - 1)).norm());
    rows[i]["to_finest_mm"] = to_finest.back();
    if (i > 0) {
      changes.push_back((tip(i) - tip(i - 1)).norm());
      rows[i]["change_mm"] = changes.back();
      shrink &= changes.size() < 2 || changes.back() <= changes[changes.size() - 2];
    }
    all_converged &= rows[i]["status"] == "converged" && rows[i]["volume_matched"].get<bool>();
    if (rows[i].contains("twist_deg")) twists.push_back(rows[i]["twist_deg"].get<double>());
    csv->RowJson(rows[i]);
  }
  const double length = rows.back()["length_mm"].get<double>();
  nlohmann::json summary = {{"label", rc.label},
                            {"robot", rc.robot},
                            {"robot_params", rc.params},
                            {"marker", rc.marker},
                            {"solver", ToString(rc.opts.solver)},
                            {"self_collision", rc.opts.collision.self},
                            {"actuation", rc.actuation},
                            {"volume_ratio", rc.volume},
                            {"resolutions", rc.resolutions},
                            {"length_mm", length},
                            {"tip_changes_mm", changes},
                            {"tip_to_finest_mm", to_finest},
                            {"last_change_percent_of_length", 100.0 * changes.back() / length},
                            {"changes_shrink", shrink},
                            {"all_converged", all_converged}};
  if (!twists.empty()) summary["twist_deg"] = twists;
  return summary;
}

}  // namespace

nlohmann::json RunRefinement(const Config& cfg, const std::string& dir, bool verbose) {
  std::vector<RefinementCase> cases = ReadCases(cfg);
  (void)cfg.Solver(FkOptions{});  // checks the solver object before any robot is built
  cfg.CheckNoUnknownKeys();
  for (auto& rc : cases) CheckCase(cfg, &rc);
  if (cfg.check_only()) return {};
  // Each resolution of each case is a unit, journaled as it finishes: a killed run rerun with
  // the same command solves only what is missing, and under mpirun the ranks share the units.
  struct Unit {
    size_t c;
    int res;
  };
  std::vector<Unit> units;
  std::vector<nlohmann::json> keys;
  for (size_t c = 0; c < cases.size(); ++c)
    for (int res : cases[c].resolutions) {
      units.push_back({c, res});
      keys.push_back(UnitKey(cases[c], res));
    }
  Sweep sweep(dir + "/refinement.jsonl", "refinement_convergence", verbose);
  sweep.Run(keys,
            [&](size_t i) { return SolveUnit(cfg, cases[units[i].c], units[i].res, verbose); });
  if (!Sweep::WritesResults()) return {};
  CsvWriter csv(dir + "/refinement.csv",
                {"case", "res", "n_vertices", "n_elements", "tip_x", "tip_y", "tip_z", "change_mm",
                 "to_finest_mm", "twist_deg", "energy", "iterations", "solve_s", "inverted",
                 "status", "actuation", "volume_ratio", "volume_matched"});
  nlohmann::json out = nlohmann::json::array();
  int shrinking = 0;
  size_t next = 0;
  for (const auto& rc : cases) {
    std::vector<nlohmann::json> rows(sweep.rows().begin() + next,
                                     sweep.rows().begin() + next + rc.resolutions.size());
    next += rc.resolutions.size();
    out.push_back(FinishCase(rc, std::move(rows), &csv));
    shrinking += out.back()["changes_shrink"].get<bool>();
  }
  return {{"cases", out},
          {"cases_whose_changes_shrink", shrinking},
          {"n_cases", cases.size()},
          {"resumed_rows", sweep.resumed()}};
}

}  // namespace softkin
