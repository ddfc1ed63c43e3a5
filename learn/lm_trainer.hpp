#pragma once
/// \file
/// Levenberg-Marquardt training of an Fnn, after MATLAB's `trainlm` (thesis §5.3.4: "The
/// Levenberg-Marquardt backpropagation is employed for training").
///
/// Loss. The mean squared error on the NORMALISED output scale (the network's output MinMaxMap):
///   mse(w) = 1 / (N n_L) sum_s sum_k (t_sk - z_sk(w))^2,
/// with t the normalised targets and z the normalised outputs, so every output counts alike
/// whatever its unit (trainlm's default measures errors in target units instead).
///
/// One epoch (as trainlm): with J = dz/dw over all training samples (N n_L x W) and e = t - z,
/// accumulate H = J^T J and g = J^T e; then repeat { solve (H + mu I) delta = g (tiled Cholesky,
/// learn/tiled_cholesky.hpp);
/// evaluate mse(w + delta); if it is lower, accept, mu *= mu_dec, end the epoch; else mu *= mu_inc
/// } until mu > mu_max. The training loss therefore never increases: it is recorded per epoch in
/// LmSummary::train_mse.
///
/// Memory and threads. H and g are accumulated over blocks of block_size samples: the block's
/// transposed Jacobian (W x block_size n_L) is built (samples in parallel), then H += J_b^T J_b is
/// added tile by tile (fixed column tiles of H, tiles in parallel, each tile by one matrix
/// product). Every number is therefore computed by the same operations in the same order whatever
/// the thread count, and the result is bitwise identical for 1, 2, ... threads. Memory is
/// O(W^2 + W block_size n_L), independent of the dataset size.
///
/// Stopping (as trainlm): the training mse <= goal; the gradient norm |d mse / dw| =
/// 2 |g| / (N n_L) < min_grad; mu > mu_max; max_epochs; max_time_s; or, with a validation set,
/// max_fail epochs in a row whose validation mse is not below the best so far (trainlm's
/// val_fail). With a validation set, the network returned is the one of the best validation mse
/// (whatever stopped the run).

#include "softkin/learn/fnn.hpp"
#include "softkin/learn/sample_set.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace softkin {

struct LmOptions {
  double mu = 1e-3;         ///< initial damping
  double mu_dec = 0.1;      ///< mu factor after an accepted step (0 < mu_dec < 1)
  double mu_inc = 10.0;     ///< mu factor after a rejected step (> 1)
  double mu_max = 1e10;     ///< stop when mu exceeds this
  double min_grad = 1e-7;   ///< stop when |d mse / dw| falls below this
  int max_epochs = 1000;    ///< epoch cap (>= 0)
  int max_fail = 6;         ///< validation failures in a row before early stopping (>= 1)
  double goal = 0.0;        ///< stop when the training mse (normalised) <= goal (>= 0)
  double max_time_s = 0.0;  ///< wall-time cap in seconds; 0 = none
  /// Samples per Jacobian block; 0 = automatic (max(1, 2048 / n_L), about 2048 Jacobian rows).
  int block_size = 0;
  int num_threads = 0;  ///< OpenMP threads; 0 = omp_get_max_threads(). Results do not depend on it.
  /// true: fit the network's normalisation to the training set and Nguyen-Widrow-initialise it
  /// from `seed` before training; false: train from the network as given (its maps are kept).
  bool initialize = true;
  std::uint64_t seed = 1;  ///< initialisation seed (used when initialize)
  bool verbose = false;    ///< progress lines on stderr
  int progress_every = 1;  ///< print every k-th epoch when verbose (>= 1)
  /// True if every field is in range; else false and *why (if given) names the field and range.
  bool IsValid(std::string* why) const;
};

enum class LmTermination {
  kGoalReached,     ///< training mse <= goal
  kMinGradient,     ///< gradient norm < min_grad
  kMuMax,           ///< mu > mu_max (no step lowers the loss)
  kMaxEpochs,       ///< epoch cap
  kMaxTime,         ///< wall-time cap
  kValidationStop,  ///< max_fail validation failures in a row
};
/// "goal", "min_gradient", "mu_max", "max_epochs", "max_time", "validation_stop".
const char* LmTerminationToString(LmTermination t);
/// Inverse of LmTerminationToString; false (and *t untouched) for an unknown name.
bool LmTerminationFromString(const std::string& name, LmTermination* t);

struct LmSummary {
  LmTermination termination = LmTermination::kMaxEpochs;
  std::string message;  ///< one line: why it stopped
  int epochs = 0;       ///< epochs run (accepted or not)
  int accepted_steps = 0;
  int rejected_steps = 0;  ///< mu increases
  /// Per epoch, index 0 = before training, index k = after epoch k (size epochs + 1).
  std::vector<double> train_mse;  ///< normalised training mse (never increases)
  std::vector<double> val_mse;    ///< normalised validation mse (empty without a validation set)
  std::vector<double> test_mse;   ///< normalised test mse (empty without a test set)
  std::vector<double> mu;         ///< mu at the end of each epoch
  std::vector<double> gradient_norm;  ///< |d mse / dw| at the start of each epoch (one entry per
                                      ///< gradient evaluated)
  std::vector<double> time_s;         ///< wall time since the start at each entry of train_mse
  int best_epoch = 0;                 ///< epoch of the returned network
  double best_val_mse = 0.0;          ///< its validation mse (0 without a validation set)
  double final_train_mse = 0.0;       ///< training mse of the returned network
  double total_time_s = 0.0;
  int num_parameters = 0;
  int num_threads = 1;  ///< threads used
  /// Wall time at which train_mse first reached <= target, or -1 if never.
  double TimeToTrainMse(double target) const;
  /// One line: termination, epochs, mse, best epoch, time.
  std::string BriefReport() const;
};

/// Bytes the trainer allocates for a network of W parameters and n_L outputs: H and its factor
/// (2 W^2 doubles) and one block's transposed Jacobian (W x block rows; block_size as in
/// LmOptions, 0: automatic).
double LmMemoryBytes(double num_parameters, int num_outputs, int block_size);

/// Train `net` on `train` by Levenberg-Marquardt (see the file comment). `validation` (may be null
/// or empty) drives early stopping; `test` (may be null or empty) is only evaluated and recorded.
/// The sets' columns must match the network (n_0 inputs, n_L outputs) unless options.initialize
/// builds the maps from `train` (the shape must still match). Throws std::invalid_argument for
/// invalid options, an empty training set, mismatched shapes or non-finite data.
LmSummary TrainLevenbergMarquardt(Fnn& net, const SampleSet& train, const SampleSet* validation,
                                  const LmOptions& options, const SampleSet* test = nullptr);

/// The normalised mse of `net` on s (see the file comment), 0 for an empty set. Throws
/// std::invalid_argument for mismatched shapes.
double NormalizedMse(const Fnn& net, const SampleSet& s);

}  // namespace softkin
