// Marker trajectories under an actuation sweep, for one or more design variants of a robot
// (Fig. 2.9: two material distributions of a cable gripper; Fig. 2.10: the DEA crawler's shape and
// leg spacing against lambda).
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <cstdio>
#include <filesystem>
#include <tuple>

namespace softkin {

namespace {

/// A design variant: a label and its robot parameters.
struct Variant {
  std::string label;
  RobotParams params;
};

/// The keys of a marker_sweep config.
struct MarkerSweepParams {
  std::string robot;
  int res = 0;
  std::vector<std::string> act_names;  ///< the swept actuators
  int steps = 8;
  bool has_start = false, has_end = false;  ///< start_value / end_value given
  double start_value = 0, end_value = 0;
  std::vector<std::string> marker_names;  ///< empty: every marker
  nlohmann::json distances;               ///< [[marker, marker], ...] or null
  int vtu_every = 0;
  FkOptions opts;
  std::vector<Variant> variants;
};

/// "variants": [{"label", "robot_params"}, ...] on top of the config's robot_params (none: one
/// variant "default").
std::vector<Variant> ReadVariants(const Config& cfg, const nlohmann::json& variants_json,
                                  const RobotParams& base_params) {
  std::vector<Variant> variants;
  if (variants_json.is_null()) {
    variants.push_back({"default", base_params});
    return variants;
  }
  if (!variants_json.is_array() || variants_json.empty())
    cfg.Fail("variants", "a non-empty array of {\"label\": ..., \"robot_params\": {...}}");
  for (size_t i = 0; i < variants_json.size(); ++i) {
    const auto& v = variants_json[i];
    const std::string key = "variants[" + std::to_string(i) + "]";
    if (!v.is_object() || !v.contains("label") || !v["label"].is_string())
      cfg.Fail("variants", "objects with a string \"label\" (" + key + " is not)");
    Variant var{v["label"].get<std::string>(), base_params};
    for (const auto& [k, x] : v.items()) {
      if (k == "label") continue;
      if (k != "robot_params" || !x.is_object())
        cfg.Fail("variants", "only \"label\" and an object \"robot_params\" in " + key +
                                 " (got key \"" + k + "\")");
      for (const auto& [pk, pv] : x.items()) {
        if (!pv.is_number()) cfg.Fail("variants", "numbers in " + key + ".robot_params." + pk);
        var.params[pk] = pv.get<double>();
      }
    }
    variants.push_back(var);
  }
  return variants;
}

MarkerSweepParams ReadMarkerSweepParams(const Config& cfg) {
  MarkerSweepParams p;
  p.robot = cfg.String("robot", "cable_gripper");
  p.res = cfg.Int("res", 0);
  p.act_names = cfg.StringList("actuators", {});
  p.steps = cfg.Int("steps", 8);
  p.has_start = cfg.json().contains("start_value");
  p.has_end = cfg.json().contains("end_value");
  p.start_value = cfg.Number("start_value", 0.0);
  p.end_value = cfg.Number("end_value", 0.0);
  p.marker_names = cfg.StringList("markers", {});
  p.distances = cfg.Raw("distances");
  const nlohmann::json variants_json = cfg.Raw("variants");
  p.vtu_every = cfg.Int("vtu_every", 0);
  const auto base_params = cfg.NumberMap("robot_params");
  if (p.vtu_every < 0) cfg.Fail("vtu_every", "an integer >= 0");
  try {
    p.opts = cfg.Solver(MakeRobot(p.robot, p.res, base_params).solver);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(cfg.path() + ": robot '" + p.robot +
                                "' (keys robot, res, robot_params): " + e.what());
  }
  cfg.CheckNoUnknownKeys();
  if (p.steps < 1) cfg.Fail("steps", "an integer >= 1");
  if (p.act_names.empty()) cfg.Fail("actuators", "a non-empty array of actuator names");
  p.variants = ReadVariants(cfg, variants_json, base_params);
  return p;
}

/// A variant's robot with the swept actuators, the markers and the marker pairs whose distances
/// are reported, checked against it.
struct VariantRobot {
  Scene scene;
  std::vector<int> acts, marks;
  std::vector<std::pair<int, int>> dist_pairs;
};

VariantRobot MakeVariantRobot(const Config& cfg, const MarkerSweepParams& p, const Variant& var) {
  const std::string& robot = p.robot;
  VariantRobot v;
  try {
    v.scene = MakeRobot(robot, p.res, var.params);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(cfg.path() + ": variant '" + var.label +
                                "' (keys robot, res, robot_params, variants): " + e.what());
  }
  const Scene& scene = v.scene;
  for (const auto& n : p.act_names) {
    const int a = scene.actuator_index(n);
    if (a < 0)
      cfg.Fail("actuators", "names of actuators of robot '" + robot + "', got '" + n + "'");
    v.acts.push_back(a);
  }
  if (p.marker_names.empty())
    for (size_t m = 0; m < scene.markers.size(); ++m) v.marks.push_back(static_cast<int>(m));
  for (const auto& n : p.marker_names) {
    const int m = scene.marker_index(n);
    if (m < 0) cfg.Fail("markers", "names of markers of robot '" + robot + "', got '" + n + "'");
    v.marks.push_back(m);
  }
  if (!p.distances.is_null()) {
    if (!p.distances.is_array()) cfg.Fail("distances", "an array of [marker, marker] pairs");
    for (const auto& d : p.distances) {
      if (!d.is_array() || d.size() != 2 || !d[0].is_string() || !d[1].is_string())
        cfg.Fail("distances", "an array of [marker, marker] pairs");
      const int m0 = scene.marker_index(d[0].get<std::string>()),
                m1 = scene.marker_index(d[1].get<std::string>());
      if (m0 < 0 || m1 < 0) cfg.Fail("distances", "pairs of marker names of robot '" + robot + "'");
      v.dist_pairs.emplace_back(m0, m1);
    }
  }
  for (int a : v.acts) {
    const Actuator& act = scene.actuators[a];
    for (const auto& [key, given, value] :
         {std::tuple<const char*, bool, double>{"start_value", p.has_start, p.start_value},
          std::tuple<const char*, bool, double>{"end_value", p.has_end, p.end_value}})
      if (given && (value < act.min || value > act.max))
        cfg.Fail(key, "a value inside the range [" + std::to_string(act.min) + ", " +
                          std::to_string(act.max) + "] of actuator '" + act.name + "'");
  }
  return v;
}

/// Sweeps one variant from its start value (step 0, solved too: it need not be the mesh's rest
/// shape) to its end value: rows of markers.csv, VTU frames, and its summary entry.
nlohmann::json SweepVariant(const MarkerSweepParams& p, const Variant& var, const VariantRobot& v,
                            const std::string& dir, CsvWriter* csv, bool verbose) {
  const Scene& scene = v.scene;
  const int steps = p.steps;
  auto model = std::make_shared<const Model>(scene);
  auto solver = MakeFkSolver(model, p.opts);
  Eigen::VectorXd c = scene.rest_actuation();
  Eigen::MatrixX3d X = scene.mesh.vertices, X_prev = X, guess;
  nlohmann::json traj = nlohmann::json::object(), dists = nlohmann::json::array(),
                 values = nlohmann::json::array();
  for (int m : v.marks) traj[scene.markers[m].name] = nlohmann::json::array();
  std::vector<std::pair<double, std::string>> frames;
  if (p.vtu_every > 0) std::filesystem::create_directories(dir + "/frames");
  double var_s = 0;
  int var_iters = 0, var_fail = 0;
  for (int s = 0; s <= steps; ++s) {
    for (int a : v.acts) {
      const Actuator& act = scene.actuators[a];
      const double v0 = p.has_start ? p.start_value : act.rest;
      const double v1 = p.has_end ? p.end_value : act.FarEnd();
      c[a] = v0 + (v1 - v0) * double(s) / steps;
    }
    guess = s > 1 ? Eigen::MatrixX3d(2.0 * X - X_prev) : X;  // secant predictor
    const FkResult r = solver->Solve(c, &guess);
    if (r.status == FkStatus::InvalidInput) throw std::runtime_error(r.message);
    X_prev = s > 0 ? X : r.positions;
    X = r.positions;
    const bool ok = r.status == FkStatus::Converged;
    var_fail += !ok;
    var_s += r.time_s;
    var_iters += r.iterations;
    const Eigen::MatrixX3d P = scene.marker_positions(X);
    const double value = c[v.acts[0]];
    values.push_back(value);
    for (int m : v.marks) {
      traj[scene.markers[m].name].push_back({P(m, 0), P(m, 1), P(m, 2)});
      csv->RowStrings({var.label, std::to_string(s), std::to_string(value), scene.markers[m].name,
                       std::to_string(P(m, 0)), std::to_string(P(m, 1)), std::to_string(P(m, 2)),
                       std::to_string(r.iterations), std::to_string(r.time_s), ok ? "1" : "0"});
    }
    nlohmann::json drow = nlohmann::json::array();
    for (const auto& [m0, m1] : v.dist_pairs) drow.push_back((P.row(m0) - P.row(m1)).norm());
    dists.push_back(drow);
    if (p.vtu_every > 0 && (s % p.vtu_every == 0 || s == steps)) {
      char name[96];
      std::snprintf(name, sizeof(name), "frames/%s_step_%04d.vtu", var.label.c_str(), s);
      WriteVtu(dir + "/" + name, scene.mesh, X);
      frames.emplace_back(value, name);
    }
    if (verbose)
      std::fprintf(stderr, "  [%s %d/%d] value %.4g: %s\n", var.label.c_str(), s, steps, value,
                   r.BriefReport().c_str());
  }
  if (!frames.empty()) WritePvd(dir + "/" + var.label + ".pvd", frames);
  nlohmann::json params = nlohmann::json::object();
  for (const auto& [k, x] : var.params) params[k] = x;
  nlohmann::json dnames = nlohmann::json::array();
  for (const auto& [m0, m1] : v.dist_pairs)
    dnames.push_back(scene.markers[m0].name + "-" + scene.markers[m1].name);
  return {{"label", var.label}, {"robot_params", params},   {"values", values},
          {"markers", traj},    {"distance_names", dnames}, {"distances", dists},
          {"solve_s", var_s},   {"iterations", var_iters},  {"non_converged_steps", var_fail}};
}

}  // namespace

nlohmann::json RunMarkerSweep(const Config& cfg, const std::string& dir, bool verbose) {
  const MarkerSweepParams p = ReadMarkerSweepParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  nlohmann::json summary_variants = nlohmann::json::array();
  CsvWriter csv(dir + "/markers.csv", {"variant", "step", "value", "marker", "x", "y", "z",
                                       "iterations", "time_s", "converged"});
  int failures = 0;
  double total_s = 0;
  Scene first_scene;
  for (size_t vi = 0; vi < p.variants.size(); ++vi) {
    const VariantRobot v = MakeVariantRobot(cfg, p, p.variants[vi]);
    if (vi == 0) first_scene = v.scene;
    const nlohmann::json jv = SweepVariant(p, p.variants[vi], v, dir, &csv, verbose);
    failures += jv["non_converged_steps"].get<int>();
    total_s += jv["solve_s"].get<double>();
    summary_variants.push_back(jv);
  }
  nlohmann::json j;
  j["robot"] = p.robot;
  j["n_tets"] = first_scene.mesh.num_tets();
  j["n_prisms"] = first_scene.mesh.num_prisms();
  j["n_vertices"] = first_scene.mesh.num_vertices();
  j["actuators"] = p.act_names;
  j["variants"] = summary_variants;
  j["total_solve_s"] = total_s;
  j["non_converged_steps"] = failures;
  return j;
}

}  // namespace softkin
