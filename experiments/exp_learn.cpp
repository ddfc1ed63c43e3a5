// Thesis Chapter 5 on three_chamber and finger_manipulator: the network architecture sweep
// (Fig. 5.5), the IK methods compared (Table 5.1) and the redundant finger_manipulator on a path
// (Fig. 5.10, 5.12). The sim-to-real experiments are in exp_learn_s2r.cpp.
#include "softkin/experiments/ik_config.hpp"
#include "softkin/experiments/learn_common.hpp"
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/experiments/sweep.hpp"
#include "softkin/ik/ik_solver.hpp"
#include "softkin/ik/objectives.hpp"
#include "softkin/ik/pcc_chamber_kinematics.hpp"
#include "softkin/ik/trajectory.hpp"
#include "softkin/learn/net_kinematics.hpp"
#include "softkin/learn/train_nets.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <random>

namespace softkin {

namespace {

// ---- Fig. 5.5: test error against the number of hidden layers h and neurons per layer b ----

/// The keys of a learn_architecture config.
struct ArchitectureParams {
  nlohmann::json datasets;           ///< an array of dataset objects
  std::vector<int> layers, neurons;  ///< h and b of N_fk
  bool jac = true;                   ///< also N_J (on datasets with Jacobians)
  std::vector<int> jac_layers, jac_neurons;
  LmOptions lm;
  unsigned seed = 0;
};

ArchitectureParams ReadArchitectureParams(const Config& cfg) {
  ArchitectureParams p;
  p.datasets = cfg.Raw("datasets");
  p.layers = cfg.IntList("layers", {1, 2, 3, 4});
  p.neurons = cfg.IntList("neurons", {10, 20, 35, 50});
  p.jac = cfg.Bool("jacobian_network", true);
  p.jac_layers = cfg.IntList("jac_layers", p.layers);
  p.jac_neurons = cfg.IntList("jac_neurons", p.neurons);
  p.lm = ReadLm(cfg);
  p.seed = cfg.seed();
  cfg.CheckNoUnknownKeys();
  if (!p.datasets.is_array() || p.datasets.empty())
    cfg.Fail("datasets", "a non-empty array of dataset objects");
  for (int h : p.layers)
    if (h < 1 || h > 8) cfg.Fail("layers", "hidden-layer counts in [1, 8]");
  for (int b : p.neurons)
    if (b < 1) cfg.Fail("neurons", "neuron counts >= 1");
  return p;
}

/// One dataset of the sweep: its samples split into training and test sets.
struct ArchitectureData {
  DatasetSpec spec;
  nlohmann::json spec_json;  ///< the config's dataset object (part of the journal's key)
  SampleSet pos, js;         ///< positions, and Jacobians (if trained)
  TrainTestSets split;
  double width = 0;  ///< workspace width, mm
  double range = 0;  ///< the largest actuation range
};

/// The journal key of one network of the sweep: every setting that determines its row.
nlohmann::json ArchitectureKey(const ArchitectureParams& p, const ArchitectureData& d,
                               const std::string& net, int h, int b) {
  return {{"dataset", d.spec_json},
          {"net", net},
          {"h", h},
          {"b", b},
          {"seed", p.seed},
          {"epochs", p.lm.max_epochs},
          {"max_train_time_s", p.lm.max_time_s}};
}

/// Trains one network and returns its row.
nlohmann::json ArchitectureRow(const ArchitectureParams& p, const ArchitectureData& d,
                               const std::string& net, int h, int b, bool verbose) {
  const SampleSet& s = net == "fk" ? d.pos : d.js;
  // The Jacobian's error is quoted as the tip displacement error of a step of 1/10 of the
  // actuation range (the finite-difference step of Sec. 5.2.1), as % of the workspace width.
  const double scale = net == "fk" ? 100.0 / d.width : 100.0 * 0.1 * d.range / d.width;
  const SampleSet train = SelectRows(s, d.split.train_rows),
                  test = SelectRows(s, d.split.test_rows);
  NetTrainOptions o;
  o.hidden.assign(h, b);
  o.lm = p.lm;
  o.split_seed = p.seed;
  const NetTrainResult t = TrainNet(train, test, o);
  const nlohmann::json row = {{"robot", d.spec.robot},
                              {"net", net},
                              {"h", h},
                              {"b", b},
                              {"parameters", t.net.num_parameters()},
                              {"test_mean", t.test.mean_dist},
                              {"test_max", t.test.max_dist},
                              {"test_mean_pct", scale * t.test.mean_dist},
                              {"test_max_pct", scale * t.test.max_dist},
                              {"relative", t.test.relative},
                              {"epochs", t.lm.epochs},
                              {"time_s", t.lm.total_time_s},
                              {"termination", LmTerminationToString(t.lm.termination)}};
  if (verbose)
    std::fprintf(
        stderr,
        "  %s N_%s h=%d b=%d: test mean %.4f%% (max %.4f%%) of %.1f mm, %d epochs, %.1f s\n",
        d.spec.robot.c_str(), net.c_str(), h, b, row["test_mean_pct"].get<double>(),
        row["test_max_pct"].get<double>(), d.width, row["epochs"].get<int>(),
        row["time_s"].get<double>());
  return row;
}

}  // namespace

nlohmann::json RunLearnArchitecture(const Config& cfg, const std::string& dir, bool verbose) {
  const ArchitectureParams p = ReadArchitectureParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  // Resume: every finished network is appended to architecture.jsonl with the settings that
  // produced it; a rerun reuses the rows whose settings match and trains only the others. Under
  // mpirun the ranks share the networks (experiments/sweep.hpp) and the datasets' samples.
  Sweep sweep(dir + "/architecture.jsonl", "architecture", verbose);
  std::vector<ArchitectureData> data(p.datasets.size());
  struct Unit {
    std::size_t d;
    std::string net;
    int h, b;
  };
  std::vector<Unit> units;
  std::vector<nlohmann::json> keys;
  nlohmann::json datasets = nlohmann::json::array();
  for (size_t r = 0; r < p.datasets.size(); ++r) {
    ArchitectureData& d = data[r];
    d.spec_json = p.datasets[r];
    d.spec = ParseDatasetSpec(d.spec_json, cfg.path() + ": datasets[" + std::to_string(r) + "]");
    nlohmann::json dinfo;
    const Dataset ds = CachedDataset(d.spec, DatasetCacheDir(dir), verbose, &dinfo);
    d.pos = PositionSamples(ds);
    d.split = SplitTrainTest(d.pos, p.seed);
    d.width = WorkspaceWidth(d.pos.Y);
    dinfo["workspace_width_mm"] = d.width;
    datasets.push_back(dinfo);
    const bool with_j = p.jac && ds.jacobians.cols() > 0;
    if (with_j) d.js = JacobianSamples(ds);
    for (const auto& b : ds.meta["config"]["actuator_bounds"])
      d.range = std::max(d.range, b[1].get<double>() - b[0].get<double>());
    for (const std::string net : {"fk", "jac"}) {
      if (net == "jac" && !with_j) continue;
      for (int h : net == "fk" ? p.layers : p.jac_layers)
        for (int b : net == "fk" ? p.neurons : p.jac_neurons) {
          units.push_back({r, net, h, b});
          keys.push_back(ArchitectureKey(p, d, net, h, b));
        }
    }
  }
  sweep.Run(keys, [&](std::size_t i) {
    const Unit& u = units[i];
    return ArchitectureRow(p, data[u.d], u.net, u.h, u.b, verbose);
  });
  if (!Sweep::WritesResults()) return {};
  const nlohmann::json rows =
      sweep.WriteTable(dir + "/architecture.csv",
                       {"robot", "net", "h", "b", "parameters", "test_mean", "test_max",
                        "test_mean_pct", "test_max_pct", "epochs", "time_s", "termination"});
  return {{"rows", rows},
          {"datasets", datasets},
          {"resumed_rows", sweep.resumed()},
          {"jacobian_error_note",
           "N_J errors are |dJ| x (range/10) (the tip error of a 1/10-range step), as % of the "
           "workspace width"},
          {"thesis",
           {{"three_chamber",
             {{"fk", {{"h", 2}, {"b", 35}, {"test_mean_mm", 0.17}, {"test_mean_pct", 0.34}}}}},
            {"finger_manipulator",
             {{"fk", {{"h", 3}, {"b", 30}, {"test_mean_pct", 0.58}}},
              {"jac", {{"h", 2}, {"b", 64}}}}}}}};
}

namespace {

// ---- Table 5.1: IK time per waypoint and error, measured by the simulator, per method ----

/// The keys of a learn_ik_methods config.
struct IkMethodsParams {
  DatasetSpec spec;
  NetsFromDatasetOptions nets;
  int n_targets = 50;
  int n_numerical = 5;        ///< targets of the (slow) simulator-in-the-loop method
  double eps_pct = 0.1;       ///< lambda of the simulator, % of the workspace width
  double net_eps_pct = 0.01;  ///< lambda of the (cheap) models
  int max_iter = 30;
  std::vector<std::string> methods;
  unsigned seed = 0;
};

IkMethodsParams ReadIkMethodsParams(const Config& cfg) {
  IkMethodsParams p;
  p.spec = SpecFromConfig(cfg, "dataset");
  NetsFromDatasetOptions& no = p.nets;
  no.fk_options.hidden = Layers(cfg, "fk_hidden", {35, 35});
  no.jac_options.hidden = Layers(cfg, "jac_hidden", {64, 64});
  no.ik_options.hidden = Layers(cfg, "ik_hidden", {35, 35});
  no.fk_options.lm = no.jac_options.lm = no.ik_options.lm = ReadLm(cfg);
  no.split_seed = no.fk_options.split_seed = no.jac_options.split_seed = no.ik_options.split_seed =
      cfg.seed();
  p.n_targets = cfg.Int("targets", 50);
  p.n_numerical = cfg.Int("numerical_targets", 5);
  p.eps_pct = cfg.Number("lambda_pct_width", 0.1);
  p.net_eps_pct = cfg.Number("network_lambda_pct_width", 0.01);
  p.max_iter = cfg.Int("max_iterations", 30);
  p.methods = cfg.StringList("methods", {"pcc", "numerical", "direct", "learned"});
  p.seed = cfg.seed();
  cfg.CheckNoUnknownKeys();
  if (!p.spec.jacobian)
    cfg.Fail("dataset.jacobian", "true (N_J is trained on the recorded Jacobians)");
  if (p.n_targets < 1) cfg.Fail("targets", "an integer >= 1");
  if (p.n_numerical < 0) cfg.Fail("numerical_targets", "an integer >= 0");
  if (!(p.eps_pct > 0)) cfg.Fail("lambda_pct_width", "a percentage > 0");
  if (!(p.net_eps_pct > 0)) cfg.Fail("network_lambda_pct_width", "a percentage > 0");
  for (const auto& m : p.methods)
    if (m != "pcc" && m != "numerical" && m != "direct" && m != "learned")
      cfg.Fail("methods", "names out of pcc, numerical, direct, learned ('" + m + "' is not)");
  return p;
}

/// n targets the truth reaches at seeded random actuations.
Eigen::MatrixX3d TruthTargets(Kinematics& truth, int n, unsigned seed) {
  const int m = truth.num_actuators();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd c_true(n, m);
  Eigen::MatrixX3d targets(n, 3);
  for (int i = 0; i < n; ++i) {
    for (int a = 0; a < m; ++a)
      c_true(i, a) = truth.lower()[a] + u(rng) * (truth.upper()[a] - truth.lower()[a]);
    const KinematicsEval e = truth.Evaluate(c_true.row(i).transpose(), false);
    if (!e.ok) throw std::runtime_error("the simulator failed at a target actuation: " + e.message);
    targets.row(i) = e.p.row(0);
  }
  return targets;
}

/// What the methods of Table 5.1 share: the data, the networks and the targets.
struct IkMethodsSetup {
  const IkMethodsParams& p;
  const Dataset& d;
  const LearnedNets& nets;
  Kinematics& truth;
  const Eigen::MatrixX3d& targets;
  double width;  ///< workspace width, mm
  IkOptions io;  ///< gauss-newton to the simulator's lambda
};

/// One method of Table 5.1 on the targets: rows of targets.csv and the method's summary row.
nlohmann::json IkMethodRow(const IkMethodsSetup& s, const std::string& method, CsvWriter* csv,
                           bool verbose) {
  static const std::map<std::string, std::pair<double, double>> kThesis = {
      {"pcc", {12.6, 8.2}},
      {"numerical", {138000.0, 4.7}},
      {"direct", {3.2, 0.97}},
      {"learned", {28.0, 0.78}}};
  static const std::map<std::string, std::string> kLabel = {
      {"pcc", "PCC analytical"},
      {"numerical", "simulation-in-the-loop (implicit J)"},
      {"direct", "direct IK learning"},
      {"learned", "learned Jacobian"}};
  const IkMethodsParams& p = s.p;
  std::unique_ptr<Kinematics> model;
  nlohmann::json extra = nlohmann::json::object();
  if (method == "learned") {
    model = std::make_unique<NetKinematics>(s.nets, JacobianSource::kNetwork, false);
  } else if (method == "numerical") {
    model = MakeSpecKinematics(p.spec);
  } else if (method == "pcc") {
    nlohmann::json fit;
    model = FitPccBaseline(s.d, &fit);
    extra["pcc_fit"] = fit;
  }
  ConfigurationSamples samples;
  if (model) {
    SamplingOptions so;
    so.samples_per_axis = 5;
    samples = SampleConfigurationSpace(*model, model->point_names().front(), so);
    extra["sampling_time_s"] = samples.time_s;
  }
  const int n = method == "numerical" ? std::min(p.n_numerical, p.n_targets) : p.n_targets;
  double sum = 0, worst = 0, time = 0;
  int ok = 0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d t = s.targets.row(i).transpose();
    Eigen::VectorXd c;
    double pred = 0;
    int iters = 0;
    const auto t0 = std::chrono::steady_clock::now();
    if (method == "direct") {
      c = DirectIk(s.nets, t);
    } else {
      const Eigen::VectorXd c0 = samples.c.row(ClosestSample(samples, t)).transpose();
      PointTrackingObjective obj(model->point_names(), model->point_names().front(), t);
      IkOptions mo = s.io;
      if (method != "numerical")
        mo.lambda = std::pow(p.net_eps_pct / 100.0 * s.width, 2);  // models are cheap
      const IkResult r = SolveIk(*model, obj, c0, mo);
      c = r.c;
      pred = std::sqrt(r.objective);
      iters = r.summary.iterations;
    }
    const double dt = SecondsSince(t0);
    // The error the simulator measures at the method's actuation.
    const KinematicsEval e = s.truth.Evaluate(c, false);
    const double err = e.ok ? (e.p.row(0) - s.targets.row(i)).norm() : -1.0;
    csv->RowStrings({method, std::to_string(i), std::to_string(t.x()), std::to_string(t.y()),
                     std::to_string(t.z()), std::to_string(err), std::to_string(pred),
                     std::to_string(1e3 * dt), std::to_string(iters)});
    if (err < 0) continue;
    ++ok;
    sum += err;
    worst = std::max(worst, err);
    time += dt;
    if (verbose && method == "numerical")
      std::fprintf(stderr, "  numerical target %d/%d: %.3f mm, %.2f s\n", i + 1, n, err, dt);
  }
  nlohmann::json row = {{"method", method},
                        {"label", kLabel.at(method)},
                        {"targets", n},
                        {"evaluated", ok},
                        {"ms_per_waypoint", ok ? 1e3 * time / ok : 0.0},
                        {"mean_err_mm", ok ? sum / ok : 0.0},
                        {"max_err_mm", worst},
                        {"mean_err_pct_width", ok ? 100.0 * sum / ok / s.width : 0.0},
                        {"thesis_ms_per_waypoint", kThesis.at(method).first},
                        {"thesis_mean_err_mm", kThesis.at(method).second}};
  row.update(extra);
  if (verbose)
    std::fprintf(stderr,
                 "  %-10s %3d targets: %.3f ms per waypoint, error mean %.3f mm, max %.3f mm "
                 "(thesis %.1f ms, %.2f mm)\n",
                 method.c_str(), ok, row["ms_per_waypoint"].get<double>(),
                 row["mean_err_mm"].get<double>(), worst, kThesis.at(method).first,
                 kThesis.at(method).second);
  return row;
}

}  // namespace

