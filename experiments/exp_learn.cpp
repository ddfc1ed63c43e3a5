// Thesis Chapter 5 on three_chamber and finger_manipulator: the network architecture sweep
// (Fig. 5.5), the IK methods compared (Table 5.1) and, with ik/pcc_chamber_kinematics, the
// simulator against the analytical PCC model as the data source of sim-to-real (Fig. 5.14).
#include "softkin/experiments/ik_config.hpp"
#include "softkin/experiments/learn_common.hpp"
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/ik/ik_solver.hpp"
#include "softkin/ik/objectives.hpp"
#include "softkin/ik/pcc_chamber_kinematics.hpp"
#include "softkin/ik/trajectory.hpp"
#include "softkin/learn/net_kinematics.hpp"
#include "softkin/learn/train_nets.hpp"
#include "softkin/learn/twin.hpp"
#include "softkin/ik/trajectory_io.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>

namespace softkin {

namespace {

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
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

/// The PCC baseline of three_chamber calibrated on a dataset's tip positions (gain, chamber
/// offset and cap length fitted; the thesis calibrates its PCC model on measurements likewise).
std::unique_ptr<PccChamberKinematics> FitPccBaseline(const Dataset& d, nlohmann::json* info) {
  if (d.num_actuators != 3)
    throw std::invalid_argument("the PCC baseline models three_chamber (3 actuators), the dataset has " +
                                std::to_string(d.num_actuators));
  PccChamberParams start;
  if (d.meta.is_object() && d.meta.contains("config") && d.meta["config"].contains("actuator_bounds")) {
    start.lower = d.meta["config"]["actuator_bounds"][0][0].get<double>();
    start.upper = d.meta["config"]["actuator_bounds"][0][1].get<double>();
    start.rest = start.lower;
  }
  const PccFitResult f = FitPccChamber(d.inputs, d.positions.leftCols(3), start);
  if (info)
    *info = {{"gain", f.params.gain}, {"offset_mm", f.params.offset}, {"cap_mm", f.params.cap},
             {"fit_rms_mm", f.rms_mm}, {"start_rms_mm", f.rms_start_mm}, {"fit_samples", d.inputs.rows()}};
  return std::make_unique<PccChamberKinematics>(f.params);
}

}  // namespace

// ---- Fig. 5.5: test error against the number of hidden layers h and neurons per layer b ----
nlohmann::json RunLearnArchitecture(const Config& cfg, const std::string& dir, bool verbose) {
  const nlohmann::json robots = cfg.Raw("datasets");
  const std::vector<int> layers = cfg.IntList("layers", {1, 2, 3, 4});
  const std::vector<int> neurons = cfg.IntList("neurons", {10, 20, 35, 50});
  const bool jac = cfg.Bool("jacobian_network", true);
  const std::vector<int> jac_layers = cfg.IntList("jac_layers", layers);
  const std::vector<int> jac_neurons = cfg.IntList("jac_neurons", neurons);
  const LmOptions lm = ReadLm(cfg);
  cfg.CheckNoUnknownKeys();
  if (!robots.is_array() || robots.empty()) cfg.Fail("datasets", "a non-empty array of dataset objects");
  for (int h : layers)
    if (h < 1 || h > 8) cfg.Fail("layers", "hidden-layer counts in [1, 8]");
  for (int b : neurons)
    if (b < 1) cfg.Fail("neurons", "neuron counts >= 1");

  // Resume: every finished network is appended to architecture.jsonl with the settings that
  // produced it; a rerun reuses the rows whose settings match and trains only the others.
  ResumeJournal journal(dir + "/architecture.jsonl");

  CsvWriter csv(dir + "/architecture.csv",
                {"robot", "net", "h", "b", "parameters", "test_mean", "test_max", "test_mean_pct",
                 "test_max_pct", "epochs", "time_s", "termination"});
  nlohmann::json rows = nlohmann::json::array(), datasets = nlohmann::json::array();
  for (size_t r = 0; r < robots.size(); ++r) {
    const DatasetSpec spec = ParseDatasetSpec(robots[r], cfg.path() + ": datasets[" + std::to_string(r) + "]");
    nlohmann::json dinfo;
    const Dataset d = CachedDataset(spec, DatasetCacheDir(dir), verbose, &dinfo);
    const SampleSet pos = PositionSamples(d);
    const TrainTestSets split = SplitTrainTest(pos, cfg.seed());
    const double width = WorkspaceWidth(pos.Y);
    dinfo["workspace_width_mm"] = width;
    datasets.push_back(dinfo);
    const bool with_j = jac && d.jacobians.cols() > 0;
    SampleSet js;
    if (with_j) js = JacobianSamples(d);
    // The Jacobian's error is quoted as the tip displacement error of a step of 1/10 of the
    // actuation range (the finite-difference step of Sec. 5.2.1), as % of the workspace width.
    double range = 0;
    for (const auto& b : d.meta["config"]["actuator_bounds"]) range = std::max(range, b[1].get<double>() - b[0].get<double>());
    for (const std::string net : {"fk", "jac"}) {
      if (net == "jac" && !with_j) continue;
      const SampleSet& s = net == "fk" ? pos : js;
      const SampleSet train = SelectRows(s, split.train_rows), test = SelectRows(s, split.test_rows);
      for (int h : net == "fk" ? layers : jac_layers)
        for (int b : net == "fk" ? neurons : jac_neurons) {
          const nlohmann::json key = {{"dataset", robots[r]}, {"net", net}, {"h", h}, {"b", b},
                                      {"seed", cfg.seed()}, {"epochs", lm.max_epochs},
                                      {"max_train_time_s", lm.max_time_s}};
          const double scale = net == "fk" ? 100.0 / width : 100.0 * 0.1 * range / width;
          const nlohmann::json* done = journal.Reuse(key);
          nlohmann::json row;
          if (done) {
            row = *done;
          } else {
            NetTrainOptions o;
            o.hidden.assign(h, b);
            o.lm = lm;
            o.split_seed = cfg.seed();
            const NetTrainResult t = TrainNet(train, test, o);
            row = {{"robot", spec.robot}, {"net", net}, {"h", h}, {"b", b},
                   {"parameters", t.net.num_parameters()},
                   {"test_mean", t.test.mean_dist}, {"test_max", t.test.max_dist},
                   {"test_mean_pct", scale * t.test.mean_dist},
                   {"test_max_pct", scale * t.test.max_dist},
                   {"relative", t.test.relative}, {"epochs", t.lm.epochs},
                   {"time_s", t.lm.total_time_s},
                   {"termination", LmTerminationToString(t.lm.termination)}};
            journal.Append(key, row);
          }
          csv.RowJson(row);
          rows.push_back(row);
          if (verbose)
            std::fprintf(stderr, "  %s N_%s h=%d b=%d: test mean %.4f%% (max %.4f%%) of %.1f mm, %d epochs, %.1f s%s\n",
                         spec.robot.c_str(), net.c_str(), h, b, row["test_mean_pct"].get<double>(),
                         row["test_max_pct"].get<double>(), width, row["epochs"].get<int>(),
                         row["time_s"].get<double>(), done ? " (resumed from architecture.jsonl)" : "");
        }
    }
  }
  return {{"rows", rows}, {"datasets", datasets}, {"resumed_rows", journal.reused()},
          {"jacobian_error_note",
           "N_J errors are |dJ| x (range/10) (the tip error of a 1/10-range step), as % of the workspace width"},
          {"thesis", {{"three_chamber", {{"fk", {{"h", 2}, {"b", 35}, {"test_mean_mm", 0.17}, {"test_mean_pct", 0.34}}}}},
                      {"finger_manipulator", {{"fk", {{"h", 3}, {"b", 30}, {"test_mean_pct", 0.58}}},
                                              {"jac", {{"h", 2}, {"b", 64}}}}}}}};
}

// ---- Table 5.1: IK time per waypoint and error, measured by the simulator, per method ----
nlohmann::json RunLearnIkMethods(const Config& cfg, const std::string& dir, bool verbose) {
  const DatasetSpec spec = SpecFromConfig(cfg, "dataset");
  NetsFromDatasetOptions no;
  no.fk_options.hidden = Layers(cfg, "fk_hidden", {35, 35});
  no.jac_options.hidden = Layers(cfg, "jac_hidden", {64, 64});
  no.ik_options.hidden = Layers(cfg, "ik_hidden", {35, 35});
  no.fk_options.lm = no.jac_options.lm = no.ik_options.lm = ReadLm(cfg);
  no.split_seed = no.fk_options.split_seed = no.jac_options.split_seed = no.ik_options.split_seed = cfg.seed();
  const int n_targets = cfg.Int("targets", 50);
  const int n_numerical = cfg.Int("numerical_targets", 5);
  const double eps_pct = cfg.Number("lambda_pct_width", 0.1);
  const double net_eps_pct = cfg.Number("network_lambda_pct_width", 0.01);
  const int max_iter = cfg.Int("max_iterations", 30);
  const std::vector<std::string> methods =
      cfg.StringList("methods", {"pcc", "numerical", "direct", "learned"});
  cfg.CheckNoUnknownKeys();
  if (!spec.jacobian) cfg.Fail("dataset.jacobian", "true (N_J is trained on the recorded Jacobians)");
  if (n_targets < 1) cfg.Fail("targets", "an integer >= 1");
  if (n_numerical < 0) cfg.Fail("numerical_targets", "an integer >= 0");
  if (!(eps_pct > 0)) cfg.Fail("lambda_pct_width", "a percentage > 0");
  if (!(net_eps_pct > 0)) cfg.Fail("network_lambda_pct_width", "a percentage > 0");
  for (const auto& m : methods)
    if (m != "pcc" && m != "numerical" && m != "direct" && m != "learned")
      cfg.Fail("methods", "names out of pcc, numerical, direct, learned ('" + m + "' is not)");

  // Data and networks.
  nlohmann::json dinfo;
  const Dataset d = CachedDataset(spec, DatasetCacheDir(dir), verbose, &dinfo);
  if (verbose) std::fprintf(stderr, "  training N_fk, N_J, N_ik on %lld samples\n", static_cast<long long>(d.inputs.rows()));
  const auto t_train = std::chrono::steady_clock::now();
  LearnedNets nets = CachedNets(d, dinfo["path"].get<std::string>(), spec.Tag(), no, NetsCacheDir(dir), verbose);
  const double train_s = Seconds(t_train);
  nets.Save(dir + "/nets");
  const double width = nets.info["dataset"]["workspace_width_mm"].get<double>();
  const double eps_mm = eps_pct / 100.0 * width;

  // The truth: the simulator the data came from; targets it reaches at seeded random actuations.
  std::unique_ptr<Kinematics> truth = MakeSpecKinematics(spec);
  const int m = truth->num_actuators();
  std::mt19937_64 rng(cfg.seed());
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd c_true(n_targets, m);
  Eigen::MatrixX3d targets(n_targets, 3);
  for (int i = 0; i < n_targets; ++i) {
    for (int a = 0; a < m; ++a)
      c_true(i, a) = truth->lower()[a] + u(rng) * (truth->upper()[a] - truth->lower()[a]);
    const KinematicsEval e = truth->Evaluate(c_true.row(i).transpose(), false);
    if (!e.ok) throw std::runtime_error("the simulator failed at a target actuation: " + e.message);
    targets.row(i) = e.p.row(0);
  }
  auto true_error = [&](const Eigen::VectorXd& c, int i) {
    const KinematicsEval e = truth->Evaluate(c, false);
    return e.ok ? (e.p.row(0) - targets.row(i)).norm() : -1.0;
  };

  IkOptions io;
  io.method = IkMethod::kGaussNewton;
  io.lambda = eps_mm * eps_mm;
  io.max_iterations = max_iter;
  CsvWriter csv(dir + "/targets.csv", {"method", "i", "target_x", "target_y", "target_z", "err_mm",
                                        "predicted_err_mm", "time_ms", "iterations"});
  nlohmann::json rows = nlohmann::json::array();
  const std::map<std::string, std::pair<double, double>> thesis = {
      {"pcc", {12.6, 8.2}}, {"numerical", {138000.0, 4.7}}, {"direct", {3.2, 0.97}}, {"learned", {28.0, 0.78}}};
  const std::map<std::string, std::string> label = {
      {"pcc", "PCC analytical"}, {"numerical", "simulation-in-the-loop (implicit J)"},
      {"direct", "direct IK learning"}, {"learned", "learned Jacobian"}};
  for (const auto& method : methods) {
    std::unique_ptr<Kinematics> model;
    nlohmann::json extra = nlohmann::json::object();
    if (method == "learned") {
      model = std::make_unique<NetKinematics>(nets, JacobianSource::kNetwork, false);
    } else if (method == "numerical") {
      model = MakeSpecKinematics(spec);
    } else if (method == "pcc") {
      nlohmann::json fit;
      model = FitPccBaseline(d, &fit);
      extra["pcc_fit"] = fit;
    }
    ConfigurationSamples samples;
    if (model) {
      SamplingOptions so;
      so.samples_per_axis = 5;
      samples = SampleConfigurationSpace(*model, model->point_names().front(), so);
      extra["sampling_time_s"] = samples.time_s;
    }
    const int n = method == "numerical" ? std::min(n_numerical, n_targets) : n_targets;
    double sum = 0, worst = 0, time = 0;
    int ok = 0;
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d t = targets.row(i).transpose();
      Eigen::VectorXd c;
      double pred = 0;
      int iters = 0;
      const auto t0 = std::chrono::steady_clock::now();
      if (method == "direct") {
        c = DirectIk(nets, t);
      } else {
        const Eigen::VectorXd c0 = samples.c.row(ClosestSample(samples, t)).transpose();
        PointTrackingObjective obj(model->point_names(), model->point_names().front(), t);
        IkOptions mo = io;
        if (method != "numerical") mo.lambda = std::pow(net_eps_pct / 100.0 * width, 2);  // models are cheap
        const IkResult r = SolveIk(*model, obj, c0, mo);
        c = r.c;
        pred = std::sqrt(r.objective);
        iters = r.summary.iterations;
      }
      const double dt = Seconds(t0);
      const double err = true_error(c, i);
      csv.RowStrings({method, std::to_string(i), std::to_string(t.x()), std::to_string(t.y()),
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
    nlohmann::json row = {{"method", method}, {"label", label.at(method)}, {"targets", n},
                          {"evaluated", ok},
                          {"ms_per_waypoint", ok ? 1e3 * time / ok : 0.0},
                          {"mean_err_mm", ok ? sum / ok : 0.0}, {"max_err_mm", worst},
                          {"mean_err_pct_width", ok ? 100.0 * sum / ok / width : 0.0},
                          {"thesis_ms_per_waypoint", thesis.at(method).first},
                          {"thesis_mean_err_mm", thesis.at(method).second}};
    row.update(extra);
    rows.push_back(row);
    if (verbose)
      std::fprintf(stderr, "  %-10s %3d targets: %.3f ms per waypoint, error mean %.3f mm, max %.3f mm (thesis %.1f ms, %.2f mm)\n",
                   method.c_str(), ok, row["ms_per_waypoint"].get<double>(), row["mean_err_mm"].get<double>(),
                   worst, thesis.at(method).first, thesis.at(method).second);
  }
  return {{"rows", rows}, {"dataset", dinfo}, {"networks", nets.info}, {"training_time_s", train_s},
          {"workspace_width_mm", width}, {"lambda_mm", eps_mm},
          {"model_lambda_mm", net_eps_pct / 100.0 * width},
          {"errors_note", "every error is measured by the simulator at the method's actuation, on seeded random targets the simulator reaches (not on the training grid)"}};
}

// ---- Fig. 5.14: sim-to-real on networks learned from the simulator or from the PCC model ----
nlohmann::json RunLearnDataSource(const Config& cfg, const std::string& dir, bool verbose) {
  const DatasetSpec sim_spec = SpecFromConfig(cfg, "dataset");
  const DatasetSpec twin_spec = SpecFromConfig(cfg, "twin_dataset");
  const std::vector<int> sizes = cfg.IntList("s2r_samples", {50, 100, 200, 300, 500, 1000});
  const double eta = cfg.Number("eta", 0.25);
  const int test_n = cfg.Int("test_samples", 200);
  const std::vector<int> fk_hidden = Layers(cfg, "fk_hidden", {35, 35});
  const LmOptions lm = ReadLm(cfg);
  cfg.CheckNoUnknownKeys();
  if (twin_spec.twin.empty()) cfg.Fail("twin_dataset", "a dataset object with \"twin\"");
  if (twin_spec.robot != "three_chamber" || sim_spec.robot != "three_chamber")
    cfg.Fail("dataset", "three_chamber datasets (the PCC model is of three_chamber)");
  if (!(eta > 0)) cfg.Fail("eta", "a number > 0");
  if (test_n < 10) cfg.Fail("test_samples", "an integer >= 10");
  for (int s : sizes)
    if (s < 10) cfg.Fail("s2r_samples", "sample counts >= 10");

  nlohmann::json sim_info, twin_info;
  const Dataset sim = CachedDataset(sim_spec, DatasetCacheDir(dir), verbose, &sim_info);
  const Dataset twin = CachedDataset(twin_spec, DatasetCacheDir(dir), verbose, &twin_info);
  const int max_train = *std::max_element(sizes.begin(), sizes.end());
  if (twin.inputs.rows() < max_train + test_n)
    cfg.Fail("twin_dataset", "at least max(s2r_samples) + test_samples = " + std::to_string(max_train + test_n) +
                                 " twin samples (it has " + std::to_string(twin.inputs.rows()) + ")");
  // The twin's last test_n samples are the test set; the s2r training sets are nested prefixes.
  const Eigen::MatrixXd c_test = twin.inputs.bottomRows(test_n), p_test = twin.positions.bottomRows(test_n).leftCols(3);
  const double width = WorkspaceWidth(twin.positions.leftCols(3));

  // The analytical data: the PCC model calibrated on the simulator's data, sampled on the same
  // actuations, so both networks see the same inputs.
  nlohmann::json fit;
  const std::unique_ptr<PccChamberKinematics> pcc = FitPccBaseline(sim, &fit);
  Dataset ana = sim;
  ana.jacobians.resize(ana.inputs.rows(), 0);
  ana.point_names = {"tip"};
  ana.positions.resize(ana.inputs.rows(), 3);
  for (int i = 0; i < ana.inputs.rows(); ++i)
    ana.positions.row(i) = PccChamberKinematics::Tip(pcc->params(), ana.inputs.row(i).transpose()).transpose();
  Dataset simd = sim;
  simd.jacobians.resize(simd.inputs.rows(), 0);
  simd.positions = sim.positions.leftCols(3).eval();
  simd.point_names = {"tip"};

  CsvWriter csv(dir + "/errors.csv", {"source", "ts", "sample", "err_mm", "err_pct"});
  nlohmann::json rows = nlohmann::json::array(), sources = nlohmann::json::array();
  for (const std::string source : {"simulator", "pcc"}) {
    NetsFromDatasetOptions o;
    o.jac = o.ik = false;
    o.fk_options.hidden = fk_hidden;
    o.fk_options.lm = lm;
    o.split_seed = o.fk_options.split_seed = cfg.seed();
    const LearnedNets base = CachedNets(source == "simulator" ? simd : ana, source,
                                        (source == "simulator" ? "" : "pccfit-") + sim_spec.Tag(), o,
                                        NetsCacheDir(dir), verbose);
    // Without s2r: N_fk against the twin.
    const Eigen::MatrixXd pred0 = base.fk.ForwardBatch(c_test);
    const double err0 = (pred0 - p_test).rowwise().norm().mean();
    sources.push_back({{"source", source}, {"fk_test_pct_width", base.info["fk"]["test_mean_pct_width"]},
                       {"twin_mean_err_without_s2r_mm", err0}});
    if (verbose) std::fprintf(stderr, "  N_fk from %s: %.3f mm mean error on the twin without s2r\n", source.c_str(), err0);
    for (int ts : sizes) {
      LearnedNets nets = base;
      Dataset part = twin;
      part.inputs = twin.inputs.topRows(ts);
      part.positions = twin.positions.topRows(ts).leftCols(3);
      part.jacobians.resize(ts, 0);
      part.point_names = {"tip"};
      // All ts samples train (the fixed held-out twin test set measures); 15 % of them validate.
      NetTrainOptions so;
      so.hidden = {S2rNeurons(eta, ts)};
      so.lm = lm;
      so.split_seed = cfg.seed();
      const NetTrainResult r = TrainNet(S2rSamples(nets.fk, part.inputs, part.positions), SampleSet{}, so);
      const Eigen::MatrixXd pred = r.net.ForwardBatch(nets.fk.ForwardBatch(c_test));
      const Eigen::VectorXd e = (pred - p_test).rowwise().norm();
      int within = 0;
      for (int i = 0; i < e.size(); ++i) {
        within += e[i] <= 0.01 * width;
        csv.RowStrings({source, std::to_string(ts), std::to_string(i), std::to_string(e[i]),
                        std::to_string(100.0 * e[i] / width)});
      }
      rows.push_back({{"source", source}, {"ts", ts}, {"s2r_neurons", so.hidden[0]},
                      {"mean_err_mm", e.mean()}, {"max_err_mm", e.maxCoeff()},
                      {"mean_err_pct", 100.0 * e.mean() / width},
                      {"within_1pct", static_cast<double>(within) / e.size()}});
      if (verbose)
        std::fprintf(stderr, "  %s + s2r(TS#=%d): mean %.3f mm (%.2f %%), %.0f %% of test points within 1 %%\n",
                     source.c_str(), ts, e.mean(), 100.0 * e.mean() / width, 100.0 * within / e.size());
    }
  }
  return {{"rows", rows}, {"sources", sources}, {"pcc_fit", fit}, {"dataset", sim_info},
          {"twin_dataset", twin_info}, {"twin_label", "twin data (simulated hardware, docs/twins.md)"},
          {"workspace_width_mm", width}, {"test_samples", test_n}, {"eta", eta},
          {"thesis", {{"within_1pct_at_ts", {{"simulator", 300}, {"pcc", 1000}}}}}};
}

namespace {

std::vector<DatasetSpec> TwinSpecs(const Config& cfg, const std::string& key) {
  const nlohmann::json j = cfg.Raw(key);
  if (!j.is_array() || j.empty()) cfg.Fail(key, "a non-empty array of twin dataset objects {\"twin\", ...}");
  std::vector<DatasetSpec> out;
  for (size_t i = 0; i < j.size(); ++i) {
    out.push_back(ParseDatasetSpec(j[i], cfg.path() + ": " + key + "[" + std::to_string(i) + "]"));
    if (out.back().twin.empty()) cfg.Fail(key + "[" + std::to_string(i) + "]", "a dataset object with \"twin\"");
  }
  return out;
}

/// Mean tip distance between rows of A and B (first 3 columns).
double MeanDist(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B) {
  return (A.leftCols(3) - B.leftCols(3)).rowwise().norm().mean();
}

}  // namespace

// ---- Fig. 5.6: s2r error against eta and against the number of twin samples ----
nlohmann::json RunLearnS2rSweep(const Config& cfg, const std::string& dir, bool verbose) {
  const DatasetSpec sim_spec = SpecFromConfig(cfg, "dataset");
  const std::vector<DatasetSpec> twins = TwinSpecs(cfg, "twin_datasets");
  const std::vector<double> etas = cfg.NumberList("etas", {1.0 / 16, 1.0 / 8, 0.25, 0.5, 1.0});
  const std::vector<int> sizes = cfg.IntList("sizes", {64, 125, 216, 343, 620});
  const int eta_size = cfg.Int("eta_sweep_samples", 343);
  const double size_eta = cfg.Number("size_sweep_eta", 0.25);
  const int test_n = cfg.Int("test_samples", 200);
  const std::vector<int> fk_hidden = Layers(cfg, "fk_hidden", {35, 35});
  const LmOptions lm = ReadLm(cfg);
  cfg.CheckNoUnknownKeys();
  for (double e : etas)
    if (!(e > 0)) cfg.Fail("etas", "numbers > 0");
  int need = eta_size;
  for (int n : sizes) {
    if (n < 10) cfg.Fail("sizes", "sample counts >= 10");
    need = std::max(need, n);
  }
  nlohmann::json sim_info;
  const Dataset sim = CachedDataset(sim_spec, DatasetCacheDir(dir), verbose, &sim_info);
  NetsFromDatasetOptions o;
  o.jac = o.ik = false;
  o.fk_options.hidden = fk_hidden;
  o.fk_options.lm = lm;
  o.split_seed = o.fk_options.split_seed = cfg.seed();
  const LearnedNets nets = CachedNets(sim, sim_info["path"].get<std::string>(), sim_spec.Tag(), o,
                                     NetsCacheDir(dir), verbose);

  CsvWriter csv(dir + "/s2r_sweep.csv", {"twin", "sweep", "eta", "samples", "neurons", "train_mm",
                                         "test_mm", "without_mm"});
  nlohmann::json rows = nlohmann::json::array(), tinfo = nlohmann::json::array();
  for (const DatasetSpec& ts : twins) {
    nlohmann::json info;
    const Dataset twin = CachedDataset(ts, DatasetCacheDir(dir), verbose, &info);
    if (twin.inputs.rows() < need + test_n)
      cfg.Fail("twin_datasets", "at least " + std::to_string(need + test_n) + " samples per twin (" + ts.twin +
                                    " has " + std::to_string(twin.inputs.rows()) + ")");
    tinfo.push_back(info);
    const SampleSet all = S2rSamples(nets.fk, twin.inputs, twin.positions.leftCols(3));
    const int n = all.size();
    std::vector<int> test_rows, train_rows;
    for (int i = n - test_n; i < n; ++i) test_rows.push_back(i);
    const SampleSet test = SelectRows(all, test_rows);
    const double without = MeanDist(test.X, test.Y);
    auto run = [&](const std::string& sweep, double eta, int samples) {
      std::vector<int> rows_k;
      for (int i = 0; i < samples; ++i) rows_k.push_back(i);
      NetTrainOptions so;
      so.hidden = {S2rNeurons(eta, samples)};
      so.lm = lm;
      so.split_seed = cfg.seed();
      const NetTrainResult r = TrainNet(SelectRows(all, rows_k), test, so);
      rows.push_back({{"twin", ts.twin}, {"sweep", sweep}, {"eta", eta}, {"samples", samples},
                      {"neurons", so.hidden[0]}, {"train_mm", r.train.mean_dist},
                      {"test_mm", r.test.mean_dist}, {"test_max_mm", r.test.max_dist},
                      {"without_mm", without}});
      csv.RowStrings({ts.twin, sweep, std::to_string(eta), std::to_string(samples),
                      std::to_string(so.hidden[0]), std::to_string(r.train.mean_dist),
                      std::to_string(r.test.mean_dist), std::to_string(without)});
      if (verbose)
        std::fprintf(stderr, "  %s eta %.4g, %d samples (%d neurons): train %.3f mm, test %.3f mm (without s2r %.3f mm)\n",
                     ts.twin.c_str(), eta, samples, so.hidden[0], r.train.mean_dist, r.test.mean_dist, without);
    };
    for (double eta : etas) run("eta", eta, eta_size);
    for (int size : sizes) run("samples", size_eta, size);
  }
  return {{"rows", rows}, {"dataset", sim_info}, {"twin_datasets", tinfo},
          {"fk", nets.info["fk"]}, {"twin_label", "twin data (simulated hardware, docs/twins.md)"},
          {"thesis", {{"eta", 0.25}, {"twin_samples", {343, 620}}}}};
}

// ---- Fig. 5.7 / 5.8: path following on the twins, learned Jacobian IK with and without s2r ----
nlohmann::json RunLearnS2rPaths(const Config& cfg, const std::string& dir, bool verbose) {
  const DatasetSpec sim_spec = SpecFromConfig(cfg, "dataset");
  const std::vector<DatasetSpec> twins = TwinSpecs(cfg, "twin_datasets");
  const nlohmann::json path_spec = cfg.Raw("path");
  const double eta = cfg.Number("eta", 0.25);
  const double eps_pct = cfg.Number("lambda_pct_width", 0.1);
  NetsFromDatasetOptions no;
  no.ik = false;
  no.fk_options.hidden = Layers(cfg, "fk_hidden", {35, 35});
  no.jac_options.hidden = Layers(cfg, "jac_hidden", {64, 64});
  no.fk_options.lm = no.jac_options.lm = ReadLm(cfg);
  no.split_seed = no.fk_options.split_seed = no.jac_options.split_seed = cfg.seed();
  const LmOptions lm = no.fk_options.lm;
  cfg.CheckNoUnknownKeys();
  if (!sim_spec.jacobian) cfg.Fail("dataset.jacobian", "true (N_J is trained on the recorded Jacobians)");
  if (!(eta > 0)) cfg.Fail("eta", "a number > 0");
  if (!(eps_pct > 0)) cfg.Fail("lambda_pct_width", "a percentage > 0");

  nlohmann::json sim_info;
  const Dataset sim = CachedDataset(sim_spec, DatasetCacheDir(dir), verbose, &sim_info);
  const LearnedNets nominal = CachedNets(sim, sim_info["path"].get<std::string>(), sim_spec.Tag(), no,
                                        NetsCacheDir(dir), verbose);
  const double width = nominal.info["dataset"]["workspace_width_mm"].get<double>();
  NetKinematics nominal_kin(nominal, JacobianSource::kNetwork, false);
  SamplingOptions so;
  so.samples_per_axis = 5;
  const ConfigurationSamples samples = SampleConfigurationSpace(nominal_kin, "tip", so);
  const IkPath path = MakeIkPath(path_spec, cfg.path() + ": path", nominal_kin, samples);

  TrajectoryOptions to;
  to.ik.method = IkMethod::kGaussNewton;
  to.ik.lambda = std::pow(eps_pct / 100.0 * width, 2);
  to.ik.max_iterations = 30;
  to.sampling = so;

  nlohmann::json rows = nlohmann::json::array(), tinfo = nlohmann::json::array();
  for (const DatasetSpec& ts : twins) {
    nlohmann::json info;
    const Dataset twin = CachedDataset(ts, DatasetCacheDir(dir), verbose, &info);
    tinfo.push_back(info);
    LearnedNets nets = nominal;
    TrainS2r(nets, twin, info["path"].get<std::string>(), eta, lm, cfg.seed());
    // The twin measures the answer without its measurement noise (its systematic gap remains).
    TwinOptions mo;
    mo.res = ts.res;
    mo.noise = false;
    mo.gradient_tolerance = ts.gradient_tolerance;
    TwinKinematics measure(GetTwinSpec(ts.twin), mo);
    for (bool with_s2r : {false, true}) {
      NetKinematics kin(nets, JacobianSource::kNetwork, with_s2r);
      const TrajectoryResult r = FollowTrajectory(kin, path.waypoints, to);
      const std::string tag = ts.twin.substr(ts.twin.find('/') + 1) + (with_s2r ? "_s2r" : "_nominal");
      CsvWriter csv(dir + "/path_" + tag + ".csv", {"i", "target_x", "target_y", "target_z", "x", "y", "z",
                                                     "err_mm", "predicted_err_mm", "time_ms"});
      double sum = 0, worst = 0, time = 0;
      int ok = 0;
      for (const WaypointResult& w : r.waypoints) {
        const KinematicsEval e = measure.Evaluate(w.c, false);
        if (!e.ok) continue;
        const Eigen::Vector3d p = e.p.row(0).transpose();
        const double err = (p - w.target).norm();
        csv.Row({static_cast<double>(w.index), w.target.x(), w.target.y(), w.target.z(), p.x(), p.y(), p.z(),
                 err, w.error_mm, 1e3 * w.time_s});
        ++ok;
        sum += err;
        worst = std::max(worst, err);
        time += w.time_s;
      }
      rows.push_back({{"twin", ts.twin}, {"s2r", with_s2r}, {"waypoints", path.waypoints.rows()},
                      {"measured", ok}, {"mean_err_mm", ok ? sum / ok : 0.0}, {"max_err_mm", worst},
                      {"ms_per_waypoint", ok ? 1e3 * time / ok : 0.0}, {"max_jump", r.max_jump},
                      {"csv", "path_" + tag + ".csv"}});
      if (verbose)
        std::fprintf(stderr, "  %s %s: error on the twin mean %.3f mm, max %.3f mm, %.2f ms per waypoint\n",
                     ts.twin.c_str(), with_s2r ? "with s2r" : "without s2r", ok ? sum / ok : 0.0, worst,
                     ok ? 1e3 * time / ok : 0.0);
    }
  }
  return {{"rows", rows}, {"path", path.info}, {"thesis", path.thesis}, {"dataset", sim_info},
          {"twin_datasets", tinfo}, {"networks", nominal.info}, {"workspace_width_mm", width},
          {"twin_label", "errors are measured on the twin (simulated hardware, docs/twins.md) without its measurement noise"}};
}

// ---- Fig. 5.10 / 5.12: the redundant finger_manipulator on a path, learned Jacobian vs direct IK ----
namespace {

/// A figure '8' (lemniscate of Gerono) of n waypoints in the plane of axes (au, av) around
/// centre: u = half_u sin t, v = half_v sin t cos t, t = 2 pi i / n.
Eigen::MatrixX3d EightPath(const nlohmann::json& spec, const std::string& where) {
  auto num = [&](const char* k) {
    if (!spec.contains(k) || !spec[k].is_number()) throw std::invalid_argument(where + "." + k + ": expected a number");
    return spec[k].get<double>();
  };
  for (auto it = spec.begin(); it != spec.end(); ++it)
    if (it.key() != "name" && it.key() != "type" && it.key() != "center" && it.key() != "half_u" &&
        it.key() != "half_v" && it.key() != "axes" && it.key() != "n" && it.key() != "thesis")
      throw std::invalid_argument(where + "." + it.key() + ": unknown key (expected name, type, center, half_u, half_v, axes, n, thesis)");
  if (!spec.contains("center") || !spec["center"].is_array() || spec["center"].size() != 3)
    throw std::invalid_argument(where + ".center: expected [x, y, z] in mm");
  Eigen::Vector3d c;
  for (int d = 0; d < 3; ++d) c[d] = spec["center"][d].get<double>();
  int au = 1, av = 0;
  if (spec.contains("axes")) {
    au = spec["axes"][0].get<int>();
    av = spec["axes"][1].get<int>();
  }
  if (au < 0 || au > 2 || av < 0 || av > 2 || au == av) throw std::invalid_argument(where + ".axes: expected two different axes out of 0, 1, 2");
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

}  // namespace

nlohmann::json RunLearnRedundantPath(const Config& cfg, const std::string& dir, bool verbose) {
  const DatasetSpec spec = SpecFromConfig(cfg, "dataset");
  const nlohmann::json path_spec = cfg.Raw("path");
  const double eps_pct = cfg.Number("lambda_pct_width", 0.1);
  NetsFromDatasetOptions no;
  no.fk_options.hidden = Layers(cfg, "fk_hidden", {30, 30, 30});
  no.jac_options.hidden = Layers(cfg, "jac_hidden", {30, 30});
  no.ik_options.hidden = Layers(cfg, "ik_hidden", {30, 30});
  no.fk_options.lm = no.jac_options.lm = no.ik_options.lm = ReadLm(cfg);
  no.split_seed = no.fk_options.split_seed = no.jac_options.split_seed = no.ik_options.split_seed = cfg.seed();
  const int max_iter = cfg.Int("max_iterations", 30);
  cfg.CheckNoUnknownKeys();
  if (!spec.jacobian) cfg.Fail("dataset.jacobian", "true (N_J is trained on the recorded Jacobians)");
  if (!path_spec.is_object()) cfg.Fail("path", "a path object");

  nlohmann::json dinfo;
  const Dataset d = CachedDataset(spec, DatasetCacheDir(dir), verbose, &dinfo);
  LearnedNets nets = CachedNets(d, dinfo["path"].get<std::string>(), spec.Tag(), no, NetsCacheDir(dir), verbose);
  const double width = nets.info["dataset"]["workspace_width_mm"].get<double>();
  NetKinematics kin(nets, JacobianSource::kNetwork, false);
  SamplingOptions so;
  so.samples_per_axis = 5;
  const ConfigurationSamples samples = SampleConfigurationSpace(kin, nets.points.front(), so);
  Eigen::MatrixX3d waypoints;
  nlohmann::json pinfo = path_spec;
  if (path_spec.value("type", "") == "eight") {
    waypoints = EightPath(path_spec, cfg.path() + ": path");
  } else {
    const IkPath p = MakeIkPath(path_spec, cfg.path() + ": path", kin, samples);
    waypoints = p.waypoints;
    pinfo = p.info;
  }
  std::unique_ptr<Kinematics> truth = MakeSpecKinematics(spec);
  const Eigen::VectorXd range = truth->upper() - truth->lower();

  TrajectoryOptions to;
  to.point = nets.points.front();
  to.ik.method = IkMethod::kGaussNewton;
  to.ik.lambda = std::pow(eps_pct / 100.0 * width, 2);
  to.ik.max_iterations = max_iter;
  to.sampling = so;
  nlohmann::json rows = nlohmann::json::array();
  for (const std::string method : {"learned", "direct"}) {
    std::vector<Eigen::VectorXd> cs;
    std::vector<double> times;
    if (method == "learned") {
      const TrajectoryResult r = FollowTrajectory(kin, waypoints, to);
      for (const auto& w : r.waypoints) {
        cs.push_back(w.c);
        times.push_back(w.time_s);
      }
    } else {
      for (int i = 0; i < waypoints.rows(); ++i) {
        const auto t0 = std::chrono::steady_clock::now();
        cs.push_back(DirectIk(nets, waypoints.row(i).transpose()));
        times.push_back(Seconds(t0));
      }
    }
    std::vector<std::string> head = {"i", "target_x", "target_y", "target_z", "x", "y", "z", "err_mm", "time_ms", "jump"};
    for (int a = 0; a < truth->num_actuators(); ++a) head.push_back("c" + std::to_string(a));
    CsvWriter csv(dir + "/path_" + method + ".csv", head);
    double sum = 0, worst = 0, time = 0, max_jump = 0, max_jump_frac = 0;
    int ok = 0;
    for (size_t i = 0; i < cs.size(); ++i) {
      const KinematicsEval e = truth->Evaluate(cs[i], false);  // warm-started along the path
      double jump = 0;
      if (i > 0) {
        jump = (cs[i] - cs[i - 1]).cwiseAbs().maxCoeff();
        max_jump = std::max(max_jump, jump);
        max_jump_frac = std::max(max_jump_frac, (cs[i] - cs[i - 1]).cwiseAbs().cwiseQuotient(range).maxCoeff());
      }
      if (!e.ok) continue;
      const Eigen::Vector3d p = e.p.row(0).transpose(), t = waypoints.row(i).transpose();
      const double err = (p - t).norm();
      std::vector<double> row = {static_cast<double>(i), t.x(), t.y(), t.z(), p.x(), p.y(), p.z(), err,
                                 1e3 * times[i], jump};
      for (int a = 0; a < cs[i].size(); ++a) row.push_back(cs[i][a]);
      csv.Row(row);
      ++ok;
      sum += err;
      worst = std::max(worst, err);
      time += times[i];
      if (verbose && (i + 1) % 20 == 0)
        std::fprintf(stderr, "  %s: %zu/%zu waypoints measured by the simulator\n", method.c_str(), i + 1, cs.size());
    }
    rows.push_back({{"method", method}, {"waypoints", cs.size()}, {"measured", ok},
                    {"mean_err_mm", ok ? sum / ok : 0.0}, {"max_err_mm", worst},
                    {"mean_err_pct", ok ? 100.0 * sum / ok / width : 0.0}, {"max_err_pct", 100.0 * worst / width},
                    {"ms_per_waypoint", ok ? 1e3 * time / ok : 0.0}, {"max_jump", max_jump},
                    {"max_jump_fraction", max_jump_frac}});
    if (verbose)
      std::fprintf(stderr, "  %s: error mean %.3f mm (%.3f %%), max %.3f mm (%.3f %%), largest jump %.3f (%.1f %% of the range), %.3f ms per waypoint\n",
                   method.c_str(), ok ? sum / ok : 0.0, ok ? 100.0 * sum / ok / width : 0.0, worst, 100.0 * worst / width,
                   max_jump, 100.0 * max_jump_frac, ok ? 1e3 * time / ok : 0.0);
  }
  return {{"rows", rows}, {"path", pinfo}, {"dataset", dinfo}, {"networks", nets.info},
          {"workspace_width_mm", width},
          {"errors_note", "errors are measured by the simulator at each method's actuation"},
          {"thesis", path_spec.value("thesis", nlohmann::json::object())}};
}

}  // namespace softkin
