// Chapter 3 collision experiments (Sec. 3.4; Fig. 3.8, 3.10, 3.12, 3.13, Table 3.1).
//
// "collision_sweep": one robot, optional obstacles, several variants (collision options and/or
// robot parameters), each driven from rest to its end actuation in `steps` warm-started steps.
// Per step: tip, bend, springs, the exact collision check of the state (contacts left and the
// deepest penetration, with or without response), contact with each obstacle and the time split
// (detection, response, local-global). VTU of every variant's final shape.
//
// "collision_costs" (Table 3.1): per robot, the time of one simulation step split as the thesis
// does: mesh generation, collision check, collision response and iterative solver.
#include "softkin/experiments/measure.hpp"
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/solver/collision/collision_response.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/remesh/remesh.hpp"
#include "softkin/solver/robots/robot_twisting.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <map>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

namespace softkin {

namespace {

using Clock = std::chrono::steady_clock;
Eigen::Vector3d JsonVec(const Config& cfg, const std::string& key, const nlohmann::json& v) {
  if (!v.is_array() || v.size() != 3) cfg.Fail(key, "an array of 3 numbers [x, y, z]");
  Eigen::Vector3d out;
  for (int d = 0; d < 3; ++d) {
    if (!v[d].is_number() || !std::isfinite(v[d].get<double>()))
      cfg.Fail(key, "an array of 3 finite numbers");
    out[d] = v[d].get<double>();
  }
  return out;
}

/// Obstacles of a config: [{"type": "box", "min": [..], "max": [..]} | {"type": "cylinder",
/// "base", "axis", "radius", "height", ["segments"]} | {"type": "file", "path": "x.obj"}] (paths
/// relative to the config's folder).
std::vector<TriangleSurface> ConfigObstacles(const Config& cfg, const nlohmann::json& list) {
  std::vector<TriangleSurface> out;
  if (list.is_null()) return out;
  if (!list.is_array()) cfg.Fail("obstacles", "an array of obstacle objects");
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string key = "obstacles[" + std::to_string(i) + "]";
    const auto& o = list[i];
    if (!o.is_object() || !o.contains("type") || !o["type"].is_string())
      cfg.Fail(key, "an object with \"type\": box, cylinder or file");
    const std::string type = o["type"].get<std::string>();
    auto need = [&](const char* k) -> const nlohmann::json& {
      if (!o.contains(k))
        cfg.Fail(key + "." + k, std::string("a value (required for type ") + type + ")");
      return o.at(k);
    };
    std::vector<std::string> allowed;
    if (type == "box")
      allowed = {"type", "min", "max"};
    else if (type == "cylinder")
      allowed = {"type", "base", "axis", "radius", "height", "segments"};
    else if (type == "file")
      allowed = {"type", "path"};
    else
      cfg.Fail(key + ".type", "one of box, cylinder, file");
    for (auto it = o.begin(); it != o.end(); ++it)
      if (std::find(allowed.begin(), allowed.end(), it.key()) == allowed.end())
        cfg.Fail(key + "." + it.key(), "no such key for type " + type);
    try {
      if (type == "box") {
        out.push_back(MakeBoxSurface(JsonVec(cfg, key + ".min", need("min")),
                                     JsonVec(cfg, key + ".max", need("max"))));
      } else if (type == "cylinder") {
        const auto& r = need("radius");
        const auto& h = need("height");
        if (!r.is_number() || !h.is_number()) cfg.Fail(key, "numbers for radius and height (mm)");
        const int seg = o.contains("segments") && o["segments"].is_number_integer()
                            ? o["segments"].get<int>()
                            : 48;
        out.push_back(MakeCylinderSurface(JsonVec(cfg, key + ".base", need("base")),
                                          JsonVec(cfg, key + ".axis", need("axis")),
                                          r.get<double>(), h.get<double>(), seg));
      } else {
        const auto& p = need("path");
        if (!p.is_string()) cfg.Fail(key + ".path", "a file name (.obj or .stl)");
        std::filesystem::path file(p.get<std::string>());
        if (file.is_relative()) file = std::filesystem::path(cfg.path()).parent_path() / file;
        out.push_back(ReadSurfaceMesh(file.string()));
      }
      CheckClosedSurface(&out.back());
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(cfg.path() + ": " + key + ": " + e.what());
    }
  }
  return out;
}

/// Actuation from {"name": value, ...} on top of the scene's rest actuation.
Eigen::VectorXd ConfigActuation(const Config& cfg, const std::string& key, const nlohmann::json& j,
                                const Scene& scene) {
  Eigen::VectorXd c = scene.rest_actuation();
  if (!j.is_object() || j.empty()) cfg.Fail(key, "an object {\"actuator name\": end value, ...}");
  for (auto it = j.begin(); it != j.end(); ++it) {
    const int a = scene.actuator_index(it.key());
    if (a < 0) {
      std::string known;
      for (const auto& act : scene.actuators) known += (known.empty() ? "" : ", ") + act.name;
      cfg.Fail(key + "." + it.key(), "an actuator of robot '" + scene.name + "' (" + known + ")");
    }
    const auto& act = scene.actuators[a];
    if (!it.value().is_number() || it.value().get<double>() < act.min ||
        it.value().get<double>() > act.max)
      cfg.Fail(key + "." + it.key(),
               "a number in [" + std::to_string(act.min) + ", " + std::to_string(act.max) + "]");
    c[a] = it.value().get<double>();
  }
  return c;
}

/// Robot vertices within `dist` of an obstacle's surface (touching it), and their extent along x.
struct ContactPatch {
  int vertices = 0;
  double extent_mm = 0, area_mm2 = 0;
};

ContactPatch MeasureContact(const Obstacle& obs, const Mesh& mesh, const Eigen::MatrixX3d& X,
                            double dist) {
  ContactPatch c;
  std::vector<char> touch(mesh.num_vertices(), 0);
  double lo = 1e300, hi = -1e300;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::Vector3d p = X.row(v);
    const double d = (obs.ClosestPoint(p) - p).norm();
    if (d <= dist || obs.Contains(p)) {
      touch[v] = 1;
      ++c.vertices;
      lo = std::min(lo, p.x());
      hi = std::max(hi, p.x());
    }
  }
  if (c.vertices) c.extent_mm = hi - lo;
  // Area of boundary triangles whose three corners all touch (tet meshes).
  std::map<std::array<int, 3>, int> faces;
  static constexpr int kF[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  for (const auto& e : mesh.elements) {
    if (e.type != ElementType::Tet) continue;
    for (const auto& f : kF) {
      std::array<int, 3> k = {e.v[f[0]], e.v[f[1]], e.v[f[2]]};
      if (!touch[k[0]] || !touch[k[1]] || !touch[k[2]]) continue;
      std::sort(k.begin(), k.end());
      ++faces[k];
    }
  }
  for (const auto& [k, n] : faces)
    if (n == 1) {
      const Eigen::Vector3d a = X.row(k[0]), b = X.row(k[1]), cc = X.row(k[2]);
      c.area_mm2 += 0.5 * (b - a).cross(cc - a).norm();
    }
  return c;
}

/// Adds (or overrides) the numbers of the JSON object `j` (at config key `key`) in *p; anything but
/// an object of numbers fails with the key.
void MergeRobotParams(const Config& cfg, const std::string& key, const nlohmann::json& j,
                      RobotParams* p) {
  if (!j.is_object()) cfg.Fail(key, "an object of numbers");
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (!it.value().is_number()) cfg.Fail(key + "." + it.key(), "a number");
    (*p)[it.key()] = it.value().get<double>();
  }
}

