#include "softkin/solver/materials/calibration.hpp"

#include "softkin/solver/common/text_format.hpp"

#include "softkin/solver/factory/fk_factory.hpp"

#include "softkin/solver/fk/energy.hpp"
#include "softkin/solver/mesh/mesh_gen.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace softkin {

namespace {

constexpr double kPi = 3.14159265358979323846;

void Require(bool ok, const std::string& field, const std::string& expected, double value) {
  if (ok) return;
  std::ostringstream s;
  s << "calibration: " << field << " = " << value << ", expected " << expected;
  throw std::invalid_argument(s.str());
}

Scene Bar(double r_omega_a, double r_omega_b, const BarTestOptions& opt) {
  return MakeRobot(
      "bimaterial_bar", opt.res,
      {{"interface", opt.interface}, {"r_omega_a", r_omega_a}, {"r_omega_b", r_omega_b}});
}

const Marker& FindMarker(const Scene& s, const std::string& name) {
  const int i = s.marker_index(name);
  if (i < 0) throw std::runtime_error("calibration: bimaterial_bar has no marker '" + name + "'");
  return s.markers[i];
}

double MeanX(const Marker& m, const Eigen::MatrixX3d& X) {
  double x = 0;
  for (int v : m.vertices) x += X(v, 0);
  return x / m.vertices.size();
}

/// Best-fit rotation (degrees) about +x of a cross-section's vertices from rest X0 to X: the angle
/// that minimises the squared distances of the centred (y, z) offsets.
double SectionRotation(const Marker& m, const Eigen::MatrixX3d& X0, const Eigen::MatrixX3d& X) {
  Eigen::Vector2d c0 = Eigen::Vector2d::Zero(), c = Eigen::Vector2d::Zero();
  for (int v : m.vertices) {
    c0 += X0.row(v).tail<2>().transpose();
    c += X.row(v).tail<2>().transpose();
  }
  c0 /= m.vertices.size();
  c /= m.vertices.size();
  double cross = 0, dot = 0;
  for (int v : m.vertices) {
    const Eigen::Vector2d a = X0.row(v).tail<2>().transpose() - c0;
    const Eigen::Vector2d b = X.row(v).tail<2>().transpose() - c;
    cross += a.x() * b.y() - a.y() * b.x();
    dot += a.dot(b);
  }
  return std::atan2(cross, dot) * 180.0 / kPi;
}

FkResult SolveBar(const Scene& s, double twist, double stretch, int steps, const FkOptions& base,
                  const char* test) {
  FkOptions o = base;
  o.continuation_steps = std::max(o.continuation_steps, steps);
  Eigen::VectorXd c(2);
  c << twist, stretch;  // bimaterial_bar's actuators: twist (deg), stretch (mm)
  FkResult r = SolveFk(s, c, &o);
  if (r.status != FkStatus::Converged)
    throw std::runtime_error(std::string("calibration: the ") + test +
                             " test did not converge: " + r.BriefReport());
  return r;
}

}  // namespace

void BarTestOptions::Validate() const {
  Require(res >= 0, "res", "0 (the default) or a resolution in bimaterial_bar's range", res);
  Require(interface > 0.05 - 1e-12 && interface < 0.95 + 1e-12, "interface",
          "a fraction of the length in [0.05, 0.95]", interface);
  Require(stretch_mm > 0 && stretch_mm <= 40, "stretch_mm", "a displacement in (0, 40] mm",
          stretch_mm);
  Require(twist_deg != 0 && std::abs(twist_deg) <= 180, "twist_deg",
          "an angle in [-180, 180], not 0", twist_deg);
  Require(twist_steps >= 1, "twist_steps", "an integer >= 1", twist_steps);
  std::string why;
  if (!solver.IsValid(&why)) throw std::invalid_argument("calibration: solver options: " + why);
}

double ElasticityRatio(double L, double L1, double dL, double dL1) {
  if (!(L1 > 0 && L1 < L) || !(dL1 > 0 && dL1 < dL)) {
    std::ostringstream s;
    s << "Eq. 2.9 needs 0 < L1 < L and 0 < dL1 < dL; got L = " << L << ", L1 = " << L1
      << ", dL = " << dL << ", dL1 = " << dL1;
    throw std::invalid_argument(s.str());
  }
  return L1 * (dL - dL1) / ((L - L1) * dL1);
}

