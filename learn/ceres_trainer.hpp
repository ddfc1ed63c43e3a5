#pragma once
/// \file
/// A peer check of the in-house Levenberg-Marquardt trainer (learn/lm_trainer.hpp): the same
/// network's parameters fitted as a Ceres nonlinear least-squares problem on the same data.
///
/// Problem. One parameter block (the flat parameter vector w, Fnn layout); one residual block per
/// block of samples, residuals r_sk = z_sk(w) - t_sk on the network's normalised output scale, with
/// the analytic parameter Jacobian (Fnn::ParameterJacobianNormalized) as a ceres::CostFunction. So
/// Ceres minimises 0.5 sum r^2 = 0.5 N n_L mse(w), the same loss as the in-house trainer.
///
/// Differences from the in-house trainer: Ceres's LM is a trust-region method with Marquardt's
/// diagonal scaling (D = diag(J^T J)) and its own radius updates (not trainlm's mu rules), and its
/// dense linear solvers form the whole N n_L x W Jacobian (memory O(N n_L W), against O(W^2) for
/// the in-house trainer). The fit stops when the training mse reaches `target_mse` (an
/// IterationCallback), so the time to a given loss can be compared with LmSummary::TimeToTrainMse.

#include "softkin/learn/fnn.hpp"
#include "softkin/learn/sample_set.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace softkin {

struct CeresFitOptions {
  int max_iterations = 1000;  ///< Ceres iterations (>= 0)
  double target_mse = 0.0;    ///< stop once the normalised training mse <= this (0: no target)
  double max_time_s = 0.0;    ///< wall-time cap in seconds, 0 = none
  /// Samples per residual block; 0 = automatic (max(1, 256 / n_L)).
  int block_size = 0;
  int num_threads = 1;  ///< Ceres threads (>= 1)
  /// Ceres linear solver: "dense_normal_cholesky" (default) or "dense_qr".
  std::string linear_solver = "dense_normal_cholesky";
  /// true: fit the normalisation to the data and Nguyen-Widrow-initialise from `seed` first (as
  /// LmOptions::initialize); false: start from the network as given.
  bool initialize = true;
  std::uint64_t seed = 1;
  bool verbose = false;  ///< Ceres progress on stdout
  /// True if every field is in range; else false and *why names the field.
  bool IsValid(std::string* why) const;
};

struct CeresFitSummary {
  bool reached_target = false;    ///< training mse <= target_mse (only with a target)
  double initial_mse = 0.0;       ///< normalised training mse before the fit
  double final_mse = 0.0;         ///< ... and after it
  int iterations = 0;             ///< Ceres iterations (excluding iteration 0)
  double total_time_s = 0.0;      ///< wall time of the whole call (set-up included)
  double time_to_target_s = -1;   ///< wall time when the target was first reached, or -1
  std::vector<double> train_mse;  ///< per Ceres iteration (index 0 = start)
  std::vector<double> time_s;     ///< wall time since the call started, per entry of train_mse
  std::string ceres_report;       ///< ceres::Solver::Summary::BriefReport()
  /// One line: mse, iterations, time (to target).
  std::string BriefReport() const;
};

/// Fit `net` to `train` with Ceres (see the file comment); the network is left at the solution.
/// Throws std::invalid_argument for invalid options, an empty set, mismatched shapes or
/// non-finite data.
CeresFitSummary FitFnnWithCeres(Fnn& net, const SampleSet& train, const CeresFitOptions& options);

}  // namespace softkin