/// Progressive remeshing (Algorithm 2) of a collision_costs robot from its "remesh" object
/// {"alpha_max", "d_max", "method", "chamber_rest", "remesh_iterations", "max_remeshes_per_step"}
/// (every key optional; the thesis's 4 / 4, auto, remeshed, 3, 2); the ladder is the robot's
/// `steps` values.
ProgressiveOptions CostsRemeshOptions(const Config& cfg, const std::string& key,
                                      const nlohmann::json& j, const std::string& robot, int res,
                                      const RobotParams& params) {
  if (!j.is_object())
    cfg.Fail(
        key,
        "an object {\"alpha_max\", \"d_max\", \"method\", \"chamber_rest\", \"remesh_iterations\", "
        "\"max_remeshes_per_step\"}");
  auto number = [&](const char* k, double def) {
    if (!j.contains(k)) return def;
    if (!j[k].is_number() || !std::isfinite(j[k].get<double>()))
      cfg.Fail(key + "." + k, "a finite number");
    return j[k].get<double>();
  };
  auto integer = [&](const char* k, int def) {
    if (!j.contains(k)) return def;
    if (!j[k].is_number_integer() || j[k].get<int>() < 1)
      cfg.Fail(key + "." + k, "an integer >= 1");
    return j[k].get<int>();
  };
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key() != "alpha_max" && it.key() != "d_max" && it.key() != "method" &&
        it.key() != "chamber_rest" && it.key() != "remesh_iterations" &&
        it.key() != "max_remeshes_per_step")
      cfg.Fail(key + "." + it.key(),
               "one of alpha_max, d_max, method, chamber_rest, remesh_iterations, "
               "max_remeshes_per_step");
  ProgressiveOptions popt;
  popt.criteria = {number("alpha_max", 4.0), number("d_max", 4.0)};
  popt.max_remeshes_per_step = integer("max_remeshes_per_step", 2);
  const std::string method =
      j.contains("method") && j["method"].is_string() ? j["method"].get<std::string>() : "auto";
  if ((j.contains("method") && !j["method"].is_string()) ||
      !RemeshMethodFromString(method, &popt.remesh_options.method))
    cfg.Fail(key + ".method", "auto, chamber or whole");
  const std::string rest = j.contains("chamber_rest") && j["chamber_rest"].is_string()
                               ? j["chamber_rest"].get<std::string>()
                               : "remeshed";
  if ((j.contains("chamber_rest") && !j["chamber_rest"].is_string()) ||
      !ChamberRestFromString(rest, &popt.remesh_options.rest))
    cfg.Fail(key + ".chamber_rest", "remeshed or original");
  popt.remesh_options.region.iterations = integer("remesh_iterations", 3);
  popt.remesh_options.region.seed = cfg.seed();
  if (robot == "twisting_robot")
    popt.remesh_options.tessellation = TwistingRobotTessellation(res, params);
  popt.remesh_options.tessellation.seed = cfg.seed();
  std::string why;
  if (!popt.IsValid(&why)) {
    // why = "<key>: expected <what>, got <value>"; Fail adds the key path and the value found.
    const size_t colon = why.find(": ");
    std::string what = colon == std::string::npos ? why : why.substr(colon + 2);
    if (what.rfind("expected ", 0) == 0) what = what.substr(9);
    cfg.Fail(key + "." + why.substr(0, colon), what.substr(0, what.find(", got")));
  }
  return popt;
}

