// Hyperelastic body elements (thesis Sec. 3.3.1, Eq. 3.6-3.7; our derivation in
// solver/materials/hyperelastic.hpp): the fitted R_omega(strain) of each Mooney-Rivlin material,
// and its uniaxial response three ways against the analytic Mooney-Rivlin curve: the homogeneous
// state of the law, a simulated tension test of a bar with the law, and the same bar with the
// constant R_omega of Ch. 2. Stresses are normalised by each response's small-strain modulus.
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/solver/materials/calibration.hpp"
#include "softkin/solver/materials/hyperelastic.hpp"

#include <cmath>
#include <cstdio>

namespace softkin {

namespace {

/// The keys of a hyperelastic_fit config.
struct HyperelasticParams {
  std::vector<std::string> names;  ///< named Mooney-Rivlin materials
  double rho0 = 1.0;               ///< zero-strain R_omega
  double lambda_max = 4.0;         ///< largest fitted stretch
  int knots = 61;
  std::vector<double> stretches;  ///< end stretches of the tension tests
  int res = 3;
  FkOptions solver;
};

HyperelasticParams ReadHyperelasticParams(const Config& cfg) {
  HyperelasticParams p;
  p.names = cfg.StringList("materials", {"ecoflex-00-30", "dragon-skin-20"});
  p.rho0 = cfg.Number("r_omega0", 1.0);
  p.lambda_max = cfg.Number("lambda_max", 4.0);
  p.knots = cfg.Int("knots", 61);
  p.stretches =
      cfg.NumberList("stretches", {1.01, 1.1, 1.2, 1.3, 1.4, 1.5, 1.6, 1.7, 1.8, 1.9, 2.0});
  p.res = cfg.Int("res", 3);
  p.solver = cfg.Solver(FkOptions());
  cfg.CheckNoUnknownKeys();
  if (p.names.empty()) cfg.Fail("materials", "a non-empty list of named Mooney-Rivlin materials");
  if (!(p.rho0 > 0 && p.rho0 <= 1)) cfg.Fail("r_omega0", "a zero-strain R_omega in (0, 1]");
  if (!(p.lambda_max > 1)) cfg.Fail("lambda_max", "a largest fitted stretch > 1");
  if (p.knots < 2) cfg.Fail("knots", "an integer >= 2");
  if (p.stretches.size() < 2 || p.stretches[0] > 1.05)
    cfg.Fail("stretches",
             "increasing end stretches in (1, 2], the first <= 1.05 (it sets the modulus)");
  if (p.res < 1 || p.res > 12) cfg.Fail("res", "cells across the 10 mm bar, integer in [1, 12]");
  return p;
}

/// One material: its fitted curve (curve.csv), its uniaxial responses (response.csv) and its
/// summary entry.
nlohmann::json FitMaterial(const Config& cfg, const HyperelasticParams& p, const std::string& name,
                           CsvWriter* curve_csv, CsvWriter* resp_csv, bool verbose) {
  MooneyRivlin mr;
  if (!NamedMooneyRivlin(name, &mr)) {
    std::string known;
    for (const auto& n : NamedMooneyRivlinNames()) known += (known.empty() ? "" : ", ") + n;
    cfg.Fail("materials", "named materials (" + known + "), got '" + name + "'");
  }
  const double rho0 = p.rho0;
  const ROmegaCurve curve = FitMooneyRivlinROmega(mr, rho0, p.lambda_max, p.knots);
  for (size_t i = 0; i < curve.eps().size(); ++i)
    curve_csv->RowStrings({name, std::to_string(curve.eps()[i]), std::to_string(curve.rho()[i])});
  const Material hyper{name, rho0, 1.0, MaterialLaw::kMooneyRivlin, mr.c1, mr.c2};
  const Material constant{name + " (constant R_omega)", rho0, 1.0, MaterialLaw::kBlend, 0, 0};
  const auto h = SimulateUniaxialTension(hyper, p.stretches, p.res, p.solver);
  const auto b = SimulateUniaxialTension(constant, p.stretches, p.res, p.solver);
  const double Eh = h[0].stress / (h[0].mid_stretch - 1), Eb = b[0].stress / (b[0].mid_stretch - 1);
  const double Elaw = 6 * rho0 / (2 + rho0);
  double worst_h = 0, worst_b = 0, worst_law = 0;
  for (size_t i = 0; i < h.size(); ++i) {
    const double lam = h[i].mid_stretch;
    const double mrn = mr.NominalStress(lam) / mr.Modulus();
    const double law = CurveUniaxialStress(curve, lam) / Elaw;
    const double sh = h[i].stress / Eh;
    const double sb = b[i].stress / Eb;
    const double mrb = mr.NominalStress(b[i].mid_stretch) / mr.Modulus();
    resp_csv->RowStrings({name, std::to_string(h[i].end_stretch), std::to_string(lam),
                          std::to_string(mrn), std::to_string(law), std::to_string(sh),
                          std::to_string(b[i].mid_stretch), std::to_string(sb),
                          std::to_string(h[i].lateral_stretch),
                          std::to_string(b[i].lateral_stretch), std::to_string(h[i].iterations)});
    if (i == 0) continue;
    worst_h = std::max(worst_h, std::abs(sh / mrn - 1));
    worst_b = std::max(worst_b, std::abs(sb / mrb - 1));
    worst_law = std::max(worst_law, std::abs(law / mrn - 1));
  }
  double rho2 = 0;
  CurveUniaxialStress(curve, 2.0, nullptr, &rho2);
  if (verbose)
    std::fprintf(
        stderr,
        "  %s: R_omega(stretch 2) = %.3f; worst error vs Mooney-Rivlin up to stretch %.1f: "
        "law %.3f, simulated bar %.3f, constant R_omega %.3f\n",
        name.c_str(), rho2, p.stretches.back(), worst_law, worst_h, worst_b);
  return {{"c1", mr.c1},
          {"c2", mr.c2},
          {"r_omega0", rho0},
          {"knots", curve.eps().size()},
          {"r_omega_at_stretch_2", rho2},
          {"max_rel_error_law_homogeneous", worst_law},
          {"max_rel_error_sim_hyperelastic", worst_h},
          {"max_rel_error_sim_constant_r_omega", worst_b},
          {"lateral_stretch_at_2_hyperelastic", h.back().lateral_stretch},
          {"lateral_stretch_at_2_constant_r_omega", b.back().lateral_stretch}};
}

}  // namespace

nlohmann::json RunHyperelasticFit(const Config& cfg, const std::string& dir, bool verbose) {
  const HyperelasticParams p = ReadHyperelasticParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  CsvWriter curve_csv(dir + "/curve.csv", {"material", "strain", "r_omega"});
  CsvWriter resp_csv(dir + "/response.csv",
                     {"material", "end_stretch", "mid_stretch", "mooney_rivlin", "law_homogeneous",
                      "sim_hyperelastic", "mid_stretch_constant", "sim_constant_r_omega",
                      "lateral_hyperelastic", "lateral_constant_r_omega", "iterations"});
  nlohmann::json out = nlohmann::json::object();
  for (const std::string& name : p.names)
    out[name] = FitMaterial(cfg, p, name, &curve_csv, &resp_csv, verbose);
  nlohmann::json j;
  j["materials"] = out;
  j["res"] = p.res;
  j["r_omega0"] = p.rho0;
  j["stretches"] = p.stretches;
  return j;
}

}  // namespace softkin
