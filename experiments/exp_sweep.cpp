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

nlohmann::json RunMarkerSweep(const Config& cfg, const std::string& dir, bool verbose) {
  const std::string robot = cfg.String("robot", "cable_gripper");
  const int res = cfg.Int("res", 0);
  const std::vector<std::string> act_names = cfg.StringList("actuators", {});
  const int steps = cfg.Int("steps", 8);
  const bool has_start = cfg.json().contains("start_value"), has_end = cfg.json().contains("end_value");
  const double start_value = cfg.Number("start_value", 0.0);
  const double end_value = cfg.Number("end_value", 0.0);
  const std::vector<std::string> marker_names = cfg.StringList("markers", {});
  const nlohmann::json distances = cfg.Raw("distances");
  const nlohmann::json variants_json = cfg.Raw("variants");
  const int vtu_every = cfg.Int("vtu_every", 0);
  const auto base_params = cfg.NumberMap("robot_params");
  if (vtu_every < 0) cfg.Fail("vtu_every", "an integer >= 0");
  FkOptions opts;
  try {
    opts = cfg.Solver(MakeRobot(robot, res, base_params).solver);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(cfg.path() + ": robot '" + robot + "' (keys robot, res, robot_params): " +
                                e.what());
  }
  cfg.CheckNoUnknownKeys();
  if (steps < 1) cfg.Fail("steps", "an integer >= 1");
  if (act_names.empty()) cfg.Fail("actuators", "a non-empty array of actuator names");

  struct Variant {
    std::string label;
    RobotParams params;
  };
  std::vector<Variant> variants;
  if (variants_json.is_null()) {
    variants.push_back({"default", base_params});
  } else {
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
  }

  nlohmann::json summary_variants = nlohmann::json::array();
  CsvWriter csv(dir + "/markers.csv", {"variant", "step", "value", "marker", "x", "y", "z",
                                       "iterations", "time_s", "converged"});
  int failures = 0;
  double total_s = 0;
  Scene first_scene;
  for (size_t vi = 0; vi < variants.size(); ++vi) {
    const Variant& var = variants[vi];
    Scene scene;
    try {
      scene = MakeRobot(robot, res, var.params);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(cfg.path() + ": variant '" + var.label +
                                  "' (keys robot, res, robot_params, variants): " + e.what());
    }
    if (vi == 0) first_scene = scene;
    std::vector<int> acts, marks;
    for (const auto& n : act_names) {
      const int a = scene.actuator_index(n);
      if (a < 0) cfg.Fail("actuators", "names of actuators of robot '" + robot + "', got '" + n + "'");
      acts.push_back(a);
    }
    if (marker_names.empty())
      for (size_t m = 0; m < scene.markers.size(); ++m) marks.push_back(static_cast<int>(m));
    for (const auto& n : marker_names) {
      const int m = scene.marker_index(n);
      if (m < 0) cfg.Fail("markers", "names of markers of robot '" + robot + "', got '" + n + "'");
      marks.push_back(m);
    }
    std::vector<std::pair<int, int>> dist_pairs;
    if (!distances.is_null()) {
      if (!distances.is_array()) cfg.Fail("distances", "an array of [marker, marker] pairs");
      for (const auto& d : distances) {
        if (!d.is_array() || d.size() != 2 || !d[0].is_string() || !d[1].is_string())
          cfg.Fail("distances", "an array of [marker, marker] pairs");
        const int m0 = scene.marker_index(d[0].get<std::string>()),
                  m1 = scene.marker_index(d[1].get<std::string>());
        if (m0 < 0 || m1 < 0) cfg.Fail("distances", "pairs of marker names of robot '" + robot + "'");
        dist_pairs.emplace_back(m0, m1);
      }
    }
    for (int a : acts) {
      const Actuator& act = scene.actuators[a];
      for (const auto& [key, given, value] :
           {std::tuple<const char*, bool, double>{"start_value", has_start, start_value},
            std::tuple<const char*, bool, double>{"end_value", has_end, end_value}})
        if (given && (value < act.min || value > act.max))
          cfg.Fail(key, "a value inside the range [" + std::to_string(act.min) + ", " +
                            std::to_string(act.max) + "] of actuator '" + act.name + "'");
    }
    auto model = std::make_shared<const Model>(scene);
    auto solver = MakeFkSolver(model, opts);
    Eigen::VectorXd c = scene.rest_actuation();
    Eigen::MatrixX3d X = scene.mesh.vertices, X_prev = X, guess;
    nlohmann::json traj = nlohmann::json::object(), dists = nlohmann::json::array(),
                   values = nlohmann::json::array();
    for (int m : marks) traj[scene.markers[m].name] = nlohmann::json::array();
    std::vector<std::pair<double, std::string>> frames;
    if (vtu_every > 0) std::filesystem::create_directories(dir + "/frames");
    double var_s = 0;
    int var_iters = 0, var_fail = 0;
    // Step 0 is the sweep's start value (solved too: it need not be the mesh's rest shape).
    for (int s = 0; s <= steps; ++s) {
      for (int a : acts) {
        const Actuator& act = scene.actuators[a];
        const double v0 = has_start ? start_value : act.rest;
        const double v1 = has_end ? end_value : act.FarEnd();
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
      values.push_back(c[acts[0]]);
      for (int m : marks) {
        traj[scene.markers[m].name].push_back({P(m, 0), P(m, 1), P(m, 2)});
        csv.RowStrings({var.label, std::to_string(s), std::to_string(c[acts[0]]),
                        scene.markers[m].name, std::to_string(P(m, 0)), std::to_string(P(m, 1)),
                        std::to_string(P(m, 2)), std::to_string(r.iterations),
                        std::to_string(r.time_s), ok ? "1" : "0"});
      }
      nlohmann::json drow = nlohmann::json::array();
      for (const auto& [m0, m1] : dist_pairs) drow.push_back((P.row(m0) - P.row(m1)).norm());
      dists.push_back(drow);
      if (vtu_every > 0 && (s % vtu_every == 0 || s == steps)) {
        char name[96];
        std::snprintf(name, sizeof(name), "frames/%s_step_%04d.vtu", var.label.c_str(), s);
        WriteVtu(dir + "/" + name, scene.mesh, X);
        frames.emplace_back(c[acts[0]], name);
      }
      if (verbose)
        std::fprintf(stderr, "  [%s %d/%d] value %.4g: %s\n", var.label.c_str(), s, steps,
                     c[acts[0]], r.BriefReport().c_str());
    }
    if (!frames.empty()) WritePvd(dir + "/" + var.label + ".pvd", frames);
    failures += var_fail;
    total_s += var_s;
    nlohmann::json params = nlohmann::json::object();
    for (const auto& [k, v] : var.params) params[k] = v;
    nlohmann::json dnames = nlohmann::json::array();
    for (const auto& [m0, m1] : dist_pairs)
      dnames.push_back(scene.markers[m0].name + "-" + scene.markers[m1].name);
    summary_variants.push_back({{"label", var.label}, {"robot_params", params}, {"values", values},
                                {"markers", traj}, {"distance_names", dnames}, {"distances", dists},
                                {"solve_s", var_s}, {"iterations", var_iters},
                                {"non_converged_steps", var_fail}});
  }
  nlohmann::json j;
  j["robot"] = robot;
  j["n_tets"] = first_scene.mesh.num_tets();
  j["n_prisms"] = first_scene.mesh.num_prisms();
  j["n_vertices"] = first_scene.mesh.num_vertices();
  j["actuators"] = act_names;
  j["variants"] = summary_variants;
  j["total_solve_s"] = total_s;
  j["non_converged_steps"] = failures;
  return j;
}

}  // namespace softkin
