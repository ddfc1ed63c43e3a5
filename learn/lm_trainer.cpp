#include "softkin/learn/lm_trainer.hpp"

#include "softkin/learn/tiled_cholesky.hpp"
#include "softkin/solver/fk/fk_options.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace softkin {

namespace {

constexpr int kSubBlock =
    16;  // samples per parallel Jacobian task (fixed: results do not depend on threads)
constexpr int kTile = 64;           // columns of H per parallel product task
constexpr int kCholeskyTile = 128;  // tile of the damped normal matrix's factorisation
constexpr double kMuMin = 1e-20;    // trainlm's floor on mu

using Clock = std::chrono::steady_clock;

// While alive, the calling thread's OpenMP default team size is 1, which threads spawned by our
// own parallel regions inherit. Eigen then never parallelises a product or factorisation by
// itself (its block sizes depend on its thread count, which would make the numbers depend on it).
class SerialEigenGuard {
 public:
  SerialEigenGuard() : saved_(omp_get_max_threads()) { omp_set_num_threads(1); }
  ~SerialEigenGuard() { omp_set_num_threads(saved_); }
  int saved() const { return saved_; }

 private:
  int saved_;
};

void CheckSet(const Fnn& net, const SampleSet& s, const char* what) {
  if (s.X.rows() != s.Y.rows())
    throw std::invalid_argument(std::string("TrainLevenbergMarquardt: ") + what + " set has " +
                                std::to_string(s.X.rows()) + " inputs but " +
                                std::to_string(s.Y.rows()) + " targets");
  if (s.X.cols() != net.num_inputs() || s.Y.cols() != net.num_outputs())
    throw std::invalid_argument(std::string("TrainLevenbergMarquardt: ") + what + " set is " +
                                std::to_string(s.X.cols()) + " -> " + std::to_string(s.Y.cols()) +
                                " columns, the network is " + net.Describe());
  if (!s.X.allFinite() || !s.Y.allFinite())
    throw std::invalid_argument(std::string("TrainLevenbergMarquardt: ") + what +
                                " set has non-finite entries");
}

// A sample set on the network's normalised scale, column per sample.
struct NormalizedSet {
  Eigen::MatrixXd U;  // n_0 x N
  Eigen::MatrixXd T;  // n_L x N
  int size() const { return static_cast<int>(U.cols()); }
};

NormalizedSet Normalize(const Fnn& net, const SampleSet& s) {
  NormalizedSet n;
  n.U = s.X.transpose();
  n.T = s.Y.transpose();
  net.input_map().ApplyColumns(n.U);
  net.output_map().ApplyColumns(n.T);
  return n;
}

// Per-thread scratch.
struct ThreadScratch {
  FnnBlockWorkspace ws;
  Eigen::MatrixXd Z;
};

// Sum of squared normalised errors of `net` on `set`, over fixed blocks of `bs` samples (blocks in
// parallel, partial sums added in block order: the same bits for any thread count).
double SumSquaredError(const Fnn& net, const NormalizedSet& set, int bs, int nt,
                       std::vector<ThreadScratch>& scratch) {
  const int N = set.size();
  if (N == 0) return 0.0;
  const int nblocks = (N + bs - 1) / bs;
  std::vector<double> partial(nblocks, 0.0);
#pragma omp parallel for num_threads(nt) schedule(dynamic, 1)
  for (int b = 0; b < nblocks; ++b) {
    ThreadScratch& sc = scratch[omp_get_thread_num()];
    const int s0 = b * bs, n = std::min(bs, N - s0);
    sc.Z.resize(net.num_outputs(), n);
    net.ForwardNormalized(set.U.middleCols(s0, n), sc.ws, sc.Z);
    partial[b] = (set.T.middleCols(s0, n) - sc.Z).squaredNorm();
  }
  double sum = 0.0;
  for (double p : partial) sum += p;
  return sum;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

bool LmOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& msg) {
    if (why) *why = msg;
    return false;
  };
  if (!(mu > 0.0 && std::isfinite(mu))) return fail("mu must be finite and > 0");
  if (!(mu_dec > 0.0 && mu_dec < 1.0)) return fail("mu_dec must be in (0, 1)");
  if (!(mu_inc > 1.0 && std::isfinite(mu_inc))) return fail("mu_inc must be finite and > 1");
  if (!(mu_max >= mu && std::isfinite(mu_max))) return fail("mu_max must be finite and >= mu");
  if (!(min_grad >= 0.0)) return fail("min_grad must be >= 0");
  if (max_epochs < 0) return fail("max_epochs must be >= 0");
  if (max_fail < 1) return fail("max_fail must be >= 1");
  if (!(goal >= 0.0)) return fail("goal must be >= 0");
  if (!(max_time_s >= 0.0)) return fail("max_time_s must be >= 0 (0: no limit)");
  if (block_size < 0) return fail("block_size must be >= 0 (0: automatic)");
  if (num_threads < 0 || num_threads > kMaxThreads)
    return fail("num_threads must be in [0, " + std::to_string(kMaxThreads) +
                "] (0: OpenMP default)");
  if (progress_every < 1) return fail("progress_every must be >= 1");
  return true;
}

