#pragma once
/// \file
/// What the Chapter 5 experiments share: dataset specs read from a config, generated once into a
/// cache beside the results (resumable: an interrupted run continues where it stopped, and a
/// finished dataset is reused by every experiment that asks for the same one), and the kinematics
/// they come from (a robot's simulator, or a labelled "hardware" twin); networks trained once into
/// a cache likewise; the config keys the experiments share (trainer, layers, dataset objects) and
/// the PCC baseline.

#include "softkin/experiments/config.hpp"
#include "softkin/ik/kinematics.hpp"
#include "softkin/ik/pcc_chamber_kinematics.hpp"
#include "softkin/learn/dataset.hpp"
#include "softkin/learn/lm_trainer.hpp"

#include <nlohmann/json.hpp>

#include <memory>
#include <string>
#include <vector>

namespace softkin {

struct DatasetSpec {
  std::string robot;  ///< embedded robot (always set; a twin's nominal robot)
  std::string twin;   ///< "" or a twin name (learn/twin.hpp)
  int res = 0;        ///< resolution (<= 0: the robot's default)
  std::vector<std::string> points = {"tip"};
  DatasetSampling sampling;          ///< grid N^m or seeded random
  bool jacobian = false;             ///< record J (implicit differentiation)
  double gradient_tolerance = 1e-4;  ///< forward-solve stopping ratio
  /// A file-name-safe key of everything above (the cache file's name).
  std::string Tag() const;
  nlohmann::json Json() const;
};

/// Parses a dataset object {"robot" | "twin", "res", "grid" | "random" + "seed", "points",
/// "jacobian", "gradient_tolerance", "block"}; `where` names it in errors ("cfg.json: dataset").
/// Unknown keys and wrong types throw std::invalid_argument naming where.key.
DatasetSpec ParseDatasetSpec(const nlohmann::json& j, const std::string& where);

/// The kinematics a spec samples (SimulatorKinematics or TwinKinematics).
std::unique_ptr<Kinematics> MakeSpecKinematics(const DatasetSpec& spec);

/// The shared cache directory of an experiment's result dir: <dir>/../_datasets.
std::string DatasetCacheDir(const std::string& result_dir);

/// Generates (or resumes, or reuses) the spec's dataset at <cache_dir>/<tag>.csv and loads it.
/// *info (if given) receives {path, samples, generated_now, time_s, ms_per_sample}.
Dataset CachedDataset(const DatasetSpec& spec, const std::string& cache_dir, bool verbose,
                      nlohmann::json* info = nullptr);

}  // namespace softkin

namespace softkin {

struct NetsFromDatasetOptions;
struct LearnedNets;

/// Trains the networks of `opt` on `d` (TrainNetsFromDataset), or loads them from
/// <cache_dir>/<key> when a run with the same dataset, architectures, epochs, split and seed
/// saved them there (training N_J on thousands of Jacobians takes minutes; several experiments
/// share the same networks). *cached says which happened.
LearnedNets CachedNets(const Dataset& d, const std::string& dataset_path,
                       const std::string& dataset_tag, const NetsFromDatasetOptions& opt,
                       const std::string& cache_dir, bool verbose, bool* cached = nullptr);

/// The shared network cache directory of an experiment's result dir: <dir>/../_nets.
std::string NetsCacheDir(const std::string& result_dir);

}  // namespace softkin

namespace softkin {

// ---- config keys shared by the Chapter 5 experiments ----

/// The trainer's options: "epochs" (1000), "threads" (0: OpenMP's), "max_train_time_s" (0: none),
/// seeded with the config's seed.
LmOptions ReadLm(const Config& cfg);

/// A list of hidden-layer sizes at `key` (each >= 1, not empty).
std::vector<int> Layers(const Config& cfg, const std::string& key, const std::vector<int>& def);

/// The dataset object at `key` (required).
DatasetSpec SpecFromConfig(const Config& cfg, const std::string& key);

/// The PCC baseline of three_chamber calibrated on a dataset's tip positions (gain, chamber
/// offset and cap length fitted; the thesis calibrates its PCC model on measurements likewise).
/// *info (if given) receives the fit. Throws std::invalid_argument unless the dataset has 3
/// actuators.
std::unique_ptr<PccChamberKinematics> FitPccBaseline(const Dataset& d, nlohmann::json* info);

}  // namespace softkin
