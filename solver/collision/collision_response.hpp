#pragma once
/// \file collision_response.hpp
/// Collision response by spring elements (thesis Sec. 3.2.3 and 3.3.1, Eq. 3.5, 3.8, 3.9).
///
/// Each collided vertex v gets a "virtual" spring of energy k ||v - v_c||^2 (Eq. 3.5) that pulls
/// it to a collision-free target v_c:
///  - self-collision (v inside a tet not incident to it): from v along -n(v), n(v) the outward
///    normal of the robot's boundary at v (area-weighted over its boundary faces, at the current
///    positions), walking tet to tet through the collided region until the ray leaves it through
///    a boundary face at v_s; v_c = v_s + eps (-n(v)). If the ray re-enters a tet incident to v
///    (a fold, where -n(v) points back into v's own part), the walk is retried from v along the
///    direction from the collided tet's centroid to v.
///  - obstacle (v strictly inside it): v_s = the closest point on the obstacle surface (CGAL
///    AABB tree), v_c = v_s + eps n, n the obstacle's outward normal there. With
///    options.obstacle_spring "plane" (the default) the spring keeps only the normal part,
///    k (n . (v - v_c))^2: a frictionless contact against the tangent plane at v_c, whose
///    k n n^T Hessian Solve adds to the factored per-axis system by the Woodbury identity.
/// Springs are added for every newly collided vertex and their targets refreshed at every check.
/// A spring whose vertex is no longer in collision is released once the vertex is more than eps
/// beyond its target along the spring normal (Eq. 3.8: n . (v - v_c) > eps), i.e. when the body
/// pulls away from the contact on its own; until then it holds the vertex at the contact, which
/// keeps contact without adhesion. The local-global solver minimises E_ela + E_col (Eq. 3.9):
/// targets are fixed in the global step, whose matrix gains k on the springs' rows, kept factored
/// by SpringSystem (CHOLMOD update/downdate).
///
/// With options.self_spring "pair" (the default; "target" is the fixed v_c above), a self spring
/// instead pulls v to the exit point taken as a point of the exit face f, sum_i w_i x_fi (w its
/// barycentric coordinates when detected), plus an offset delta (eps along the exit direction): E =
/// k ||v - sum_i w_i x_fi - delta||^2. The face's vertices are unknowns of the global step too, so
/// the spring pushes v out and the face back with equal and opposite forces, and the target follows
/// the face within the step. The whole overlap is the target (the face moves too). While a contact
/// persists its face and weights are kept (delta absorbs the refreshed exit point), so the matrix
/// changes only when a contact starts, ends, or slides to another face or by a fifth of the face.
#include "softkin/solver/collision/collision.hpp"
#include "softkin/solver/fk/contact_term.hpp"
#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/collision/spring_system.hpp"

#include <Eigen/Dense>

#include <array>
#include <memory>
#include <vector>

namespace softkin {

/// One spring element.
struct CollisionSpring {
  enum class Kind { Self, Obstacle };
  int vertex = -1;
  Kind kind = Kind::Self;
  int other = -1;  ///< collided tet (Self) or obstacle index (Obstacle) when last detected
  Eigen::Vector3d target = Eigen::Vector3d::Zero();  ///< v_c, mm
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  ///< unit direction out of the collided region
  double depth = 0;  ///< |v - v_s| when last detected in collision, mm
  /// Self: the boundary face the walk left the collided region through (tet * 4 + local face),
  /// whose current plane gives the contact surface while the vertex is out of collision.
  int exit_face = -1;
  /// Vertex-face ("pair") springs: the face's vertex ids, the barycentric weights of the point
  /// the spring pulls v to, and the offset delta; the target is sum_i w_i x_fi + delta. face[0]
  /// < 0 for a fixed target.
  std::array<int, 3> face{-1, -1, -1};
  Eigen::Vector3d weights = Eigen::Vector3d::Zero();
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  bool pair() const { return face[0] >= 0; }
  /// The point sum_i w_i x_fi of a pair spring's face at positions X.
  Eigen::Vector3d FacePoint(const Eigen::Ref<const Eigen::MatrixX3d>& X) const {
    return weights[0] * X.row(face[0]).transpose() + weights[1] * X.row(face[1]).transpose() +
           weights[2] * X.row(face[2]).transpose();
  }
  /// Where the spring pulls v to at positions X.
  Eigen::Vector3d TargetAt(const Eigen::Ref<const Eigen::MatrixX3d>& X) const {
    return pair() ? Eigen::Vector3d(FacePoint(X) + offset) : target;
  }
  SpringStencil Stencil() const {
    return pair() ? SpringStencil::VertexFace(vertex, face, weights) : SpringStencil::Unit(vertex);
  }
};

class CollisionResponse : public ContactTerm {
 public:
  /// Builds the detectors for `model`'s mesh (self-collision needs a tet-only mesh: throws
  /// std::invalid_argument otherwise) and the obstacles of its scene. `model` must outlive it.
  CollisionResponse(const Model& model, const CollisionOptions& options);
  ~CollisionResponse() override;

