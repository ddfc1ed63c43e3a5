#pragma once
/// \file twin.hpp
/// The "hardware" twins of the sim-to-real experiments (DESIGN.md, "The hardware in sim-to-real";
/// thesis Sec. 5.3): a twin is a Kinematics that stands in for a fabricated robot. It wraps a
/// simulator of a perturbed copy of a nominal robot (other material parameters, perturbed
/// geometry) and measures its tracked points the way a tracking system would: with a fixed
/// marker offset and Gaussian measurement noise. It gives positions only, like hardware: asking
/// for a Jacobian fails (ok = false). Its name() starts with "twin:", and every output made from
/// it must carry that label. The twins and their measured differences from the nominal robots
/// are documented in docs/twins.md; no result made with a twin claims physical accuracy.
///
/// Noise: each coordinate of each point gets sigma * z, z ~ N(0, 1) drawn from a counter-based
/// generator keyed by (seed, the bits of c, point, coordinate): a frozen noise field. The same c
/// always gives the same measurement, so datasets made from a twin are reproducible, resumable
/// and shardable like any other.
#include "softkin/ik/kinematics.hpp"
#include "softkin/ik/simulator_kinematics.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace softkin {

/// How a twin differs from its nominal robot.
struct TwinSpec {
  std::string name;                    ///< e.g. "three_chamber/robot1"
  std::string robot;                   ///< the nominal robot (solver/robots/robots.hpp)
  RobotParams params;                  ///< geometry / design parameters given to MakeRobot
  double body_r_omega = 1.0;           ///< R_omega of every body region (nominal: the robot's own)
  bool set_body_r_omega = false;       ///< whether body_r_omega replaces the robot's values
  double actuator_weight_scale = 1.0;  ///< multiplies every actuator's element weight (> 0)
  Eigen::Vector3d marker_offset = Eigen::Vector3d::Zero();  ///< added to every point, mm
  double noise_sigma_mm = 0.05;  ///< measurement noise per coordinate, mm (>= 0)
  std::uint64_t noise_seed = 0;
  std::string doc;  ///< one line: what differs
};

/// Names of the built-in twins: "three_chamber/robot1", "three_chamber/robot2",
/// "finger_manipulator/robot1".
std::vector<std::string> TwinNames();
/// The built-in twin `name`. Throws std::invalid_argument for an unknown name (listing the known).
TwinSpec GetTwinSpec(const std::string& name);
/// The perturbed scene of a twin at resolution res (<= 0: the robot's default).
Scene MakeTwinScene(const TwinSpec& spec, int res);

struct TwinOptions {
  int res = 0;  ///< robot resolution (<= 0: the robot's default)
  /// Tracked points (SimulatorKinematicsOptions::points; empty: every marker).
  std::vector<std::string> points;
  bool noise = true;   ///< add the measurement noise (false: for calibration checks)
  bool offset = true;  ///< add the marker offset
  /// Forward-solve gradient tolerance (FkOptions::gradient_tolerance; 0: the robot's own).
  double gradient_tolerance = 0.0;
};

class TwinKinematics : public Kinematics {
 public:
  /// Builds the twin's perturbed simulator. Throws std::invalid_argument for an invalid spec
  /// (naming the field) or bad options.
  TwinKinematics(const TwinSpec& spec, const TwinOptions& options = TwinOptions());
  /// "twin:<spec name>".
  std::string name() const override { return "twin:" + spec_.name; }
  int num_actuators() const override { return sim_->num_actuators(); }
  const std::vector<std::string>& point_names() const override { return sim_->point_names(); }
  const Eigen::VectorXd& lower() const override { return sim_->lower(); }
  const Eigen::VectorXd& upper() const override { return sim_->upper(); }
  Eigen::VectorXd rest() const override { return sim_->rest(); }
  /// Measured positions (#points x 3, mm): the perturbed simulator's points plus the marker
  /// offset and the noise. with_jacobian: ok = false (hardware has no Jacobian).
  KinematicsEval Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c, bool with_jacobian) override;
  long long total_fk_solves() const override { return sim_->total_fk_solves(); }
  /// Forgets the simulator's warm-start state.
  void Reset() { sim_->Reset(); }
  const TwinSpec& spec() const { return spec_; }
  const SimulatorKinematics& simulator() const { return *sim_; }

  /// The noise added at actuation c to coordinate d of point q, mm (0 when noise is off).
  double Noise(const Eigen::Ref<const Eigen::VectorXd>& c, int q, int d) const;

 private:
  TwinSpec spec_;
  TwinOptions options_;
  std::unique_ptr<SimulatorKinematics> sim_;
};

}  // namespace softkin
