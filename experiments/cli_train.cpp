#include "softkin/experiments/cli_train.hpp"

#include "softkin/solver/fk/fk_options.hpp"

#include "softkin/experiments/cli_args.hpp"
#include "softkin/experiments/results.hpp"
#include "softkin/learn/dataset.hpp"
#include "softkin/learn/net_kinematics.hpp"
#include "softkin/learn/train_nets.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <cmath>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace softkin {

namespace fs = std::filesystem;

CLI::App* AddTrainCommand(CLI::App* app, TrainCommandArgs* a) {
  auto* t = app->add_subcommand(
      "train",
      "Train the kinematics networks of thesis Sec. 5.3 with the in-house Levenberg-Marquardt "
      "trainer: from a simulator dataset (`softkin dataset`), N_fk (c -> points), N_J (c -> the "
      "flattened Jacobian) and the direct-IK baseline N_ik (tip -> c) on one seeded 70/30 "
      "train/test split, 15 % of the training rows held out for early stopping; or, with --s2r, "
      "the sim-to-real layer N_s2r (one hidden layer of eta x samples neurons) from a twin "
      "dataset, added to an existing network directory. Writes DIR/nets.json (points, bounds, "
      "errors, provenance) and one softkin-fnn file per network; `softkin ik --method learned "
      "--nets DIR` uses them. Exit 0 on success, 2 for bad input. See docs/learning.md");
  auto* o_ds =
      t->add_option("--dataset", a->dataset, "Simulator dataset CSV (with its .json sidecar)");
  auto* o_s2r = t->add_option("--s2r", a->s2r,
                              "Twin dataset CSV: train N_s2r and add it to the networks in --out");
  o_ds->excludes(o_s2r);
  t->add_option("--out", a->out, "Network directory (created; --s2r: must hold N_fk already)")
      ->required();
  t->add_option("--what", a->what,
                "Networks to train: comma list of fk, jac, ik, or auto (fk and ik, and jac when "
                "the dataset has Jacobians; default)");
  t->add_option("--hidden", a->hidden,
                "Hidden layers of N_fk, neurons per layer (default 35,35: h = 2, b = 35)");
  t->add_option("--hidden-jac", a->hidden_jac, "Hidden layers of N_J (default 64,64)");
  t->add_option("--hidden-ik", a->hidden_ik, "Hidden layers of N_ik (default 35,35)");
  t->add_option("--eta", a->eta, "N_s2r neurons per training sample (default 0.25, Sec. 5.3.4)");
  t->add_option("--epochs", a->epochs, "Epoch cap per network (default 1000)");
  t->add_option("--max-time", a->max_time_s, "Wall-time cap per network, s (default: none)");
  t->add_option("--seed", a->seed, "Seed of the initialisation and of the splits (default 1)");
  t->add_option("--threads", a->threads,
                "Trainer threads (default: OpenMP's; results do not depend on it)");
  t->add_flag("--quiet", a->quiet, "No progress on stderr");
  return t;
}