  /// Detection at positions X (#V x 3) and the spring rule: adds, refreshes and releases springs.
  /// Returns true if the set of spring vertices (hence the global matrix) changed.
  bool Update(const Eigen::Ref<const Eigen::MatrixX3d>& X) override;
  /// Adds the springs' constant terms to the free right-hand side (layout of Model::GatherFree):
  /// k c_s (delta_s - c_s . x_prescribed) per spring, k v_c for a fixed target. X supplies the
  /// prescribed coordinates (of a pair spring's face).
  void AddToRhs(const Eigen::Ref<const Eigen::MatrixX3d>& X, Eigen::VectorXd* Bf) const override;
  /// Adds K x to y (x: free coordinates, layout of Model::GatherFree).
  void AddSpringProduct(const Eigen::VectorXd& x, Eigen::VectorXd* y) const override;
  /// Releases every spring and zeroes the statistics (the start of a new solve).
  void Reset() override;
  /// E_col = sum k ||v - v_c||^2 at positions X (v_c = CollisionSpring::TargetAt(X)).
  double Energy(const Eigen::Ref<const Eigen::MatrixX3d>& X) const override;
  /// Solves (A_ff + K) y = rhs (free layout). With plane obstacle springs, K also holds their
  /// k u_s u_s^T terms (u_s = n_s on the vertex's free coordinates), applied to the factored
  /// per-axis system by the Woodbury identity (the file comment).
  Eigen::VectorXd Solve(const Eigen::VectorXd& rhs) const override;
  /// (A_ff + K) x (free layout).
  Eigen::VectorXd Multiply(const Eigen::VectorXd& x) const;
  /// Number of plane (normal-only) obstacle springs in the current set.
  int num_plane_springs() const { return static_cast<int>(plane_.size()); }
  /// Exact check of positions X: contacts left and the deepest penetration (for a self contact,
  /// the shortest exit found along -n(v), away from the collided tet's centroid and the six axis
  /// directions: an upper bound on the distance to the collided region's surface), and the
  /// inverted elements and the self contacts among them (CollisionCheck::tangled_contacts).
  CollisionCheck Check(const Eigen::Ref<const Eigen::MatrixX3d>& X) const override;

  /// Whether `check` has contacts of a kind this response handles (self contacts only count when
  /// options.self is on, obstacle contacts when it responds to obstacles).
  bool HasHandledContacts(const CollisionCheck& check) const override {
    return (options_.self && check.self_contacts > 0) ||
           (!obstacles_.empty() && check.obstacle_contacts > 0);
  }
  /// Penalty continuation: multiplies k by 4 (refactoring the system) unless it has already been
  /// raised `max_raises` times; returns whether it did. The solver calls it when it has converged
  /// with contacts left (finite springs yield by force / k).
  bool Stiffen(int max_raises = 3) override;

  const std::vector<CollisionSpring>& springs() const { return springs_; }
  double stiffness() const { return k_; }
  const CollisionStats& stats() const override { return stats_; }
  int num_springs() const override { return static_cast<int>(springs_.size()); }
  const SpringSystem& system() const { return system_; }
  const std::vector<Obstacle>& obstacles() const { return obstacles_; }

  /// Exit point of the ray from v (at X) along unit `dir` through the tets starting at `tet`,
  /// where it leaves the region for the outside of the mesh. Returns false if the ray meets a tet
  /// incident to v first, degenerates, or takes too many steps. Exposed for tests.
  bool WalkOut(const Eigen::Ref<const Eigen::MatrixX3d>& X, int v, int tet,
               const Eigen::Vector3d& dir, Eigen::Vector3d* exit, int* exit_face = nullptr) const;
  /// Outward unit normal of the boundary at vertex v (at X); zero for an interior vertex.
  Eigen::Vector3d VertexNormal(const Eigen::Ref<const Eigen::MatrixX3d>& X, int v) const;
  /// Body of vertex v: the connected component (tets sharing a vertex) of the mesh it belongs to.
  int body(int v) const { return body_[v]; }
  int num_bodies() const { return num_bodies_; }

