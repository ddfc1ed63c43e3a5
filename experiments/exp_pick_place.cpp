// Thesis Sec. 4.4, Fig. 4.7-4.11: pick-and-place with multi_segment_gripper in three IK stages.
//  1. pick (Eq. 4.5, 4.6): c1, c2 (gripper c3 at rest) put P0 at distance R + d from the object's
//     centre p1, with n . (p1 - p0) = 0;
//  2. grasp (Eq. 4.7): c3 alone (c1, c2 held), from `grasp_start`, bends the gripper until the
//     circle fitted to its inextensible layer's inner surface has the object's diameter 2R;
//  3. place: c1, c2 (c3 held) bring P0 to R + d from the object's new centre p1t.
//
// Geometry (docs/ik.md, objectives): P0 is the centre of the end face of the second segment's
// connector, where the gripper starts; n is the normal of that face (from three of its corner
// vertices), i.e. the direction the gripper leaves P0 in. The gripper wraps an object whose centre
// lies in that face's plane (n . P0P1 = 0, Fig. 4.9b) on the inner (inextensible-layer) side, at
// the distance R + d of the gripper's mid-surface, d = half the gripper's height.
// Where the object is: `pick_design_actuation` (c1, c2) is a pose; the object's centre is put at
// R + d from its P0 on the inner side of its end face. The pick stage then starts from rest and
// must find a pose that holds it. The place target is p1 + `place_offset`.
#include "softkin/experiments/ik_config.hpp"
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/ik/subset_kinematics.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace softkin {

namespace {

nlohmann::json V(const Eigen::VectorXd& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}
nlohmann::json V3(const Eigen::Vector3d& v) { return {v[0], v[1], v[2]}; }

/// Vertex order index (within the marker) of the vertex that minimises score(rest position).
template <class F>
int MarkerVertex(const Scene& scene, const Marker& m, F score) {
  int best = 0;
  for (size_t i = 1; i < m.vertices.size(); ++i)
    if (score(scene.mesh.vertices.row(m.vertices[i])) <
        score(scene.mesh.vertices.row(m.vertices[best])))
      best = static_cast<int>(i);
  return best;
}

/// The keys of an ik_pick_and_place config.
struct PickPlaceParams {
  IkExperimentSetup s;
  double R = 20.0;             ///< object radius, mm
  double d = 7.5;              ///< half the gripper's height, mm
  double omega1 = 1.0;         ///< the pick objective's weight of the normal term
  std::vector<double> design;  ///< pick_design_actuation [c1, c2]
  std::vector<double> offset;  ///< place_offset [dx, dy, dz], mm
  // Stop rule of the three stages on O itself (mm^2): the stages' objectives are not distances
  // to one point, so lambda_mm (for point tracking) does not apply.
  double stage_lambda = 0.04;
  // Where the grasp stage starts c3: at rest the gripper is straight and its layer's circle fit is
  // degenerate (two parallel rows of points), so it starts part-way (default: the middle of c3's
  // range).
  double grasp_start = -1.0;
  int m0 = -1, mg = -1;  ///< the markers P0 and grip_layer
};

PickPlaceParams ReadPickPlaceParams(const Config& cfg) {
  PickPlaceParams p;
  p.s = ReadIkSetup(cfg, "multi_segment_gripper");
  p.R = cfg.Number("object_radius", 20.0);
  p.d = cfg.Number("half_width", 7.5);
  p.omega1 = cfg.Number("omega1", 1.0);
  p.design = cfg.NumberList("pick_design_actuation", {});
  p.offset = cfg.NumberList("place_offset", {});
  p.stage_lambda = cfg.Number("stage_lambda", 0.04);
  p.grasp_start = cfg.Number("grasp_start", -1.0);
  cfg.CheckNoUnknownKeys();
  if (!(p.R > 0)) cfg.Fail("object_radius", "a radius > 0 mm");
  if (!(p.d >= 0)) cfg.Fail("half_width", "a distance >= 0 mm");
  if (!(p.omega1 >= 0)) cfg.Fail("omega1", "a weight >= 0");
  if (!(p.stage_lambda >= 0)) cfg.Fail("stage_lambda", "a threshold >= 0 mm^2");
  if (p.offset.size() != 3) cfg.Fail("place_offset", "[dx, dy, dz] in mm");
  p.m0 = p.s.scene.marker_index("P0");
  p.mg = p.s.scene.marker_index("grip_layer");
  if (p.m0 < 0 || p.mg < 0 || p.s.scene.num_actuators() != 3)
    cfg.Fail("robot",
             "a robot with markers P0 and grip_layer and three actuators (multi_segment_gripper)");
  if (p.design.size() != 2) cfg.Fail("pick_design_actuation", "[c1, c2]");
  return p;
}

/// The points the kinematics tracks: P0, three corners of its face (pa, pb, pc), the grip layer's
/// inner-surface vertices and the tip.
struct GripperPoints {
  std::string pa, pb, pc;
  std::vector<std::string> names;
  int inner_count = 0;  ///< grip layer vertices
};

GripperPoints TrackedPoints(const PickPlaceParams& p) {
  const Scene& scene = p.s.scene;
  GripperPoints g;
  // Three corners of P0's face: bottom (y min, z min), y max at the bottom, top (y min, z max).
  const Marker& pm = scene.markers[p.m0];
  const int va = MarkerVertex(scene, pm, [](const Eigen::RowVector3d& x) { return x.y() + x.z(); });
  const int vb =
      MarkerVertex(scene, pm, [](const Eigen::RowVector3d& x) { return -x.y() + x.z(); });
  const int vc = MarkerVertex(scene, pm, [](const Eigen::RowVector3d& x) { return x.y() - x.z(); });
  g.pa = "P0[" + std::to_string(va) + "]";
  g.pb = "P0[" + std::to_string(vb) + "]";
  g.pc = "P0[" + std::to_string(vc) + "]";
  // The grasp circle is fitted to the layer's inner surface (its vertices at the lowest rest z):
  // the surface that closes on the object. Fitting both faces of the thin layer at once makes the
  // fit degenerate as the gripper straightens (two parallel rows), and the diameter then peaks
  // (about 67 mm at c3 = 4.9 on res 6) instead of growing without bound.
  const Marker& gm = scene.markers[p.mg];
  double zmin = std::numeric_limits<double>::infinity();
  for (int v : gm.vertices) zmin = std::min(zmin, scene.mesh.vertices(v, 2));
  g.names = {"P0", g.pa, g.pb, g.pc};
  for (size_t i = 0; i < gm.vertices.size(); ++i)
    if (std::abs(scene.mesh.vertices(gm.vertices[i], 2) - zmin) < 1e-9) {
      g.names.push_back("grip_layer[" + std::to_string(i) + "]");
      ++g.inner_count;
    }
  g.names.push_back("tip");
  return g;
}

// Rows of the kinematics' points: P0 and the corners pa, pb, pc of its face.
constexpr int kP0 = 0, kA = 1, kB = 2, kC = 3;

/// Where the object is: at R + d from P0 of the design pose, on the inner side of its end face.
struct ObjectPlacement {
  Eigen::Vector3d dp0, n;   ///< P0 and its face's normal at the design pose
  Eigen::Vector3d p1, p1t;  ///< the object's centre, and where it is placed
};

ObjectPlacement PlaceObject(const Config& cfg, const PickPlaceParams& p, SimulatorKinematics& kin) {
  Eigen::VectorXd c_design = kin.rest();
  c_design[0] = p.design[0];
  c_design[1] = p.design[1];
  {
    const std::string why = CheckKinematicsInput(kin, c_design);
    if (!why.empty()) cfg.Fail("pick_design_actuation", "values inside the box (" + why + ")");
  }
  kin.Reset();
  const KinematicsEval de = kin.Evaluate(c_design, false);
  if (!de.ok)
    throw std::runtime_error("the forward solve at pick_design_actuation failed: " + de.message);
  ObjectPlacement o;
  o.dp0 = de.p.row(kP0).transpose();
  o.n = (de.p.row(kB) - de.p.row(kA)).cross(de.p.row(kC) - de.p.row(kA)).transpose();
  o.n.normalize();
  Eigen::Vector3d inner = (de.p.row(kA) - de.p.row(kC)).transpose();  // top -> bottom of the face
  inner -= inner.dot(o.n) * o.n;
  inner.normalize();
  o.p1 = o.dp0 + (p.R + p.d) * inner;
  o.p1t = o.p1 + Eigen::Vector3d(p.offset[0], p.offset[1], p.offset[2]);
  return o;
}

/// Runs the IK stages on subsets of the actuators, writing stages.csv and the side view of each
/// stage's shape (shapes.csv).
class StageRunner {
 public:
  StageRunner(SimulatorKinematics& kin, const IkOptions& ik, const Scene& scene,
              const std::string& dir, bool verbose)
      : kin_(kin),
        ik_(ik),
        verbose_(verbose),
        stages_(dir + "/stages.csv",
                {"stage", "c1", "c2", "c3", "initial_objective", "final_objective", "iterations",
                 "evaluations", "fk_solves", "time_s", "termination"}),
        shapes_(dir + "/shapes.csv", {"stage", "x", "z"}) {
    for (int v = 0; v < scene.mesh.num_vertices(); ++v)
      if (std::abs(scene.mesh.vertices(v, 1)) < 1e-9) side_.push_back(v);
  }

  /// Solves the full actuation `full` from rest and writes its side view; returns the evaluation.
  KinematicsEval WriteShape(const std::string& stage, const Eigen::VectorXd& full) {
    kin_.Reset();
    const KinematicsEval e = kin_.Evaluate(full, false);
    if (!e.ok) throw std::runtime_error(stage + ": the forward solve failed: " + e.message);
    const Eigen::MatrixX3d& X = kin_.last_positions();
    for (int v : side_)
      shapes_.RowStrings({stage, std::to_string(X(v, 0)), std::to_string(X(v, 2))});
    return e;
  }

  /// Minimises obj over the `driven` actuators from c0 (the others as in `fixed`); returns the
  /// full actuation found and the stage's summary entry.
  std::pair<Eigen::VectorXd, nlohmann::json> Run(const std::string& stage,
                                                 const std::vector<int>& driven,
                                                 const Eigen::VectorXd& fixed, const Objective& obj,
                                                 const Eigen::VectorXd& c0) {
    SubsetKinematics sub(kin_, driven, fixed);
    kin_.Reset();
    const IkResult r = SolveIk(sub, obj, c0, ik_);
    const Eigen::VectorXd full = sub.Full(r.c);
    if (verbose_)
      std::fprintf(stderr, "  [%s] %s\n", stage.c_str(), r.summary.BriefReport().c_str());
    stages_.RowStrings({stage, std::to_string(full[0]), std::to_string(full[1]),
                        std::to_string(full[2]), std::to_string(r.summary.initial_objective),
                        std::to_string(r.summary.final_objective),
                        std::to_string(r.summary.iterations), std::to_string(r.summary.evaluations),
                        std::to_string(r.summary.fk_solves), std::to_string(r.summary.time_s),
                        IkTerminationToString(r.summary.termination)});
    total_time_ += r.summary.time_s;
    nlohmann::json j = {{"stage", stage},
                        {"objective", obj.name()},
                        {"c", V(full)},
                        {"initial_objective", r.summary.initial_objective},
                        {"final_objective", r.summary.final_objective},
                        {"converged", r.summary.converged()},
                        {"inverted_elements", r.inverted_elements},
                        {"termination", IkTerminationToString(r.summary.termination)},
                        {"iterations", r.summary.iterations},
                        {"evaluations", r.summary.evaluations},
                        {"fk_solves", r.summary.fk_solves},
                        {"time_s", r.summary.time_s}};
    return std::make_pair(full, j);
  }

  double total_time() const { return total_time_; }

 private:
  SimulatorKinematics& kin_;
  IkOptions ik_;
  bool verbose_;
  CsvWriter stages_, shapes_;
  std::vector<int> side_;  ///< vertices of the side face y = 0, for the side view
  double total_time_ = 0;
};

const std::vector<int> kArm = {0, 1}, kGripper = {2};

/// 1. pick (Eq. 4.5, 4.6): c1, c2 from rest put P0 at R + d from p1, with n . (p1 - p0) = 0.
nlohmann::json PickStage(const PickPlaceParams& p, const GripperPoints& g, const ObjectPlacement& o,
                         SimulatorKinematics& kin, StageRunner* stages, Eigen::VectorXd* c_pick) {
  PickParams pp;
  pp.p0 = "P0";
  pp.normal.points = {g.pa, g.pb, g.pc};
  pp.center = o.p1;
  pp.object_radius = p.R;
  pp.half_width = p.d;
  pp.omega1 = p.omega1;
  const PickObjective pick(kin.point_names(), pp);
  auto [c, j] = stages->Run("pick", kArm, kin.rest(), pick, kin.rest().head(2));
  const KinematicsEval e = stages->WriteShape("pick", c);
  const Eigen::Vector3d p0 = e.p.row(kP0).transpose();
  const Eigen::Vector3d nn = pick.Normal(e.p);
  j["distance_residual_mm"] = (o.p1 - p0).norm() - (p.R + p.d);
  j["angle_n_p0p1_deg"] =
      std::acos(std::clamp(nn.dot((o.p1 - p0).normalized()), -1.0, 1.0)) * 180.0 / std::acos(-1.0);
  j["p0"] = V3(p0);
  *c_pick = c;
  return j;
}

/// 2. grasp (Eq. 4.7): c3 alone from `grasp_start` until the fitted circle has diameter 2R.
nlohmann::json GraspStage(const Config& cfg, const PickPlaceParams& p, SimulatorKinematics& kin,
                          const Eigen::VectorXd& c_pick, StageRunner* stages,
                          Eigen::VectorXd* c_grasp, double* c3_start_out) {
  GraspParams gp;
  gp.group = "grip_layer";
  gp.object_diameter = 2 * p.R;
  gp.plane_normal = Eigen::Vector3d::UnitY();
  const GraspObjective grasp(kin.point_names(), gp);
  Eigen::VectorXd c3_start(1);
  c3_start[0] = p.grasp_start >= 0 ? p.grasp_start : 0.5 * (kin.lower()[2] + kin.upper()[2]);
  if (c3_start[0] < kin.lower()[2] || c3_start[0] > kin.upper()[2])
    cfg.Fail("grasp_start", "a value of c3 inside its range");
  auto [c, j] = stages->Run("grasp", kGripper, c_pick, grasp, c3_start);
  const KinematicsEval e = stages->WriteShape("grasp", c);
  j["fitted_diameter_mm"] = grasp.FittedDiameter(e.p);
  j["object_diameter_mm"] = 2 * p.R;
  *c_grasp = c;
  *c3_start_out = c3_start[0];
  return j;
}

/// 3. place: c1, c2 (c3 held) bring P0 to R + d from the object's new centre p1t.
nlohmann::json PlaceStage(const PickPlaceParams& p, const ObjectPlacement& o,
                          SimulatorKinematics& kin, const Eigen::VectorXd& c_grasp,
                          StageRunner* stages) {
  PlaceParams lp;
  lp.p0 = "P0";
  lp.target_center = o.p1t;
  lp.object_radius = p.R;
  lp.half_width = p.d;
  const PlaceObjective place(kin.point_names(), lp);
  auto [c, j] = stages->Run("place", kArm, c_grasp, place, c_grasp.head(2));
  const KinematicsEval e = stages->WriteShape("place", c);
  const Eigen::Vector3d p0 = e.p.row(kP0).transpose();
  j["distance_residual_mm"] = (o.p1t - p0).norm() - (p.R + p.d);
  j["p0"] = V3(p0);
  return j;
}

}  // namespace

nlohmann::json RunIkPickAndPlace(const Config& cfg, const std::string& dir, bool verbose) {
  const PickPlaceParams p = ReadPickPlaceParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  const GripperPoints g = TrackedPoints(p);
  SimulatorKinematics kin(p.s.scene, p.s.KinematicsFor(g.names), &p.s.fk);
  IkOptions ik = p.s.ik;
  ik.lambda = p.stage_lambda;
  const ObjectPlacement o = PlaceObject(cfg, p, kin);
  StageRunner stages(kin, ik, p.s.scene, dir, verbose);
  stages.WriteShape("rest", kin.rest());

  nlohmann::json out = nlohmann::json::array();
  Eigen::VectorXd c_pick, c_grasp;
  double c3_start = 0;
  out.push_back(PickStage(p, g, o, kin, &stages, &c_pick));
  out.push_back(GraspStage(cfg, p, kin, c_pick, &stages, &c_grasp, &c3_start));
  out.push_back(PlaceStage(p, o, kin, c_grasp, &stages));

  nlohmann::json j = p.s.Json();
  j.erase("point");
  j["stage_lambda"] = p.stage_lambda;
  j["grasp_start"] = c3_start;
  j["object"] = {{"radius_mm", p.R},       {"half_width_mm", p.d},
                 {"omega1", p.omega1},     {"pick_design_actuation", p.design},
                 {"center", V3(o.p1)},     {"place_center", V3(o.p1t)},
                 {"design_p0", V3(o.dp0)}, {"design_normal", V3(o.n)}};
  j["normal_points"] = {g.pa, g.pb, g.pc};
  j["grip_points"] = g.inner_count;
  j["stages"] = out;
  j["total_time_s"] = stages.total_time();
  return j;
}

}  // namespace softkin
