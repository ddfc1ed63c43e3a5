#pragma once
/// \file
/// `softkin train`: the networks of Sec. 5.3 from a dataset CSV (`softkin dataset`), into a
/// network directory (learn/net_kinematics.hpp) that `softkin ik --nets DIR` uses.

#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>

namespace softkin {

struct TrainCommandArgs {
  std::string dataset;           ///< simulator dataset (N_fk, N_J, N_ik)
  std::string s2r;               ///< twin dataset: add N_s2r to an existing --out directory
  std::string out;               ///< network directory
  std::string what = "auto";     ///< comma list of fk, jac, ik; auto = fk, ik and jac if J exists
  std::string hidden = "35,35";
  std::string hidden_jac = "64,64";
  std::string hidden_ik = "35,35";
  double eta = 0.25;
  int epochs = 1000;
  double max_time_s = 0;
  std::uint64_t seed = 1;
  int threads = 0;
  bool quiet = false;
};

CLI::App* AddTrainCommand(CLI::App* app, TrainCommandArgs* args);

int RunTrainCommand(const TrainCommandArgs& args, const std::string& command_line);

}  // namespace softkin