// ---- collision_sweep ----

/// A variant of the sweep, read and checked before the first one runs.
struct SweepVariant {
  std::string name;
  Scene scene;
  FkOptions opts;
};

/// The keys of a collision_sweep config.
struct CollisionSweepParams {
  std::string robot;
  int steps = 10;
  double contact_dist = 0.5;
  // Optional: the final positions of the vertices of this region tag, per variant (for height
  // maps, e.g. the membrane), in surface_<variant>.csv.
  int export_region = -1;
  std::vector<TriangleSurface> obstacles;
  Eigen::VectorXd c_end;  ///< the end actuation
  std::vector<SweepVariant> variants;
};

/// variants[vi]: {"name", ["collision"], ["robot_params"]} on top of the base robot and options.
SweepVariant ReadSweepVariant(const Config& cfg, size_t vi, const nlohmann::json& v,
                              const Scene& base, const FkOptions& base_opts,
                              const CollisionSweepParams& p, int res) {
  const std::string key = "variants[" + std::to_string(vi) + "]";
  if (!v.is_object() || !v.contains("name") || !v["name"].is_string())
    cfg.Fail(key, "an object with a \"name\"");
  for (auto it = v.begin(); it != v.end(); ++it)
    if (it.key() != "name" && it.key() != "collision" && it.key() != "robot_params")
      cfg.Fail(key + "." + it.key(), "one of name, collision, robot_params");
  SweepVariant pv;
  pv.name = v["name"].get<std::string>();
  pv.scene = base;
  if (v.contains("robot_params")) {
    RobotParams rp = cfg.NumberMap("robot_params");
    MergeRobotParams(cfg, key + ".robot_params", v["robot_params"], &rp);
    try {
      pv.scene = MakeRobot(p.robot, res, rp);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(cfg.path() + ": " + key + ".robot_params: " + e.what());
    }
  }
  pv.scene.obstacles = p.obstacles;
  pv.opts = base_opts;  // the robot's defaults (e.g. self on), then the config's solver
  if (v.contains("collision")) {
    nlohmann::json wrap = {{"collision", v["collision"]}};
    ApplySolverJson(wrap, cfg.path() + ": " + key, &pv.opts);
  }
  pv.scene.solver = pv.opts;
  return pv;
}

CollisionSweepParams ReadCollisionSweepParams(const Config& cfg) {
  CollisionSweepParams p;
  p.robot = cfg.String("robot", "selfcollision_finger");
  const int res = cfg.Int("res", 0);
  p.steps = cfg.Int("steps", 10);
  const nlohmann::json obstacles_j = cfg.Raw("obstacles");
  const nlohmann::json end_j = cfg.Raw("actuation");
  const nlohmann::json variants_j = cfg.Raw("variants");
  p.contact_dist = cfg.Number("contact_distance_mm", 0.5);
  p.export_region = cfg.Int("export_region", -1);
  const Scene base = ConfigRobot(cfg, p.robot, res);
  const FkOptions base_opts = cfg.Solver(base.solver);
  cfg.CheckNoUnknownKeys();
  if (p.steps < 1) cfg.Fail("steps", "an integer >= 1");
  if (!(p.contact_dist >= 0)) cfg.Fail("contact_distance_mm", "a number >= 0");
  p.obstacles = ConfigObstacles(cfg, obstacles_j);
  p.c_end = ConfigActuation(cfg, "actuation", end_j, base);
  if (!variants_j.is_array() || variants_j.empty())
    cfg.Fail("variants", "a non-empty array of {\"name\", [\"collision\"], [\"robot_params\"]}");
  // Every variant is read and checked before the first one runs: a bad key in the last variant
  // fails at once, not after the others' minutes of solving.
  for (size_t vi = 0; vi < variants_j.size(); ++vi)
    p.variants.push_back(ReadSweepVariant(cfg, vi, variants_j[vi], base, base_opts, p, res));
  return p;
}

