#include "softkin/learn/twin.hpp"

#include <cmath>
#include <cstring>
#include <stdexcept>

namespace softkin {

namespace {

std::uint64_t Mix(std::uint64_t x) {  // SplitMix64
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

/// Uniform in (0, 1].
double Unit(std::uint64_t h) {
  return (static_cast<double>(h >> 11) + 1.0) * (1.0 / 9007199254740992.0);
}

/// The built-in twins (docs/twins.md gives the measured tip differences).
std::vector<TwinSpec> BuiltIn() {
  std::vector<TwinSpec> t;
  {
    // Robot 1: a softer body material (R_omega 0.85: more volume-preserving than the nominal
    // as-rigid-as-possible body) and slightly larger chambers (thinner outer wall).
    TwinSpec s;
    s.name = "three_chamber/robot1";
    s.robot = "three_chamber";
    s.params = {{"chamber_radius", 7.5}};
    s.set_body_r_omega = true;
    s.body_r_omega = 0.85;
    s.actuator_weight_scale = 1.0;
    s.marker_offset = Eigen::Vector3d(0.6, 1.0, -0.4);
    s.noise_seed = 101;
    s.doc =
        "body R_omega 0.85 (nominal 1), chamber radius 7.5 mm (nominal 7: outer wall 3.5 "
        "instead of 4 mm), marker offset (0.6, 1.0, -0.4) mm, noise 0.05 mm";
    t.push_back(s);
  }
  {
    // Robot 2: a stiffer chamber response (actuation elements weigh 20 % less against the body:
    // the chambers reach less of their volume) and smaller chambers (thicker outer wall).
    TwinSpec s;
    s.name = "three_chamber/robot2";
    s.robot = "three_chamber";
    s.params = {{"chamber_radius", 6.5}};
    s.actuator_weight_scale = 0.8;
    s.marker_offset = Eigen::Vector3d(-0.5, 0.8, 0.7);
    s.noise_seed = 202;
    s.doc =
        "actuator element weight x0.8 (chambers reach less of their volume), chamber radius "
        "6.5 mm (outer wall 4.5 mm), marker offset (-0.5, 0.8, 0.7) mm, noise 0.05 mm";
    t.push_back(s);
  }
  {
    // Finger manipulator: chambers grow less per unit of actuation (gain 3.6 instead of 4: a
    // pressure-to-volume calibration error), a softer body and a lighter chamber weight. Its
    // walls snap to whole voxel cells, so a sub-cell geometry change has no effect; the
    // geometry is left nominal.
    TwinSpec s;
    s.name = "finger_manipulator/robot1";
    s.robot = "finger_manipulator";
    s.params = {{"gain", 3.6}, {"body_r_omega", 0.9}, {"chamber_weight", 17.0}};
    s.marker_offset = Eigen::Vector3d(0.7, -0.5, 0.3);
    s.noise_seed = 303;
    s.doc =
        "gain 3.6 (nominal 4), body R_omega 0.9 (nominal 1), chamber weight 17 (nominal 20), "
        "marker offset (0.7, -0.5, 0.3) mm, noise 0.05 mm";
    t.push_back(s);
  }
  return t;
}

}  // namespace

std::vector<std::string> TwinNames() {
  std::vector<std::string> n;
  for (const auto& s : BuiltIn()) n.push_back(s.name);
  return n;
}

TwinSpec GetTwinSpec(const std::string& name) {
  std::string known;
  for (const auto& s : BuiltIn()) {
    if (s.name == name) return s;
    known += (known.empty() ? "" : ", ") + s.name;
  }
  throw std::invalid_argument("unknown twin '" + name + "'; known twins: " + known);
}

Scene MakeTwinScene(const TwinSpec& spec, int res) {
  if (!(spec.actuator_weight_scale > 0.0) || !std::isfinite(spec.actuator_weight_scale))
    throw std::invalid_argument("twin " + spec.name + ": actuator_weight_scale must be > 0");
  if (spec.set_body_r_omega && !(spec.body_r_omega >= 0.0 && spec.body_r_omega <= 1.0))
    throw std::invalid_argument("twin " + spec.name + ": body_r_omega must lie in [0, 1]");
  Scene s = MakeRobot(spec.robot, res, spec.params);
  if (spec.set_body_r_omega)
    for (auto& [region, mat] : s.body)
      if (!mat.hyperelastic()) mat.r_omega = spec.body_r_omega;
  for (auto& a : s.actuators) a.weight *= spec.actuator_weight_scale;
  s.name = "twin:" + spec.name;
  s.validate();
  return s;
}

TwinKinematics::TwinKinematics(const TwinSpec& spec, const TwinOptions& options)
    : spec_(spec), options_(options) {
  if (!(spec.noise_sigma_mm >= 0.0) || !std::isfinite(spec.noise_sigma_mm))
    throw std::invalid_argument("twin " + spec.name + ": noise_sigma_mm must be >= 0");
  if (!spec.marker_offset.allFinite())
    throw std::invalid_argument("twin " + spec.name + ": marker_offset must be finite");
  SimulatorKinematicsOptions ko;
  ko.points = options.points;
  ko.jacobian = JacobianMode::kFdWarm;  // never used: a twin gives no Jacobian
  const Scene scene = MakeTwinScene(spec, options.res);
  FkOptions fk = scene.solver;
  if (options.gradient_tolerance > 0) fk.gradient_tolerance = options.gradient_tolerance;
  std::string why;
  if (!fk.IsValid(&why))
    throw std::invalid_argument("twin " + spec.name + ": gradient_tolerance: " + why);
  sim_ = std::make_unique<SimulatorKinematics>(scene, ko, &fk);
}

double TwinKinematics::Noise(const Eigen::Ref<const Eigen::VectorXd>& c, int q, int d) const {
  if (!options_.noise || spec_.noise_sigma_mm == 0.0) return 0.0;
  std::uint64_t h = Mix(spec_.noise_seed);
  for (Eigen::Index a = 0; a < c.size(); ++a) {
    std::uint64_t bits;
    const double v = c[a] == 0.0 ? 0.0 : c[a];  // -0 and +0 are the same actuation
    std::memcpy(&bits, &v, sizeof bits);
    h = Mix(h ^ bits);
  }
  h = Mix(h ^ (static_cast<std::uint64_t>(q) * 3 + static_cast<std::uint64_t>(d)));
  // Box-Muller.
  const double u1 = Unit(Mix(h)), u2 = Unit(Mix(h ^ 0xA5A5A5A5A5A5A5A5ULL));
  const double z = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::acos(-1.0) * u2);
  return spec_.noise_sigma_mm * z;
}

KinematicsEval TwinKinematics::Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c,
                                        bool with_jacobian) {
  if (with_jacobian) {
    KinematicsEval ev;
    ev.message = name() +
                 " gives positions only, like the hardware it stands for: no Jacobian "
                 "(use a simulator or a learned network for J)";
    return ev;
  }
  KinematicsEval ev = sim_->Evaluate(c, false);
  if (!ev.ok) return ev;
  for (int q = 0; q < ev.p.rows(); ++q) {
    if (options_.offset) ev.p.row(q) += spec_.marker_offset.transpose();
    for (int d = 0; d < 3; ++d) ev.p(q, d) += Noise(c, q, d);
  }
  return ev;
}

}  // namespace softkin
