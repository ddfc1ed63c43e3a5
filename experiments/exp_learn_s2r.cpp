// Thesis Chapter 5, sim-to-real on three_chamber: the simulator against the analytical PCC model
// as the data source (Fig. 5.14), the s2r layer's error against eta and the number of twin samples
// (Fig. 5.6), and path following on the twins with and without it (Fig. 5.7, 5.8).
#include "softkin/experiments/ik_config.hpp"
#include "softkin/experiments/learn_common.hpp"
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/ik/pcc_chamber_kinematics.hpp"
#include "softkin/ik/trajectory.hpp"
#include "softkin/learn/net_kinematics.hpp"
#include "softkin/learn/train_nets.hpp"
#include "softkin/learn/twin.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace softkin {

namespace {

// ---- Fig. 5.14: sim-to-real on networks learned from the simulator or from the PCC model ----

/// The keys of a learn_data_source config.
struct DataSourceParams {
  DatasetSpec sim_spec, twin_spec;
  std::vector<int> sizes;  ///< twin samples the s2r layer is trained on
  double eta = 0.25;
  int test_n = 200;  ///< the twin's last samples, the test set
  std::vector<int> fk_hidden;
  LmOptions lm;
  unsigned seed = 0;
};

DataSourceParams ReadDataSourceParams(const Config& cfg) {
  DataSourceParams p;
  p.sim_spec = SpecFromConfig(cfg, "dataset");
  p.twin_spec = SpecFromConfig(cfg, "twin_dataset");
  p.sizes = cfg.IntList("s2r_samples", {50, 100, 200, 300, 500, 1000});
  p.eta = cfg.Number("eta", 0.25);
  p.test_n = cfg.Int("test_samples", 200);
  p.fk_hidden = Layers(cfg, "fk_hidden", {35, 35});
  p.lm = ReadLm(cfg);
  p.seed = cfg.seed();
  cfg.CheckNoUnknownKeys();
  if (p.twin_spec.twin.empty()) cfg.Fail("twin_dataset", "a dataset object with \"twin\"");
  if (p.twin_spec.robot != "three_chamber" || p.sim_spec.robot != "three_chamber")
    cfg.Fail("dataset", "three_chamber datasets (the PCC model is of three_chamber)");
  if (!(p.eta > 0)) cfg.Fail("eta", "a number > 0");
  if (p.test_n < 10) cfg.Fail("test_samples", "an integer >= 10");
  for (int s : p.sizes)
    if (s < 10) cfg.Fail("s2r_samples", "sample counts >= 10");
  return p;
}

/// The simulator's data with its tip positions only (the network's training data).
Dataset TipDataset(const Dataset& sim) {
  Dataset simd = sim;
  simd.jacobians.resize(simd.inputs.rows(), 0);
  simd.positions = sim.positions.leftCols(3).eval();
  simd.point_names = {"tip"};
  return simd;
}

/// The analytical data: the PCC model sampled on the simulator's actuations, so both networks see
/// the same inputs.
Dataset PccDataset(const Dataset& sim, const PccChamberKinematics& pcc) {
  Dataset ana = sim;
  ana.jacobians.resize(ana.inputs.rows(), 0);
  ana.point_names = {"tip"};
  ana.positions.resize(ana.inputs.rows(), 3);
  for (int i = 0; i < ana.inputs.rows(); ++i)
    ana.positions.row(i) =
        PccChamberKinematics::Tip(pcc.params(), ana.inputs.row(i).transpose()).transpose();
  return ana;
}

/// The twin's data, and its test set.
struct TwinData {
  const Dataset& twin;
  Eigen::MatrixXd c_test, p_test;
  double width = 0;  ///< workspace width, mm
};

/// N_s2r on the first `ts` twin samples over `base`'s N_fk: rows of errors.csv and its row.
nlohmann::json S2rRow(const DataSourceParams& p, const std::string& source, const LearnedNets& base,
                      const TwinData& t, int ts, CsvWriter* csv, bool verbose) {
  LearnedNets nets = base;
  Dataset part = t.twin;
  part.inputs = t.twin.inputs.topRows(ts);
  part.positions = t.twin.positions.topRows(ts).leftCols(3);
  part.jacobians.resize(ts, 0);
  part.point_names = {"tip"};
  // All ts samples train (the fixed held-out twin test set measures); 15 % of them validate.
  NetTrainOptions so;
  so.hidden = {S2rNeurons(p.eta, ts)};
  so.lm = p.lm;
  so.split_seed = p.seed;
  const NetTrainResult r =
      TrainNet(S2rSamples(nets.fk, part.inputs, part.positions), SampleSet{}, so);
  const Eigen::MatrixXd pred = r.net.ForwardBatch(nets.fk.ForwardBatch(t.c_test));
  const Eigen::VectorXd e = (pred - t.p_test).rowwise().norm();
  const double width = t.width;
  int within = 0;
  for (int i = 0; i < e.size(); ++i) {
    within += e[i] <= 0.01 * width;
    csv->RowStrings({source, std::to_string(ts), std::to_string(i), std::to_string(e[i]),
                     std::to_string(100.0 * e[i] / width)});
  }
  if (verbose)
    std::fprintf(stderr,
                 "  %s + s2r(TS#=%d): mean %.3f mm (%.2f %%), %.0f %% of test points within 1 %%\n",
                 source.c_str(), ts, e.mean(), 100.0 * e.mean() / width, 100.0 * within / e.size());
  return {{"source", source},
          {"ts", ts},
          {"s2r_neurons", so.hidden[0]},
          {"mean_err_mm", e.mean()},
          {"max_err_mm", e.maxCoeff()},
          {"mean_err_pct", 100.0 * e.mean() / width},
          {"within_1pct", static_cast<double>(within) / e.size()}};
}

}  // namespace

