#include "softkin/learn/train_nets.hpp"

#include "softkin/solver/common/memory_guard.hpp"
#include "softkin/solver/common/text_format.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace softkin {

bool NetTrainOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (hidden.empty()) return fail("hidden: expected at least one hidden layer");
  for (int b : hidden)
    if (b < 1) return fail("hidden: every layer needs >= 1 neuron");
  if (!(validation_fraction >= 0.0 && validation_fraction < 0.9))
    return fail("validation_fraction: expected a fraction in [0, 0.9)");
  std::string w;
  if (!lm.IsValid(&w)) return fail("lm: " + w);
  return true;
}

nlohmann::json NetErrors::Json() const {
  return {{"samples", samples},
          {"rmse", rmse},
          {"mean_dist", mean_dist},
          {"max_dist", max_dist},
          {"relative", relative}};
}

NetErrors EvaluateNet(const Fnn& net, const SampleSet& s) {
  NetErrors e;
  e.samples = s.size();
  if (s.empty()) return e;
  if (s.X.cols() != net.num_inputs() || s.Y.cols() != net.num_outputs())
    throw std::invalid_argument("EvaluateNet: the set has " + std::to_string(s.X.cols()) + " -> " +
                                std::to_string(s.Y.cols()) + " columns, the network maps " +
                                std::to_string(net.num_inputs()) + " -> " +
                                std::to_string(net.num_outputs()));
  const Eigen::MatrixXd Yh = net.ForwardBatch(s.X);  // n x outputs
  const Eigen::MatrixXd D = Yh - s.Y;
  e.rmse = std::sqrt(D.squaredNorm() / static_cast<double>(D.size()));
  const double ref = s.Y.norm();
  e.relative = ref > 0 ? D.norm() / ref : D.norm();
  const int groups = static_cast<int>(D.cols()) / 3;
  if (groups > 0 && D.cols() % 3 == 0) {
    double sum = 0;
    for (int i = 0; i < D.rows(); ++i)
      for (int g = 0; g < groups; ++g) {
        const double d = D.block<1, 3>(i, 3 * g).norm();
        sum += d;
        e.max_dist = std::max(e.max_dist, d);
      }
    e.mean_dist = sum / (static_cast<double>(D.rows()) * groups);
  } else {  // not points: per-entry absolute errors
    e.mean_dist = D.cwiseAbs().mean();
    e.max_dist = D.cwiseAbs().maxCoeff();
  }
  return e;
}

nlohmann::json NetTrainResult::Json() const {
  nlohmann::json j;
  j["layers"] = net.layer_sizes();
  j["parameters"] = net.num_parameters();
  j["train"] = train.Json();
  j["validation"] = validation.Json();
  j["test"] = test.Json();
  j["epochs"] = lm.epochs;
  j["best_epoch"] = lm.best_epoch;
  j["termination"] = LmTerminationToString(lm.termination);
  j["final_train_mse"] = lm.final_train_mse;
  j["time_s"] = lm.total_time_s;
  j["threads"] = lm.num_threads;
  return j;
}

void CheckTrainingMemory(const std::string& name, int inputs, const NetTrainOptions& opt,
                         int outputs) {
  const double W = Fnn::CountParameters(inputs, opt.hidden, outputs);
  std::string sizes = std::to_string(inputs);
  for (int h : opt.hidden) sizes += "-" + std::to_string(h);
  sizes += "-" + std::to_string(outputs);
  CheckMemoryEstimate(name + ": network " + sizes, LmMemoryBytes(W, outputs, opt.lm.block_size),
                      "Levenberg-Marquardt's W x W normal matrix and its factor, W = " +
                          FormatNumber(W) + " weights",
                      "use fewer hidden neurons");
}

