#include "softkin/experiments/learn_common.hpp"

#include "softkin/experiments/dataset_mpi.hpp"
#include "softkin/experiments/results.hpp"
#include "softkin/ik/simulator_kinematics.hpp"
#include "softkin/learn/twin.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <stdexcept>

namespace softkin {

namespace fs = std::filesystem;

std::string DatasetSpec::Tag() const {
  std::ostringstream s;
  s << (twin.empty() ? robot : "twin_" + twin) << "_r" << res << "_";
  if (sampling.kind == DatasetSampling::Kind::kGrid)
    s << "g" << sampling.grid;
  else
    s << "rnd" << sampling.random << "s" << sampling.seed;
  s << "_b" << sampling.block << (jacobian ? "_J" : "") << "_gt" << gradient_tolerance;
  for (const auto& p : points) s << "_" << p;
  std::string t = s.str();
  for (char& c : t)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-' && c != '.') c = '-';
  return t;
}

nlohmann::json DatasetSpec::Json() const {
  return {{"robot", robot},
          {"twin", twin},
          {"res", res},
          {"points", points},
          {"sampling", sampling.ToJson()},
          {"jacobian", jacobian},
          {"gradient_tolerance", gradient_tolerance}};
}

DatasetSpec ParseDatasetSpec(const nlohmann::json& j, const std::string& where) {
  auto bad = [&where](const std::string& key, const std::string& what) {
    return std::invalid_argument(where + "." + key + ": expected " + what);
  };
  if (!j.is_object())
    throw std::invalid_argument(where + ": expected a dataset object {\"robot\", \"grid\", ...}");
  const std::set<std::string> known = {
      "robot", "twin", "res", "points", "grid", "random", "seed", "jacobian", "gradient_tolerance",
      "block"};
  for (auto it = j.begin(); it != j.end(); ++it)
    if (!known.count(it.key()))
      throw std::invalid_argument(where + "." + it.key() + ": unknown key");
  DatasetSpec s;
  if (j.contains("twin")) {
    if (!j["twin"].is_string()) throw bad("twin", "a twin name");
    s.twin = j["twin"].get<std::string>();
    try {
      s.robot = GetTwinSpec(s.twin).robot;
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(where + ".twin: " + e.what());
    }
    if (j.contains("robot")) throw std::invalid_argument(where + ": give robot or twin, not both");
  } else {
    if (!j.contains("robot") || !j["robot"].is_string())
      throw bad("robot", "an embedded robot name");
    s.robot = j["robot"].get<std::string>();
  }
  if (j.contains("res")) {
    if (!j["res"].is_number_integer()) throw bad("res", "an integer");
    s.res = j["res"].get<int>();
  }
  if (j.contains("points")) {
    if (!j["points"].is_array() || j["points"].empty())
      throw bad("points", "a non-empty array of marker names");
    s.points.clear();
    for (const auto& p : j["points"]) {
      if (!p.is_string()) throw bad("points", "marker names");
      s.points.push_back(p.get<std::string>());
    }
  }
  if (j.contains("random")) {
    if (!j["random"].is_number_integer() || j["random"].get<long long>() < 1)
      throw bad("random", "a sample count >= 1");
    if (!j.contains("seed") || !j["seed"].is_number_integer())
      throw bad("seed", "an integer seed (required with random)");
    s.sampling.kind = DatasetSampling::Kind::kRandom;
    s.sampling.random = j["random"].get<long long>();
    s.sampling.seed = j["seed"].get<std::uint64_t>();
    if (j.contains("grid")) throw std::invalid_argument(where + ": give grid or random, not both");
  } else {
    if (!j.contains("grid") || !j["grid"].is_number_integer())
      throw bad("grid", "an integer N >= 2 (N^m samples)");
    s.sampling.grid = j["grid"].get<int>();
  }
  if (j.contains("block")) {
    if (!j["block"].is_number_integer()) throw bad("block", "an integer >= 1");
    s.sampling.block = j["block"].get<int>();
  }
  if (j.contains("jacobian")) {
    if (!j["jacobian"].is_boolean()) throw bad("jacobian", "true or false");
    s.jacobian = j["jacobian"].get<bool>();
  }
  if (j.contains("gradient_tolerance")) {
    if (!j["gradient_tolerance"].is_number() || !(j["gradient_tolerance"].get<double>() > 0))
      throw bad("gradient_tolerance", "a number > 0");
    s.gradient_tolerance = j["gradient_tolerance"].get<double>();
  }
  std::string why;
  if (!s.sampling.IsValid(&why)) throw std::invalid_argument(where + ": " + why);
  if (!s.twin.empty() && s.jacobian)
    throw std::invalid_argument(where + ".jacobian: a twin has no Jacobian");
  return s;
}

std::unique_ptr<Kinematics> MakeSpecKinematics(const DatasetSpec& spec) {
  if (!spec.twin.empty()) {
    TwinOptions to;
    to.res = spec.res;
    to.points = spec.points;
    to.gradient_tolerance = spec.gradient_tolerance;
    return std::make_unique<TwinKinematics>(GetTwinSpec(spec.twin), to);
  }
  const Scene scene = MakeRobot(spec.robot, spec.res);
  FkOptions fk = scene.solver;
  fk.gradient_tolerance = spec.gradient_tolerance;
  SimulatorKinematicsOptions ko;
  ko.points = spec.points;
  ko.jacobian = JacobianMode::kImplicit;
  return std::make_unique<SimulatorKinematics>(scene, ko, &fk);
}

std::string DatasetCacheDir(const std::string& result_dir) {
  return (fs::path(result_dir).parent_path() / "_datasets").string();
}

Dataset CachedDataset(const DatasetSpec& spec, const std::string& cache_dir, bool verbose,
                      nlohmann::json* info) {
  fs::create_directories(cache_dir);
  const std::string path = (fs::path(cache_dir) / (spec.Tag() + ".csv")).string();
  std::unique_ptr<Kinematics> kin = MakeSpecKinematics(spec);
  DatasetRunOptions run;
  run.out = path;
  run.jacobian = spec.jacobian;
  run.source = spec.Json();
  run.source["kind"] = spec.twin.empty() ? "robot" : "twin";
  if (!spec.twin.empty()) run.source["twin"] = "twin:" + spec.twin;
  run.provenance = {{"git_commit", GitCommit()},
                    {"command", "softkin run (experiment dataset cache)"}};
  Kinematics* raw = kin.get();
  run.reset = [raw] {
    if (auto* t = dynamic_cast<TwinKinematics*>(raw))
      t->Reset();
    else if (auto* s = dynamic_cast<SimulatorKinematics*>(raw))
      s->Reset();
  };
  if (verbose) std::cerr << "  dataset " << path << " (" << kin->name() << ")\n";
  run.progress = verbose;
  // Under mpirun (a sweep, experiments/sweep.hpp) the ranks share the samples; in one process
  // this is GenerateDataset.
  const DatasetRunSummary s = GenerateDatasetMpi(*kin, spec.sampling, run);
  Dataset d = LoadDataset(path);
  if (info) {
    *info = {{"path", path},
             {"spec", spec.Json()},
             {"samples", d.inputs.rows()},
             {"failed", d.failed},
             {"inverted", d.inverted},
             {"generated_now", s.written},
             {"already_cached", s.already},
             {"time_s", s.time_s},
             {"ms_per_sample", s.written > 0 ? 1e3 * s.time_s / s.written : 0.0}};
  }
  return d;
}

}  // namespace softkin