nlohmann::json RunLearnDataSource(const Config& cfg, const std::string& dir, bool verbose) {
  const DataSourceParams p = ReadDataSourceParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  nlohmann::json sim_info, twin_info;
  const Dataset sim = CachedDataset(p.sim_spec, DatasetCacheDir(dir), verbose, &sim_info);
  const Dataset twin = CachedDataset(p.twin_spec, DatasetCacheDir(dir), verbose, &twin_info);
  const int max_train = *std::max_element(p.sizes.begin(), p.sizes.end());
  if (twin.inputs.rows() < max_train + p.test_n)
    cfg.Fail("twin_dataset",
             "at least max(s2r_samples) + test_samples = " + std::to_string(max_train + p.test_n) +
                 " twin samples (it has " + std::to_string(twin.inputs.rows()) + ")");
  // The twin's last test_n samples are the test set; the s2r training sets are nested prefixes.
  const TwinData t{twin, twin.inputs.bottomRows(p.test_n),
                   twin.positions.bottomRows(p.test_n).leftCols(3),
                   WorkspaceWidth(twin.positions.leftCols(3))};

  // The analytical data: the PCC model calibrated on the simulator's data.
  nlohmann::json fit;
  const std::unique_ptr<PccChamberKinematics> pcc = FitPccBaseline(sim, &fit);
  const Dataset ana = PccDataset(sim, *pcc);
  const Dataset simd = TipDataset(sim);

  CsvWriter csv(dir + "/errors.csv", {"source", "ts", "sample", "err_mm", "err_pct"});
  nlohmann::json rows = nlohmann::json::array(), sources = nlohmann::json::array();
  for (const std::string source : {"simulator", "pcc"}) {
    NetsFromDatasetOptions o;
    o.jac = o.ik = false;
    o.fk_options.hidden = p.fk_hidden;
    o.fk_options.lm = p.lm;
    o.split_seed = o.fk_options.split_seed = p.seed;
    const LearnedNets base = CachedNets(source == "simulator" ? simd : ana, source,
                                        (source == "simulator" ? "" : "pccfit-") + p.sim_spec.Tag(),
                                        o, NetsCacheDir(dir), verbose);
    // Without s2r: N_fk against the twin.
    const Eigen::MatrixXd pred0 = base.fk.ForwardBatch(t.c_test);
    const double err0 = (pred0 - t.p_test).rowwise().norm().mean();
    sources.push_back({{"source", source},
                       {"fk_test_pct_width", base.info["fk"]["test_mean_pct_width"]},
                       {"twin_mean_err_without_s2r_mm", err0}});
    if (verbose)
      std::fprintf(stderr, "  N_fk from %s: %.3f mm mean error on the twin without s2r\n",
                   source.c_str(), err0);
    for (int ts : p.sizes) rows.push_back(S2rRow(p, source, base, t, ts, &csv, verbose));
  }
  return {{"rows", rows},
          {"sources", sources},
          {"pcc_fit", fit},
          {"dataset", sim_info},
          {"twin_dataset", twin_info},
          {"twin_label", "twin data (simulated hardware, docs/twins.md)"},
          {"workspace_width_mm", t.width},
          {"test_samples", p.test_n},
          {"eta", p.eta},
          {"thesis", {{"within_1pct_at_ts", {{"simulator", 300}, {"pcc", 1000}}}}}};
}

