#pragma once
/// \file cli_calibrate.hpp
/// `softkin calibrate`: R_omega^A / R_omega^B from a measured elasticity ratio R_m by elongation
/// tests on bimaterial_bar (thesis Eq. 2.9, Table 2.1; docs/calibration.md), optionally with the
/// twisting test at the result.
#include "softkin/solver/materials/calibration.hpp"

#include <CLI/CLI.hpp>

#include <string>

namespace softkin {

/// The values of `softkin calibrate`'s options, filled in by CLI11.
struct CalibrateCommandArgs {
  double rm = 0;       ///< measured elasticity ratio R_m = E_A / E_B
  BarTestOptions bar;  ///< res, interface, stretch_mm, twist_deg
  bool twist = false;  ///< also run the twisting test
  std::string json_out;
};

/// Adds the `calibrate` subcommand to `app`, bound to *args; returns it.
CLI::App* AddCalibrateCommand(CLI::App* app, CalibrateCommandArgs* args);

/// Runs `softkin calibrate`. Throws std::invalid_argument for bad input; returns the exit code (0).
int RunCalibrateCommand(const CalibrateCommandArgs& args);

}  // namespace softkin