#include "softkin/learn/train_nets.hpp"

namespace softkin {

std::string NetsCacheDir(const std::string& result_dir) {
  return (fs::path(result_dir).parent_path() / "_nets").string();
}

namespace {

std::string LayersTag(const std::vector<int>& v) {
  std::string s;
  for (int b : v) s += (s.empty() ? "" : "x") + std::to_string(b);
  return s;
}

std::string NetTag(const char* name, bool on, const NetTrainOptions& o) {
  if (!on) return "";
  std::ostringstream s;
  s << "_" << name << LayersTag(o.hidden) << "e" << o.lm.max_epochs << "s" << o.lm.seed << "v"
    << o.validation_fraction << "q" << o.split_seed;
  if (o.lm.max_time_s > 0) s << "t" << o.lm.max_time_s;
  return s.str();
}

}  // namespace

LearnedNets CachedNets(const Dataset& d, const std::string& dataset_path,
                       const std::string& dataset_tag, const NetsFromDatasetOptions& opt,
                       const std::string& cache_dir, bool verbose, bool* cached) {
  std::ostringstream key;
  key << dataset_tag << "_n" << d.inputs.rows() << "_split" << opt.split_seed << "f"
      << opt.train_fraction;
  const fs::path dir = fs::path(cache_dir) / key.str();
  fs::create_directories(dir);
  // Bounds, points and the split's record, without training anything.
  NetsFromDatasetOptions none = opt;
  none.fk = none.jac = none.ik = false;
  LearnedNets out = TrainNetsFromDataset(d, dataset_path, none);
  NetsFromDatasetOptions missing = none;
  struct Item {
    const char* name;
    bool want;
    const NetTrainOptions* o;
    Fnn* net;
    bool* miss;
  } items[3] = {{"fk", opt.fk, &opt.fk_options, &out.fk, &missing.fk},
                {"jac", opt.jac, &opt.jac_options, &out.jac, &missing.jac},
                {"ik", opt.ik, &opt.ik_options, &out.ik, &missing.ik}};
  bool all_cached = true;
  for (Item& it : items) {
    if (!it.want) continue;
    const std::string base = (dir / NetTag(it.name, true, *it.o).substr(1)).string();
    try {
      if (fs::exists(base + ".fnn") && fs::exists(base + ".json")) {
        Fnn f = Fnn::Load(base + ".fnn");
        std::ifstream in(base + ".json");
        const nlohmann::json info = nlohmann::json::parse(in);
        *it.net = std::move(f);
        out.info[it.name] = info;
        if (verbose) std::cerr << "  N_" << it.name << " from the cache " << base << ".fnn\n";
        continue;
      }
    } catch (const std::exception& e) {
      if (verbose)
        std::cerr << "  ignoring the unreadable cached network " << base << ": " << e.what()
                  << "\n";
    }
    *it.miss = true;
    all_cached = false;
  }
  if (!all_cached) {
    if (verbose)
      std::cerr << "  training" << (missing.fk ? " N_fk" : "") << (missing.jac ? " N_J" : "")
                << (missing.ik ? " N_ik" : "") << " on " << d.inputs.rows() << " samples\n";
    LearnedNets trained = TrainNetsFromDataset(d, dataset_path, missing);
    Fnn* from[3] = {&trained.fk, &trained.jac, &trained.ik};
    for (int k = 0; k < 3; ++k) {
      if (!*items[k].miss) continue;
      const std::string base = (dir / NetTag(items[k].name, true, *items[k].o).substr(1)).string();
      *items[k].net = *from[k];
      out.info[items[k].name] = trained.info[items[k].name];
      out.info[items[k].name]["git_commit"] = GitCommit();
      from[k]->Save(base + ".fnn");
      WriteJson(base + ".json", out.info[items[k].name]);
    }
  }
  if (cached) *cached = all_cached;
  return out;
}

LmOptions ReadLm(const Config& cfg) {
  LmOptions lm;
  lm.max_epochs = cfg.Int("epochs", 1000);
  lm.num_threads = cfg.Int("threads", 0);
  lm.max_time_s = cfg.Number("max_train_time_s", 0.0);
  lm.seed = cfg.seed();
  if (lm.max_epochs < 1) cfg.Fail("epochs", "an integer >= 1");
  if (lm.num_threads < 0) cfg.Fail("threads", "an integer >= 0 (0: OpenMP's default)");
  if (!(lm.max_time_s >= 0)) cfg.Fail("max_train_time_s", "a time >= 0 s (0: none)");
  return lm;
}

std::vector<int> Layers(const Config& cfg, const std::string& key, const std::vector<int>& def) {
  const std::vector<int> v = cfg.IntList(key, def);
  if (v.empty()) cfg.Fail(key, "a non-empty list of neuron counts");
  for (int b : v)
    if (b < 1) cfg.Fail(key, "neuron counts >= 1");
  return v;
}

DatasetSpec SpecFromConfig(const Config& cfg, const std::string& key) {
  const nlohmann::json j = cfg.Raw(key);
  if (j.is_null()) cfg.Fail(key, "a dataset object {\"robot\", \"res\", \"grid\", ...}");
  return ParseDatasetSpec(j, cfg.path() + ": " + key);
}

std::unique_ptr<PccChamberKinematics> FitPccBaseline(const Dataset& d, nlohmann::json* info) {
  if (d.num_actuators != 3)
    throw std::invalid_argument(
        "the PCC baseline models three_chamber (3 actuators), the dataset has " +
        std::to_string(d.num_actuators));
  PccChamberParams start;
  if (d.meta.is_object() && d.meta.contains("config") &&
      d.meta["config"].contains("actuator_bounds")) {
    start.lower = d.meta["config"]["actuator_bounds"][0][0].get<double>();
    start.upper = d.meta["config"]["actuator_bounds"][0][1].get<double>();
    start.rest = start.lower;
  }
  const PccFitResult f = FitPccChamber(d.inputs, d.positions.leftCols(3), start);
  if (info)
    *info = {{"gain", f.params.gain},          {"offset_mm", f.params.offset},
             {"cap_mm", f.params.cap},         {"fit_rms_mm", f.rms_mm},
             {"start_rms_mm", f.rms_start_mm}, {"fit_samples", d.inputs.rows()}};
  return std::make_unique<PccChamberKinematics>(f.params);
}

}  // namespace softkin
