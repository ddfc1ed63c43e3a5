#include "softkin/experiments/fem_trajectory.hpp"

#include "softkin/experiments/measure.hpp"
#include "softkin/solver/baselines/ccx_run.hpp"

#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

namespace softkin {

PressureFemOptions ReadPressureFemOptions(const Config& cfg, double default_max_increment,
                                          double default_time_limit_s) {
  PressureFemOptions o;
  o.element = cfg.String("fem_element", "C3D10");
  o.young = cfg.Number("young_mpa", 1.0);
  o.poisson = cfg.Number("poisson", 0.45);
  o.max_increment = cfg.Number("max_increment", default_max_increment);
  o.time_limit_s = cfg.Number("fem_time_limit_s", default_time_limit_s);
  CheckFemElement(cfg, "fem_element", o.element);
  if (!(o.young > 0)) cfg.Fail("young_mpa", "a positive Young's modulus (MPa)");
  if (!(o.poisson >= 0 && o.poisson < 0.5)) cfg.Fail("poisson", "a value in [0, 0.5)");
  CheckMaxIncrement(cfg, "max_increment", o.max_increment);
  if (!(o.time_limit_s >= 0)) cfg.Fail("fem_time_limit_s", "seconds >= 0 (0: no limit)");
  return o;
}

void CheckFemLaw(const Config& cfg, const std::string& key, const std::string& law) {
  if (law != "linear" && law != "neo-hooke")
    cfg.Fail(key, "linear (FEM 1) or neo-hooke (FEM 2), not '" + law + "'");
}

void CheckFemElement(const Config& cfg, const std::string& key, const std::string& element) {
  if (element != "C3D10" && element != "C3D4") cfg.Fail(key, "C3D10 or C3D4");
}

void CheckMaxIncrement(const Config& cfg, const std::string& key, double max_increment) {
  if (!(max_increment > 0 && max_increment <= 1)) cfg.Fail(key, "a fraction of the ramp in (0, 1]");
}

void CheckPressureFemCanRun(const Config& cfg, const std::string& key, const Scene& scene,
                            const std::string& element) {
  if (FindCcx().empty()) cfg.Fail(key, "a machine with CalculiX: " + CcxMissingMessage());
  try {
    (void)BuildPressureFemMesh(Model(scene), element);
  } catch (const std::invalid_argument& e) {
    cfg.Fail(key, std::string("a robot the pressure FEM can mesh: ") + e.what());
  }
}

FemTrajectory RunFemTrajectory(const Scene& scene, const Model& model,
                               const Eigen::Ref<const Eigen::VectorXd>& pressure, int measured,
                               const PressureFemOptions& options) {
  FemTrajectory t;
  t.law = options.law;
  t.run = RunPressureFem(model, pressure, options);
  if (!t.run.ok) return t;
  const bool has_bend = scene.marker_index("tip_top") >= 0 && scene.marker_index("tip_bottom") >= 0;
  std::unique_ptr<BendAngle> bend;
  if (has_bend) bend = std::make_unique<BendAngle>(scene);
  const int tip = scene.marker_index("tip");
  auto measure = [&](const Eigen::MatrixX3d& X, FemTrajectoryPoint* q) {
    const Eigen::MatrixX3d P = scene.marker_positions(X);
    if (tip >= 0) q->tip = P.row(tip).transpose();
    q->bend_deg = has_bend ? (*bend)(X) : 0.0;
    // A marker in a chamber element interpolates nodes the hollow FEM mesh does not have.
    if (!q->tip.allFinite() || !std::isfinite(q->bend_deg))
      throw std::runtime_error("scene '" + scene.name +
                               "': a marker lies in a chamber, which the pressure FEM leaves "
                               "hollow, so it cannot be measured on the FEM");
  };
  FemTrajectoryPoint rest;
  measure(scene.mesh.vertices, &rest);
  t.points.push_back(rest);
  for (const PressureFemIncrement& inc : t.run.increments) {
    FemTrajectoryPoint q;
    q.load = inc.load;
    q.pressure = inc.pressure[measured];
    q.cavity_ratio = inc.cavity_ratio[measured];
    q.wall_s = inc.wall_s;
    measure(inc.positions, &q);
    t.max_bend_deg = std::max(t.max_bend_deg, q.bend_deg);
    t.points.push_back(q);
  }
  return t;
}

std::vector<std::string> FemTrajectoryColumns() {
  return {"law",      "increment", "load",  "pressure_mpa", "cavity_ratio",
          "bend_deg", "tip_x",     "tip_y", "tip_z",        "wall_s"};
}

void AppendFemRows(const FemTrajectory& t, CsvWriter* csv) {
  for (size_t k = 0; k < t.points.size(); ++k) {
    const FemTrajectoryPoint& q = t.points[k];
    nlohmann::json row = {{"law", t.law},
                          {"increment", static_cast<int>(k)},
                          {"load", q.load},
                          {"pressure_mpa", q.pressure},
                          {"cavity_ratio", q.cavity_ratio},
                          {"bend_deg", q.bend_deg},
                          {"tip_x", q.tip.x()},
                          {"tip_y", q.tip.y()},
                          {"tip_z", q.tip.z()},
                          {"wall_s", q.wall_s}};
    csv->RowJson(row);
  }
}

double FemTimeToBend(const FemTrajectory& t, double deg) {
  for (size_t k = 1; k < t.points.size(); ++k)
    if (t.points[k].bend_deg >= deg) return t.points[k].wall_s;
  return -1.0;
}

nlohmann::json FemTrajectorySummary(const FemTrajectory& t, const std::vector<double>& milestones) {
  nlohmann::json j;
  j["law"] = t.law;
  j["status"] = !t.run.ok ? "not_run" : t.run.reached_end ? "reached_end" : "stopped";
  j["message"] = t.run.message;
  j["nodes"] = t.run.nodes;
  j["elements"] = t.run.elements;
  j["time_s"] = t.run.time_s;
  j["increments"] = static_cast<int>(t.run.increments.size());
  const FemTrajectoryPoint& last = t.points.empty() ? FemTrajectoryPoint{} : t.points.back();
  j["end_load"] = last.load;
  j["end_pressure_mpa"] = last.pressure;
  j["end_cavity_ratio"] = last.cavity_ratio;
  j["max_bend_deg"] = t.max_bend_deg;
  for (double m : milestones) {
    char key[32];
    std::snprintf(key, sizeof(key), "t%.0f_s", m);
    const double s = FemTimeToBend(t, m);
    j[key] = s >= 0 ? nlohmann::json(s) : nlohmann::json(nullptr);
  }
  return j;
}

}  // namespace softkin