nlohmann::json RunLearnIkMethods(const Config& cfg, const std::string& dir, bool verbose) {
  const IkMethodsParams p = ReadIkMethodsParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  // Data and networks.
  nlohmann::json dinfo;
  const Dataset d = CachedDataset(p.spec, DatasetCacheDir(dir), verbose, &dinfo);
  if (verbose)
    std::fprintf(stderr, "  training N_fk, N_J, N_ik on %lld samples\n",
                 static_cast<long long>(d.inputs.rows()));
  const auto t_train = std::chrono::steady_clock::now();
  LearnedNets nets = CachedNets(d, dinfo["path"].get<std::string>(), p.spec.Tag(), p.nets,
                                NetsCacheDir(dir), verbose);
  const double train_s = SecondsSince(t_train);
  nets.Save(dir + "/nets");
  const double width = nets.info["dataset"]["workspace_width_mm"].get<double>();
  const double eps_mm = p.eps_pct / 100.0 * width;

  // The truth: the simulator the data came from; targets it reaches at seeded random actuations.
  std::unique_ptr<Kinematics> truth = MakeSpecKinematics(p.spec);
  const Eigen::MatrixX3d targets = TruthTargets(*truth, p.n_targets, p.seed);
  IkOptions io;
  io.method = IkMethod::kGaussNewton;
  io.lambda = eps_mm * eps_mm;
  io.max_iterations = p.max_iter;
  const IkMethodsSetup setup{p, d, nets, *truth, targets, width, io};
  CsvWriter csv(dir + "/targets.csv", {"method", "i", "target_x", "target_y", "target_z", "err_mm",
                                       "predicted_err_mm", "time_ms", "iterations"});
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& method : p.methods) rows.push_back(IkMethodRow(setup, method, &csv, verbose));
  const std::string measured_by = p.spec.twin.empty() ? "simulator" : "twin " + p.spec.twin;
  return {{"rows", rows},
          {"error_measured_by", measured_by},
          {"thesis_error_measured_by", "hardware"},
          {"dataset", dinfo},
          {"networks", nets.info},
          {"training_time_s", train_s},
          {"workspace_width_mm", width},
          {"lambda_mm", eps_mm},
          {"model_lambda_mm", p.net_eps_pct / 100.0 * width},
          {"errors_note",
           "every SoftKin error is measured by the " + measured_by +
               " at the method's actuation, on seeded random targets it reaches (not on the "
               "training grid); the thesis's errors (thesis_mean_err_mm) were measured on the "
               "physical robot, so the two are not the same measurement"}};
}