 private:
  /// Target of a self-collided vertex v inside `tet`; false if none was found.
  bool SelfTarget(const Eigen::Ref<const Eigen::MatrixX3d>& X, int v, int tet,
                  CollisionSpring* s) const;
  void ObstacleTarget(const Eigen::Vector3d& p, int obstacle, CollisionSpring* s) const;
  /// Sets the target of self spring s (vertex, normal = exit direction set) from its exit point
  /// on the boundary face `face` (vertex ids): half way plus eps, or the face point plus eps.
  void SetSelfTarget(const Eigen::Ref<const Eigen::MatrixX3d>& X, const Eigen::Vector3d& exit,
                     const std::array<int, 3>& face, CollisionSpring* s) const;
  std::vector<SpringStencil> Stencils() const;
  /// Target of vertex v (at X) inside body b != body(v): the closest point on b's boundary
  /// surface (`surface`, at the current positions). False if b has no boundary faces.
  bool BodyTarget(const MovingSurface& surface, int b, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                  int v, CollisionSpring* s) const;
  /// A boundary surface per body, built (once) if the mesh has more than one body.
  std::vector<MovingSurface> MakeBodySurfaces() const;
  /// Whether spring s is a plane (normal-only) obstacle spring.
  bool IsPlane(const CollisionSpring& s) const {
    return s.kind == CollisionSpring::Kind::Obstacle &&
           options_.obstacle_spring == ObstacleSpring::kPlane;
  }
  /// Rebuilds the Woodbury terms of the plane springs from springs_ (after any change of the
  /// springs, their normals, k or the factored system; `system_changed`: the factored system
  /// changed, so the cached solves S^-1 e_v are stale).
  void RebuildPlanes(bool system_changed);
  /// Adds k U U^T x to y (the plane springs' part of K).
  void AddPlaneProduct(const Eigen::VectorXd& x, Eigen::VectorXd* y) const;

  const Model& model_;
  CollisionOptions options_;
  std::vector<Obstacle> obstacles_;
  std::unique_ptr<SelfCollisionDetector> detector_;
  SpringSystem system_;
  double k_ = 0, k0_ = 0;
  int raises_ = 0;
  std::vector<CollisionSpring> springs_;  // sorted by vertex
  std::vector<int> check_vertices_;       // vertices tested against obstacles
  // Tet faces: neighbour across face j of tet t is adj_[4 t + j] (-1: boundary face).
  std::vector<int> adj_;
  // Boundary faces (outward, v0 v1 v2) and, per vertex, its boundary faces (CSR).
  std::vector<std::array<int, 3>> bfaces_;
  std::vector<int> vface_offset_, vface_;
  std::vector<int> bface_slot_;  // tet * 4 + local face of each boundary face
  // Bodies: connected components of the mesh (tets sharing a vertex), per vertex. Contacts
  // between two bodies take the closest point of the other body's surface as their exit
  // (options.self_target "auto"); body_surface_[b] holds body b's boundary faces.
  std::vector<int> body_;
  int num_bodies_ = 0;
  std::vector<MovingSurface> body_surface_;
  std::vector<std::vector<int>> body_faces_;  // per body, indices into bfaces_
  // Plane obstacle springs (options.obstacle_spring "plane"): energy k (n_s . v_s - b_s)^2 with
  // b_s = n_s . v_c. Their k U U^T is not in system_ (it couples x, y and z, which system_ solves
  // apart); Solve adds it by the Woodbury identity:
  //   (S + k U U^T)^-1 r = y - W (I / k + U^T W)^-1 U^T y,  y = S^-1 r,  W = S^-1 U.
  // Column s of W is n_s spread over the axis blocks of S^-1 (sum_d e_(v_s, d)) (S is block
  // diagonal by axis), cached per vertex in plane_solve_ until the factored system changes.
  struct PlaneSpring {
    int vertex;
    Eigen::Vector3d normal;
    double offset;
  };
  std::vector<PlaneSpring> plane_;
  std::vector<std::pair<int, Eigen::VectorXd>>
      plane_solve_;                                 // (vertex, S^-1 sum_d e_(v,d)), sorted
  std::vector<int> plane_solve_of_;                 // per plane spring, its entry there
  Eigen::LDLT<Eigen::MatrixXd> plane_capacitance_;  // I / k + U^T W
  /// U^T x: per plane spring, n_s . (x's free coordinates of v_s).
  Eigen::VectorXd PlaneDot(const Eigen::VectorXd& x) const;
  CollisionStats stats_;
};

}  // namespace softkin
