#include "softkin/experiments/ik_config.hpp"

#include "softkin/experiments/runner.hpp"
#include "softkin/ik/trajectory_io.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <stdexcept>

namespace softkin {

namespace {

[[noreturn]] void Bad(const std::string& where, const std::string& what) {
  throw std::invalid_argument(where + ": " + what);
}

Eigen::Vector3d Vec3(const nlohmann::json& v, const std::string& where) {
  if (!v.is_array() || v.size() != 3) Bad(where, "expected [x, y, z] in mm");
  Eigen::Vector3d p;
  for (int d = 0; d < 3; ++d) {
    if (!v[d].is_number()) Bad(where, "expected [x, y, z] in mm");
    p[d] = v[d].get<double>();
    if (!std::isfinite(p[d])) Bad(where, "expected finite coordinates");
  }
  return p;
}

double Num(const nlohmann::json& spec, const std::string& key, const std::string& where, double def,
           bool required = false) {
  if (!spec.contains(key)) {
    if (required) Bad(where + "." + key, "missing (expected a number)");
    return def;
  }
  if (!spec[key].is_number()) Bad(where + "." + key, "expected a number");
  return spec[key].get<double>();
}

int Int(const nlohmann::json& spec, const std::string& key, const std::string& where, int lo) {
  if (!spec.contains(key) || !spec[key].is_number_integer() || spec[key].get<int>() < lo)
    Bad(where + "." + key, "expected an integer >= " + std::to_string(lo));
  return spec[key].get<int>();
}

void OnlyKeys(const nlohmann::json& spec, const std::set<std::string>& keys,
              const std::string& where) {
  for (auto it = spec.begin(); it != spec.end(); ++it)
    if (!keys.count(it.key())) {
      std::string list;
      for (const auto& k : keys) list += (list.empty() ? "" : ", ") + k;
      Bad(where + "." + it.key(), "unknown key (expected one of " + list + ")");
    }
}

/// The thesis flame (Fig. 4.2): a teardrop, round at the bottom and pointed at the top, with a
/// flicker on its sides. Parameter t in [0, 2 pi): u = w sin t cos^2(t/2) (1 + 0.3 sin 3t),
/// v = -h cos t / 2 (t = 0 is the bottom), turned by tilt_deg from the u axis towards the v axis.
/// Returned densely as a closed polyline.
std::vector<Eigen::Vector3d> FlameCurve(const Eigen::Vector3d& c, int au, int av, double w,
                                        double h, double tilt_deg) {
  const double pi = std::acos(-1.0);
  std::vector<Eigen::Vector3d> curve;
  const int m = 2000;
  for (int i = 0; i < m; ++i) {
    const double t = 2 * pi * i / m;
    const double ct = std::cos(0.5 * t);
    const double u = w * std::sin(t) * ct * ct * (1.0 + 0.3 * std::sin(3 * t));
    const double v = -0.5 * h * std::cos(t);
    const double a = tilt_deg * pi / 180.0;
    Eigen::Vector3d p = c;
    p[au] += std::cos(a) * u - std::sin(a) * v;
    p[av] += std::sin(a) * u + std::cos(a) * v;
    curve.push_back(p);
  }
  return curve;
}

/// Maps waypoints given in another robot's frame into this robot's workspace. Sideways (the plane
/// of the two axes other than `axis`) it is a similarity about the rest points:
///   h' = t0_h + s_h R (p_h - p0_h),
/// p0 = the file's first waypoint (the other robot's rest tip), t0 = this robot's point at rest,
/// s_h and the rotation R about `axis` chosen so that the file's waypoint farthest from p0 lands
/// on this robot's point at `anchor_actuation`. Along `axis`, the file's heights follow the other
/// robot's bending, which differs from ours (three_chamber's tip first rises, then drops, as one
/// chamber inflates), so a linear scale would put the inner waypoints out of reach. The height is
/// therefore this robot's own: the height of its point along the actuation ray
/// c(s) = rest + s (anchor - rest), s in [0, 1] (`profile_steps` forward solves), at the same
/// sideways distance from t0 (linear interpolation), plus `lift` mm.
Eigen::MatrixX3d MapToWorkspace(const Eigen::MatrixX3d& W, const nlohmann::json& m,
                                const std::string& where, Kinematics& kin,
                                const ConfigurationSamples& samples, nlohmann::json* info) {
  OnlyKeys(m, {"axis", "anchor_actuation", "profile_steps", "lift"}, where);
  if (!m.contains("axis") || !m["axis"].is_number_integer() || m["axis"].get<int>() < 0 ||
      m["axis"].get<int>() > 2)
    Bad(where + ".axis", "expected 0, 1 or 2 (the robot's long axis)");
  const int ax = m["axis"].get<int>(), au = (ax + 1) % 3, av = (ax + 2) % 3;
  if (!m.contains("anchor_actuation") || !m["anchor_actuation"].is_array() ||
      static_cast<int>(m["anchor_actuation"].size()) != kin.num_actuators())
    Bad(where + ".anchor_actuation",
        "expected " + std::to_string(kin.num_actuators()) + " actuation values");
  Eigen::VectorXd ca(kin.num_actuators());
  for (int a = 0; a < ca.size(); ++a) {
    if (!m["anchor_actuation"][a].is_number()) Bad(where + ".anchor_actuation", "expected numbers");
    ca[a] = m["anchor_actuation"][a].get<double>();
  }
  const std::string why = CheckKinematicsInput(kin, ca);
  if (!why.empty()) Bad(where + ".anchor_actuation", why);
  int steps = 8;
  if (m.contains("profile_steps")) {
    if (!m["profile_steps"].is_number_integer() || m["profile_steps"].get<int>() < 2)
      Bad(where + ".profile_steps", "expected an integer >= 2");
    steps = m["profile_steps"].get<int>();
  }
  const double lift = Num(m, "lift", where, 0.0);
  auto hdist = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::hypot(a[au] - b[au], a[av] - b[av]);
  };
  // The profile along the anchor's actuation ray: sideways distance -> height.
  const Eigen::VectorXd c_rest = kin.rest();
  std::vector<double> prof_r, prof_h;
  Eigen::Vector3d t0 = Eigen::Vector3d::Zero(), ta = Eigen::Vector3d::Zero();
  for (int k = 0; k <= steps; ++k) {
    const Eigen::VectorXd c = c_rest + (ca - c_rest) * (double(k) / steps);
    const KinematicsEval e = kin.Evaluate(c, false);
    if (!e.ok)
      throw std::runtime_error(where +
                               ": the forward solve along the anchor ray failed: " + e.message);
    const Eigen::Vector3d p = e.p.row(0).transpose();
    if (k == 0) t0 = p;
    if (k == steps) ta = p;
    prof_r.push_back(hdist(p, t0));
    prof_h.push_back(p[ax]);
  }
  for (size_t k = 1; k < prof_r.size(); ++k)
    if (!(prof_r[k] > prof_r[k - 1]))
      Bad(where + ".anchor_actuation",
          "the point does not move steadily sideways along the ray (step " + std::to_string(k) +
              ")");
  auto height = [&](double r) {
    size_t k = 1;
    while (k + 1 < prof_r.size() && prof_r[k] < r) ++k;
    const double f = std::clamp((r - prof_r[k - 1]) / (prof_r[k] - prof_r[k - 1]), 0.0, 1.0);
    return (1 - f) * prof_h[k - 1] + f * prof_h[k];
  };
  const Eigen::Vector3d p0 = W.row(0).transpose();
  int far = 0;
  double far_r = 0;
  for (int i = 0; i < W.rows(); ++i) {
    const double r = hdist(W.row(i).transpose(), p0);
    if (r > far_r) {
      far_r = r;
      far = i;
    }
  }
  if (far_r <= 0)
    Bad(where, "every waypoint has the first one's sideways position; nothing to scale");
  const Eigen::Vector3d pf = W.row(far).transpose();
  const double anchor_r = prof_r.back();
  if (anchor_r <= 1e-9) Bad(where + ".anchor_actuation", "does not move the point sideways");
  const double s_h = anchor_r / far_r;
  const double ang =
      std::atan2(ta[av] - t0[av], ta[au] - t0[au]) - std::atan2(pf[av] - p0[av], pf[au] - p0[au]);
  const double co = std::cos(ang), si = std::sin(ang);
  Eigen::MatrixX3d out(W.rows(), 3);
  for (int i = 0; i < W.rows(); ++i) {
    const Eigen::Vector3d d = W.row(i).transpose() - p0;
    Eigen::Vector3d q = t0;
    q[au] += s_h * (co * d[au] - si * d[av]);
    q[av] += s_h * (si * d[au] + co * d[av]);
    q[ax] = height(hdist(q, t0)) + lift;
    out.row(i) = q.transpose();
  }
  double sampled_reach = 0;
  for (int i = 0; i < samples.p.rows(); ++i)
    sampled_reach = std::max(sampled_reach, hdist(samples.p.row(i).transpose(), t0));
  (*info)["mapping"] = {
      {"sideways", "h' = t0_h + s_h R (p_h - p0_h)"},
      {"height",
       "our point's height along the anchor's actuation ray at the same sideways distance, + lift"},
      {"p0_file_first_waypoint", {p0[0], p0[1], p0[2]}},
      {"t0_rest_point", {t0[0], t0[1], t0[2]}},
      {"anchor_waypoint", far},
      {"anchor_point", {ta[0], ta[1], ta[2]}},
      {"scale_sideways", s_h},
      {"rotation_deg", ang * 180.0 / std::acos(-1.0)},
      {"lift_mm", lift},
      {"profile_sideways_mm", prof_r},
      {"profile_height_mm", prof_h},
      {"file_max_sideways_mm", far_r},
      {"file_height_range_mm", W.col(ax).maxCoeff() - W.col(ax).minCoeff()},
      {"anchor_sideways_mm", anchor_r},
      {"sampled_max_sideways_mm", sampled_reach}};
  return out;
}

}  // namespace

