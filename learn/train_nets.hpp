#pragma once
/// \file
/// Training the networks of Sec. 5.3 from datasets: one call per network, with the errors the
/// thesis reports (RMSE, and the mean and largest point distance in mm, also as % of the
/// workspace width), and the sim-to-real samples of Sec. 5.3.4.

#include "softkin/learn/dataset.hpp"
#include "softkin/learn/fnn.hpp"
#include "softkin/learn/lm_trainer.hpp"
#include "softkin/learn/net_kinematics.hpp"
#include "softkin/learn/sample_set.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <vector>

namespace softkin {

struct NetTrainOptions {
  std::vector<int> hidden = {35, 35};  ///< neurons per hidden layer (Sec. 5.3.3: h = 2, b = 35)
  LmOptions lm;                        ///< the trainer (seed = the initialisation seed)
  double validation_fraction = 0.15;   ///< of the training set, held out for early stopping
  std::uint64_t split_seed = 1;        ///< seed of the training / validation split
  bool IsValid(std::string* why) const;
};

/// Errors of a network on a set, in the outputs' own units.
struct NetErrors {
  int samples = 0;
  double rmse = 0;  ///< sqrt(mean over every output entry of the squared error)
  /// Outputs grouped in threes (x, y, z of a point; the flattened Jacobian's rows likewise):
  /// the mean and the largest Euclidean distance over samples and groups.
  double mean_dist = 0, max_dist = 0;
  double relative = 0;  ///< ||Y_hat - Y||_F / ||Y||_F over the set
  nlohmann::json Json() const;
};

NetErrors EvaluateNet(const Fnn& net, const SampleSet& s);

struct NetTrainResult {
  Fnn net;
  LmSummary lm;
  NetErrors train, validation, test;  ///< test is empty (samples = 0) without a test set
  nlohmann::json Json() const;        ///< architecture, errors, epochs, termination, time
};

/// Splits `train` into training and validation (validation_fraction, split_seed), builds a network
/// with opt.hidden tansig layers, fits its normalisation and trains it with Levenberg-Marquardt
/// (early stopping on the validation set); then evaluates it on the three sets. `test` may be
/// empty. Throws std::invalid_argument for invalid options or sets.
NetTrainResult TrainNet(const SampleSet& train, const SampleSet& test, const NetTrainOptions& opt);

/// Throws std::invalid_argument, naming `name` (e.g. "N_fk (--hidden)") and the estimate, if the
/// Levenberg-Marquardt training of an inputs-hidden-outputs network would not fit in memory
/// (LmMemoryBytes, CheckMemoryEstimate). TrainNet checks it; call it first to refuse a job before
/// any network of it is trained.
void CheckTrainingMemory(const std::string& name, int inputs, const NetTrainOptions& opt,
                         int outputs);

/// The largest extent, over x, y and z, of the first tracked point (columns 0-2 of P), mm: the
/// "workspace width" that errors are quoted against (Sec. 5.3.3).
double WorkspaceWidth(const Eigen::Ref<const Eigen::MatrixXd>& P);

/// Sim-to-real training samples (Sec. 5.3.4): inputs N_fk(c_i) (the simulated points the network
/// predicts at the measured actuation), outputs the measured p_real_i.
SampleSet S2rSamples(const Fnn& fk, const Eigen::Ref<const Eigen::MatrixXd>& c,
                     const Eigen::Ref<const Eigen::MatrixXd>& p_real);

/// Hidden neurons of N_s2r: max(1, round(eta * samples)).
int S2rNeurons(double eta, int samples);

/// Which networks TrainNetsFromDataset trains, and how.
struct NetsFromDatasetOptions {
  bool fk = true;   ///< N_fk: c -> p (every tracked point)
  bool jac = true;  ///< N_J: c -> vec(J) (only when the dataset has Jacobians)
  bool ik = true;   ///< N_ik: p (first point) -> c, the direct-IK baseline
  NetTrainOptions fk_options, jac_options, ik_options;  ///< jac defaults to h = 2, b = 64
  double train_fraction = 0.7;  ///< the seeded train / test split (Sec. 5.3.2)
  std::uint64_t split_seed = 1;
  Eigen::VectorXd rest;  ///< rest actuation (empty: the lower bound)
  NetsFromDatasetOptions() { jac_options.hidden = {64, 64}; }
};

/// Trains the requested networks on one dataset (same train / test rows for all) and returns
/// them with info: per network its NetTrainResult::Json(), and for N_fk the test errors as % of
/// the workspace width of the dataset; the dataset's sidecar under "dataset". Throws
/// std::invalid_argument when the dataset cannot provide what is asked (e.g. jac without J).
LearnedNets TrainNetsFromDataset(const Dataset& d, const std::string& dataset_path,
                                 const NetsFromDatasetOptions& opt);

/// Adds a sim-to-real layer to `nets` (Sec. 5.3.4), trained on a twin dataset (the measured
/// points at the measured actuations): one hidden layer of S2rNeurons(eta, #train) neurons. The
/// twin's points must be the networks' points. Records in nets.info["s2r"] the errors with and
/// without the layer on the twin's test rows (the improvement factor). Returns the result.
NetTrainResult TrainS2r(LearnedNets& nets, const Dataset& twin, const std::string& twin_path,
                        double eta, const LmOptions& lm, std::uint64_t split_seed = 1,
                        double train_fraction = 0.7);

}  // namespace softkin
