#pragma once
/// \file
/// The kinematics interface (thesis Ch. 4-5, DESIGN.md): the one thing IK and learning see.
/// A Kinematics maps an actuation vector c (one value per actuator, within [lower, upper]) to the
/// positions p(c) of a fixed list of tracked points (mm) and, on request, to the Jacobian
/// J(c) = dp/dc. Implementations: the simulator (ik/simulator_kinematics.hpp; Jacobian by central
/// differences, warm-started differences or implicit differentiation), and later the learned
/// networks and analytical models. IK code never knows which one it drives.

#include <Eigen/Core>

#include <string>
#include <vector>

namespace softkin {

/// What one evaluation returns.
struct KinematicsEval {
  bool ok = false;  ///< false: p (and J) are not valid; `message` says why
  std::string message;
  Eigen::MatrixX3d p;  ///< #points x 3 tracked point positions, mm
  /// 3 #points x #actuators Jacobian dp/dc (row 3 i + d is coordinate d of point i), mm per unit
  /// of actuation; empty unless requested.
  Eigen::MatrixXd J;
  /// Body elements inverted (signed volume <= 0) in the simulated state behind p, and the
  /// smallest signed / rest volume of a body element there: p of such a state is not a
  /// physical answer. 0 and 1 for kinematics without a mesh (networks, PCC models).
  int inverted_elements = 0;
  double min_volume_ratio = 1.0;
  int fk_solves = 0;    ///< forward solves this evaluation took (simulator), or 0
  double time_s = 0.0;  ///< wall time of this evaluation
};

class Kinematics {
 public:
  virtual ~Kinematics() = default;
  /// Short name for reports, e.g. "simulator(implicit)".
  virtual std::string name() const = 0;
  virtual int num_actuators() const = 0;
  /// Names of the tracked points, in the row order of p (e.g. "tip", "grip_layer[3]").
  virtual const std::vector<std::string>& point_names() const = 0;
  int num_points() const { return static_cast<int>(point_names().size()); }
  /// Index of the tracked point with that name, or -1.
  int point_index(const std::string& name) const;
  /// Box bounds of the actuation (#actuators each): c_min, c_max.
  virtual const Eigen::VectorXd& lower() const = 0;
  virtual const Eigen::VectorXd& upper() const = 0;
  /// The rest actuation (where IK starts when nothing better is known).
  virtual Eigen::VectorXd rest() const = 0;
  /// p(c), and J(c) when with_jacobian. c must have #actuators finite entries within the bounds
  /// (else ok = false with the reason). Never throws for bad c.
  virtual KinematicsEval Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c,
                                  bool with_jacobian) = 0;
  /// Total forward solves (or model evaluations) since construction.
  virtual long long total_fk_solves() const = 0;
};

/// "" if c has the right size, is finite and lies in [lower, upper] (with a relative slack of
/// 1e-12 of the range); else the reason, naming the actuator.
std::string CheckKinematicsInput(const Kinematics& k, const Eigen::Ref<const Eigen::VectorXd>& c);

}  // namespace softkin
