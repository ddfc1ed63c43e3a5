#include "softkin/experiments/cli_calibrate.hpp"

#include "softkin/experiments/cli_args.hpp"
#include "softkin/experiments/results.hpp"

#include <nlohmann/json.hpp>

#include <iostream>

namespace softkin {

CLI::App* AddCalibrateCommand(CLI::App* app, CalibrateCommandArgs* a) {
  auto* cal = app->add_subcommand(
      "calibrate",
      "Calibrate R_omega^A / R_omega^B from a measured elasticity ratio R_m (thesis Eq. 2.9, "
      "Table 2.1) by elongation tests on bimaterial_bar (docs/calibration.md)");
  cal->add_option("--rm", a->rm, "Measured elasticity ratio R_m = E_A / E_B (> 0)")->required();
  cal->add_option("--res", a->bar.res, "bimaterial_bar resolution (default: its own)")
      ->check(CLI::Range(1, 1 << 20));
  cal->add_option("--interface", a->bar.interface,
                  "Interface position, fraction of the length from the fixed end (default 0.5)");
  cal->add_option("--stretch", a->bar.stretch_mm,
                  "End displacement of the elongation test, mm (default 8)");
  cal->add_flag("--twist", a->twist, "Also run the twisting test (Fig. 2.6d) with the result");
  cal->add_option("--twist-deg", a->bar.twist_deg,
                  "End rotation of the twisting test, degrees (default 90)");
  cal->add_option("--json", a->json_out, "Write the result as JSON to this file");
  return cal;
}

int RunCalibrateCommand(const CalibrateCommandArgs& a) {
  CheckCommandPaths({}, {{"--json", a.json_out}});  // before the calibration's solves
  const BarTestOptions& bar = a.bar;
  const CalibrationResult c = CalibrateROmega(a.rm, bar);
  nlohmann::json j = {
      {"rm", c.target_rm},          {"r_omega_ratio", c.ratio},     {"r_omega_a", c.r_omega_a},
      {"r_omega_b", c.r_omega_b},   {"achieved_rm", c.achieved_rm}, {"evaluations", c.evaluations},
      {"interface", bar.interface}, {"stretch_mm", bar.stretch_mm}, {"res", bar.res}};
  std::cout << "R_omega^A / R_omega^B = " << c.ratio << "  (R_omega^A = " << c.r_omega_a
            << ", R_omega^B = " << c.r_omega_b << "; simulated R_m = " << c.achieved_rm << " after "
            << c.evaluations << " elongation tests)\n";
  if (a.twist) {
    const TwistResult t = RunTwistTest(c.r_omega_a, c.r_omega_b, bar);
    j["twist"] = {
        {"twist_deg", t.twist_deg}, {"angle_a_deg", t.angle_a_deg}, {"angle_b_deg", t.angle_b_deg}};
    std::cout << "twisting test: end turned " << t.twist_deg << " deg; material A turns "
              << t.angle_a_deg << " deg, material B " << t.angle_b_deg << " deg\n";
  }
  if (!a.json_out.empty()) WriteJson(a.json_out, j);
  return 0;
}

}  // namespace softkin
