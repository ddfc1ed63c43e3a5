#include "softkin/learn/ceres_trainer.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <ceres/ceres.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>

namespace softkin {

namespace {

constexpr int kSubBlock =
    16;  // samples per Jacobian kernel call (keeps Eigen's products serial-sized)

using Clock = std::chrono::steady_clock;
// Ceres calls this from its own threads; Eigen must not open OpenMP teams from inside them.
class SerialEigenScope {
 public:
  SerialEigenScope() : saved_(omp_get_max_threads()) { omp_set_num_threads(1); }
  ~SerialEigenScope() { omp_set_num_threads(saved_); }

 private:
  int saved_;
};

// Residuals z(w) - t of one block of samples (normalised scale), with the analytic Jacobian.
class FnnBlockCost final : public ceres::CostFunction {
 public:
  FnnBlockCost(const Fnn& net, Eigen::MatrixXd U, Eigen::MatrixXd T)
      : net_(net), U_(std::move(U)), T_(std::move(T)) {
    set_num_residuals(static_cast<int>(T_.size()));
    mutable_parameter_block_sizes()->push_back(net_.num_parameters());
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    SerialEigenScope serial;
    const int W = net_.num_parameters();
    const int nL = net_.num_outputs();
    const int B = static_cast<int>(U_.cols());
    net_.set_parameters(Eigen::Map<const Eigen::VectorXd>(parameters[0], W));
    Eigen::Map<Eigen::MatrixXd> R(residuals, nL, B);  // column s = residuals of sample s
    if (jacobians && jacobians[0]) {
      // Row-major (B n_L) x W Jacobian = column-major W x (B n_L) transposed Jacobian.
      Eigen::Map<Eigen::MatrixXd> Jt(jacobians[0], W, static_cast<Eigen::Index>(B) * nL);
      for (int a = 0; a < B; a += kSubBlock) {
        const int m = std::min(kSubBlock, B - a);
        net_.ParameterJacobianNormalized(U_.middleCols(a, m), ws_, R.middleCols(a, m),
                                         Jt.middleCols(static_cast<Eigen::Index>(a) * nL, m * nL));
      }
    } else {
      net_.ForwardNormalized(U_, ws_, R);
    }
    R -= T_;
    return R.allFinite();
  }

 private:
  mutable Fnn net_;  // this block's copy (Ceres evaluates one block on one thread at a time)
  mutable FnnBlockWorkspace ws_;
  Eigen::MatrixXd U_, T_;
};

class TargetCallback final : public ceres::IterationCallback {
 public:
  TargetCallback(double denom, double target, Clock::time_point t0, CeresFitSummary* sum)
      : denom_(denom), target_(target), t0_(t0), sum_(sum) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& it) override {
    const double mse = 2.0 * it.cost / denom_;
    if (it.iteration == 0 || it.step_is_successful || sum_->train_mse.empty()) {
      sum_->train_mse.push_back(mse);
    } else {
      sum_->train_mse.push_back(sum_->train_mse.back());  // rejected step: the loss stays
    }
    sum_->time_s.push_back(SecondsSince(t0_));
    if (target_ > 0.0 && sum_->train_mse.back() <= target_) {
      if (sum_->time_to_target_s < 0.0) sum_->time_to_target_s = sum_->time_s.back();
      return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
    }
    return ceres::SOLVER_CONTINUE;
  }

 private:
  double denom_, target_;
  Clock::time_point t0_;
  CeresFitSummary* sum_;
};

}  // namespace

bool CeresFitOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& msg) {
    if (why) *why = msg;
    return false;
  };
  if (max_iterations < 0) return fail("max_iterations must be >= 0");
  if (!(target_mse >= 0.0)) return fail("target_mse must be >= 0 (0: no target)");
  if (!(max_time_s >= 0.0)) return fail("max_time_s must be >= 0 (0: no limit)");
  if (block_size < 0) return fail("block_size must be >= 0 (0: automatic)");
  if (num_threads < 1) return fail("num_threads must be >= 1");
  if (linear_solver != "dense_normal_cholesky" && linear_solver != "dense_qr")
    return fail("linear_solver must be \"dense_normal_cholesky\" or \"dense_qr\", got \"" +
                linear_solver + "\"");
  return true;
}

