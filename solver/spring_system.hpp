#pragma once
/// \file spring_system.hpp
/// The global system of Eq. 3.9: the model's free-free matrix A_ff plus k I on the rows of the
/// vertices that hold a collision spring (Eq. 3.5), kept factored while springs come and go.
///
/// Adding a spring at free coordinate i adds k e_i e_i^T to A_ff, a rank-one change; releasing it
/// subtracts the same. Two ways to keep the factor up to date, chosen by `Method`:
///  - kUpdown (default): CHOLMOD's multiple-rank update/downdate (cholmod_updown, Davis and Hager)
///    on a private copy of the model's factor: L D L^T +/- C C^T with one column sqrt(k) e_i per
///    changed vertex. Its cost follows the changed columns' paths in the elimination tree, not
///    the matrix size. The copy is converted to LDL^T by CHOLMOD on the first update.
///  - kRefactor: a numeric refactorisation of A_ff + K (reusing the symbolic analysis) whenever
///    the spring set changes. The reference the update/downdate is measured against.
/// Long update histories accumulate round-off; after `refactor_after` updated columns (default: a
/// quarter of the matrix size) the factor is recomputed from A_ff + K.
#include "solver/model.hpp"

#include <Eigen/Dense>

#include <memory>
#include <vector>

namespace softkin {

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

  /// Makes the springs exactly those on `vertices` (distinct vertex ids), each of stiffness k > 0
  /// (same units as A's entries, mm^3). Coordinates a vertex has prescribed are skipped. Changing
  /// k releases every spring and adds them again. Returns true if the set changed. Throws
  /// std::runtime_error if CHOLMOD fails even after a refactorisation.
  bool SetSprings(const std::vector<int>& vertices, double k);
  /// Solves (A_ff + K) y = rhs in the free-coordinate layout of Model::GatherFree.
  Eigen::VectorXd Solve(const Eigen::VectorXd& rhs) const;
  /// (A_ff + K) x for free coordinates x (A_ff of the model plus the springs' diagonal).
  Eigen::VectorXd Multiply(const Eigen::VectorXd& x) const;

  const std::vector<int>& springs() const { return vertices_; }
  double stiffness() const { return k_; }
  Method method() const { return method_; }
  const Stats& stats() const { return stats_; }
  /// Recomputes every factor from A_ff + K now (also what kRefactor does on each change).
  void Refactor();
  /// Threshold of updated columns after which the factor is recomputed (<= 0: never).
  void set_refactor_after(long columns) { refactor_after_ = columns; }

 private:
  struct Impl;
  /// Applies +/- sqrt(k) e_i columns for `verts` to every factor. Returns true if CHOLMOD failed
  /// and the factors were recomputed from A_ff + K (which already holds the new set) instead.
  bool Modify(const std::vector<int>& verts, bool add);
  const Model& model_;
  Method method_;
  std::unique_ptr<Impl> impl_;
  std::vector<int> vertices_;  // sorted
  double k_ = 0;
  long since_refactor_ = 0, refactor_after_ = 0;
  mutable Stats stats_;
};

}  // namespace softkin