nlohmann::json IkExperimentSetup::Json() const {
  return {{"robot", robot},
          {"res", res},
          {"n_vertices", scene.mesh.num_vertices()},
          {"n_tets", scene.mesh.num_tets()},
          {"point", point},
          {"method", IkMethodToString(ik.method)},
          {"jacobian", JacobianModeToString(kin.jacobian)},
          {"lambda_mm", lambda_mm},
          {"max_iterations", ik.max_iterations},
          {"max_evaluations", ik.max_evaluations},
          {"samples_per_axis", samples_per_axis},
          {"first_waypoint_starts", first_waypoint_starts},
          {"fk_solver", ToString(fk.solver)}};
}

SimulatorKinematicsOptions IkExperimentSetup::KinematicsFor(
    const std::vector<std::string>& points) const {
  SimulatorKinematicsOptions o = kin;
  o.points = points;
  return o;
}

IkExperimentSetup ReadIkSetup(const Config& cfg, const std::string& default_robot) {
  IkExperimentSetup s;
  s.robot = cfg.String("robot", default_robot);
  s.res = cfg.Int("res", 0);
  s.scene = ConfigRobot(cfg, s.robot, s.res);
  s.fk = cfg.Solver(s.scene.solver);
  s.point = cfg.String("point", "tip");
  const std::string jac = cfg.String("jacobian", "implicit");
  if (!JacobianModeFromString(jac, &s.kin.jacobian))
    cfg.Fail("jacobian", "one of " + JacobianModeNames());
  s.kin.fd_step = cfg.Number("fd_step", s.kin.fd_step);
  s.kin.trace = cfg.Bool("trace_fk", false);  // one stderr line per forward solve
  std::string why;
  if (!s.kin.IsValid(&why)) cfg.Fail("fd_step", "a valid step (" + why + ")");
  const std::string method = cfg.String("method", "softls");
  if (!StringToIkMethod(method, &s.ik.method)) cfg.Fail("method", "one of " + IkMethodNames());
  s.lambda_mm = cfg.Number("lambda_mm", 0.2);
  if (!(s.lambda_mm >= 0) || !std::isfinite(s.lambda_mm))
    cfg.Fail("lambda_mm", "a distance >= 0 mm");
  s.ik.lambda = s.lambda_mm * s.lambda_mm;
  s.ik.max_iterations = cfg.Int("max_iterations", 30);
  s.ik.max_evaluations = cfg.Int("max_evaluations", 300);
  s.ik.max_time_s = cfg.Number("max_time_s", 600.0);
  if (!s.ik.IsValid(&why)) throw std::invalid_argument(cfg.path() + ": " + why);
  s.samples_per_axis = cfg.Int("samples_per_axis", 5);
  if (s.samples_per_axis < 2 || s.samples_per_axis > 20)
    cfg.Fail("samples_per_axis", "an integer in [2, 20]");
  s.first_waypoint_starts = cfg.Int("first_waypoint_starts", 3);
  if (s.first_waypoint_starts < 1 || s.first_waypoint_starts > 1000)
    cfg.Fail("first_waypoint_starts", "an integer in [1, 1000]");
  if (s.scene.marker_index(s.point.substr(0, s.point.find('['))) < 0)
    cfg.Fail("point", "a marker of robot '" + s.robot + "'");
  return s;
}