namespace {

std::vector<DatasetSpec> TwinSpecs(const Config& cfg, const std::string& key) {
  const nlohmann::json j = cfg.Raw(key);
  if (!j.is_array() || j.empty())
    cfg.Fail(key, "a non-empty array of twin dataset objects {\"twin\", ...}");
  std::vector<DatasetSpec> out;
  for (size_t i = 0; i < j.size(); ++i) {
    out.push_back(ParseDatasetSpec(j[i], cfg.path() + ": " + key + "[" + std::to_string(i) + "]"));
    if (out.back().twin.empty())
      cfg.Fail(key + "[" + std::to_string(i) + "]", "a dataset object with \"twin\"");
  }
  return out;
}

/// Mean tip distance between rows of A and B (first 3 columns).
double MeanDist(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B) {
  return (A.leftCols(3) - B.leftCols(3)).rowwise().norm().mean();
}

// ---- Fig. 5.6: s2r error against eta and against the number of twin samples ----

/// The keys of a learn_s2r_sweep config.
struct S2rSweepParams {
  DatasetSpec sim_spec;
  std::vector<DatasetSpec> twins;
  std::vector<double> etas;  ///< the eta sweep, on eta_size samples
  std::vector<int> sizes;    ///< the sample sweep, at size_eta
  int eta_size = 343;
  double size_eta = 0.25;
  int test_n = 200;
  std::vector<int> fk_hidden;
  LmOptions lm;
  unsigned seed = 0;
  int need = 0;  ///< training samples needed per twin
};

S2rSweepParams ReadS2rSweepParams(const Config& cfg) {
  S2rSweepParams p;
  p.sim_spec = SpecFromConfig(cfg, "dataset");
  p.twins = TwinSpecs(cfg, "twin_datasets");
  p.etas = cfg.NumberList("etas", {1.0 / 16, 1.0 / 8, 0.25, 0.5, 1.0});
  p.sizes = cfg.IntList("sizes", {64, 125, 216, 343, 620});
  p.eta_size = cfg.Int("eta_sweep_samples", 343);
  p.size_eta = cfg.Number("size_sweep_eta", 0.25);
  p.test_n = cfg.Int("test_samples", 200);
  p.fk_hidden = Layers(cfg, "fk_hidden", {35, 35});
  p.lm = ReadLm(cfg);
  p.seed = cfg.seed();
  cfg.CheckNoUnknownKeys();
  for (double e : p.etas)
    if (!(e > 0)) cfg.Fail("etas", "numbers > 0");
  p.need = p.eta_size;
  for (int n : p.sizes) {
    if (n < 10) cfg.Fail("sizes", "sample counts >= 10");
    p.need = std::max(p.need, n);
  }
  return p;
}

/// Both sweeps on one twin: rows of s2r_sweep.csv and of the summary.
void SweepTwin(const S2rSweepParams& p, const DatasetSpec& ts, const Dataset& twin,
               const LearnedNets& nets, CsvWriter* csv, nlohmann::json* rows, bool verbose) {
  const SampleSet all = S2rSamples(nets.fk, twin.inputs, twin.positions.leftCols(3));
  const int n = all.size();
  std::vector<int> test_rows;
  for (int i = n - p.test_n; i < n; ++i) test_rows.push_back(i);
  const SampleSet test = SelectRows(all, test_rows);
  const double without = MeanDist(test.X, test.Y);
  auto run = [&](const std::string& sweep, double eta, int samples) {
    std::vector<int> rows_k;
    for (int i = 0; i < samples; ++i) rows_k.push_back(i);
    NetTrainOptions so;
    so.hidden = {S2rNeurons(eta, samples)};
    so.lm = p.lm;
    so.split_seed = p.seed;
    const NetTrainResult r = TrainNet(SelectRows(all, rows_k), test, so);
    rows->push_back({{"twin", ts.twin},
                     {"sweep", sweep},
                     {"eta", eta},
                     {"samples", samples},
                     {"neurons", so.hidden[0]},
                     {"train_mm", r.train.mean_dist},
                     {"test_mm", r.test.mean_dist},
                     {"test_max_mm", r.test.max_dist},
                     {"without_mm", without}});
    csv->RowStrings({ts.twin, sweep, std::to_string(eta), std::to_string(samples),
                     std::to_string(so.hidden[0]), std::to_string(r.train.mean_dist),
                     std::to_string(r.test.mean_dist), std::to_string(without)});
    if (verbose)
      std::fprintf(stderr,
                   "  %s eta %.4g, %d samples (%d neurons): train %.3f mm, test %.3f mm (without "
                   "s2r %.3f mm)\n",
                   ts.twin.c_str(), eta, samples, so.hidden[0], r.train.mean_dist, r.test.mean_dist,
                   without);
  };
  for (double eta : p.etas) run("eta", eta, p.eta_size);
  for (int size : p.sizes) run("samples", p.size_eta, size);
}

}  // namespace