ElongationResult RunElongationTest(double r_omega_a, double r_omega_b, const BarTestOptions& opt) {
  opt.Validate();
  const Scene s = Bar(r_omega_a, r_omega_b, opt);
  ElongationResult e;
  e.fk = SolveBar(s, 0.0, opt.stretch_mm, 1, opt.solver, "elongation");
  e.l_mm = MeanX(FindMarker(s, "tip"), s.mesh.vertices);  // the fixed end is x = 0
  e.l1_mm = MeanX(FindMarker(s, "interface"), s.mesh.vertices);
  e.dl_mm = opt.stretch_mm;
  e.dl1_mm = MeanX(FindMarker(s, "interface"), e.fk.positions) - e.l1_mm;
  if (!(e.dl1_mm > 0 && e.dl1_mm < e.dl_mm)) {
    std::ostringstream m;
    m << "calibration: the interface moved " << e.dl1_mm << " mm for an end displacement of "
      << e.dl_mm << " mm (expected a move between 0 and the end's)";
    throw std::runtime_error(m.str());
  }
  e.rm = ElasticityRatio(e.l_mm, e.l1_mm, e.dl_mm, e.dl1_mm);
  return e;
}

TwistResult RunTwistTest(double r_omega_a, double r_omega_b, const BarTestOptions& opt) {
  opt.Validate();
  const Scene s = Bar(r_omega_a, r_omega_b, opt);
  TwistResult t;
  t.twist_deg = opt.twist_deg;
  t.l_mm = MeanX(FindMarker(s, "tip"), s.mesh.vertices);
  t.l1_mm = MeanX(FindMarker(s, "interface"), s.mesh.vertices);
  t.fk = SolveBar(s, opt.twist_deg, 0.0, opt.twist_steps, opt.solver, "twisting");
  const Eigen::MatrixX3d& X0 = s.mesh.vertices;
  t.angle_a_deg = SectionRotation(FindMarker(s, "interface"), X0, t.fk.positions);
  t.angle_b_deg = opt.twist_deg - t.angle_a_deg;
  t.a_mid_deg = SectionRotation(FindMarker(s, "a_mid"), X0, t.fk.positions);
  t.b_mid_deg = SectionRotation(FindMarker(s, "b_mid"), X0, t.fk.positions);
  return t;
}

CalibrationResult CalibrateROmega(double target_rm, const BarTestOptions& opt, double rel_tol,
                                  double r_min) {
  Require(std::isfinite(target_rm) && target_rm > 0, "rm", "a finite elasticity ratio > 0",
          target_rm);
  Require(rel_tol > 0 && rel_tol < 0.5, "rel_tol", "a relative tolerance in (0, 0.5)", rel_tol);
  Require(r_min > 0 && r_min < 1, "r_min", "a lower bound of R_omega in (0, 1)", r_min);
  opt.Validate();
  // R_m > 1: A is stiffer, B's R_omega is searched; R_m < 1: the other way round, and the
  // simulated ratio is inverted so that the searched function always grows as R_omega falls.
  const bool soft_b = target_rm >= 1.0;
  const double goal = soft_b ? target_rm : 1.0 / target_rm;
  CalibrationResult out;
  out.target_rm = target_rm;
  auto eval = [&](double r) {
    const ElongationResult e =
        soft_b ? RunElongationTest(1.0, r, opt) : RunElongationTest(r, 1.0, opt);
    ++out.evaluations;
    out.history.emplace_back(r, e.rm);
    return soft_b ? e.rm : 1.0 / e.rm;
  };
  auto done = [&](double r, double rm) {
    out.r_omega_a = soft_b ? 1.0 : r;
    out.r_omega_b = soft_b ? r : 1.0;
    out.ratio = out.r_omega_a / out.r_omega_b;
    out.achieved_rm = soft_b ? rm : 1.0 / rm;
    return out;
  };
  double hi = 1.0, f_hi = eval(hi);  // equal materials: R_m close to 1
  const double f_equal = f_hi;
  if (std::abs(f_hi - goal) <= rel_tol * goal) return done(hi, f_hi);
  // Bracket: step down by factors of 4 until the simulated ratio passes the goal, so that very
  // soft (slowly converging) materials are only simulated when the target needs them.
  double lo = hi, f_lo = f_hi;
  // The range reached: from equal materials down to R_omega = r_end (simulated ratio f_end).
  auto reached = [&](double r_end, double f_end) {
    std::ostringstream m;
    m << "calibration: R_m = " << target_rm << " is outside the range this specimen reaches with "
      << "R_omega in [" << r_end << ", 1]: from " << (soft_b ? f_equal : 1.0 / f_equal)
      << " (equal R_omega) to " << (soft_b ? f_end : 1.0 / f_end);
    return m.str();
  };
  if (f_hi > goal) throw std::invalid_argument(reached(1.0, f_hi) + "; expected a ratio beyond it");
  while (f_lo < goal) {
    if (lo <= r_min)
      throw std::invalid_argument(reached(lo, f_lo) + " (the lower bound of R_omega)");
    hi = lo;
    f_hi = f_lo;
    lo = std::max(lo / 4.0, r_min);
    try {
      f_lo = eval(lo);
    } catch (const std::runtime_error& e) {
      // A softer material than the solver can stretch: say how far the search got.
      std::string why = e.what();
      const std::string prefix = "calibration: ";  // SolveBar's, already in reached()'s message
      if (why.rfind(prefix, 0) == 0) why.erase(0, prefix.size());
      throw std::invalid_argument(reached(hi, f_hi) + "; at R_omega = " + FormatNumber(lo) + " " +
                                  why);
    }
    if (std::abs(f_lo - goal) <= rel_tol * goal) return done(lo, f_lo);
  }
  // Bisection on log R_omega: f falls from f_lo > goal at lo to f_hi < goal at hi.
  for (int it = 0; it < 60; ++it) {
    const double mid = std::sqrt(lo * hi);
    const double f = eval(mid);
    if (std::abs(f - goal) <= rel_tol * goal || hi / lo < 1.0 + 1e-9) return done(mid, f);
    if (f > goal) {
      lo = mid;
      f_lo = f;
    } else {
      hi = mid;
      f_hi = f;
    }
  }
  const double mid = std::sqrt(lo * hi);
  return done(mid, eval(mid));
}