/// What one variant's sweep from rest to the end actuation accumulates.
struct VariantSweep {
  Eigen::MatrixX3d X;               ///< the final shape
  std::unique_ptr<BendAngle> bend;  ///< if the robot has tip_top and tip_bottom markers
  double check_s = 0, resp_s = 0, solver_s = 0, total_s = 0;
  int iterations = 0, failed = 0;
  FkResult last;
  CollisionCheck last_check;
  std::vector<ContactPatch> patches;  ///< per obstacle, at the last step
  nlohmann::json tips = nlohmann::json::array();
};

/// Drives variant vi from rest to the end actuation in `steps` warm-started steps, a row of
/// steps.csv per step.
VariantSweep SweepCollisionVariant(const Config& cfg, const CollisionSweepParams& p, size_t vi,
                                   CsvWriter* csv, bool verbose) {
  const std::string& name = p.variants[vi].name;
  const Scene& scene = p.variants[vi].scene;
  const FkOptions& opts = p.variants[vi].opts;
  const std::string key = "variants[" + std::to_string(vi) + "]";
  const int steps = p.steps;
  auto model = std::make_shared<const Model>(scene);
  auto solver = MakeFkSolver(model, opts);
  // The exact check, also for variants without response.
  CollisionOptions probe_opts = opts.collision;
  probe_opts.self = scene.mesh.num_prisms() == 0;
  CollisionResponse probe(*model, probe_opts);
  const int tip = scene.marker_index("tip");
  VariantSweep v;
  if (scene.marker_index("tip_top") >= 0 && scene.marker_index("tip_bottom") >= 0)
    v.bend = std::make_unique<BendAngle>(scene);
  const Eigen::VectorXd rest = scene.rest_actuation();
  v.X = scene.mesh.vertices;
  for (int s = 1; s <= steps; ++s) {
    const double t = double(s) / steps;
    const Eigen::VectorXd c = rest + t * (p.c_end - rest);
    FkResult r = solver->Solve(c, s > 1 ? &v.X : nullptr);
    if (r.status == FkStatus::InvalidInput)
      throw std::runtime_error(cfg.path() + ": " + key + ": " + r.message);
    v.X = r.positions;
    const CollisionCheck ck = probe.Check(v.X);
    const bool ok = r.status == FkStatus::Converged;
    v.failed += !ok;
    v.iterations += r.iterations;
    v.check_s += r.collision_stats.check_s;
    v.resp_s += r.collision_stats.response_s;
    v.solver_s += r.local_time_s + r.global_time_s;
    v.total_s += r.time_s;
    const Eigen::MatrixX3d P = scene.marker_positions(v.X);
    const double ang = v.bend ? (*v.bend)(v.X) : 0.0;
    v.tips.push_back({P(tip, 0), P(tip, 1), P(tip, 2)});
    // The contact region with every obstacle (vertices within contact_distance_mm, area).
    int touch = 0;
    double touch_area = 0.0;
    v.patches.clear();
    for (const auto& o : probe.obstacles()) {
      v.patches.push_back(MeasureContact(o, scene.mesh, v.X, p.contact_dist));
      touch += v.patches.back().vertices;
      touch_area += v.patches.back().area_mm2;
    }
    csv->RowStrings({name,
                     std::to_string(s),
                     std::to_string(t),
                     std::to_string(P(tip, 0)),
                     std::to_string(P(tip, 1)),
                     std::to_string(P(tip, 2)),
                     std::to_string(ang),
                     std::to_string(r.iterations),
                     ok ? "1" : "0",
                     std::to_string(r.springs),
                     std::to_string(ck.self_contacts),
                     std::to_string(ck.obstacle_contacts),
                     std::to_string(ck.max_penetration),
                     std::to_string(ck.self_penetration),
                     std::to_string(ck.obstacle_penetration),
                     std::to_string(ck.inverted_elements),
                     std::to_string(ck.tangled_contacts),
                     std::to_string(touch),
                     std::to_string(touch_area),
                     std::to_string(r.collision_stats.check_s),
                     std::to_string(r.collision_stats.response_s),
                     std::to_string(r.local_time_s + r.global_time_s),
                     std::to_string(r.time_s)});
    if (verbose)
      std::fprintf(
          stderr,
          "  [%s %d/%d] %s; exact check: %d self (max depth %.3g mm; %d in tangles) + %d obstacle "
          "contacts (max depth %.3g mm); %d inverted elements\n",
          name.c_str(), s, steps, r.BriefReport().c_str(), ck.self_contacts, ck.self_penetration,
          ck.tangled_contacts, ck.obstacle_contacts, ck.obstacle_penetration, ck.inverted_elements);
    v.last = r;
    v.last_check = ck;
  }
  return v;
}

