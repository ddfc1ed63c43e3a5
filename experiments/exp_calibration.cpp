// Table 2.1 / Fig. 2.6: R_omega calibrated in simulation from the elasticity ratio R_m of an
// elongation test (Eq. 2.9) on bimaterial_bar, for the thesis's two material pairs; its
// sensitivity to the mesh resolution; the twisting test at the calibrated parameters; and the
// calibration curve R_m(R_omega^A / R_omega^B) for the plot.
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/solver/materials/calibration.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <cmath>
#include <cstdio>

namespace softkin {

namespace {

/// The keys of a calibration config.
struct CalibrationParams {
  std::vector<double> rms;       ///< measured elasticity ratios R_m
  std::vector<double> thesis;    ///< the thesis's ratio for each (or empty)
  BarTestOptions opt;            ///< the headline resolution (its default resolved) and the tests
  std::vector<int> resolutions;  ///< of the sensitivity study
  std::vector<double> curve;     ///< R_omega^A / R_omega^B of the calibration curve
  double rel_tol = 1e-3;
  Scene bar;  ///< bimaterial_bar at the headline resolution
};

CalibrationParams ReadCalibrationParams(const Config& cfg) {
  CalibrationParams p;
  p.rms = cfg.NumberList("rms", {3.75, 5.68});
  p.thesis = cfg.NumberList("thesis_ratios", {7.08, 10.30});
  BarTestOptions& opt = p.opt;
  opt.res = cfg.Int("res", 0);
  opt.interface = cfg.Number("interface", 0.5);
  opt.stretch_mm = cfg.Number("stretch_mm", 8.0);
  opt.twist_deg = cfg.Number("twist_deg", 90.0);
  opt.twist_steps = cfg.Int("twist_steps", 3);
  p.resolutions = cfg.IntList("resolutions", {2, 3, 4, 6, 8});
  p.curve = cfg.NumberList("curve_ratios", {1, 1.5, 2, 3, 5, 7, 10, 15, 20, 30});
  p.rel_tol = cfg.Number("rel_tol", 1e-3);
  try {
    p.bar = MakeRobot("bimaterial_bar", opt.res);
  } catch (const std::invalid_argument& e) {
    cfg.Fail("res", std::string("0 or a bimaterial_bar resolution (") + e.what() + ")");
  }
  if (opt.res == 0)
    for (const auto& info : ListRobots())
      if (info.name == "bimaterial_bar") opt.res = info.default_resolution;
  opt.solver = cfg.Solver(p.bar.solver);
  cfg.CheckNoUnknownKeys();
  if (p.rms.empty()) cfg.Fail("rms", "a non-empty list of elasticity ratios > 0");
  if (!p.thesis.empty() && p.thesis.size() != p.rms.size())
    cfg.Fail("thesis_ratios", "one thesis ratio per entry of rms (or an empty list)");
  for (int r : p.resolutions)
    if (r < 2 || r > 24) cfg.Fail("resolutions", "bimaterial_bar resolutions in [2, 24]");
  for (double q : p.curve)
    if (!(q >= 1)) cfg.Fail("curve_ratios", "ratios R_omega^A / R_omega^B >= 1");
  try {
    opt.Validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(cfg.path() + ": " + e.what());
  }
  return p;
}

/// The calibration curve: R_m simulated for R_omega^A = 1, R_omega^B = 1 / ratio (curve.csv).
nlohmann::json CalibrationCurve(const CalibrationParams& p, const std::string& dir, bool verbose) {
  CsvWriter curve_csv(dir + "/curve.csv", {"res", "r_omega_ratio", "r_omega_b", "rm", "dl1_mm",
                                           "iterations", "time_s"});
  nlohmann::json curve_j = nlohmann::json::array();
  for (double q : p.curve) {
    const ElongationResult e = RunElongationTest(1.0, 1.0 / q, p.opt);
    curve_csv.Row(
        {double(p.opt.res), q, 1.0 / q, e.rm, e.dl1_mm, double(e.fk.iterations), e.fk.time_s});
    curve_j.push_back({{"r_omega_ratio", q}, {"rm", e.rm}});
    if (verbose) std::fprintf(stderr, "  curve: R_omega ratio %.2f -> R_m %.4f\n", q, e.rm);
  }
  return curve_j;
}

/// Sensitivity of the calibration of rm to the mesh resolution (rows of calibration.csv); the
/// headline resolution's result c is reused rather than run again.
nlohmann::json ResolutionSensitivity(const CalibrationParams& p, double rm, double th,
                                     const CalibrationResult& c, CsvWriter* cal_csv, bool verbose) {
  nlohmann::json sens = nlohmann::json::array();
  for (int r : p.resolutions) {
    BarTestOptions o = p.opt;
    o.res = r;
    const CalibrationResult cr = r == p.opt.res ? c : CalibrateROmega(rm, o, p.rel_tol);
    const int tets =
        r == p.opt.res ? p.bar.mesh.num_tets() : MakeRobot("bimaterial_bar", r).mesh.num_tets();
    cal_csv->Row({rm, double(r), double(tets), cr.ratio, cr.r_omega_a, cr.r_omega_b, cr.achieved_rm,
                  double(cr.evaluations), th});
    sens.push_back(
        {{"res", r}, {"tets", tets}, {"r_omega_ratio", cr.ratio}, {"achieved_rm", cr.achieved_rm}});
    if (verbose) std::fprintf(stderr, "    res %d (%d tets): ratio %.3f\n", r, tets, cr.ratio);
  }
  return sens;
}

/// rms[i] calibrated, its twisting test and its sensitivity to the resolution; returns its row.
nlohmann::json CalibrateRm(const Config& cfg, const CalibrationParams& p, size_t i,
                           CsvWriter* cal_csv, CsvWriter* twist_csv, bool verbose) {
  const BarTestOptions& opt = p.opt;
  const double rm = p.rms[i];
  const double th = p.thesis.empty() ? NAN : p.thesis[i];
  CalibrationResult c;
  try {
    c = CalibrateROmega(rm, opt, p.rel_tol);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(cfg.path() + ": rms[" + std::to_string(i) + "]: " + e.what());
  }
  cal_csv->Row({rm, double(opt.res), double(p.bar.mesh.num_tets()), c.ratio, c.r_omega_a,
                c.r_omega_b, c.achieved_rm, double(c.evaluations), th});
  if (verbose)
    std::fprintf(
        stderr,
        "  R_m %.2f: R_omega^A/R_omega^B = %.3f (thesis %.2f), R_m reached %.4f in %d tests\n", rm,
        c.ratio, th, c.achieved_rm, c.evaluations);
  // The twisting test with the calibrated parameters: B's twist over A's against R_m.
  const TwistResult t = RunTwistTest(c.r_omega_a, c.r_omega_b, opt);
  const double twist_ratio = t.angle_b_deg / t.angle_a_deg;
  // Twist per unit length, B over A: the shear-modulus ratio G_A / G_B of the calibrated pair.
  const double shear_ratio = (t.angle_b_deg / (t.l_mm - t.l1_mm)) / (t.angle_a_deg / t.l1_mm);
  twist_csv->Row({rm, c.ratio, t.twist_deg, t.angle_a_deg, t.angle_b_deg, t.a_mid_deg, t.b_mid_deg,
                  twist_ratio, shear_ratio});
  if (verbose)
    std::fprintf(
        stderr,
        "  twist %.0f deg: A turns %.2f deg, B %.2f deg (per unit length B/A %.3f, R_m %.2f)\n",
        t.twist_deg, t.angle_a_deg, t.angle_b_deg, shear_ratio, rm);
  const nlohmann::json sens = ResolutionSensitivity(p, rm, th, c, cal_csv, verbose);
  return {{"rm", rm},
          {"r_omega_ratio", c.ratio},
          {"r_omega_a", c.r_omega_a},
          {"r_omega_b", c.r_omega_b},
          {"achieved_rm", c.achieved_rm},
          {"evaluations", c.evaluations},
          {"thesis_ratio", std::isfinite(th) ? nlohmann::json(th) : nlohmann::json(nullptr)},
          {"twist",
           {{"twist_deg", t.twist_deg},
            {"angle_a_deg", t.angle_a_deg},
            {"angle_b_deg", t.angle_b_deg},
            {"ratio_b_over_a", twist_ratio},
            {"shear_ratio", shear_ratio}}},
          {"resolution_sensitivity", sens}};
}

}  // namespace

nlohmann::json RunCalibration(const Config& cfg, const std::string& dir, bool verbose) {
  const CalibrationParams p = ReadCalibrationParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  const nlohmann::json curve_j = CalibrationCurve(p, dir, verbose);
  CsvWriter cal_csv(dir + "/calibration.csv",
                    {"rm", "res", "tets", "r_omega_ratio", "r_omega_a", "r_omega_b", "achieved_rm",
                     "evaluations", "thesis_ratio"});
  CsvWriter twist_csv(dir + "/twist.csv",
                      {"rm", "r_omega_ratio", "twist_deg", "angle_a_deg", "angle_b_deg",
                       "a_mid_deg", "b_mid_deg", "twist_ratio_b_over_a", "shear_ratio"});
  nlohmann::json rows = nlohmann::json::array();
  for (size_t i = 0; i < p.rms.size(); ++i)
    rows.push_back(CalibrateRm(cfg, p, i, &cal_csv, &twist_csv, verbose));
  nlohmann::json j;
  j["rows"] = rows;
  j["curve"] = curve_j;
  j["res"] = p.opt.res;
  j["tets"] = p.bar.mesh.num_tets();
  j["interface"] = p.opt.interface;
  j["stretch_mm"] = p.opt.stretch_mm;
  j["twist_deg"] = p.opt.twist_deg;
  j["rel_tol"] = p.rel_tol;
  return j;
}

}  // namespace softkin
