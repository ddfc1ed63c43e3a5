#pragma once
/// \file fk_options.hpp
/// Options shared by the forward-kinematics solvers (Ceres-style: IsValid(&why)).
#include <nlohmann/json_fwd.hpp>

#include <functional>
#include <string>
#include <vector>

namespace softkin {

// Every string-valued option is an enum with one list of names: ToString gives a value's name,
// <Enum>FromString the value of a name (std::invalid_argument naming the string and listing the
// names for any other), <Enum>Names every name in list order (the schema's and the help texts'
// choices; solver/scene/solver_options_json.hpp reads and writes the options by these names). As
// JSON (nlohmann's to_json / from_json, found by argument-dependent lookup) a value is its name,
// never its number.

/// How the factor follows the spring set (CollisionOptions::update).
enum class SpringUpdate {
  kUpdown,    ///< "updown": CHOLMOD update/downdate
  kRefactor,  ///< "refactor": a numeric refactorisation
};
std::string ToString(SpringUpdate u);
SpringUpdate SpringUpdateFromString(const std::string& s);
std::vector<std::string> SpringUpdateNames();
void to_json(nlohmann::json& j, SpringUpdate v);
void from_json(const nlohmann::json& j, SpringUpdate& v);

/// Where a self-collided vertex is sent (CollisionOptions::self_target).
enum class SelfTarget {
  kAuto,  ///< "auto"
  kWalk,  ///< "walk"
};
std::string ToString(SelfTarget t);
SelfTarget SelfTargetFromString(const std::string& s);
std::vector<std::string> SelfTargetNames();
void to_json(nlohmann::json& j, SelfTarget v);
void from_json(const nlohmann::json& j, SelfTarget& v);

/// What a self-collision spring pulls a vertex to (CollisionOptions::self_spring).
enum class SelfSpring {
  kTarget,  ///< "target"
  kPair,    ///< "pair"
};
std::string ToString(SelfSpring s);
SelfSpring SelfSpringFromString(const std::string& s);
std::vector<std::string> SelfSpringNames();
void to_json(nlohmann::json& j, SelfSpring v);
void from_json(const nlohmann::json& j, SelfSpring& v);

/// What an obstacle spring resists (CollisionOptions::obstacle_spring).
enum class ObstacleSpring {
  kPlane,  ///< "plane"
  kPoint,  ///< "point"
};
std::string ToString(ObstacleSpring s);
ObstacleSpring ObstacleSpringFromString(const std::string& s);
std::vector<std::string> ObstacleSpringNames();
void to_json(nlohmann::json& j, ObstacleSpring v);
void from_json(const nlohmann::json& j, ObstacleSpring& v);

/// Collision response (thesis Sec. 3.2.3, Eq. 3.5, 3.8, 3.9; collision_response.hpp). It is
/// active in the local-global solvers when `self` is on or the scene has obstacles (and
/// `obstacles` is on).
struct CollisionOptions {
  bool self = false;      ///< respond to self-collision (boundary vertices inside other tets)
  bool obstacles = true;  ///< respond to the scene's obstacles (if it has any)
  /// Offset eps of the contact boundary (mm): springs pull a vertex eps beyond the surface, and
  /// release it once it is more than eps beyond its target (Eq. 3.8).
  double epsilon = 0.05;
  /// Spring stiffness k of Eq. 3.5 relative to the median diagonal entry of the global matrix
  /// over the boundary vertices (so it scales with the mesh and the element weights).
  double stiffness = 20.0;
  /// Run detection every this many iterations (1: every iteration, as Algorithm 2), and always
  /// before the solver is allowed to stop.
  int check_interval = 1;
  /// How the factor follows the spring set: "updown" (CHOLMOD update/downdate) or "refactor".
  SpringUpdate update = SpringUpdate::kUpdown;
  /// Where a self-collided vertex is sent. "walk" (the default): along -n(v) through the
  /// collided region to its boundary (the thesis's rule, Sec. 3.2.3) for every contact. "auto":
  /// the same within one body, but a vertex inside another body of the mesh (a separate
  /// connected component, like the membrane over its chambers) goes to the closest point of that
  /// body's surface facing it, never further than the shortest way out. Not the default: on the
  /// measured cases it converges no better, and it unbalances the pressed blocks' contact forces
  /// more (docs/collision_response.md).
  SelfTarget self_target = SelfTarget::kWalk;
  /// What a self-collision spring pulls a vertex v to. "pair" (the default): the exit point as a
  /// point of the exit face, sum_i w_i x_fi, plus eps: the energy k ||v - sum_i w_i x_fi -
  /// delta||^2 moves with the face and loads both sides equally and oppositely (action and
  /// reaction), so it couples v with the face's vertices in the global matrix (SpringSystem).
  /// "target" (Eq. 3.5 as the thesis writes it): a fixed point v_c, half way to the exit point
  /// plus eps (both sides of a contact get springs), set at each check; its forces on the two
  /// sides of a contact need not balance, and a held contact is sticky, which stiffens a finger
  /// whose walls touch (docs/collision_response.md).
  SelfSpring self_spring = SelfSpring::kPair;
  /// What an obstacle spring resists. "plane" (the default): only the normal part of the offset
  /// to v_c (the closest point plus eps), k (n . (v - v_c))^2, against the obstacle's tangent
  /// plane at v_c: a frictionless contact. Its n n^T term couples a vertex's x, y and z, so the
  /// global step adds it to the factored per-axis system by a low-rank (Woodbury) correction.
  /// "point" (Eq. 3.5 as written): k ||v - v_c||^2, refreshed at each check; it has the same
  /// fixed point, but between checks it also holds the vertex tangentially, so a sliding contact
  /// creeps by the tangential force / k per check (docs/collision_response.md).
  ObstacleSpring obstacle_spring = ObstacleSpring::kPlane;
  bool IsValid(std::string* why) const;
};

/// The forward-kinematics solvers (solver/factory/fk_factory.hpp builds them).
enum class FkSolverType {
  kLg,                 ///< "lg": plain local-global (Algorithm 1)
  kLgAa,               ///< "lg-aa": Anderson-accelerated local-global
  kNewton,             ///< "newton": Newton-Krylov on the same equilibrium (solver/newton/)
  kAuto,               ///< "auto": lg-aa, then newton if lg-aa is slow (solver/newton/auto_solver)
  kCeres,              ///< "ceres": the energy by Ceres (solver/baselines/nlp_solvers.hpp)
  kIpoptLbfgs,         ///< "ipopt-lbfgs": the energy by Ipopt with L-BFGS
  kIpoptNewton,        ///< "ipopt-newton": the energy by Ipopt with the exact Hessian
  kIpoptHard,          ///< "ipopt-hard": body energy, hard actuation constraints, by Ipopt
  kCalculixLinear,     ///< "calculix-linear": FEM baseline (solver/baselines/calculix.hpp)
  kCalculixNonlinear,  ///< "calculix-nonlinear": FEM baseline, neo-Hookean
};
std::string ToString(FkSolverType t);
FkSolverType FkSolverTypeFromString(const std::string& s);
/// Every solver name, in enum order: the one list of solvers.
std::vector<std::string> FkSolverTypeNames();
void to_json(nlohmann::json& j, FkSolverType v);
void from_json(const nlohmann::json& j, FkSolverType& v);

/// Which Anderson steps are kept (FkOptions::anderson_safeguard).
enum class AndersonSafeguard {
  kHybrid,  ///< "hybrid"
  kEnergy,  ///< "energy"
  kNone,    ///< "none"
};
std::string ToString(AndersonSafeguard g);
AndersonSafeguard AndersonSafeguardFromString(const std::string& s);
std::vector<std::string> AndersonSafeguardNames();
void to_json(nlohmann::json& j, AndersonSafeguard v);
void from_json(const nlohmann::json& j, AndersonSafeguard& v);

/// The most OpenMP threads any option accepts (a larger count crashed libgomp: 100000 threads).
constexpr int kMaxThreads = 256;

struct FkOptions {
  /// The solver: lg (plain local-global, Algorithm 1), lg-aa (Anderson-accelerated), newton,
  /// auto (lg-aa, then newton where lg-aa is slow: the default), or one of the general-purpose
  /// optimisers and FEM baselines (FkSolverType).
  FkSolverType solver = FkSolverType::kAuto;
  int max_iterations = 10000;
  /// Stop when every vertex moves less than tolerance * model size in one iteration ...
  double tolerance = 1e-5;
  /// ... and the energy gradient norm has fallen below gradient_tolerance times its value at the
  /// first iteration (guards against slow creeping on thin, bending-dominated parts).
  double gradient_tolerance = 1e-6;
  /// Anderson history length. 15, not the 5-6 often used for local-global solvers: on the
  /// bending finger a full actuation from rest takes 1909 iterations with 15 against 7634 with 6
  /// (13138 plain), and the fig2_11 sweep half as many (aa_ablation, docs/benchmarks.md).
  int anderson_window = 15;
  /// When an Anderson step is rejected and the plain step taken instead (Sec. "safeguard" in
  /// local_global.hpp): "hybrid" keeps it if it lowers the energy OR the fixed-point residual
  /// ||G(x) - x|| relative to the point it extrapolates from; "energy" keeps it only if it does not
  /// raise the energy (Peng et al. 2018); "none" keeps every finite step.
  AndersonSafeguard anderson_safeguard = AndersonSafeguard::kHybrid;
  /// Apply the actuation in this many equal steps (continuation), warm-starting each.
  int continuation_steps = 1;
  /// OpenMP threads for the local step (0 = library default).
  int threads = 0;
  /// Wall-clock limit of one Solve() call in seconds (0 = none); when it runs out the solver
  /// returns status time_limit with its last checked iterate. For comparisons that must end.
  double time_limit_s = 0.0;
  /// Collision response settings (used by lg and lg-aa).
  CollisionOptions collision;
  /// Progress report, called after each continuation step of a Solve() (lg, lg-aa and the
  /// general-purpose optimisers) with the step (1-based), the number of steps, the step's status
  /// (FkStatusToString), the iterations and the seconds so far. Empty: no report.
  std::function<void(int step, int steps, const std::string& status, int iterations,
                     double seconds)>
      on_step;
  /// Progress report during one long solve: called by lg, lg-aa and newton about every
  /// progress_interval_s seconds with the iterations so far, the residual ratio of the last
  /// checked iterate (FkResult::gradient_ratio) and the seconds since Solve() began. Empty: none.
  std::function<void(int iterations, double residual_ratio, double seconds)> on_progress;
  double progress_interval_s = 10.0;  ///< seconds between two on_progress calls (> 0)

  bool IsValid(std::string* why) const;
};

}  // namespace softkin