const char* LmTerminationToString(LmTermination t) {
  switch (t) {
    case LmTermination::kGoalReached:
      return "goal";
    case LmTermination::kMinGradient:
      return "min_gradient";
    case LmTermination::kMuMax:
      return "mu_max";
    case LmTermination::kMaxEpochs:
      return "max_epochs";
    case LmTermination::kMaxTime:
      return "max_time";
    case LmTermination::kValidationStop:
      return "validation_stop";
  }
  return "unknown";
}

bool LmTerminationFromString(const std::string& name, LmTermination* t) {
  for (LmTermination c :
       {LmTermination::kGoalReached, LmTermination::kMinGradient, LmTermination::kMuMax,
        LmTermination::kMaxEpochs, LmTermination::kMaxTime, LmTermination::kValidationStop}) {
    if (name == LmTerminationToString(c)) {
      *t = c;
      return true;
    }
  }
  return false;
}

double LmSummary::TimeToTrainMse(double target) const {
  for (std::size_t i = 0; i < train_mse.size() && i < time_s.size(); ++i)
    if (train_mse[i] <= target) return time_s[i];
  return -1.0;
}

std::string LmSummary::BriefReport() const {
  char buf[512];
  std::snprintf(
      buf, sizeof(buf),
      "LM: %s after %d epochs (%d accepted, %d rejected steps), train mse %.4g, best epoch %d%s, "
      "%d parameters, %.3g s on %d thread(s)",
      LmTerminationToString(termination), epochs, accepted_steps, rejected_steps, final_train_mse,
      best_epoch,
      val_mse.empty() ? "" : (" (val mse " + std::to_string(best_val_mse) + ")").c_str(),
      num_parameters, total_time_s, num_threads);
  return buf;
}

double NormalizedMse(const Fnn& net, const SampleSet& s) {
  if (s.empty()) return 0.0;
  CheckSet(net, s, "evaluation");
  SerialEigenGuard guard;
  const NormalizedSet n = Normalize(net, s);
  std::vector<ThreadScratch> scratch(1);
  return SumSquaredError(net, n, 256, 1, scratch) /
         (static_cast<double>(n.size()) * net.num_outputs());
}

double LmMemoryBytes(double num_parameters, int num_outputs, int block_size) {
  const double rows =
      block_size > 0 ? static_cast<double>(block_size) * num_outputs : std::max(2048, num_outputs);
  return 8.0 * num_parameters * (2.0 * num_parameters + rows);
}