NetTrainResult TrainNet(const SampleSet& train, const SampleSet& test, const NetTrainOptions& opt) {
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument("TrainNet: " + why);
  CheckTrainingMemory("TrainNet", static_cast<int>(train.X.cols()), opt,
                      static_cast<int>(train.Y.cols()));
  if (train.size() < 2)
    throw std::invalid_argument("TrainNet: the training set needs >= 2 samples");
  SampleSet tr = train, val;
  if (opt.validation_fraction > 0 && train.size() >= 10) {
    const SplitIndices idx =
        RandomSplit(train.size(), 1.0 - opt.validation_fraction, opt.split_seed);
    tr = SelectRows(train, idx.first);
    val = SelectRows(train, idx.second);
  }
  NetTrainResult r;
  r.net = Fnn::WithHiddenLayers(static_cast<int>(train.X.cols()), opt.hidden,
                                static_cast<int>(train.Y.cols()));
  LmOptions lm = opt.lm;
  lm.initialize = true;
  r.lm = TrainLevenbergMarquardt(r.net, tr, val.empty() ? nullptr : &val, lm,
                                 test.empty() ? nullptr : &test);
  r.train = EvaluateNet(r.net, tr);
  r.validation = EvaluateNet(r.net, val);
  r.test = EvaluateNet(r.net, test);
  return r;
}

double WorkspaceWidth(const Eigen::Ref<const Eigen::MatrixXd>& P) {
  if (P.rows() == 0 || P.cols() < 3) return 0.0;
  double w = 0;
  for (int d = 0; d < 3; ++d) w = std::max(w, P.col(d).maxCoeff() - P.col(d).minCoeff());
  return w;
}

SampleSet S2rSamples(const Fnn& fk, const Eigen::Ref<const Eigen::MatrixXd>& c,
                     const Eigen::Ref<const Eigen::MatrixXd>& p_real) {
  if (c.rows() != p_real.rows() || c.cols() != fk.num_inputs() || p_real.cols() != fk.num_outputs())
    throw std::invalid_argument("S2rSamples: expected n x " + std::to_string(fk.num_inputs()) +
                                " actuations and n x " + std::to_string(fk.num_outputs()) +
                                " measured points");
  SampleSet s;
  s.X = fk.ForwardBatch(c);
  s.Y = p_real;
  return s;
}

int S2rNeurons(double eta, int samples) {
  return std::max(1, static_cast<int>(std::lround(eta * samples)));
}

}  // namespace softkin