/// surface_<variant>.csv: the rest and final positions of the vertices of export_region.
void WriteRegionSurface(const Config& cfg, const CollisionSweepParams& p, const std::string& dir,
                        const SweepVariant& var, const Eigen::MatrixX3d& X) {
  const Scene& scene = var.scene;
  CsvWriter surf(dir + "/surface_" + var.name + ".csv", {"x0", "y0", "z0", "x", "y", "z"});
  const std::vector<int> verts = VerticesOfRegions(scene.mesh, {p.export_region});
  if (verts.empty()) cfg.Fail("export_region", "a region tag of robot '" + p.robot + "'");
  for (int q : verts)
    surf.Row({scene.mesh.vertices(q, 0), scene.mesh.vertices(q, 1), scene.mesh.vertices(q, 2),
              X(q, 0), X(q, 1), X(q, 2)});
}

/// A variant's entry in the summary.
nlohmann::json VariantJson(const CollisionSweepParams& p, const SweepVariant& var,
                           const VariantSweep& v) {
  const Scene& scene = var.scene;
  const int tip = scene.marker_index("tip");
  nlohmann::json jv;
  jv["name"] = var.name;
  jv["tets"] = scene.mesh.num_tets();
  jv["response_self"] = var.opts.collision.self;
  jv["response_obstacles"] = var.opts.collision.obstacles && !p.obstacles.empty();
  const Eigen::MatrixX3d P = scene.marker_positions(v.X);
  jv["tip"] = {P(tip, 0), P(tip, 1), P(tip, 2)};
  jv["tips"] = v.tips;
  if (v.bend) jv["bend_deg"] = (*v.bend)(v.X);
  nlohmann::json markers;
  for (int q = 0; q < static_cast<int>(scene.markers.size()); ++q)
    markers[scene.markers[q].name] = {P(q, 0), P(q, 1), P(q, 2)};
  jv["markers"] = markers;
  const CollisionCheck& ck = v.last_check;
  jv.update(CollisionCheckJson(ck));  // the exact check of the last state, in its one JSON form
  jv["springs_at_end"] = v.last.springs;
  jv["iterations"] = v.iterations;
  jv["non_converged_steps"] = v.failed;
  jv["check_s"] = v.check_s;
  jv["response_s"] = v.resp_s;
  jv["solver_s"] = v.solver_s;
  jv["total_s"] = v.total_s;
  jv["collision_share"] = v.total_s > 0 ? (v.check_s + v.resp_s) / v.total_s : 0.0;
  if (!p.obstacles.empty()) {
    nlohmann::json contacts = nlohmann::json::array();
    for (const ContactPatch& cp : v.patches) {
      contacts.push_back(
          {{"vertices", cp.vertices}, {"extent_x_mm", cp.extent_mm}, {"area_mm2", cp.area_mm2}});
    }
    jv["contact"] = contacts;
  }
  return jv;
}

// ---- collision_costs ----

/// One robot of collision_costs, its keys checked before the first one runs.
struct CostsRobot {
  std::string key;   ///< "robots[i]"
  nlohmann::json j;  ///< its object
  RobotParams params;
  std::optional<ProgressiveOptions> remesh;
};

/// The keys of a collision_costs config.
struct CollisionCostsParams {
  nlohmann::json solver_j;  ///< the solver object (null if none)
  std::vector<CostsRobot> robots;
};