std::string CeresFitSummary::BriefReport() const {
  char buf[256];
  std::snprintf(buf, sizeof(buf), "Ceres: mse %.4g -> %.4g in %d iterations, %.3g s%s", initial_mse,
                final_mse, iterations, total_time_s,
                time_to_target_s >= 0.0
                    ? (" (target at " + std::to_string(time_to_target_s) + " s)").c_str()
                    : "");
  return buf;
}

CeresFitSummary FitFnnWithCeres(Fnn& net, const SampleSet& train, const CeresFitOptions& options) {
  std::string why;
  if (!options.IsValid(&why))
    throw std::invalid_argument("FitFnnWithCeres: invalid options: " + why);
  if (net.num_layers() == 0) throw std::invalid_argument("FitFnnWithCeres: the network is empty");
  if (train.empty()) throw std::invalid_argument("FitFnnWithCeres: the training set is empty");
  if (train.X.rows() != train.Y.rows() || train.X.cols() != net.num_inputs() ||
      train.Y.cols() != net.num_outputs())
    throw std::invalid_argument(
        "FitFnnWithCeres: data of " + std::to_string(train.X.rows()) + "x" +
        std::to_string(train.X.cols()) + " -> " + std::to_string(train.Y.rows()) + "x" +
        std::to_string(train.Y.cols()) + " does not fit the network " + net.Describe());
  if (!train.X.allFinite() || !train.Y.allFinite())
    throw std::invalid_argument("FitFnnWithCeres: the training set has non-finite entries");

  const Clock::time_point t0 = Clock::now();
  if (options.initialize) {
    net.FitNormalization(train.X, train.Y);
    net.InitializeNguyenWidrow(options.seed);
  }
  Eigen::MatrixXd U = train.X.transpose(), T = train.Y.transpose();
  net.input_map().ApplyColumns(U);
  net.output_map().ApplyColumns(T);
  const int N = train.size();
  const int nL = net.num_outputs();
  const int bs = std::min(N, options.block_size > 0 ? options.block_size : std::max(1, 256 / nL));

  Eigen::VectorXd w = net.parameters();
  ceres::Problem::Options popt;  // the problem owns the cost functions
  ceres::Problem problem(popt);
  problem.AddParameterBlock(w.data(), static_cast<int>(w.size()));
  for (int s0 = 0; s0 < N; s0 += bs) {
    const int n = std::min(bs, N - s0);
    problem.AddResidualBlock(new FnnBlockCost(net, U.middleCols(s0, n), T.middleCols(s0, n)),
                             nullptr, w.data());
  }

  CeresFitSummary sum;
  const double denom = static_cast<double>(N) * nL;
  TargetCallback callback(denom, options.target_mse, t0, &sum);
  ceres::Solver::Options sopt;
  sopt.minimizer_type = ceres::TRUST_REGION;
  sopt.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  if (!ceres::StringToLinearSolverType(options.linear_solver, &sopt.linear_solver_type))
    throw std::invalid_argument("FitFnnWithCeres: unknown linear_solver \"" +
                                options.linear_solver + "\"");
  sopt.max_num_iterations = options.max_iterations;
  if (options.max_time_s > 0.0) sopt.max_solver_time_in_seconds = options.max_time_s;
  sopt.num_threads = options.num_threads;
  // Stop on the target (or the iteration / time caps), not on Ceres's relative-change tests.
  sopt.function_tolerance = 1e-15;
  sopt.gradient_tolerance = 1e-30;
  sopt.parameter_tolerance = 1e-15;
  sopt.minimizer_progress_to_stdout = options.verbose;
  sopt.callbacks.push_back(&callback);
  sopt.update_state_every_iteration = false;

  ceres::Solver::Summary csum;
  ceres::Solve(sopt, &problem, &csum);
  net.set_parameters(w);

  sum.ceres_report = csum.BriefReport();
  sum.iterations = std::max(0, static_cast<int>(csum.iterations.size()) - 1);
  sum.initial_mse = 2.0 * csum.initial_cost / denom;
  sum.final_mse = 2.0 * csum.final_cost / denom;
  sum.reached_target = options.target_mse > 0.0 && sum.final_mse <= options.target_mse;
  sum.total_time_s = SecondsSince(t0);
  return sum;
}

}  // namespace softkin