namespace softkin {

LearnedNets TrainNetsFromDataset(const Dataset& d, const std::string& dataset_path,
                                 const NetsFromDatasetOptions& opt) {
  if (d.inputs.rows() < 10)
    throw std::invalid_argument(dataset_path + ": " + std::to_string(d.inputs.rows()) +
                                " usable samples; at least 10 are needed to train");
  if (opt.jac && d.jacobians.cols() == 0)
    throw std::invalid_argument(dataset_path +
                                ": the dataset has no Jacobian columns; generate it with "
                                "`softkin dataset --jacobian implicit` or leave jac out");
  if (!(opt.train_fraction > 0.0 && opt.train_fraction < 1.0))
    throw std::invalid_argument("train_fraction: expected a fraction in (0, 1)");
  const int m = d.num_actuators, n_points = 3 * static_cast<int>(d.point_names.size());
  // Refuse a network that cannot fit before any other is trained.
  if (opt.fk) CheckTrainingMemory("N_fk (--hidden)", m, opt.fk_options, n_points);
  if (opt.jac) CheckTrainingMemory("N_J (--hidden-jac)", m, opt.jac_options, n_points * m);
  if (opt.ik) CheckTrainingMemory("N_ik (--hidden-ik)", 3, opt.ik_options, m);
  LearnedNets nets;
  nets.points = d.point_names;
  nets.lower = d.inputs.colwise().minCoeff().transpose();
  nets.upper = d.inputs.colwise().maxCoeff().transpose();
  if (d.meta.is_object() && d.meta.contains("config") &&
      d.meta["config"].contains("actuator_bounds")) {
    const auto& b = d.meta["config"]["actuator_bounds"];
    if (b.is_array() && static_cast<int>(b.size()) == m)
      for (int a = 0; a < m; ++a) {
        nets.lower[a] = b[a][0].get<double>();
        nets.upper[a] = b[a][1].get<double>();
      }
  }
  nets.rest = opt.rest.size() == m ? opt.rest : nets.lower;
  const SampleSet pos = PositionSamples(d);
  const TrainTestSets split = SplitTrainTest(pos, opt.split_seed, opt.train_fraction);
  const double width = WorkspaceWidth(pos.Y);
  nets.info["dataset"] = {
      {"path", dataset_path},         {"samples", d.inputs.rows()},  {"failed", d.failed},
      {"inverted", d.inverted},       {"train", split.train.size()}, {"test", split.test.size()},
      {"split_seed", opt.split_seed}, {"workspace_width_mm", width}, {"sidecar", d.meta}};
  auto pct = [width](double mm) { return width > 0 ? 100.0 * mm / width : 0.0; };
  if (opt.fk) {
    const NetTrainResult r = TrainNet(split.train, split.test, opt.fk_options);
    nets.fk = r.net;
    nlohmann::json j = r.Json();
    j["test_mean_pct_width"] = pct(r.test.mean_dist);
    j["test_max_pct_width"] = pct(r.test.max_dist);
    nets.info["fk"] = j;
  }
  if (opt.jac) {
    const SampleSet js = JacobianSamples(d);
    const NetTrainResult r = TrainNet(SelectRows(js, split.train_rows),
                                      SelectRows(js, split.test_rows), opt.jac_options);
    nets.jac = r.net;
    nets.info["jac"] = r.Json();
  }
  if (opt.ik) {
    SampleSet inv{pos.Y.leftCols(3), pos.X};
    const NetTrainResult r = TrainNet(SelectRows(inv, split.train_rows),
                                      SelectRows(inv, split.test_rows), opt.ik_options);
    nets.ik = r.net;
    nets.info["ik"] = r.Json();
  }
  return nets;
}

NetTrainResult TrainS2r(LearnedNets& nets, const Dataset& twin, const std::string& twin_path,
                        double eta, const LmOptions& lm, std::uint64_t split_seed,
                        double train_fraction) {
  if (!nets.has_fk()) throw std::invalid_argument("TrainS2r: the networks have no fk network");
  if (twin.point_names != nets.points)
    throw std::invalid_argument(twin_path + ": its points differ from the networks' points");
  if (twin.num_actuators != nets.num_actuators())
    throw std::invalid_argument(twin_path + ": " + std::to_string(twin.num_actuators) +
                                " actuators, the networks have " +
                                std::to_string(nets.num_actuators()));
  if (!(eta > 0.0 && std::isfinite(eta))) throw std::invalid_argument("eta: expected a number > 0");
  if (twin.inputs.rows() < 10)
    throw std::invalid_argument(twin_path + ": at least 10 samples are needed for sim-to-real");
  const SampleSet s = S2rSamples(nets.fk, twin.inputs, twin.positions);
  const TrainTestSets split = SplitTrainTest(s, split_seed, train_fraction);
  NetTrainOptions o;
  o.lm = lm;
  o.split_seed = split_seed;
  o.hidden = {S2rNeurons(eta, split.train.size())};
  NetTrainResult r = TrainNet(split.train, split.test, o);
  nets.s2r = r.net;
  // Without the layer the prediction of the measured point is N_fk(c) itself.
  NetErrors without;
  {
    const Eigen::MatrixXd D = split.test.X - split.test.Y;
    without.samples = split.test.size();
    without.rmse =
        std::sqrt(D.squaredNorm() / std::max<double>(1.0, static_cast<double>(D.size())));
    double sum = 0;
    const int groups = static_cast<int>(D.cols()) / 3;
    for (int i = 0; i < D.rows(); ++i)
      for (int g = 0; g < groups; ++g) {
        const double dd = D.block<1, 3>(i, 3 * g).norm();
        sum += dd;
        without.max_dist = std::max(without.max_dist, dd);
      }
    without.mean_dist = D.rows() > 0 ? sum / (static_cast<double>(D.rows()) * groups) : 0.0;
    without.relative = split.test.Y.norm() > 0 ? D.norm() / split.test.Y.norm() : 0.0;
  }
  nlohmann::json j = r.Json();
  j["eta"] = eta;
  j["twin_dataset"] = twin_path;
  j["twin_samples"] = twin.inputs.rows();
  j["test_without_s2r"] = without.Json();
  j["improvement"] = r.test.mean_dist > 0 ? without.mean_dist / r.test.mean_dist : 0.0;
  if (twin.meta.is_object() && twin.meta.contains("config"))
    j["twin_source"] = twin.meta["config"].value("source", nlohmann::json());
  nets.info["s2r"] = j;
  return r;
}

}  // namespace softkin