// ---- Fig. 5.10 / 5.12: the redundant finger_manipulator on a path, learned Jacobian vs direct IK
// ----
namespace {

/// A figure '8' (lemniscate of Gerono) of n waypoints in the plane of axes (au, av) around
/// centre: u = half_u sin t, v = half_v sin t cos t, t = 2 pi i / n.
Eigen::MatrixX3d EightPath(const nlohmann::json& spec, const std::string& where) {
  auto num = [&](const char* k) {
    if (!spec.contains(k) || !spec[k].is_number())
      throw std::invalid_argument(where + "." + k + ": expected a number");
    return spec[k].get<double>();
  };
  for (auto it = spec.begin(); it != spec.end(); ++it)
    if (it.key() != "name" && it.key() != "type" && it.key() != "center" && it.key() != "half_u" &&
        it.key() != "half_v" && it.key() != "axes" && it.key() != "n" && it.key() != "thesis")
      throw std::invalid_argument(
          where + "." + it.key() +
          ": unknown key (expected name, type, center, half_u, half_v, axes, n, thesis)");
  if (!spec.contains("center") || !spec["center"].is_array() || spec["center"].size() != 3)
    throw std::invalid_argument(where + ".center: expected [x, y, z] in mm");
  Eigen::Vector3d c;
  for (int d = 0; d < 3; ++d) c[d] = spec["center"][d].get<double>();
  int au = 1, av = 0;
  if (spec.contains("axes")) {
    au = spec["axes"][0].get<int>();
    av = spec["axes"][1].get<int>();
  }
  if (au < 0 || au > 2 || av < 0 || av > 2 || au == av)
    throw std::invalid_argument(where + ".axes: expected two different axes out of 0, 1, 2");
  if (!spec.contains("n") || !spec["n"].is_number_integer() || spec["n"].get<int>() < 4)
    throw std::invalid_argument(where + ".n: expected an integer >= 4");
  const int n = spec["n"].get<int>();
  const double hu = num("half_u"), hv = num("half_v");
  Eigen::MatrixX3d w(n, 3);
  for (int i = 0; i < n; ++i) {
    const double t = 2.0 * 3.14159265358979323846 * i / n;
    Eigen::Vector3d p = c;
    p[au] += hu * std::sin(t);
    p[av] += hv * std::sin(t) * std::cos(t);
    w.row(i) = p.transpose();
  }
  return w;
}

/// The keys of a learn_redundant_path config.
struct RedundantPathParams {
  DatasetSpec spec;
  nlohmann::json path_spec;
  double eps_pct = 0.1;  ///< lambda, % of the workspace width
  NetsFromDatasetOptions nets;
  int max_iter = 30;
};

RedundantPathParams ReadRedundantPathParams(const Config& cfg) {
  RedundantPathParams p;
  p.spec = SpecFromConfig(cfg, "dataset");
  p.path_spec = cfg.Raw("path");
  p.eps_pct = cfg.Number("lambda_pct_width", 0.1);
  NetsFromDatasetOptions& no = p.nets;
  no.fk_options.hidden = Layers(cfg, "fk_hidden", {30, 30, 30});
  no.jac_options.hidden = Layers(cfg, "jac_hidden", {30, 30});
  no.ik_options.hidden = Layers(cfg, "ik_hidden", {30, 30});
  no.fk_options.lm = no.jac_options.lm = no.ik_options.lm = ReadLm(cfg);
  no.split_seed = no.fk_options.split_seed = no.jac_options.split_seed = no.ik_options.split_seed =
      cfg.seed();
  p.max_iter = cfg.Int("max_iterations", 30);
  cfg.CheckNoUnknownKeys();
  if (!p.spec.jacobian)
    cfg.Fail("dataset.jacobian", "true (N_J is trained on the recorded Jacobians)");
  if (!p.path_spec.is_object()) cfg.Fail("path", "a path object");
  return p;
}

/// The actuations a method found along the path, and its time per waypoint.
struct MethodPath {
  std::vector<Eigen::VectorXd> cs;
  std::vector<double> times;
};

/// Measures a method's actuations with the truth (warm-started along the path): rows of
/// path_<method>.csv and the method's summary row.
nlohmann::json MeasurePath(const std::string& method, const MethodPath& mp,
                           const Eigen::MatrixX3d& waypoints, Kinematics& truth, double width,
                           const std::string& dir, bool verbose) {
  const std::vector<Eigen::VectorXd>& cs = mp.cs;
  const Eigen::VectorXd range = truth.upper() - truth.lower();
  std::vector<std::string> head = {"i", "target_x", "target_y", "target_z", "x",
                                   "y", "z",        "err_mm",   "time_ms",  "jump"};
  for (int a = 0; a < truth.num_actuators(); ++a) head.push_back("c" + std::to_string(a));
  CsvWriter csv(dir + "/path_" + method + ".csv", head);
  double sum = 0, worst = 0, time = 0, max_jump = 0, max_jump_frac = 0;
  int ok = 0;
  for (size_t i = 0; i < cs.size(); ++i) {
    const KinematicsEval e = truth.Evaluate(cs[i], false);  // warm-started along the path
    double jump = 0;
    if (i > 0) {
      jump = (cs[i] - cs[i - 1]).cwiseAbs().maxCoeff();
      max_jump = std::max(max_jump, jump);
      max_jump_frac =
          std::max(max_jump_frac, (cs[i] - cs[i - 1]).cwiseAbs().cwiseQuotient(range).maxCoeff());
    }
    if (!e.ok) continue;
    const Eigen::Vector3d p = e.p.row(0).transpose(), t = waypoints.row(i).transpose();
    const double err = (p - t).norm();
    std::vector<double> row = {
        static_cast<double>(i), t.x(), t.y(), t.z(), p.x(), p.y(), p.z(), err,
        1e3 * mp.times[i],      jump};
    for (int a = 0; a < cs[i].size(); ++a) row.push_back(cs[i][a]);
    csv.Row(row);
    ++ok;
    sum += err;
    worst = std::max(worst, err);
    time += mp.times[i];
    if (verbose && (i + 1) % 20 == 0)
      std::fprintf(stderr, "  %s: %zu/%zu waypoints measured by the simulator\n", method.c_str(),
                   i + 1, cs.size());
  }
  if (verbose)
    std::fprintf(stderr,
                 "  %s: error mean %.3f mm (%.3f %%), max %.3f mm (%.3f %%), largest jump %.3f "
                 "(%.1f %% of the range), %.3f ms per waypoint\n",
                 method.c_str(), ok ? sum / ok : 0.0, ok ? 100.0 * sum / ok / width : 0.0, worst,
                 100.0 * worst / width, max_jump, 100.0 * max_jump_frac,
                 ok ? 1e3 * time / ok : 0.0);
  return {{"method", method},
          {"waypoints", cs.size()},
          {"measured", ok},
          {"mean_err_mm", ok ? sum / ok : 0.0},
          {"max_err_mm", worst},
          {"mean_err_pct", ok ? 100.0 * sum / ok / width : 0.0},
          {"max_err_pct", 100.0 * worst / width},
          {"ms_per_waypoint", ok ? 1e3 * time / ok : 0.0},
          {"max_jump", max_jump},
          {"max_jump_fraction", max_jump_frac}};
}

/// The learned Jacobian IK (Algorithm 4 on the networks) along the waypoints.
MethodPath LearnedPath(NetKinematics& kin, const Eigen::MatrixX3d& waypoints,
                       const TrajectoryOptions& to) {
  MethodPath mp;
  const TrajectoryResult r = FollowTrajectory(kin, waypoints, to);
  for (const auto& w : r.waypoints) {
    mp.cs.push_back(w.c);
    mp.times.push_back(w.time_s);
  }
  return mp;
}

/// The direct-IK network N_ik at each waypoint.
MethodPath DirectPath(const LearnedNets& nets, const Eigen::MatrixX3d& waypoints) {
  MethodPath mp;
  for (int i = 0; i < waypoints.rows(); ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    mp.cs.push_back(DirectIk(nets, waypoints.row(i).transpose()));
    mp.times.push_back(SecondsSince(t0));
  }
  return mp;
}

}  // namespace