nlohmann::json RunLearnS2rSweep(const Config& cfg, const std::string& dir, bool verbose) {
  const S2rSweepParams p = ReadS2rSweepParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  nlohmann::json sim_info;
  const Dataset sim = CachedDataset(p.sim_spec, DatasetCacheDir(dir), verbose, &sim_info);
  NetsFromDatasetOptions o;
  o.jac = o.ik = false;
  o.fk_options.hidden = p.fk_hidden;
  o.fk_options.lm = p.lm;
  o.split_seed = o.fk_options.split_seed = p.seed;
  const LearnedNets nets = CachedNets(sim, sim_info["path"].get<std::string>(), p.sim_spec.Tag(), o,
                                      NetsCacheDir(dir), verbose);

  CsvWriter csv(dir + "/s2r_sweep.csv", {"twin", "sweep", "eta", "samples", "neurons", "train_mm",
                                         "test_mm", "without_mm"});
  nlohmann::json rows = nlohmann::json::array(), tinfo = nlohmann::json::array();
  for (const DatasetSpec& ts : p.twins) {
    nlohmann::json info;
    const Dataset twin = CachedDataset(ts, DatasetCacheDir(dir), verbose, &info);
    if (twin.inputs.rows() < p.need + p.test_n)
      cfg.Fail("twin_datasets", "at least " + std::to_string(p.need + p.test_n) +
                                    " samples per twin (" + ts.twin + " has " +
                                    std::to_string(twin.inputs.rows()) + ")");
    tinfo.push_back(info);
    SweepTwin(p, ts, twin, nets, &csv, &rows, verbose);
  }
  return {{"rows", rows},
          {"dataset", sim_info},
          {"twin_datasets", tinfo},
          {"fk", nets.info["fk"]},
          {"twin_label", "twin data (simulated hardware, docs/twins.md)"},
          {"thesis", {{"eta", 0.25}, {"twin_samples", {343, 620}}}}};
}

namespace {

// ---- Fig. 5.7 / 5.8: path following on the twins, learned Jacobian IK with and without s2r ----

/// The keys of a learn_s2r_paths config.
struct S2rPathsParams {
  DatasetSpec sim_spec;
  std::vector<DatasetSpec> twins;
  nlohmann::json path_spec;
  double eta = 0.25;
  double eps_pct = 0.1;  ///< lambda, % of the workspace width
  NetsFromDatasetOptions nets;
  LmOptions lm;
  unsigned seed = 0;
};

S2rPathsParams ReadS2rPathsParams(const Config& cfg) {
  S2rPathsParams p;
  p.sim_spec = SpecFromConfig(cfg, "dataset");
  p.twins = TwinSpecs(cfg, "twin_datasets");
  p.path_spec = cfg.Raw("path");
  p.eta = cfg.Number("eta", 0.25);
  p.eps_pct = cfg.Number("lambda_pct_width", 0.1);
  NetsFromDatasetOptions& no = p.nets;
  no.ik = false;
  no.fk_options.hidden = Layers(cfg, "fk_hidden", {35, 35});
  no.jac_options.hidden = Layers(cfg, "jac_hidden", {64, 64});
  no.fk_options.lm = no.jac_options.lm = ReadLm(cfg);
  no.split_seed = no.fk_options.split_seed = no.jac_options.split_seed = cfg.seed();
  p.lm = no.fk_options.lm;
  p.seed = cfg.seed();
  cfg.CheckNoUnknownKeys();
  if (!p.sim_spec.jacobian)
    cfg.Fail("dataset.jacobian", "true (N_J is trained on the recorded Jacobians)");
  if (!(p.eta > 0)) cfg.Fail("eta", "a number > 0");
  if (!(p.eps_pct > 0)) cfg.Fail("lambda_pct_width", "a percentage > 0");
  return p;
}

/// Follows the path on `nets` (with or without s2r) and measures it on the twin: path_<tag>.csv
/// and its row.
nlohmann::json TwinPathRow(const DatasetSpec& ts, const LearnedNets& nets, bool with_s2r,
                           const IkPath& path, const TrajectoryOptions& to, TwinKinematics& measure,
                           const std::string& dir, bool verbose) {
  NetKinematics kin(nets, JacobianSource::kNetwork, with_s2r);
  const TrajectoryResult r = FollowTrajectory(kin, path.waypoints, to);
  const std::string tag = ts.twin.substr(ts.twin.find('/') + 1) + (with_s2r ? "_s2r" : "_nominal");
  CsvWriter csv(dir + "/path_" + tag + ".csv", {"i", "target_x", "target_y", "target_z", "x", "y",
                                                "z", "err_mm", "predicted_err_mm", "time_ms"});
  double sum = 0, worst = 0, time = 0;
  int ok = 0;
  for (const WaypointResult& w : r.waypoints) {
    const KinematicsEval e = measure.Evaluate(w.c, false);
    if (!e.ok) continue;
    const Eigen::Vector3d p = e.p.row(0).transpose();
    const double err = (p - w.target).norm();
    csv.Row({static_cast<double>(w.index), w.target.x(), w.target.y(), w.target.z(), p.x(), p.y(),
             p.z(), err, w.error_mm, 1e3 * w.time_s});
    ++ok;
    sum += err;
    worst = std::max(worst, err);
    time += w.time_s;
  }
  if (verbose)
    std::fprintf(stderr,
                 "  %s %s: error on the twin mean %.3f mm, max %.3f mm, %.2f ms per waypoint\n",
                 ts.twin.c_str(), with_s2r ? "with s2r" : "without s2r", ok ? sum / ok : 0.0, worst,
                 ok ? 1e3 * time / ok : 0.0);
  return {{"twin", ts.twin},
          {"s2r", with_s2r},
          {"waypoints", path.waypoints.rows()},
          {"measured", ok},
          {"mean_err_mm", ok ? sum / ok : 0.0},
          {"max_err_mm", worst},
          {"ms_per_waypoint", ok ? 1e3 * time / ok : 0.0},
          {"max_jump", r.max_jump},
          {"csv", "path_" + tag + ".csv"}};
}

}  // namespace

