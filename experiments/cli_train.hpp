#pragma once
/// \file cli_train.hpp
/// `softkin train`: the networks of Sec. 5.3 from a dataset CSV (`softkin dataset`), into a
/// network directory (learn/net_kinematics.hpp) that `softkin ik --nets DIR` uses.

#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>

namespace softkin {

/// The values of `softkin train`'s options, filled in by CLI11.
struct TrainCommandArgs {
  std::string dataset;        ///< simulator dataset (N_fk, N_J, N_ik)
  std::string s2r;            ///< twin dataset: add N_s2r to an existing --out directory
  std::string out;            ///< network directory
  std::string what = "auto";  ///< comma list of fk, jac, ik; auto = fk, ik and jac if J exists
  std::string hidden = "35,35";
  std::string hidden_jac = "64,64";
  std::string hidden_ik = "35,35";
  double eta = 0.25;
  int epochs = 1000;
  double max_time_s = 0;
  std::uint64_t seed = 1;
  int threads = 0;
  bool quiet = false;
  std::string command_line;  ///< the whole command line, for nets.json (set by RunCli)
};

/// Adds the `train` subcommand to `app`, bound to *args; returns it.
CLI::App* AddTrainCommand(CLI::App* app, TrainCommandArgs* args);

/// Runs `softkin train`. Throws std::invalid_argument for bad input (naming the option) and
/// std::runtime_error when a file cannot be read or written; returns the exit code (0).
int RunTrainCommand(const TrainCommandArgs& args);

}  // namespace softkin