CostsRobot ReadCostsRobot(const Config& cfg, size_t i, const nlohmann::json& rj) {
  CostsRobot r;
  r.key = "robots[" + std::to_string(i) + "]";
  r.j = rj;
  const std::string& key = r.key;
  if (!rj.is_object() || !rj.contains("robot") || !rj["robot"].is_string())
    cfg.Fail(key, "an object with \"robot\"");
  for (auto it = rj.begin(); it != rj.end(); ++it)
    if (it.key() != "robot" && it.key() != "res" && it.key() != "robot_params" &&
        it.key() != "actuation" && it.key() != "steps" && it.key() != "obstacles" &&
        it.key() != "thesis" && it.key() != "remesh" && it.key() != "collision" &&
        it.key() != "label")
      cfg.Fail(key + "." + it.key(),
               "one of robot, label, res, robot_params, actuation, steps, obstacles, remesh, "
               "collision, thesis");
  if (rj.contains("label") && (!rj["label"].is_string() || rj["label"].get<std::string>().empty()))
    cfg.Fail(key + ".label", "a non-empty string naming the row (default: the robot)");
  if (rj.contains("res") && !rj["res"].is_number_integer()) cfg.Fail(key + ".res", "an integer");
  if (rj.contains("steps") && (!rj["steps"].is_number_integer() || rj["steps"].get<int>() < 1))
    cfg.Fail(key + ".steps", "an integer >= 1");
  if (rj.contains("robot_params"))
    MergeRobotParams(cfg, key + ".robot_params", rj["robot_params"], &r.params);
  if (rj.contains("remesh"))
    r.remesh = CostsRemeshOptions(cfg, key + ".remesh", rj["remesh"],
                                  rj["robot"].get<std::string>(), rj.value("res", 0), r.params);
  if (rj.contains("collision")) {
    FkOptions probe;
    ApplySolverJson({{"collision", rj["collision"]}}, cfg.path() + ": " + key, &probe);
  }
  return r;
}

CollisionCostsParams ReadCollisionCostsParams(const Config& cfg) {
  CollisionCostsParams p;
  const nlohmann::json robots_j = cfg.Raw("robots");
  p.solver_j = cfg.Raw("solver");
  (void)cfg.Solver(FkOptions());  // checks the solver object once
  cfg.CheckNoUnknownKeys();
  if (!robots_j.is_array() || robots_j.empty())
    cfg.Fail("robots",
             "a non-empty array of {\"robot\", \"res\", [\"robot_params\"], \"actuation\", "
             "\"steps\", [\"obstacles\"], [\"thesis\"]}");
  // Every robot's keys are read and checked before the first one runs (a bad key in the last
  // robot fails at once, not after the others' minutes of solving).
  for (size_t i = 0; i < robots_j.size(); ++i)
    p.robots.push_back(ReadCostsRobot(cfg, i, robots_j[i]));
  return p;
}

/// The time of a robot's steps split as the thesis does (sums over the steps, s), and the state
/// of the collisions after them.
struct StepCosts {
  double check = 0, resp = 0, solve = 0, total = 0, remesh_s = 0;
  CollisionCheck
      left;  ///< the exact check after the last step (collision-free if the response was off)
  bool free = true;
  nlohmann::json remesh_j;  ///< the remeshing's summary (null without remeshing)
};

/// Algorithm 2 with the collision handling on: the chamber's ratio is raised over the same
/// `steps` values, and the chamber is re-tessellated when it has grown or distorted too far.
StepCosts RemeshedStepCosts(const Config& cfg, const CostsRobot& cr, const Scene& scene,
                            const Eigen::VectorXd& c_end, int steps, double mesh_gen_s,
                            bool verbose) {
  const std::string& key = cr.key;
  const std::string robot = cr.j["robot"].get<std::string>();
  const Eigen::VectorXd rest = scene.rest_actuation();
  ProgressiveOptions popt = *cr.remesh;
  int chamber = -1;
  try {
    chamber = ChamberActuator(scene);
  } catch (const std::invalid_argument& e) {
    cfg.Fail(key + ".remesh",
             std::string("a robot with one pneumatic chamber actuator (") + e.what() + ")");
  }
  const double alpha = c_end[chamber];
  if (!(alpha > 1))
    cfg.Fail(key + ".actuation", "a chamber volume ratio > 1 (remeshing raises it)");
  for (int s = 1; s < steps; ++s)
    popt.ladder.push_back(rest[chamber] + (double(s) / steps) * (alpha - rest[chamber]));
  popt.ladder.erase(
      std::remove_if(popt.ladder.begin(), popt.ladder.end(), [](double a) { return !(a > 1); }),
      popt.ladder.end());
  popt.on_step = [&](const ProgressiveStep& st, const Scene& s_now, const Eigen::MatrixX3d&) {
    if (verbose)
      std::fprintf(
          stderr,
          "  [%s alpha %.3g] %s, %d iterations, %.2f s; %d remesh(es), %d failed, %.2f s, %d tets; "
          "exact check: %s, %d springs, %d inverted elements (%d body)\n",
          robot.c_str(), st.alpha, FkStatusToString(st.status), st.iterations, st.solver_seconds,
          st.remeshes, st.remesh_failures, st.mesh_seconds, s_now.mesh.num_tets(),
          st.collision_active ? (st.collision.collision_free() ? "collision-free" : "contacts left")
                              : "off",
          st.springs, st.collision.inverted_elements, st.collision.inverted_body_elements);
  };
  const ProgressiveResult pr = SolveProgressive(scene, alpha, popt);
  if (!pr.completed)
    throw std::runtime_error(cfg.path() + ": " + key + ": remeshing stopped: " + pr.message);
  StepCosts sc;
  for (const ProgressiveStep& st : pr.steps) {
    sc.check += st.check_seconds;
    sc.resp += st.response_seconds;
    sc.solve += st.local_global_seconds;
    sc.total += st.solver_seconds;
    sc.remesh_s += st.mesh_seconds;
    sc.free = sc.free && (!st.collision_active || st.collision.collision_free());
    if (st.collision_active) sc.left = st.collision;
  }
  sc.remesh_j = {{"remeshes", pr.remeshes},
                 {"remesh_failures", pr.remesh_failures},
                 {"first_remesh_failure", pr.first_remesh_failure},
                 {"tets_final", pr.scene.mesh.num_tets()},
                 {"chamber_volume_ratio", pr.chamber_volume_ratio},
                 {"status", FkStatusToString(pr.status)},
                 {"alpha_max", popt.criteria.alpha_max},
                 {"d_max", popt.criteria.d_max},
                 {"chamber_rest", ChamberRestToString(popt.remesh_options.rest)},
                 {"initial_mesh_s", mesh_gen_s}};
  return sc;
}