nlohmann::json RunLearnS2rPaths(const Config& cfg, const std::string& dir, bool verbose) {
  const S2rPathsParams p = ReadS2rPathsParams(cfg);
  if (cfg.check_only()) return {};  // only the settings were asked for (Config::check_only)
  nlohmann::json sim_info;
  const Dataset sim = CachedDataset(p.sim_spec, DatasetCacheDir(dir), verbose, &sim_info);
  const LearnedNets nominal = CachedNets(sim, sim_info["path"].get<std::string>(), p.sim_spec.Tag(),
                                         p.nets, NetsCacheDir(dir), verbose);
  const double width = nominal.info["dataset"]["workspace_width_mm"].get<double>();
  NetKinematics nominal_kin(nominal, JacobianSource::kNetwork, false);
  SamplingOptions so;
  so.samples_per_axis = 5;
  const ConfigurationSamples samples = SampleConfigurationSpace(nominal_kin, "tip", so);
  const IkPath path = MakeIkPath(p.path_spec, cfg.path() + ": path", nominal_kin, samples);

  TrajectoryOptions to;
  to.ik.method = IkMethod::kGaussNewton;
  to.ik.lambda = std::pow(p.eps_pct / 100.0 * width, 2);
  to.ik.max_iterations = 30;
  to.sampling = so;

  nlohmann::json rows = nlohmann::json::array(), tinfo = nlohmann::json::array();
  for (const DatasetSpec& ts : p.twins) {
    nlohmann::json info;
    const Dataset twin = CachedDataset(ts, DatasetCacheDir(dir), verbose, &info);
    tinfo.push_back(info);
    LearnedNets nets = nominal;
    TrainS2r(nets, twin, info["path"].get<std::string>(), p.eta, p.lm, p.seed);
    // The twin measures the answer without its measurement noise (its systematic gap remains).
    TwinOptions mo;
    mo.res = ts.res;
    mo.noise = false;
    mo.gradient_tolerance = ts.gradient_tolerance;
    TwinKinematics measure(GetTwinSpec(ts.twin), mo);
    for (bool with_s2r : {false, true})
      rows.push_back(TwinPathRow(ts, nets, with_s2r, path, to, measure, dir, verbose));
  }
  return {{"rows", rows},
          {"path", path.info},
          {"thesis", path.thesis},
          {"dataset", sim_info},
          {"twin_datasets", tinfo},
          {"networks", nominal.info},
          {"workspace_width_mm", width},
          {"twin_label",
           "errors are measured on the twin (simulated hardware, docs/twins.md) without its "
           "measurement noise"}};
}

}  // namespace softkin