namespace {

std::vector<int> ParseLayers(const std::string& s, const std::string& option) {
  const Eigen::VectorXd v = ParseNumberList(s, option);
  std::vector<int> out;
  for (int i = 0; i < v.size(); ++i) {
    if (!(v[i] >= 1 && v[i] <= 10000 && v[i] == std::floor(v[i])))
      throw std::invalid_argument(
          option + ": expected neuron counts (integers in [1, 10000]), got '" + s + "'");
    out.push_back(static_cast<int>(v[i]));
  }
  if (out.empty()) throw std::invalid_argument(option + ": expected at least one hidden layer");
  return out;
}

void Report(const std::string& name, const nlohmann::json& j, double width) {
  std::cout << "softkin train: " << name << " " << j["layers"].dump() << ": test mean "
            << j["test"]["mean_dist"].get<double>() << ", max "
            << j["test"]["max_dist"].get<double>() << ", rmse " << j["test"]["rmse"].get<double>();
  if (name == "fk" && width > 0)
    std::cout << " (mean " << 100.0 * j["test"]["mean_dist"].get<double>() / width << " % of the "
              << width << " mm workspace)";
  std::cout << "; " << j["epochs"] << " epochs (" << j["termination"].get<std::string>() << "), "
            << j["time_s"].get<double>() << " s\n";
}

Eigen::VectorXd RestFromSidecar(const Dataset& d) {
  try {
    const auto& src = d.meta.at("config").at("source");
    if (src.value("kind", "") != "robot") return {};
    RobotParams params;
    if (src.contains("params") && src["params"].is_object())
      for (auto it = src["params"].begin(); it != src["params"].end(); ++it)
        params[it.key()] = it.value().get<double>();
    const Scene s = MakeRobot(src.at("robot").get<std::string>(), 0, params);
    Eigen::VectorXd r(s.num_actuators());
    for (int a = 0; a < r.size(); ++a) r[a] = s.actuators[a].rest;
    return r;
  } catch (const std::exception&) {
    return {};  // not recorded: the lower bound is used
  }
}

/// Checks the options and returns the trainer's (Levenberg-Marquardt) options.
LmOptions LmFromArgs(const TrainCommandArgs& a) {
  if (a.dataset.empty() == a.s2r.empty())
    throw std::invalid_argument("train: give exactly one of --dataset FILE or --s2r TWIN_FILE");
  if (a.epochs < 0) throw std::invalid_argument("--epochs: expected an integer >= 0");
  if (!(a.max_time_s >= 0) || !std::isfinite(a.max_time_s))
    throw std::invalid_argument("--max-time: expected a time >= 0 s");
  if (a.threads < 0 || a.threads > kMaxThreads)
    throw std::invalid_argument("--threads: expected an integer in [0, " +
                                std::to_string(kMaxThreads) + "], got " +
                                std::to_string(a.threads));
  if (!(a.eta > 0) || !std::isfinite(a.eta))
    throw std::invalid_argument("--eta: expected a number > 0");
  LmOptions lm;
  lm.max_epochs = a.epochs;
  lm.max_time_s = a.max_time_s;
  lm.seed = a.seed;
  lm.num_threads = a.threads;
  lm.verbose = !a.quiet;
  lm.progress_every = 10;
  return lm;
}

/// --s2r: trains N_s2r on the twin dataset and adds it to the networks in --out.
int TrainS2rCommand(const TrainCommandArgs& a, const LmOptions& lm) {
  LearnedNets nets;
  try {
    nets = LearnedNets::Load(a.out);
  } catch (const std::runtime_error& e) {
    throw std::invalid_argument(std::string("--out (the networks to add N_s2r to): ") + e.what());
  }
  const Dataset twin = LoadDataset(a.s2r);
  if (!a.quiet)
    std::cerr << "softkin train: sim-to-real layer from " << a.s2r << " (" << twin.inputs.rows()
              << " samples, eta " << a.eta << ")\n";
  const NetTrainResult r = TrainS2r(nets, twin, a.s2r, a.eta, lm, a.seed);
  nets.info["s2r"]["command"] = a.command_line;
  nets.info["s2r"]["git_commit"] = GitCommit();
  nets.Save(a.out);
  const auto& j = nets.info["s2r"];
  std::cout << "softkin train: s2r " << j["layers"].dump() << ": test mean error "
            << r.test.mean_dist << " mm (without s2r "
            << j["test_without_s2r"]["mean_dist"].get<double>() << " mm, "
            << j["improvement"].get<double>() << "x better); wrote " << a.out << "\n";
  return 0;
}

/// The networks to train (--what) and their layers, trainer and split from the command line.
NetsFromDatasetOptions NetsOptionsFromArgs(const TrainCommandArgs& a, const Dataset& d,
                                           const LmOptions& lm) {
  NetsFromDatasetOptions o;
  o.fk = o.ik = true;
  o.jac = d.jacobians.cols() > 0;
  if (a.what != "auto") {
    o.fk = o.jac = o.ik = false;
    std::stringstream ss(a.what);
    std::string item;
    while (std::getline(ss, item, ',')) {
      if (item == "fk")
        o.fk = true;
      else if (item == "jac")
        o.jac = true;
      else if (item == "ik")
        o.ik = true;
      else
        throw std::invalid_argument("--what: unknown network '" + item +
                                    "' (expected fk, jac, ik or auto)");
    }
    if (!o.fk)
      throw std::invalid_argument(
          "--what: fk is required (N_J, N_ik and the learned IK all sit beside N_fk)");
  }
  o.fk_options.hidden = ParseLayers(a.hidden, "--hidden");
  o.jac_options.hidden = ParseLayers(a.hidden_jac, "--hidden-jac");
  o.ik_options.hidden = ParseLayers(a.hidden_ik, "--hidden-ik");
  o.fk_options.lm = o.jac_options.lm = o.ik_options.lm = lm;
  o.fk_options.split_seed = o.jac_options.split_seed = o.ik_options.split_seed = a.seed;
  o.split_seed = a.seed;
  o.rest = RestFromSidecar(d);
  return o;
}

}  // namespace

int RunTrainCommand(const TrainCommandArgs& a) {
  const LmOptions lm = LmFromArgs(a);
  // Before any work: the networks written to --out never replace the data they are trained on.
  const std::string data = a.s2r.empty() ? a.dataset : a.s2r;
  const std::string flag = a.s2r.empty() ? "--dataset" : "--s2r";
  std::vector<NamedPath> outputs;
  for (const std::string& f : LearnedNets::Files(a.out)) outputs.push_back({"--out", f});
  CheckDistinctPaths({{flag, data}, {flag + "'s sidecar", data + ".json"}}, outputs);
  if (!a.s2r.empty()) return TrainS2rCommand(a, lm);

  const Dataset d = LoadDataset(a.dataset);
  CheckSidecarMatches(d, a.dataset);  // the bounds and provenance of the networks come from it
  const NetsFromDatasetOptions o = NetsOptionsFromArgs(a, d, lm);
  if (!a.quiet)
    std::cerr << "softkin train: " << a.dataset << ": " << d.inputs.rows() << " samples, "
              << d.num_actuators << " actuators, " << d.point_names.size() << " point(s)"
              << (d.jacobians.cols() ? ", Jacobians" : "") << "; training" << (o.fk ? " fk" : "")
              << (o.jac ? " jac" : "") << (o.ik ? " ik" : "") << "\n";
  if (d.failed + d.inverted > 0)
    std::cerr << "softkin train: left out " << d.failed << " failed sample(s) and " << d.inverted
              << " with inverted elements (not physical states)\n";
  LearnedNets nets = TrainNetsFromDataset(d, a.dataset, o);
  nets.info["command"] = a.command_line;
  nets.info["git_commit"] = GitCommit();
  nets.info["machine"] = MachineInfo();
  nets.Save(a.out);
  const double width = nets.info["dataset"]["workspace_width_mm"].get<double>();
  for (const char* n : {"fk", "jac", "ik"})
    if (nets.info.contains(n)) Report(n, nets.info[n], width);
  std::cout << "softkin train: wrote " << a.out << "/nets.json\n";
  return 0;
}

}  // namespace softkin
