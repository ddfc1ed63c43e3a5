#pragma once
/// \file
/// IK objectives O(p) over the tracked points of a Kinematics (thesis Ch. 4): point tracking
/// (Eq. 4.4), pick (Eq. 4.5), grasp (Eq. 4.7), place (Sec. 4.4.1) and shape matching in
/// configuration space (Sec. 4.2), and their weighted sums.
///
/// Conventions, shared by every objective:
///  - p is the #points x 3 matrix of tracked point positions (mm), in the row order of the
///    Kinematics' point_names(); an objective is built against that name list and resolves the
///    names it needs once, at construction (a missing name throws std::invalid_argument).
///  - The gradient dO/dp has the same shape as p. With J = dp/dc (3 #points x #actuators, row
///    3 i + d = coordinate d of point i), dO/dc = J^T vec(dO/dp): see GradientWrtActuation.
///  - Every objective here is a sum of squares O = |r|^2 and exposes r(p) and dr/dp
///    (#residuals x 3 #points, column 3 i + d), which Gauss-Newton uses.
///  - A geometry on which the objective is undefined (e.g. a degenerate circle fit) throws
///    ObjectiveError; the IK solvers catch it and report it. No objective returns NaN.

#include <Eigen/Core>

#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace softkin {

/// Thrown by Objective::Evaluate / Residuals when the objective is undefined at p.
class ObjectiveError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Objective {
 public:
  virtual ~Objective() = default;
  /// Short description for reports, e.g. "point(tip)".
  virtual std::string name() const = 0;
  /// Number of tracked points p must have (the point-name list it was built against).
  int num_points() const { return num_points_; }
  /// O(p) (units: mm^2 for all objectives here) and, when grad is not null, dO/dp (#points x 3,
  /// mm). p: #points x 3, mm. Throws ObjectiveError where O is undefined.
  virtual double Evaluate(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                          Eigen::MatrixX3d* grad) const = 0;
  /// Number of least-squares residuals (O = |r|^2), or 0 if the objective has no such form.
  virtual int num_residuals() const = 0;
  /// r(p) (#residuals, mm) and, when dr_dp is not null, dr/dp (#residuals x 3 #points, column
  /// 3 i + d). Returns false (and leaves the outputs alone) if num_residuals() == 0.
  virtual bool Residuals(const Eigen::Ref<const Eigen::MatrixX3d>& p, Eigen::VectorXd* r,
                         Eigen::MatrixXd* dr_dp) const = 0;

 protected:
  explicit Objective(int num_points) : num_points_(num_points) {}
  /// Throws std::invalid_argument unless p has num_points() rows.
  void CheckPoints(const Eigen::Ref<const Eigen::MatrixX3d>& p) const;

 private:
  int num_points_;
};

/// dO/dc = J^T vec(dO/dp). J: 3 #points x #actuators; dO_dp: #points x 3. Returns #actuators.
Eigen::VectorXd GradientWrtActuation(const Eigen::Ref<const Eigen::MatrixXd>& J,
                                     const Eigen::Ref<const Eigen::MatrixX3d>& dO_dp);

/// Index of `name` in `point_names`; throws std::invalid_argument naming the objective `who`,
/// the missing point and the available ones.
int ResolvePoint(const std::vector<std::string>& point_names, const std::string& name,
                 const std::string& who);

/// The indices of a group of tracked points: `group` itself if tracked as one point, else every
/// "group[i]" in increasing i (e.g. "grip_layer" -> grip_layer[0], grip_layer[1], ...). Throws
/// std::invalid_argument if there is none.
std::vector<int> ResolvePointGroup(const std::vector<std::string>& point_names,
                                   const std::string& group, const std::string& who);

/// Eq. 4.4: O = |p_k - p_target|^2 for the tracked point named `point`.
class PointTrackingObjective : public Objective {
 public:
  /// target: mm. Throws std::invalid_argument for an unknown point or a non-finite target.
  PointTrackingObjective(const std::vector<std::string>& point_names, const std::string& point,
                         const Eigen::Vector3d& target);
  std::string name() const override { return "point(" + point_ + ")"; }
  double Evaluate(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                  Eigen::MatrixX3d* grad) const override;
  int num_residuals() const override { return 3; }
  bool Residuals(const Eigen::Ref<const Eigen::MatrixX3d>& p, Eigen::VectorXd* r,
                 Eigen::MatrixXd* dr_dp) const override;
  const Eigen::Vector3d& target() const { return target_; }
  int point_index() const { return k_; }