std::vector<UniaxialPoint> SimulateUniaxialTension(const Material& material,
                                                   const std::vector<double>& stretches, int res,
                                                   const FkOptions& solver) {
  constexpr double kL = 60.0, kW = 10.0;
  if (res < 1 || res > 12)
    throw std::invalid_argument("uniaxial test: res = " + std::to_string(res) + ", expected 1..12");
  for (size_t i = 0; i < stretches.size(); ++i)
    if (!(stretches[i] > 1.0 && stretches[i] <= 2.0) ||
        (i > 0 && !(stretches[i] > stretches[i - 1])))
      throw std::invalid_argument("uniaxial test: end stretches must increase within (1, 2]");
  const double h = kW / res;
  Scene s;
  s.name = "uniaxial_bar";
  s.mesh = VoxelTetMesh(Eigen::Vector3d::Zero(), h, Eigen::Vector3i(6 * res, res, res),
                        [](const Eigen::Vector3d&, const Eigen::Vector3i&) { return 0; });
  s.body[0] = material;
  const double eps = 1e-6 * h;
  s.fixed = VerticesOnPlane(s.mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), eps);
  Actuator pull;
  pull.name = "pull";
  pull.type = ActuatorType::Displacement;
  pull.vertices = VerticesOnPlane(s.mesh, Eigen::Vector3d(kL, 0, 0), Eigen::Vector3d::UnitX(), eps);
  pull.axis = Eigen::Vector3d::UnitX();
  pull.rest = 0.0;
  pull.min = 0.0;
  pull.max = kL;
  s.actuators = {pull};
  const std::vector<int> p1 =
      VerticesOnPlane(s.mesh, Eigen::Vector3d(2 * res * h, 0, 0), Eigen::Vector3d::UnitX(), eps);
  const std::vector<int> p2 =
      VerticesOnPlane(s.mesh, Eigen::Vector3d(4 * res * h, 0, 0), Eigen::Vector3d::UnitX(), eps);
  const std::vector<int> mid =
      VerticesOnPlane(s.mesh, Eigen::Vector3d(3 * res * h, 0, 0), Eigen::Vector3d::UnitX(), eps);
  s.validate();
  auto model = std::make_shared<const Model>(s);
  FkOptions o = solver;
  auto fk = MakeFkSolver(model, o);
  auto mean_x = [](const Eigen::MatrixX3d& X, const std::vector<int>& ids) {
    double m = 0;
    for (int v : ids) m += X(v, 0);
    return m / ids.size();
  };
  auto width = [&](const Eigen::MatrixX3d& X) {
    double lo = 1e300, hi = -1e300;
    for (int v : mid) {
      lo = std::min(lo, X(v, 1));
      hi = std::max(hi, X(v, 1));
    }
    return hi - lo;
  };
  const Eigen::MatrixX3d& X0 = s.mesh.vertices;
  const double gauge0 = mean_x(X0, p2) - mean_x(X0, p1), w0 = width(X0);
  std::vector<UniaxialPoint> out;
  Eigen::MatrixX3d X = X0;
  for (double lam : stretches) {
    Eigen::VectorXd c(1);
    c[0] = (lam - 1.0) * kL;
    FkResult r = fk->Solve(c, &X);
    if (r.status != FkStatus::Converged)
      throw std::runtime_error("uniaxial test: the solve at stretch " + std::to_string(lam) +
                               " did not converge: " + r.BriefReport());
    X = r.positions;
    Eigen::MatrixX3d G;
    FrozenTargetGradient(*model, X, c, &G);
    UniaxialPoint p;
    p.end_stretch = lam;
    p.mid_stretch = (mean_x(X, p2) - mean_x(X, p1)) / gauge0;
    p.lateral_stretch = width(X) / w0;
    for (int v : pull.vertices) p.force += G(v, 0);
    p.stress = p.force / (kW * kW);
    p.iterations = r.iterations;
    out.push_back(p);
  }
  return out;
}

}  // namespace softkin