/// `steps` warm-started steps from rest to the end actuation on the robot's one mesh.
StepCosts PlainStepCosts(const Config& cfg, const CostsRobot& cr, const Scene& scene,
                         const Eigen::VectorXd& c_end, int steps, bool verbose) {
  const std::string robot = cr.j["robot"].get<std::string>();
  const Eigen::VectorXd rest = scene.rest_actuation();
  auto model = std::make_shared<const Model>(scene);
  auto solver = MakeFkSolver(model, scene.solver);
  Eigen::MatrixX3d X = scene.mesh.vertices;
  StepCosts sc;
  for (int s = 1; s <= steps; ++s) {
    const Eigen::VectorXd c = rest + (double(s) / steps) * (c_end - rest);
    FkResult r = solver->Solve(c, s > 1 ? &X : nullptr);
    if (r.status == FkStatus::InvalidInput)
      throw std::runtime_error(cfg.path() + ": " + cr.key + ": " + r.message);
    X = r.positions;
    sc.check += r.collision_stats.check_s;
    sc.resp += r.collision_stats.response_s;
    sc.solve += r.local_time_s + r.global_time_s;
    sc.total += r.time_s;
    sc.free = sc.free && (!r.collision_active || r.collision.collision_free());
    if (r.collision_active) sc.left = r.collision;
    if (verbose)
      std::fprintf(stderr, "  [%s %d/%d] %s\n", robot.c_str(), s, steps, r.BriefReport().c_str());
  }
  return sc;
}