nlohmann::json RunLearnRedundantPath(const Config& cfg, const std::string& dir, bool verbose) {
  const RedundantPathParams p = ReadRedundantPathParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  nlohmann::json dinfo;
  const Dataset d = CachedDataset(p.spec, DatasetCacheDir(dir), verbose, &dinfo);
  LearnedNets nets = CachedNets(d, dinfo["path"].get<std::string>(), p.spec.Tag(), p.nets,
                                NetsCacheDir(dir), verbose);
  const double width = nets.info["dataset"]["workspace_width_mm"].get<double>();
  NetKinematics kin(nets, JacobianSource::kNetwork, false);
  SamplingOptions so;
  so.samples_per_axis = 5;
  const ConfigurationSamples samples = SampleConfigurationSpace(kin, nets.points.front(), so);
  Eigen::MatrixX3d waypoints;
  nlohmann::json pinfo = p.path_spec;
  if (p.path_spec.value("type", "") == "eight") {
    waypoints = EightPath(p.path_spec, cfg.path() + ": path");
  } else {
    const IkPath path = MakeIkPath(p.path_spec, cfg.path() + ": path", kin, samples);
    waypoints = path.waypoints;
    pinfo = path.info;
  }
  std::unique_ptr<Kinematics> truth = MakeSpecKinematics(p.spec);

  TrajectoryOptions to;
  to.point = nets.points.front();
  to.ik.method = IkMethod::kGaussNewton;
  to.ik.lambda = std::pow(p.eps_pct / 100.0 * width, 2);
  to.ik.max_iterations = p.max_iter;
  to.sampling = so;
  nlohmann::json rows = nlohmann::json::array();
  for (const std::string method : {"learned", "direct"}) {
    const MethodPath mp =
        method == "learned" ? LearnedPath(kin, waypoints, to) : DirectPath(nets, waypoints);
    rows.push_back(MeasurePath(method, mp, waypoints, *truth, width, dir, verbose));
  }
  return {{"rows", rows},
          {"path", pinfo},
          {"dataset", dinfo},
          {"networks", nets.info},
          {"workspace_width_mm", width},
          {"errors_note", "errors are measured by the simulator at each method's actuation"},
          {"thesis", p.path_spec.value("thesis", nlohmann::json::object())}};
}

}  // namespace softkin
