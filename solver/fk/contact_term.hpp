#pragma once
/// \file contact_term.hpp
/// The extension point through which contact handling joins the local-global solve (thesis
/// Sec. 3.3, Eq. 3.9), and the plain records a solve reports about it. The FK core knows only this
/// interface; the spring response of solver/collision/ (CollisionResponse, CGAL detection)
/// implements it, and solver/factory/ wires the two together. A ContactTerm adds an energy
/// E_col(x) = sum_s k ||c_s^T x - t_s||^2 whose targets t_s are held fixed within a global step:
/// its constant part goes to the right-hand side, its k c_s c_s^T to the matrix.
#include "softkin/solver/fk/fk_options.hpp"

#include <Eigen/Core>

#include <functional>
#include <memory>
#include <string>

namespace softkin {

class Model;
struct Scene;

/// Result of an exact collision check of a state.
struct CollisionCheck {
  int self_contacts = 0;        ///< boundary vertices inside a non-incident tet (exact predicates)
  int obstacle_contacts = 0;    ///< vertices strictly inside an obstacle
  double max_penetration = 0;   ///< largest depth among them, mm (0 if collision-free)
  double self_penetration = 0;  ///< largest depth among the self contacts, mm
  double obstacle_penetration = 0;  ///< largest depth among the obstacle contacts, mm
  /// Elements with non-positive signed volume at the checked positions (CountInvertedElements):
  /// where the mesh has folded through itself, which no spring on a boundary vertex can undo.
  int inverted_elements = 0;
  /// Those of them that are body elements (the rest belong to actuators, e.g. a chamber's gas).
  int inverted_body_elements = 0;
  /// Self contacts inside a tangle: the vertex belongs to an inverted element, or the tet it lies
  /// in is inverted. Contacts between separate parts of the surface are self_contacts minus these.
  int tangled_contacts = 0;
  bool collision_free() const { return self_contacts == 0 && obstacle_contacts == 0; }
};

/// Timings and counts of the collision handling in one solve.
struct CollisionStats {
  int checks = 0;
  int springs_added = 0, springs_released = 0;
  int max_springs = 0;
  int unresolved = 0;     ///< self contacts for which no exit point was found (no spring)
  int stiffenings = 0;    ///< times k was raised (CollisionResponse::Stiffen)
  double check_s = 0;     ///< detection (self + obstacles)
  double response_s = 0;  ///< targets, release rule and the factor update
  /// Adds the counts and times of `o` (max_springs: the larger of the two).
  void Add(const CollisionStats& o);
};

/// Contact handling inside the local-global iteration (Algorithm 1 with Eq. 3.9). Free-coordinate
/// vectors use the layout of Model::GatherFree; X is #V x 3 positions in mm.
class ContactTerm {
 public:
  virtual ~ContactTerm() = default;
  /// Detection at X and the spring rule (add, refresh, release). Returns true if the matrix
  /// A_ff + K changed.
  virtual bool Update(const Eigen::Ref<const Eigen::MatrixX3d>& X) = 0;
  /// E_col at X.
  virtual double Energy(const Eigen::Ref<const Eigen::MatrixX3d>& X) const = 0;
  /// Adds the springs' constant terms to the free right-hand side Bf.
  virtual void AddToRhs(const Eigen::Ref<const Eigen::MatrixX3d>& X, Eigen::VectorXd* Bf) const = 0;
  /// Adds K x to y.
  virtual void AddSpringProduct(const Eigen::VectorXd& x, Eigen::VectorXd* y) const = 0;
  /// Solves (A_ff + K) y = rhs.
  virtual Eigen::VectorXd Solve(const Eigen::VectorXd& rhs) const = 0;
  /// Releases every spring and zeroes the statistics (the start of a new solve).
  virtual void Reset() = 0;
  /// The exact check of positions X.
  virtual CollisionCheck Check(const Eigen::Ref<const Eigen::MatrixX3d>& X) const = 0;
  /// Whether `check` has contacts of a kind this term responds to.
  virtual bool HasHandledContacts(const CollisionCheck& check) const = 0;
  /// Penalty continuation: raises k unless it was raised `max_raises` times; returns whether it
  /// did.
  virtual bool Stiffen(int max_raises = 3) = 0;
  /// Springs in the current set.
  virtual int num_springs() const = 0;
  virtual const CollisionStats& stats() const = 0;
};

/// Builds the contact term of `model` (which must outlive it) for `options`; throws
/// std::invalid_argument for a scene it cannot handle.
using ContactTermFactory = std::function<std::unique_ptr<ContactTerm>(
    const Model& model, const CollisionOptions& options)>;

/// Whether a scene with these options needs contact handling at all: self-collision is on, or
/// obstacle response is on and the scene has obstacles.
bool ContactHandlingActive(const Scene& scene, const CollisionOptions& options);

/// A solver's contact term: *term if it is built already, else factory's for `model`. Returns
/// false with *why (naming the scene) if there is no factory (a solver built without
/// MakeFkSolver) or the factory refuses the scene.
bool EnsureContactTerm(const ContactTermFactory& factory, const Model& model,
                       const CollisionOptions& options, std::unique_ptr<ContactTerm>* term,
                       std::string* why);

}  // namespace softkin