Eigen::MatrixX3d ResamplePolyline(const std::vector<Eigen::Vector3d>& v, int n, bool closed) {
  if (v.size() < 2) throw std::invalid_argument("a polyline needs at least 2 vertices");
  if (n < 2) throw std::invalid_argument("a path needs at least 2 waypoints");
  std::vector<Eigen::Vector3d> pts = v;
  if (closed) pts.push_back(v.front());
  std::vector<double> s(pts.size(), 0.0);
  for (size_t i = 1; i < pts.size(); ++i) s[i] = s[i - 1] + (pts[i] - pts[i - 1]).norm();
  const double total = s.back();
  if (!(total > 0)) throw std::invalid_argument("the polyline has zero length");
  Eigen::MatrixX3d out(n, 3);
  size_t seg = 1;
  for (int k = 0; k < n; ++k) {
    const double target = closed ? total * k / n : total * k / (n - 1);
    while (seg + 1 < s.size() && s[seg] < target) ++seg;
    const double len = s[seg] - s[seg - 1];
    const double f = len > 0 ? std::clamp((target - s[seg - 1]) / len, 0.0, 1.0) : 0.0;
    out.row(k) = ((1 - f) * pts[seg - 1] + f * pts[seg]).transpose();
  }
  return out;
}

IkPath MakeIkPath(const nlohmann::json& spec, const std::string& where, Kinematics& kin,
                  const ConfigurationSamples& samples) {
  if (!spec.is_object()) Bad(where, "expected a path object {\"name\", \"type\", ...}");
  IkPath path;
  if (!spec.contains("name") || !spec["name"].is_string() ||
      spec["name"].get<std::string>().empty())
    Bad(where + ".name", "expected a non-empty string");
  path.name = spec["name"].get<std::string>();
  for (char ch : path.name)
    if (!(isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-'))
      Bad(where + ".name", "letters, digits, '_' or '-' only (it names a CSV file)");
  const std::string type = spec.value("type", "");
  path.info = spec;
  if (spec.contains("thesis")) {
    if (!spec["thesis"].is_object()) Bad(where + ".thesis", "expected an object of numbers");
    for (auto it = spec["thesis"].begin(); it != spec["thesis"].end(); ++it)
      if (!it.value().is_number()) Bad(where + ".thesis." + it.key(), "expected a number");
    path.thesis = spec["thesis"];
  }
  const std::set<std::string> common = {"name", "type", "thesis", "description"};
  auto with = [&](std::set<std::string> extra) {
    extra.insert(common.begin(), common.end());
    return extra;
  };
  if (type == "polyline") {
    OnlyKeys(spec, with({"vertices", "n", "closed"}), where);
    if (!spec.contains("vertices") || !spec["vertices"].is_array() || spec["vertices"].size() < 2)
      Bad(where + ".vertices", "expected at least 2 vertices [x, y, z]");
    std::vector<Eigen::Vector3d> v;
    for (size_t i = 0; i < spec["vertices"].size(); ++i)
      v.push_back(Vec3(spec["vertices"][i], where + ".vertices[" + std::to_string(i) + "]"));
    const bool closed = spec.value("closed", false);
    path.waypoints = ResamplePolyline(v, Int(spec, "n", where, 2), closed);
  } else if (type == "flame") {
    OnlyKeys(spec, with({"center", "axes", "width", "height", "tilt_deg", "n"}), where);
    const Eigen::Vector3d c = Vec3(spec.value("center", nlohmann::json()), where + ".center");
    int au = 0, av = 2;
    if (spec.contains("axes")) {
      const auto& a = spec["axes"];
      if (!a.is_array() || a.size() != 2 || !a[0].is_number_integer() ||
          !a[1].is_number_integer() || a[0].get<int>() < 0 || a[0].get<int>() > 2 ||
          a[1].get<int>() < 0 || a[1].get<int>() > 2 || a[0] == a[1])
        Bad(where + ".axes", "expected two different axes out of 0, 1, 2 (e.g. [0, 2]: x, z)");
      au = a[0].get<int>();
      av = a[1].get<int>();
    }
    const double w = Num(spec, "width", where, 0, true), h = Num(spec, "height", where, 0, true);
    if (!(w > 0) || !(h > 0)) Bad(where, "width and height must be > 0 mm");
    path.waypoints =
        ResamplePolyline(FlameCurve(c, au, av, w, h, Num(spec, "tilt_deg", where, 0.0)),
                         Int(spec, "n", where, 2), true);
  } else if (type == "file") {
    OnlyKeys(spec, with({"file", "map", "stride"}), where);
    if (!spec.contains("file") || !spec["file"].is_string())
      Bad(where + ".file", "expected a file name");
    std::filesystem::path f = spec["file"].get<std::string>();
    const bool relative = f.is_relative();
    if (relative) f = std::filesystem::path(SOFTKIN_SOURCE_DIR) / f;
    Eigen::MatrixX3d w;
    try {
      w = ReadWaypoints(f.lexically_normal().string());
    } catch (const std::invalid_argument& e) {
      Bad(where + ".file",
          std::string(e.what()) + (relative ? " (a relative file is read from the source tree, " +
                                                  std::string(SOFTKIN_SOURCE_DIR) + ")"
                                            : ""));
    }
    path.info["file_resolved"] = f.lexically_normal().string();
    path.info["file_waypoints"] = w.rows();
    if (spec.contains("stride")) {
      const int k = Int(spec, "stride", where, 1);
      Eigen::MatrixX3d sub((w.rows() + k - 1) / k, 3);
      for (int i = 0; i < sub.rows(); ++i) sub.row(i) = w.row(i * k);
      w = sub;
    }
    if (spec.contains("map")) {
      if (!spec["map"].is_object())
        Bad(where + ".map", "expected an object {axis, anchor_actuation}");
      w = MapToWorkspace(w, spec["map"], where + ".map", kin, samples, &path.info);
    }
    path.waypoints = w;
  } else {
    Bad(where + ".type", "expected one of polyline, flame, file");
  }
  return path;
}

}  // namespace softkin
