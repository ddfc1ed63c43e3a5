#pragma once
/// \file equilibrium_jacobian.hpp
/// Implicit differentiation of the local-global equilibrium (the fixed point of Algorithm 1) with
/// respect to the actuation: dX/dc without re-solving the forward problem.
///
/// The local-global solver (local_global.hpp) stops at a fixed point of x <- A_ff^-1 (B_f(X, c) -
/// A_fc x_c): the free coordinates x satisfy
///     G(x, c) = A_ff x + A_fc x_c(c) - B_f(X, c) = 0,
/// where B(X, c) = sum_i w_i Vol_i S_i^T T_i(X, c) gathers the element targets (targets.hpp) and
/// x_c are the prescribed coordinates (fixed, held, moved by motion actuators). The targets depend
/// on X through the best rotations (polar factors), the volume-restoring scale of blended bodies
/// and, for actuation elements, the local ratios r_i, which are proportional to each element's
/// current measure and normalised by the group's total current measure (ComputeLocalRatios: a
/// coupling of every element of a group). Differentiating G = 0:
///     H dx/dc = dB_f/dc + (K_fc - A_fc) dx_c/dc,    H = A_ff - K_ff,    K = dB/dX,
/// and dX/dc = [dx/dc ; dx_c/dc]. K is applied matrix-free and exactly (no finite differences):
///   - polar factor: for M = R S (S = R^T M symmetric), R^T dR = [w]_x with
///     (tr(S) I - S) w = axial(R^T dM - dM^T R);
///   - blend scale s = cbrt(Vol_0 / Vol(D)): ds = -(s / 3) dVol / Vol;
///   - ratios: r_i = m_i sigma / mu_i, sigma = (rho(c) (M + L_R) - L_R) / sum_j m_j, so
///     dr_i = (sigma dm_i + m_i dsigma) / mu_i with dsigma = -sigma d(sum m_j) / sum m_j +
///     (M + L_R) drho / sum m_j: a per-group rank-one coupling, applied as such.
/// H is not symmetric in general (the blended and ratio-coupled targets are not minimisers of one
/// energy), so the linear solve is restarted GMRES (all columns in lockstep, one batched product
/// per round), left-preconditioned by A_ff^-1 with the model's prefactored CHOLMOD factor
/// (Model::SolveFree): the preconditioned operator is I - A_ff^-1 K_ff, the identity minus the
/// Jacobian of the local-global map, whose spectrum the local-global iteration itself contracts;
/// GMRES needs far fewer products than that iteration.
///
///   - hyperelastic bodies (Eq. 3.6-3.7), T = c Bl with Bl = t R P + (1 - t) D, t = R_omega(eps),
///     c = cbrt(Vol_0 / Vol(Bl)): dBl = dt (R P - D) + t d(R P) + (1 - t) dD, dt = R_omega'(eps)
///     <d eps/dF, dF> (EquivalentStrainGradient; F = D^T P (P^T P)^-1), or on the blend-volume
///     floor the dt that keeps Vol(Bl) at the floor; dc = -(c / 3) <grad Vol(Bl), dBl> / Vol(Bl).
/// Supported: body elements with the blend law (Eq. 2.3-2.5) or a Mooney-Rivlin curve, pneumatic,
/// cable and DEA actuation elements (vented chambers too), fixed / held coordinates and motion
/// actuators. Not supported: collision springs (the caller must check FkOptions::collision
/// itself; this file only sees the energy). Clamped quantities (kMinMeasure floors, the blend
/// scale capped at 10, R_omega beyond the curve's last knot) have zero derivative, which is their
/// true one-sided derivative; at a knot of the piecewise-linear R_omega curve the slope of the
/// interval to its right is used.
#include "softkin/solver/fk/model.hpp"

#include <Eigen/CholmodSupport>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace softkin {

/// The CHOLMOD factor of the "local" preconditioner (EquilibriumJacobianOptions::preconditioner).
using LocalPreconditioner = Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower>;
/// One element's block of K_local (3k x 3k, k <= 6 vertices).
using LocalBlock = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 18, 18>;

class EquilibriumLinearization;