/// One robot's row of Table 3.1: its costs per step, a row of costs.csv and the summary's row.
nlohmann::json RunCostsRobot(const Config& cfg, const CollisionCostsParams& p, const CostsRobot& cr,
                             CsvWriter* csv, bool verbose) {
  const std::string& key = cr.key;
  const nlohmann::json& rj = cr.j;
  const std::string robot = rj["robot"].get<std::string>();
  const int res = rj.value("res", 0);
  const int steps = rj.value("steps", 4);
  const auto t0 = Clock::now();
  Scene scene;
  try {
    scene = MakeRobot(robot, res, cr.params);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(cfg.path() + ": " + key + ": " + e.what());
  }
  const double mesh_gen_s = SecondsSince(t0);
  if (rj.contains("obstacles")) scene.obstacles = ConfigObstacles(cfg, rj["obstacles"]);
  if (!rj.contains("actuation"))
    cfg.Fail(key + ".actuation", "an object {\"actuator\": end value}");
  const Eigen::VectorXd c_end = ConfigActuation(cfg, key + ".actuation", rj["actuation"], scene);
  FkOptions opts = scene.solver;  // the robot's defaults, then the config's solver object
  if (!p.solver_j.is_null()) ApplySolverJson(p.solver_j, cfg.path() + ": solver", &opts);
  // ... then the robot's own collision options (e.g. a spring stiffness for its contact set).
  if (rj.contains("collision"))
    ApplySolverJson({{"collision", rj["collision"]}}, cfg.path() + ": " + key, &opts);
  scene.solver = opts;
  const StepCosts sc = cr.remesh
                           ? RemeshedStepCosts(cfg, cr, scene, c_end, steps, mesh_gen_s, verbose)
                           : PlainStepCosts(cfg, cr, scene, c_end, steps, verbose);
  nlohmann::json row;
  row["robot"] = robot;
  row["label"] = rj.value("label", robot);
  row["tets"] = scene.mesh.num_tets();
  // The thesis's mesh generation for a remeshed robot is its chamber re-tessellation per step;
  // without remeshing it is the robot's one tessellation.
  row["mesh_gen_s"] = sc.remesh_j.is_null() ? mesh_gen_s : sc.remesh_s / steps;
  if (!sc.remesh_j.is_null()) row["remesh"] = sc.remesh_j;
  row["spring_stiffness"] = opts.collision.stiffness;
  row["col_check_s"] = sc.check / steps;
  row["col_resp_s"] = sc.resp / steps;
  row["solver_s"] = sc.solve / steps;
  row["step_s"] = sc.total / steps;
  row["collision_share"] = sc.total > 0 ? (sc.check + sc.resp) / sc.total : 0.0;
  row["collision_free"] = sc.free;
  // What the exact check found after the last step (Sec. 3.2.3: the penetration left).
  row["final_check"] = CollisionCheckJson(sc.left);
  if (rj.contains("thesis")) {
    const auto& t = rj["thesis"];
    row["thesis"] = t;
    // Per-step speed ratios against the thesis (same robot type, its tet count in "tets").
    if (t.contains("solver_s") && t["solver_s"].is_number() && row["step_s"].get<double>() > 0) {
      const double thesis_step =
          t.value("col_check_s", 0.0) + t.value("col_resp_s", 0.0) + t["solver_s"].get<double>();
      row["speedup_vs_thesis_step"] = thesis_step / (sc.total / steps);
    }
  }
  csv->RowStrings({robot, row["label"].get<std::string>(), std::to_string(scene.mesh.num_tets()),
                   std::to_string(row["mesh_gen_s"].get<double>()),
                   std::to_string(sc.check / steps), std::to_string(sc.resp / steps),
                   std::to_string(sc.solve / steps), std::to_string(sc.total / steps),
                   std::to_string(steps), sc.free ? "1" : "0"});
  return row;
}

}  // namespace

nlohmann::json RunCollisionSweep(const Config& cfg, const std::string& dir, bool verbose) {
  const CollisionSweepParams p = ReadCollisionSweepParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  std::filesystem::create_directories(dir + "/frames");
  CsvWriter csv(dir + "/steps.csv", {"variant",
                                     "step",
                                     "actuation_scale",
                                     "tip_x",
                                     "tip_y",
                                     "tip_z",
                                     "bend_deg",
                                     "iterations",
                                     "converged",
                                     "springs",
                                     "self_contacts",
                                     "obstacle_contacts",
                                     "max_penetration_mm",
                                     "self_penetration_mm",
                                     "obstacle_penetration_mm",
                                     "inverted_elements",
                                     "tangled_contacts",
                                     "contact_vertices",
                                     "contact_area_mm2",
                                     "check_s",
                                     "response_s",
                                     "solver_s",
                                     "time_s"});
  nlohmann::json out_variants = nlohmann::json::array();
  std::vector<std::pair<double, std::string>> frames;
  for (size_t vi = 0; vi < p.variants.size(); ++vi) {
    const SweepVariant& var = p.variants[vi];
    VariantSweep v = SweepCollisionVariant(cfg, p, vi, &csv, verbose);
    if (p.export_region >= 0) WriteRegionSurface(cfg, p, dir, var, v.X);
    const std::string vtu = "frames/" + var.name + ".vtu";
    WriteVtu(dir + "/" + vtu, var.scene.mesh, v.X);
    frames.emplace_back(double(vi), vtu);
    out_variants.push_back(VariantJson(p, var, v));
  }
  WritePvd(dir + "/variants.pvd", frames);
  nlohmann::json j;
  j["robot"] = p.robot;
  j["steps"] = p.steps;
  j["variants"] = out_variants;
  j["contact_distance_mm"] = p.contact_dist;
  return j;
}

nlohmann::json RunCollisionCosts(const Config& cfg, const std::string& dir, bool verbose) {
  const CollisionCostsParams p = ReadCollisionCostsParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  CsvWriter csv(dir + "/costs.csv",
                {"robot", "label", "tets", "mesh_gen_s", "col_check_s", "col_resp_s", "solver_s",
                 "step_s", "steps", "collision_free"});
  nlohmann::json rows = nlohmann::json::array();
  for (const CostsRobot& cr : p.robots) rows.push_back(RunCostsRobot(cfg, p, cr, &csv, verbose));
  nlohmann::json j;
  j["rows"] = rows;
  return j;
}

}  // namespace softkin