LmSummary TrainLevenbergMarquardt(Fnn& net, const SampleSet& train, const SampleSet* validation,
                                  const LmOptions& options, const SampleSet* test) {
  std::string why;
  if (!options.IsValid(&why))
    throw std::invalid_argument("TrainLevenbergMarquardt: invalid options: " + why);
  if (net.num_layers() == 0)
    throw std::invalid_argument("TrainLevenbergMarquardt: the network is empty");
  if (train.empty())
    throw std::invalid_argument("TrainLevenbergMarquardt: the training set is empty");
  CheckSet(net, train, "training");
  const bool has_val = validation && !validation->empty();
  const bool has_test = test && !test->empty();
  if (has_val) CheckSet(net, *validation, "validation");
  if (has_test) CheckSet(net, *test, "test");

  const Clock::time_point t0 = Clock::now();
  SerialEigenGuard guard;
  const int nt = options.num_threads > 0 ? options.num_threads : std::max(1, guard.saved());

  if (options.initialize) {
    net.FitNormalization(train.X, train.Y);
    net.InitializeNguyenWidrow(options.seed);
  }
  const NormalizedSet tr = Normalize(net, train);
  const NormalizedSet va = has_val ? Normalize(net, *validation) : NormalizedSet();
  const NormalizedSet te = has_test ? Normalize(net, *test) : NormalizedSet();

  const int N = tr.size();
  const int nL = net.num_outputs();
  const int W = net.num_parameters();
  const int bs = std::min(N, options.block_size > 0 ? options.block_size : std::max(1, 2048 / nL));
  const double denom = static_cast<double>(N) * nL;

  std::vector<ThreadScratch> scratch(nt);
  Fnn trial = net;
  auto mse_of = [&](const Fnn& f, const NormalizedSet& set) {
    return set.size() == 0
               ? 0.0
               : SumSquaredError(f, set, bs, nt, scratch) / (static_cast<double>(set.size()) * nL);
  };

  LmSummary sum;
  sum.num_parameters = W;
  sum.num_threads = nt;

  Eigen::VectorXd w = net.parameters();
  double loss = mse_of(net, tr);
  double mu = options.mu;
  sum.train_mse.push_back(loss);
  if (has_val) sum.val_mse.push_back(mse_of(net, va));
  if (has_test) sum.test_mse.push_back(mse_of(net, te));
  sum.mu.push_back(mu);
  sum.time_s.push_back(SecondsSince(t0));

  Eigen::VectorXd best_w = w;
  double best_val = has_val ? sum.val_mse.back() : 0.0;
  int best_epoch = 0;
  int val_fail = 0;

  // O(W^2) state, allocated once.
  Eigen::MatrixXd H(W, W), A(W, W);
  Eigen::VectorXd g(W), delta(W);
  Eigen::MatrixXd Jt(W, static_cast<Eigen::Index>(bs) * nL);
  Eigen::MatrixXd Zb(nL, bs);
  const int ntiles = (W + kTile - 1) / kTile;

  auto progress = [&](int epoch, bool force) {
    if (!options.verbose || (!force && epoch % options.progress_every != 0)) return;
    std::fprintf(stderr, "LM epoch %d/%d: mse %.4e", epoch, options.max_epochs, loss);
    if (has_val)
      std::fprintf(stderr, "  val %.4e (best %.4e @%d, fail %d)", sum.val_mse.back(), best_val,
                   best_epoch, val_fail);
    std::fprintf(stderr, "  mu %.1e", mu);
    if (!sum.gradient_norm.empty()) std::fprintf(stderr, "  |grad| %.2e", sum.gradient_norm.back());
    std::fprintf(stderr, "  %.1f s\n", SecondsSince(t0));
  };
  progress(0, true);

  int epoch = 0;
  for (;;) {
    if (loss <= options.goal) {
      sum.termination = LmTermination::kGoalReached;
      break;
    }
    if (epoch >= options.max_epochs) {
      sum.termination = LmTermination::kMaxEpochs;
      break;
    }
    if (options.max_time_s > 0.0 && SecondsSince(t0) >= options.max_time_s) {
      sum.termination = LmTermination::kMaxTime;
      break;
    }

    // ---- H = J^T J (lower triangle), g = J^T e over blocks ----
    H.setZero();
    g.setZero();
    for (int s0 = 0; s0 < N; s0 += bs) {
      const int n = std::min(bs, N - s0);
      const int nsub = (n + kSubBlock - 1) / kSubBlock;
      const int rows = n * nL;
#pragma omp parallel num_threads(nt)
      {
        ThreadScratch& sc = scratch[omp_get_thread_num()];
#pragma omp for schedule(static)
        for (int q = 0; q < nsub; ++q) {
          const int a = q * kSubBlock, m = std::min(kSubBlock, n - a);
          net.ParameterJacobianNormalized(tr.U.middleCols(s0 + a, m), sc.ws, Zb.middleCols(a, m),
                                          Jt.middleCols(static_cast<Eigen::Index>(a) * nL, m * nL));
        }
        // e = t - z, column s n_L + k (the column order of Jt); kept in Zb.
#pragma omp single
        Zb.leftCols(n) = tr.T.middleCols(s0, n) - Zb.leftCols(n);
        const Eigen::Map<const Eigen::VectorXd> e(Zb.data(), rows);
#pragma omp for schedule(dynamic, 1)
        for (int t = 0; t < ntiles; ++t) {
          const int c0 = t * kTile, tw = std::min(kTile, W - c0);
          H.block(c0, c0, W - c0, tw).noalias() +=
              Jt.block(c0, 0, W - c0, rows) * Jt.block(c0, 0, tw, rows).transpose();
          g.segment(c0, tw).noalias() += Jt.block(c0, 0, tw, rows) * e;
        }
      }
    }
    const double grad_norm = 2.0 * g.norm() / denom;
    sum.gradient_norm.push_back(grad_norm);
    if (grad_norm < options.min_grad) {
      sum.termination = LmTermination::kMinGradient;
      break;
    }

    // ---- mu loop: (H + mu I) delta = g ----
    bool accepted = false;
    while (mu <= options.mu_max) {
      A.triangularView<Eigen::Lower>() = H.triangularView<Eigen::Lower>();
      A.diagonal().array() += mu;
      if (TiledCholeskyInPlace(A, kCholeskyTile, nt)) {
        delta = g;
        TiledCholeskySolveInPlace(A, delta);
        trial.set_parameters(w + delta);
        const double trial_loss = mse_of(trial, tr);
        if (std::isfinite(trial_loss) && trial_loss < loss) {
          w += delta;
          net.set_parameters(w);
          loss = trial_loss;
          mu = std::max(mu * options.mu_dec, kMuMin);
          ++sum.accepted_steps;
          accepted = true;
          break;
        }
      }
      mu *= options.mu_inc;
      ++sum.rejected_steps;
    }
    ++epoch;
    sum.train_mse.push_back(loss);
    if (has_val) sum.val_mse.push_back(accepted ? mse_of(net, va) : sum.val_mse.back());
    if (has_test) sum.test_mse.push_back(accepted ? mse_of(net, te) : sum.test_mse.back());
    sum.mu.push_back(mu);
    sum.time_s.push_back(SecondsSince(t0));
    if (!accepted) {
      progress(epoch, true);
      sum.termination = LmTermination::kMuMax;
      break;
    }
    if (has_val) {
      const double v = sum.val_mse.back();
      if (v < best_val) {
        best_val = v;
        best_w = w;
        best_epoch = epoch;
        val_fail = 0;
      } else if (v > best_val) {
        ++val_fail;
      }
    } else {
      best_epoch = epoch;
    }
    progress(epoch, false);
    if (has_val && val_fail >= options.max_fail) {
      sum.termination = LmTermination::kValidationStop;
      break;
    }
  }

  sum.epochs = epoch;
  if (has_val) {
    net.set_parameters(best_w);
    sum.best_val_mse = best_val;
    sum.final_train_mse = sum.train_mse[best_epoch];
  } else {
    sum.final_train_mse = loss;
  }
  sum.best_epoch = best_epoch;
  sum.total_time_s = SecondsSince(t0);
  std::ostringstream msg;
  switch (sum.termination) {
    case LmTermination::kGoalReached:
      msg << "training mse " << loss << " <= goal " << options.goal;
      break;
    case LmTermination::kMinGradient:
      msg << "gradient norm " << sum.gradient_norm.back() << " < min_grad " << options.min_grad;
      break;
    case LmTermination::kMuMax:
      msg << "mu " << mu << " > mu_max " << options.mu_max << ": no step lowers the loss";
      break;
    case LmTermination::kMaxEpochs:
      msg << "reached max_epochs " << options.max_epochs;
      break;
    case LmTermination::kMaxTime:
      msg << "reached max_time_s " << options.max_time_s;
      break;
    case LmTermination::kValidationStop:
      msg << options.max_fail << " validation failures in a row; best validation mse " << best_val
          << " at epoch " << best_epoch;
      break;
  }
  sum.message = msg.str();
  if (options.verbose) std::fprintf(stderr, "%s\n", sum.BriefReport().c_str());
  return sum;
}

}  // namespace softkin