/// What the "local" preconditioner keeps from one Jacobian to the next of the same model: the
/// sparsity pattern of A_ff - sym(K_local) and CHOLMOD's symbolic analysis (ordering, supernodes),
/// so later Jacobians only assemble and factor numerically. Not thread-safe; one per caller.
class EquilibriumJacobianWorkspace {
 public:
  EquilibriumJacobianWorkspace();
  ~EquilibriumJacobianWorkspace();
  EquilibriumJacobianWorkspace(const EquilibriumJacobianWorkspace&) = delete;
  EquilibriumJacobianWorkspace& operator=(const EquilibriumJacobianWorkspace&) = delete;
  /// Numeric factorisations done with this workspace.
  int factorizations() const;
  /// Assembles P = A_ff - sym(K_local)_ff at lin's state (the per-element blocks of
  /// EquilibriumLinearization::ForEachLocalBlock) and factors it; the pattern and the symbolic
  /// analysis are kept for later calls on the same model. `project`: replace each element's block
  /// by V |Lambda| V^T (the absolute values of its eigenvalues) from now on, which keeps P
  /// positive definite; without it that happens only once P was found indefinite. Returns false
  /// if P is not positive definite (factor() is then null).
  bool Factor(const Model& model, const EquilibriumLinearization& lin, int threads, bool project);
  /// The factor of the last successful factorisation (by Factor or by a Jacobian's "local"
  /// preconditioner), or null.
  const LocalPreconditioner* factor() const;
  /// Whether the element blocks are projected (asked for, or found indefinite once).
  bool projected() const;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The Krylov method of the implicit solve (EquilibriumJacobianOptions::krylov). Names as for the
/// FK options (fk_options.hpp): ToString, KrylovMethodFromString, KrylovMethodNames.
enum class KrylovMethod {
  kGmres,     ///< "gmres": restarted GMRES
  kBicgstab,  ///< "bicgstab": BiCGSTAB, no stored basis
};
std::string ToString(KrylovMethod k);
KrylovMethod KrylovMethodFromString(const std::string& s);
std::vector<std::string> KrylovMethodNames();

/// The preconditioner of the implicit solve (EquilibriumJacobianOptions::preconditioner).
enum class JacobianPreconditioner {
  kAff,    ///< "A_ff": the global step's prefactored matrix
  kLocal,  ///< "local": A_ff - sym(K_local), factored
};
std::string ToString(JacobianPreconditioner p);
JacobianPreconditioner JacobianPreconditionerFromString(const std::string& s);
std::vector<std::string> JacobianPreconditionerNames();

struct EquilibriumJacobianOptions {
  /// Krylov method: "gmres" (restarted, see restart) or "bicgstab" (no stored basis).
  KrylovMethod krylov = KrylovMethod::kGmres;
  /// Stop GMRES when the preconditioned residual has dropped by this factor (relative to the
  /// preconditioned right-hand side, whatever the starting guess).
  double tolerance = 1e-8;
  /// Krylov iterations (operator products) allowed per column, over all restarts.
  int max_iterations = 1000;
  /// GMRES restart length (Krylov basis size; the basis grows as needed, up to 8 x #free dofs x
  /// (restart + 1) bytes per column). Restarting loses the slow modes and costs far more products
  /// (cable_finger res 5 to 1e-8: 732 products with restart 80, ~480 without restart), so it is
  /// large.
  int restart = 300;
  /// GMRES only: solve all columns in lockstep, each in its own Krylov space but with one batched
  /// operator product per round (one pass over the elements for every column, and one CHOLMOD
  /// solve with 3 x #columns right-hand sides). Same iterates as column by column, in about half
  /// the time on three_chamber (docs/kinematics.md). false: one column after the other.
  bool lockstep = true;
  /// OpenMP threads for the per-element products (0 = library default).
  int threads = 0;
  /// "A_ff": precondition by the global step's prefactored matrix (no setup cost). "local"
  /// (default): factor A_ff - sym(K_local) (K_local: the per-element blocks of K,
  /// LocalStiffness) with CHOLMOD's supernodal Cholesky, closer to H (for rigid bodies it is the
  /// ARAP Hessian; only the groups' rank-one coupling and the skew part are left to GMRES) but a
  /// factorisation of 3 #V unknowns; falls back to A_ff if it is not positive definite
  /// (docs/kinematics.md).
  JacobianPreconditioner preconditioner = JacobianPreconditioner::kLocal;
  /// "local" with a workspace: use the workspace's factor of an earlier state instead of
  /// factoring again, while it still works (GMRES converges within max(2 n, n + 10) rounds, n the
  /// rounds right after it was factored; past that it is refactored at the next Jacobian, and at
  /// once if GMRES did not converge). Along an IK path the state changes slowly.
  bool reuse_preconditioner = true;
  bool IsValid(std::string* why) const;
};

/// The linearisation of the right-hand side B(X, c) of the global step (AssembleRhs of the targets
/// of ComputeLocalRatios/LocalStep) at one state: caches per element the best rotation and the
/// inverse of tr(S) I - S, per group its current measures and normalisation.
class EquilibriumLinearization {
 public:
  /// Linearises at positions X (#V x 3, mm) and actuation c (#actuators). Returns false with the
  /// reason in *why for a degenerate element (flat or inverted: tr(S) I - S singular), true
  /// otherwise.
  bool Setup(const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
             const Eigen::Ref<const Eigen::VectorXd>& c, std::string* why, int threads = 0);
  /// dB = the directional derivative of B(X, c) (#V x 3) along positions dX (#V x 3, mm; every
  /// coordinate, prescribed ones included) and actuation dc (#actuators). Exact up to round-off.
  void ApplyRhsDerivative(const Eigen::Ref<const Eigen::MatrixX3d>& dX,
                          const Eigen::Ref<const Eigen::VectorXd>& dc, Eigen::MatrixX3d* dB);
  /// ApplyRhsDerivative for m directions at once, in one pass over the elements: dX is #V x 3m
  /// (direction j in columns 3j..3j+2, mm), dc is #actuators x m, dB receives #V x 3m. Column
  /// block j equals ApplyRhsDerivative(dX block j, dc.col(j)) to round-off.
  void ApplyRhsDerivativeBatch(const Eigen::Ref<const Eigen::MatrixXd>& dX,
                               const Eigen::Ref<const Eigen::MatrixXd>& dc, Eigen::MatrixXd* dB);
  /// Calls f(i, Kb, thread) for every element i, in parallel (thread: the OpenMP thread number,
  /// for per-thread accumulation), with Kb its (3k x 3k) block of K_local (row and column 3 q + d:
  /// coordinate d of the element's vertex q), as LocalStiffness assembles them.
  void ForEachLocalBlock(
      const std::function<void(int element, const LocalBlock& block, int thread)>& f) const;
  /// The per-element part of K = dB/dX as a sparse 3 #V x 3 #V matrix (row and column 3 v + d):
  /// each element's exact block (rotation, blend scale, and the ratio's dependence on the
  /// element's own measure), without the groups' rank-one coupling through their total measure.
  /// For rigid bodies A - K is then the ARAP Hessian. Used to build a preconditioner.
  Eigen::SparseMatrix<double> LocalStiffness() const;
  const Model& model() const { return *model_; }