 private:
  std::string point_;
  int k_;
  Eigen::Vector3d target_;
};

/// One term of MultiPointTrackingObjective.
struct PointTarget {
  std::string point;       ///< tracked point name
  Eigen::Vector3d target;  ///< mm
  double weight = 1.0;     ///< >= 0
};

/// O = sum_j w_j |p_{k_j} - t_j|^2 (several points of Eq. 4.4 at once).
class MultiPointTrackingObjective : public Objective {
 public:
  /// Throws std::invalid_argument for an empty list, an unknown point, a negative or non-finite
  /// weight or a non-finite target.
  MultiPointTrackingObjective(const std::vector<std::string>& point_names,
                              std::vector<PointTarget> targets);
  std::string name() const override;
  double Evaluate(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                  Eigen::MatrixX3d* grad) const override;
  int num_residuals() const override { return 3 * static_cast<int>(targets_.size()); }
  bool Residuals(const Eigen::Ref<const Eigen::MatrixX3d>& p, Eigen::VectorXd* r,
                 Eigen::MatrixXd* dr_dp) const override;

 private:
  std::vector<PointTarget> targets_;
  std::vector<int> index_;
};

/// The normal n of a plane of the robot, from tracked points (the pick objective's "normal of the
/// second segment's upper plane", Fig. 4.8). Two names (a, b): n = (b - a)/|b - a| (e.g. from the
/// bottom to the top of a cross-section, which for a planar bending segment is the normal of its
/// upper surface there). Three names (a, b, c): n = (b - a) x (c - a) / |...| (three points on
/// the plane itself).
struct PlaneNormalSpec {
  std::vector<std::string> points;
};

/// Eq. 4.5: O = (|p1 - p0| - (R + d))^2 + w1 (n . (p1 - p0))^2, with p0 the tracked point P0,
/// p1 the object's centre, R the object's radius and d half the gripper's width.
/// (The thesis calls R a diameter in its text; geometrically |p1 - p0| = R + d needs the radius,
/// which is what this takes. See docs/ik.md.)
struct PickParams {
  std::string p0 = "P0";   ///< tracked point that must reach the grasp position
  PlaneNormalSpec normal;  ///< 2 or 3 tracked point names, see PlaneNormalSpec
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< p1, the object's centre, mm
  double object_radius = 0.0;                        ///< R, mm, >= 0
  double half_width = 0.0;                           ///< d, mm, >= 0
  double omega1 = 1.0;                               ///< w1, weight of the orthogonality term, >= 0
};

class PickObjective : public Objective {
 public:
  /// Throws std::invalid_argument for unknown points, a normal spec of other than 2 or 3 points,
  /// or negative / non-finite parameters.
  PickObjective(const std::vector<std::string>& point_names, PickParams params);
  std::string name() const override { return "pick(" + params_.p0 + ")"; }
  double Evaluate(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                  Eigen::MatrixX3d* grad) const override;
  int num_residuals() const override { return 2; }
  /// r = (|p1 - p0| - (R + d), sqrt(w1) n . (p1 - p0)).
  bool Residuals(const Eigen::Ref<const Eigen::MatrixX3d>& p, Eigen::VectorXd* r,
                 Eigen::MatrixXd* dr_dp) const override;
  /// The plane normal at p (unit); throws ObjectiveError if its points are degenerate.
  Eigen::Vector3d Normal(const Eigen::Ref<const Eigen::MatrixX3d>& p) const;

 private:
  PickParams params_;
  int k0_;
  std::vector<int> kn_;
};

/// Sec. 4.4.1, the place stage: O = (|p1t - p0| - (R + d))^2, the pick distance term towards the
/// new object position p1t (orientation no longer controlled).
struct PlaceParams {
  std::string p0 = "P0";
  Eigen::Vector3d target_center = Eigen::Vector3d::Zero();  ///< p1t, mm
  double object_radius = 0.0;                               ///< R, mm
  double half_width = 0.0;                                  ///< d, mm
};

