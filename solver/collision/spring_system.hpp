#pragma once
/// \file spring_system.hpp
/// The global system of Eq. 3.9: the model's free-free matrix A_ff plus K = k sum_s c_s c_s^T, one
/// term per collision spring, kept factored while springs come and go.
///
/// A spring is a stencil c_s over at most four vertices: its energy is k (c_s^T x - delta)^2 per
/// axis. A spring to a fixed target (Eq. 3.5) is the unit stencil c_s = e_v; a vertex-face spring
/// that pulls v towards a point of a moving face, sum_i w_i x_fi, is c_s = e_v - sum_i w_i e_fi
/// (SpringStencil). Coordinates a vertex has prescribed drop out of c_s (they go to the right-hand
/// side). Adding a spring adds the rank-one k c_s c_s^T to A_ff; releasing it subtracts the same.
/// Two ways to keep the factor up to date, chosen by `Method`:
///  - kUpdown (default): CHOLMOD's multiple-rank update/downdate (cholmod_updown, Davis and Hager)
///    on a private copy of the model's factor: L D L^T +/- C C^T with one column sqrt(k) c_s per
///    changed spring. Its cost follows the changed columns' paths in the elimination tree, not
///    the matrix size. The copy is converted to LDL^T by CHOLMOD on the first update.
///  - kRefactor: a numeric refactorisation of A_ff + K whenever the spring set changes (reusing
///    the symbolic analysis while K is diagonal; vertex-face springs couple vertices that A does
///    not, so then A_ff + K is analysed afresh). The reference the update/downdate is measured
///    against.
/// Long update histories accumulate round-off; after `refactor_after` updated columns (default: a
/// quarter of the matrix size) the factor is recomputed from A_ff + K.
#include "softkin/solver/fk/model.hpp"

#include <Eigen/Dense>

#include <array>
#include <memory>
#include <vector>

namespace softkin {

/// The coefficient vector c of one spring over at most four vertices (entries with vertex -1 are
/// unused). Ordered and compared entry by entry, so that sets of springs can be diffed.
struct SpringStencil {
  std::array<int, 4> vertex{-1, -1, -1, -1};
  std::array<double, 4> coef{0, 0, 0, 0};
  /// c = e_v: a spring of v to a fixed target.
  static SpringStencil Unit(int v);
  /// c = e_v - sum_i w_i e_{f_i}: v to the point sum_i w_i x_{f_i} of the face f (v not in f).
  static SpringStencil VertexFace(int v, const std::array<int, 3>& f, const Eigen::Vector3d& w);
  bool operator<(const SpringStencil& o) const {
    return vertex != o.vertex ? vertex < o.vertex : coef < o.coef;
  }
  bool operator==(const SpringStencil& o) const { return vertex == o.vertex && coef == o.coef; }
};

class SpringSystem {
 public:
  enum class Method { kUpdown, kRefactor };

  /// Statistics since construction (seconds are wall-clock).
  struct Stats {
    int changes = 0;           ///< SetSprings calls that changed the set
    long columns_updated = 0;  ///< rank-one updates + downdates (kUpdown)
    double update_s = 0;       ///< time in cholmod_updown
    int refactors = 0;         ///< numeric refactorisations (kRefactor, drift or fallback)
    double refactor_s = 0;     ///< time in cholmod_factorize
    double solve_s = 0;        ///< time in the triangular solves
    int solves = 0;
  };

  /// Copies the model's factor(s). `model` must outlive this object.
  explicit SpringSystem(const Model& model, Method method = Method::kUpdown);
  ~SpringSystem();
  SpringSystem(const SpringSystem&) = delete;
  SpringSystem& operator=(const SpringSystem&) = delete;

  /// Makes the springs exactly `springs` (a multiset: a stencil given twice counts twice), each
  /// of stiffness k > 0 (same units as A's entries, mm^3). Coordinates a vertex has prescribed
  /// are skipped. Changing k releases every spring and adds them again. Returns true if the set
  /// changed. Throws std::invalid_argument for a bad k or vertex id, std::runtime_error if CHOLMOD
  /// fails even after a refactorisation.
  bool SetSprings(const std::vector<SpringStencil>& springs, double k);
  /// Unit springs on `vertices` (distinct ids; repeats are dropped).
  bool SetSprings(const std::vector<int>& vertices, double k);
  /// Solves (A_ff + K) y = rhs in the free-coordinate layout of Model::GatherFree.
  Eigen::VectorXd Solve(const Eigen::VectorXd& rhs) const;
  /// (A_ff + K) x for free coordinates x.
  Eigen::VectorXd Multiply(const Eigen::VectorXd& x) const;
  /// Adds K x to y (both in the free layout).
  void AddSpringProduct(const Eigen::VectorXd& x, Eigen::VectorXd* y) const;

  /// The current springs, sorted.
  const std::vector<SpringStencil>& springs() const { return springs_; }
  double stiffness() const { return k_; }
  Method method() const { return method_; }
  const Stats& stats() const { return stats_; }
  /// Recomputes every factor from A_ff + K now (also what kRefactor does on each change).
  void Refactor();
  /// Threshold of updated columns after which the factor is recomputed (<= 0: never).
  void set_refactor_after(long columns) { refactor_after_ = columns; }

 private:
  struct Impl;
  /// Applies +/- sqrt(k) c_s columns for `springs` to every factor. Returns true if CHOLMOD
  /// failed and the factors were recomputed from A_ff + K (which already holds the new set).
  bool Modify(const std::vector<SpringStencil>& springs, bool add);
  const Model& model_;
  Method method_;
  std::unique_ptr<Impl> impl_;
  std::vector<SpringStencil> springs_;  // sorted
  double k_ = 0;
  long since_refactor_ = 0, refactor_after_ = 0;
  mutable Stats stats_;
};

}  // namespace softkin