  /// Hyperelastic body elements (Eq. 3.6-3.7): T = c Bl, Bl = t R P + (1 - t) D with
  /// t = R_omega(eps(D)) (or the blend-volume floor's weight), c = cbrt(Vol_0 / Vol(Bl)).
  struct HyperCache {
    ElemRows diff;      ///< R P - D (rows), the direction t moves Bl in
    ElemRows blend;     ///< Bl
    ElemRows vol_grad;  ///< d Vol(Bl) / d Bl
    ElemRows drho;      ///< d R_omega / dD (curve slope times d eps / dD); unused on the floor
    double t = 0.0, c = 1.0, vol = 0.0;
    bool floor = false;  ///< t from the blend-volume floor (HyperelasticBlendWeight), not the curve
  };

 private:
  /// dT of element i for a centred change dD of its rows and dr of its ratio; Ps / dPs0 are the
  /// cable / DEA reshaped rest rows and their ratio derivative (unused otherwise).
  void ElementTargetDerivative(int i, bool vented, const ElemRows& dD, double dr,
                               const ElemRows& Ps, const ElemRows& dPs0, ElemRows* dT) const;
  struct ElementCache {
    Eigen::Matrix3d R;      ///< best rotation of the element's target
    Eigen::Matrix3d Sinv;   ///< (tr(S) I - S)^-1, S = R^T M
    double s = 1.0;         ///< blend scale (body, r_omega < 1)
    double vol = 0.0;       ///< current volume (body blend) or 0
    bool s_active = false;  ///< blend scale not clamped: it varies with X
  };
  struct GroupCache {
    bool vented = false;
    double sigma = 0.0, Md = 0.0;  ///< scale and current total measure
    bool num_active = false;       ///< rho (M + L_R) - L_R above its floor: sigma varies with c
    double drho = 0.0;             ///< d rho / d c[actuator]
  };
  const Model* model_ = nullptr;
  Eigen::MatrixX3d X_;
  std::vector<double> ratios_;
  std::vector<ElementCache> cache_;
  std::vector<GroupCache> groups_;
  std::vector<ElemRows> rows_;  ///< centred current rows D (blended bodies, cable, DEA)
  /// Rigid bodies (R_omega = 1) and loaded pneumatic elements (HasClosedFormDerivative), whose
  /// target derivative has the closed form of ApplyRhsDerivativeBatch: the rows R P_q of the
  /// rotated rest shape, and R (tr(S) I - S)^-1 R^T. Unset for other elements.
  std::vector<ElemRows> rotated_rest_;
  std::vector<Eigen::Matrix3d> rotated_sinv_;
  std::vector<ElemRows> vol_grad_;      ///< d Vol / dD of blended bodies with an active scale
  std::vector<HyperCache> hyper_;       ///< per element if the model has hyperelastic bodies
  std::vector<double> measure_;         ///< m_i (floored) of actuation elements
  std::vector<char> measure_active_;    ///< m_i above its floor
  std::vector<ElemRows> measure_grad_;  ///< dm_i/dD of actuation elements (others unused)
  std::vector<double> dratio_;          ///< scratch: dr_i per direction (#E x m)
  std::vector<ElemRows> weighted_;      ///< scratch: w_i Vol_i dT_i per direction (#E x m)
  int threads_ = 0;
};

/// What ComputeEquilibriumJacobian returns.
struct EquilibriumJacobianResult {
  bool ok = false;
  std::string message;
  /// 3 #V x #columns: dX/dc (row 3 v + d: coordinate d of vertex v), mm per unit of actuation;
  /// column j is actuator columns[j].
  Eigen::MatrixXd dXdc;
  /// Operator products per column (GMRES / BiCGSTAB iterations plus the residual checks).
  std::vector<int> iterations;
  std::vector<double> residuals;  ///< final ||H y - rhs|| / ||rhs|| per column (unpreconditioned)
  /// Batched operator applications (lockstep rounds; equals the sum of iterations without
  /// lockstep).
  int rounds = 0;
  double time_s = 0.0;
  std::string preconditioner;          ///< what preconditioned the solve (and why, on a fallback)
  double preconditioner_time_s = 0.0;  ///< assembling and factoring it ("local")
};

/// dX/dc at the equilibrium X (#V x 3, a converged local-global state for actuation c) for the
/// actuators in `columns` (empty: all, in order). `initial_guess` (optional, 3 #V x #columns in the
/// layout of dXdc, e.g. the previous Jacobian of a path) starts each Krylov solve from its free
/// coordinates instead of 0; the tolerance stays relative to the right-hand side, so a close guess
/// saves products without loosening the result. ok = false with a message for degenerate
/// elements or a Krylov solve that does not reach options.tolerance within
/// options.max_iterations (never NaN). Uses the model's CHOLMOD factors, so not concurrently on
/// one Model. `workspace` (optional) keeps the "local" preconditioner's pattern and symbolic
/// analysis between calls on the same model.
EquilibriumJacobianResult ComputeEquilibriumJacobian(
    const Model& model, const Eigen::Ref<const Eigen::MatrixX3d>& X,
    const Eigen::Ref<const Eigen::VectorXd>& c, const std::vector<int>& columns = {},
    const EquilibriumJacobianOptions& options = EquilibriumJacobianOptions(),
    const Eigen::MatrixXd* initial_guess = nullptr,
    EquilibriumJacobianWorkspace* workspace = nullptr);

/// d(prescribed coordinates)/dc[a] (#V x 3, zero on free coordinates): nonzero only for motion
/// actuators (their vertices' rigid motion), computed by a central difference of
/// Model::ApplyConstraints with a step of 1e-6 of the actuator's range (translations are exact;
/// rotations have an O(step^2) error of ~1e-12 relative).
Eigen::MatrixX3d PrescribedDerivative(const Model& model,
                                      const Eigen::Ref<const Eigen::VectorXd>& c, int a);

}  // namespace softkin