class PlaceObjective : public Objective {
 public:
  PlaceObjective(const std::vector<std::string>& point_names, PlaceParams params);
  std::string name() const override { return "place(" + params_.p0 + ")"; }
  double Evaluate(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                  Eigen::MatrixX3d* grad) const override;
  int num_residuals() const override { return 1; }
  bool Residuals(const Eigen::Ref<const Eigen::MatrixX3d>& p, Eigen::VectorXd* r,
                 Eigen::MatrixXd* dr_dp) const override;

 private:
  PlaceParams params_;
  int k0_;
};

/// Eq. 4.7: O = (f_fit(V) - D)^2, f_fit the diameter of the least-squares circle (FitCircle)
/// through the tracked points of a group (e.g. "grip_layer" -> grip_layer[i]), D the object's
/// diameter.
struct GraspParams {
  std::string group = "grip_layer";
  double object_diameter = 0.0;  ///< D, mm, > 0
  /// Normal of the circle's plane (e.g. the motion plane's normal, (0, 1, 0) for
  /// multi_segment_gripper, whose grip layer is a slab wider than it is bent), or zero to fit the
  /// plane to the points too.
  Eigen::Vector3d plane_normal = Eigen::Vector3d::Zero();
};

class GraspObjective : public Objective {
 public:
  /// Throws std::invalid_argument for an unknown group, fewer than 3 points or D <= 0.
  GraspObjective(const std::vector<std::string>& point_names, GraspParams params);
  std::string name() const override { return "grasp(" + params_.group + ")"; }
  double Evaluate(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                  Eigen::MatrixX3d* grad) const override;
  int num_residuals() const override { return 1; }
  bool Residuals(const Eigen::Ref<const Eigen::MatrixX3d>& p, Eigen::VectorXd* r,
                 Eigen::MatrixXd* dr_dp) const override;
  /// The fitted circle's diameter at p, mm (throws ObjectiveError if the fit is degenerate).
  double FittedDiameter(const Eigen::Ref<const Eigen::MatrixX3d>& p) const;

 private:
  GraspParams params_;
  std::vector<int> idx_;
};

/// Sec. 4.2: shape matching in configuration space, O = sum_i |M(c)_i - M^t_i|^2 over a region's
/// tracked points (a group as in ResolvePointGroup, or an explicit name list).
class ShapeMatchingObjective : public Objective {
 public:
  /// target: one row per point of the region (#region x 3, mm). Throws std::invalid_argument for
  /// unknown points, a row-count mismatch or non-finite targets.
  ShapeMatchingObjective(const std::vector<std::string>& point_names,
                         const std::vector<std::string>& region_points,
                         const Eigen::Ref<const Eigen::MatrixX3d>& target);
  /// Convenience: the region is a group ("backbone" -> backbone[i]).
  static ShapeMatchingObjective ForGroup(const std::vector<std::string>& point_names,
                                         const std::string& group,
                                         const Eigen::Ref<const Eigen::MatrixX3d>& target);
  std::string name() const override { return "shape(" + std::to_string(idx_.size()) + " points)"; }
  double Evaluate(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                  Eigen::MatrixX3d* grad) const override;
  int num_residuals() const override { return 3 * static_cast<int>(idx_.size()); }
  bool Residuals(const Eigen::Ref<const Eigen::MatrixX3d>& p, Eigen::VectorXd* r,
                 Eigen::MatrixXd* dr_dp) const override;

 private:
  ShapeMatchingObjective(int num_points, std::vector<int> idx, Eigen::MatrixX3d target);
  std::vector<int> idx_;
  Eigen::MatrixX3d target_;
};

/// O = sum_j w_j O_j(p). Least-squares form (stacked sqrt(w_j) r_j) when every term has one.
class WeightedSumObjective : public Objective {
 public:
  explicit WeightedSumObjective(int num_points) : Objective(num_points) {}
  /// Adds w * term; throws std::invalid_argument for a negative or non-finite weight, a null
  /// term or a term built for another number of points.
  WeightedSumObjective& Add(double weight, std::shared_ptr<const Objective> term);
  std::string name() const override;
  double Evaluate(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                  Eigen::MatrixX3d* grad) const override;
  int num_residuals() const override;
  bool Residuals(const Eigen::Ref<const Eigen::MatrixX3d>& p, Eigen::VectorXd* r,
                 Eigen::MatrixXd* dr_dp) const override;

 private:
  std::vector<std::pair<double, std::shared_ptr<const Objective>>> terms_;
};

}  // namespace softkin
