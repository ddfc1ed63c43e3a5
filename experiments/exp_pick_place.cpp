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

nlohmann::json V(const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); }
nlohmann::json V3(const Eigen::Vector3d& v) { return {v[0], v[1], v[2]}; }

/// Vertex order index (within the marker) of the vertex that minimises score(rest position).
template <class F>
int MarkerVertex(const Scene& scene, const Marker& m, F score) {
  int best = 0;
  for (size_t i = 1; i < m.vertices.size(); ++i)
    if (score(scene.mesh.vertices.row(m.vertices[i])) < score(scene.mesh.vertices.row(m.vertices[best])))
      best = static_cast<int>(i);
  return best;
}

}  // namespace

nlohmann::json RunIkPickAndPlace(const Config& cfg, const std::string& dir, bool verbose) {
  IkExperimentSetup s = ReadIkSetup(cfg, "multi_segment_gripper");
  const double R = cfg.Number("object_radius", 20.0);
  const double d = cfg.Number("half_width", 7.5);
  const double omega1 = cfg.Number("omega1", 1.0);
  const std::vector<double> design = cfg.NumberList("pick_design_actuation", {});
  const std::vector<double> offset = cfg.NumberList("place_offset", {});
  // Stop rule of the three stages on O itself (mm^2): the stages' objectives are not distances
  // to one point, so lambda_mm (for point tracking) does not apply.
  const double stage_lambda = cfg.Number("stage_lambda", 0.04);
  // Where the grasp stage starts c3: at rest the gripper is straight and its layer's circle fit is
  // degenerate (two parallel rows of points), so it starts part-way (default: the middle of c3's
  // range).
  const double grasp_start = cfg.Number("grasp_start", -1.0);
  cfg.CheckNoUnknownKeys();
  if (!(R > 0)) cfg.Fail("object_radius", "a radius > 0 mm");
  if (!(d >= 0)) cfg.Fail("half_width", "a distance >= 0 mm");
  if (!(omega1 >= 0)) cfg.Fail("omega1", "a weight >= 0");
  if (!(stage_lambda >= 0)) cfg.Fail("stage_lambda", "a threshold >= 0 mm^2");
  if (offset.size() != 3) cfg.Fail("place_offset", "[dx, dy, dz] in mm");
  const int m0 = s.scene.marker_index("P0"), mg = s.scene.marker_index("grip_layer");
  if (m0 < 0 || mg < 0 || s.scene.num_actuators() != 3)
    cfg.Fail("robot", "a robot with markers P0 and grip_layer and three actuators (multi_segment_gripper)");
  if (design.size() != 2) cfg.Fail("pick_design_actuation", "[c1, c2]");

  // Three corners of P0's face: bottom (y min, z min), y max at the bottom, top (y min, z max).
  const Marker& pm = s.scene.markers[m0];
  const int va = MarkerVertex(s.scene, pm, [](const Eigen::RowVector3d& x) { return x.y() + x.z(); });
  const int vb = MarkerVertex(s.scene, pm, [](const Eigen::RowVector3d& x) { return -x.y() + x.z(); });
  const int vc = MarkerVertex(s.scene, pm, [](const Eigen::RowVector3d& x) { return x.y() - x.z(); });
  const std::string pa = "P0[" + std::to_string(va) + "]", pb = "P0[" + std::to_string(vb) + "]",
                    pc = "P0[" + std::to_string(vc) + "]";
  // The grasp circle is fitted to the layer's inner surface (its vertices at the lowest rest z): the
  // surface that closes on the object. Fitting both faces of the thin layer at once makes the fit
  // degenerate as the gripper straightens (two parallel rows), and the diameter then peaks
  // (about 67 mm at c3 = 4.9 on res 6) instead of growing without bound.
  const Marker& gm = s.scene.markers[mg];
  double zmin = std::numeric_limits<double>::infinity();
  for (int v : gm.vertices) zmin = std::min(zmin, s.scene.mesh.vertices(v, 2));
  std::vector<std::string> points = {"P0", pa, pb, pc};
  int inner_count = 0;
  for (size_t i = 0; i < gm.vertices.size(); ++i)
    if (std::abs(s.scene.mesh.vertices(gm.vertices[i], 2) - zmin) < 1e-9) {
      points.push_back("grip_layer[" + std::to_string(i) + "]");
      ++inner_count;
    }
  points.push_back("tip");
  SimulatorKinematics kin(s.scene, s.KinematicsFor(points), &s.fk);
  const auto& names = kin.point_names();
  const int i0 = 0, ia = 1, ib = 2, ic = 3;

  IkOptions ik = s.ik;
  ik.lambda = stage_lambda;

  // The object: from the design pose.
  Eigen::VectorXd c_design = kin.rest();
  c_design[0] = design[0];
  c_design[1] = design[1];
  {
    const std::string why = CheckKinematicsInput(kin, c_design);
    if (!why.empty()) cfg.Fail("pick_design_actuation", "values inside the box (" + why + ")");
  }
  kin.Reset();
  const KinematicsEval de = kin.Evaluate(c_design, false);
  if (!de.ok) throw std::runtime_error("the forward solve at pick_design_actuation failed: " + de.message);
  const Eigen::Vector3d dp0 = de.p.row(i0).transpose();
  Eigen::Vector3d n = (de.p.row(ib) - de.p.row(ia)).cross(de.p.row(ic) - de.p.row(ia)).transpose();
  n.normalize();
  Eigen::Vector3d inner = (de.p.row(ia) - de.p.row(ic)).transpose();  // top -> bottom of the face
  inner -= inner.dot(n) * n;
  inner.normalize();
  const Eigen::Vector3d p1 = dp0 + (R + d) * inner;
  const Eigen::Vector3d p1t = p1 + Eigen::Vector3d(offset[0], offset[1], offset[2]);

  const std::vector<int> arm = {0, 1}, gripper = {2};
  CsvWriter stages(dir + "/stages.csv", {"stage", "c1", "c2", "c3", "initial_objective", "final_objective",
                                         "iterations", "evaluations", "fk_solves", "time_s", "termination"});
  CsvWriter shapes(dir + "/shapes.csv", {"stage", "x", "z"});
  std::vector<int> side;  // vertices of the side face y = 0, for the side view
  for (int v = 0; v < s.scene.mesh.num_vertices(); ++v)
    if (std::abs(s.scene.mesh.vertices(v, 1)) < 1e-9) side.push_back(v);
  auto write_shape = [&](const std::string& stage, const Eigen::VectorXd& full) {
    kin.Reset();
    const KinematicsEval e = kin.Evaluate(full, false);
    if (!e.ok) throw std::runtime_error(stage + ": the forward solve failed: " + e.message);
    const Eigen::MatrixX3d& X = kin.last_positions();
    for (int v : side)
      shapes.RowStrings({stage, std::to_string(X(v, 0)), std::to_string(X(v, 2))});
    return e;
  };
  write_shape("rest", kin.rest());

  nlohmann::json out = nlohmann::json::array();
  double total_time = 0;
  auto run_stage = [&](const std::string& stage, const std::vector<int>& driven, const Eigen::VectorXd& fixed,
                       const Objective& obj, const Eigen::VectorXd& c0) {
    SubsetKinematics sub(kin, driven, fixed);
    kin.Reset();
    const IkResult r = SolveIk(sub, obj, c0, ik);
    const Eigen::VectorXd full = sub.Full(r.c);
    if (verbose) std::fprintf(stderr, "  [%s] %s\n", stage.c_str(), r.summary.BriefReport().c_str());
    stages.RowStrings({stage, std::to_string(full[0]), std::to_string(full[1]), std::to_string(full[2]),
                       std::to_string(r.summary.initial_objective), std::to_string(r.summary.final_objective),
                       std::to_string(r.summary.iterations), std::to_string(r.summary.evaluations),
                       std::to_string(r.summary.fk_solves), std::to_string(r.summary.time_s),
                       IkTerminationToString(r.summary.termination)});
    total_time += r.summary.time_s;
    nlohmann::json j = {{"stage", stage},
                        {"objective", obj.name()},
                        {"c", V(full)},
                        {"initial_objective", r.summary.initial_objective},
                        {"final_objective", r.summary.final_objective},
                        {"converged", r.summary.converged()},
                        {"termination", IkTerminationToString(r.summary.termination)},
                        {"iterations", r.summary.iterations},
                        {"evaluations", r.summary.evaluations},
                        {"fk_solves", r.summary.fk_solves},
                        {"time_s", r.summary.time_s}};
    return std::make_pair(full, j);
  };

  // 1. pick
  PickParams pp;
  pp.p0 = "P0";
  pp.normal.points = {pa, pb, pc};
  pp.center = p1;
  pp.object_radius = R;
  pp.half_width = d;
  pp.omega1 = omega1;
  const PickObjective pick(names, pp);
  auto [c_pick, j_pick] = run_stage("pick", arm, kin.rest(), pick, kin.rest().head(2));
  {
    const KinematicsEval e = write_shape("pick", c_pick);
    const Eigen::Vector3d p0 = e.p.row(i0).transpose();
    const Eigen::Vector3d nn = pick.Normal(e.p);
    j_pick["distance_residual_mm"] = (p1 - p0).norm() - (R + d);
    j_pick["angle_n_p0p1_deg"] = std::acos(std::clamp(nn.dot((p1 - p0).normalized()), -1.0, 1.0)) * 180.0 / std::acos(-1.0);
    j_pick["p0"] = V3(p0);
  }
  out.push_back(j_pick);

  // 2. grasp
  GraspParams gp;
  gp.group = "grip_layer";
  gp.object_diameter = 2 * R;
  gp.plane_normal = Eigen::Vector3d::UnitY();
  const GraspObjective grasp(names, gp);
  Eigen::VectorXd c3_start(1);
  c3_start[0] = grasp_start >= 0 ? grasp_start : 0.5 * (kin.lower()[2] + kin.upper()[2]);
  if (c3_start[0] < kin.lower()[2] || c3_start[0] > kin.upper()[2])
    cfg.Fail("grasp_start", "a value of c3 inside its range");
  auto [c_grasp, j_grasp] = run_stage("grasp", gripper, c_pick, grasp, c3_start);
  {
    const KinematicsEval e = write_shape("grasp", c_grasp);
    j_grasp["fitted_diameter_mm"] = grasp.FittedDiameter(e.p);
    j_grasp["object_diameter_mm"] = 2 * R;
  }
  out.push_back(j_grasp);

  // 3. place
  PlaceParams lp;
  lp.p0 = "P0";
  lp.target_center = p1t;
  lp.object_radius = R;
  lp.half_width = d;
  const PlaceObjective place(names, lp);
  auto [c_place, j_place] = run_stage("place", arm, c_grasp, place, c_grasp.head(2));
  {
    const KinematicsEval e = write_shape("place", c_place);
    const Eigen::Vector3d p0 = e.p.row(i0).transpose();
    j_place["distance_residual_mm"] = (p1t - p0).norm() - (R + d);
    j_place["p0"] = V3(p0);
  }
  out.push_back(j_place);

  nlohmann::json j = s.Json();
  j.erase("point");
  j["stage_lambda"] = stage_lambda;
  j["grasp_start"] = c3_start[0];
  j["object"] = {{"radius_mm", R}, {"half_width_mm", d}, {"omega1", omega1},
                 {"pick_design_actuation", design}, {"center", V3(p1)}, {"place_center", V3(p1t)},
                 {"design_p0", V3(dp0)}, {"design_normal", V3(n)}};
  j["normal_points"] = {pa, pb, pc};
  j["grip_points"] = inner_count;
  j["stages"] = out;
  j["total_time_s"] = total_time;
  return j;
}

}  // namespace softkin
