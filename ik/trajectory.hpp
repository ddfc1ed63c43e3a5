#pragma once
/// \file
/// Trajectory following (thesis Algorithm 4, Sec. 4.3.1): drive one tracked point through a list
/// of waypoints by solving point-tracking IK (Eq. 4.4) at each.
///  1. The configuration space is sampled on a regular grid (samples_per_axis per actuator, e.g.
///     5^3 = 125); the first waypoint starts from the actuation of the sample whose point is
///     closest to it. The samples can be cached in a CSV file (see SampleConfigurationSpace).
///  2. Each later waypoint starts from the previous waypoint's solution (the warm start; a
///     simulator Kinematics also keeps its own deformed state). With the `broyden` method the
///     previous waypoint's (secant-updated) Jacobian is handed over too, so a warm waypoint
///     evaluates no Jacobian unless a step with it fails.
///  3. For every waypoint: the actuation, the reached point, its distance to the target (for a
///     waypoint outside the workspace, the distance to the closest point IK found), iterations,
///     evaluations, FK solves and time; and the largest actuation jump between neighbours.
/// Results go to a callback as they are computed (the CLI streams CSV rows), and a run can resume
/// from a waypoint with the previous actuation as the warm start.

#include "softkin/ik/ik_solver.hpp"

#include <functional>
#include <string>
#include <vector>

namespace softkin {

struct SamplingOptions {
  int samples_per_axis = 5;  ///< grid points per actuator, >= 2 (the box corners included)
  /// CSV cache file, or "" for none. If it exists and was built for the same kinematics name,
  /// point, key, bounds and grid, it is loaded; else the samples are computed and it is
  /// (over)written.
  std::string cache_file;
  /// What the samples were built for beyond the kinematics' name (e.g. "cable_finger res=8
  /// jacobian=fd"), recorded in the cache and compared on load.
  std::string cache_key;
  bool IsValid(std::string* why) const;
};

/// A sampled configuration space: one row per sample that could be evaluated.
struct ConfigurationSamples {
  Eigen::MatrixXd c;    ///< #samples x #actuators
  Eigen::MatrixX3d p;   ///< #samples x 3, the tracked point, mm
  int failed = 0;       ///< grid points whose evaluation failed (left out)
  double time_s = 0.0;  ///< time to build or load
  /// "built" (no cache file), "loaded", "written" (built, cache written) or
  /// "rebuilt: <reason the cache was rejected>".
  std::string cache_status;
};

/// Samples the grid of samples_per_axis^#actuators actuations over [lower, upper] (deterministic,
/// no randomness: the grid is regular), evaluating the tracked point `point`. Throws
/// std::invalid_argument for invalid options, an unknown point or a grid above 10^6 samples, and
/// std::runtime_error if the cache file cannot be written.
ConfigurationSamples SampleConfigurationSpace(Kinematics& kin, const std::string& point,
                                              const SamplingOptions& options);

/// Row of the sample whose point is closest to `target` (ties: the first), or -1 if none.
int ClosestSample(const ConfigurationSamples& samples, const Eigen::Vector3d& target);
/// Rows of the `count` samples closest to `target`, closest first (ties: lower row first).
std::vector<int> ClosestSamples(const ConfigurationSamples& samples, const Eigen::Vector3d& target,
                                int count);

struct TrajectoryOptions {
  std::string point = "tip";  ///< the tracked point that follows the path
  IkOptions ik;               ///< per waypoint; lambda on |p - target|^2 (0.04 = 0.2 mm)
  SamplingOptions sampling;
  /// Resume: solve waypoints from this index on (>= 0)...
  int first_waypoint = 0;
  /// ...starting from this actuation (the solution of waypoint first_waypoint - 1). Empty: start
  /// from the closest configuration-space sample (Algorithm 4, line 2).
  Eigen::VectorXd warm_start;
  /// Without a warm start, the first waypoint is solved from up to this many samples, closest
  /// first, until one converges; the best answer is kept and the waypoint's counts and time add
  /// up over the tries. A closest sample on a corner of the box can be a stationary point of the
  /// box-constrained problem (every actuator pushed against its bound), from which no method
  /// moves. >= 1; 1 is Algorithm 4 as written.
  int first_waypoint_starts = 3;
  /// Without a warm start: samples to use instead of sampling (e.g. shared by several runs on
  /// one robot); must outlive the call. nullptr: sample with `sampling`.
  const ConfigurationSamples* samples = nullptr;
  bool IsValid(std::string* why) const;
};

struct WaypointResult {
  int index = 0;
  Eigen::Vector3d target = Eigen::Vector3d::Zero();   ///< mm
  Eigen::VectorXd c;                                  ///< actuation found
  Eigen::Vector3d reached = Eigen::Vector3d::Zero();  ///< the tracked point at c, mm
  /// |reached - target|; -1 (and reached = 0) when not even the start actuation could be
  /// evaluated (the kinematics failed there; `message` says why).
  double error_mm = 0.0;
  double objective = 0.0;  ///< error_mm^2 (-1 as error_mm)
  bool converged = false;  ///< objective <= lambda, in a state with no inverted body element
  /// Body elements inverted in the simulated state at c (IkResult): > 0 flags a reached point
  /// that is not a physical answer (such a waypoint is never `converged`).
  int inverted_elements = 0;
  double min_volume_ratio = 1.0;
  IkTermination termination = IkTermination::kConverged;
  std::string message;
  int iterations = 0;
  int evaluations = 0;
  long long fk_solves = 0;
  double time_s = 0.0;
  /// max over actuators of |c - c_previous| (actuation units), and as a fraction of each range;
  /// the previous is the last waypoint's solution (or the initial guess for the first one).
  double jump = 0.0;
  double jump_fraction = 0.0;
};

struct TrajectoryResult {
  std::vector<WaypointResult> waypoints;
  double max_jump = 0.0;           ///< largest WaypointResult::jump after the first waypoint
  double max_jump_fraction = 0.0;  ///< the same as a fraction of the range
  int max_jump_index = -1;         ///< the waypoint where it happened (-1: fewer than 2 waypoints)
  int converged = 0;               ///< waypoints with O <= lambda
  int inverted = 0;                ///< waypoints whose state has inverted body elements
  double mean_error_mm = 0.0, max_error_mm = 0.0;  ///< over the waypoints with a reached point
  /// Sample the kept answer of the first waypoint started from (-1: warm start given).
  int initial_sample = -1;
  int initial_starts_tried = 0;   ///< samples the first waypoint was solved from (0: warm start)
  Eigen::VectorXd initial_guess;  ///< the actuation the kept first-waypoint answer started from
  ConfigurationSamples
      samples;                ///< empty when a warm start or TrajectoryOptions::samples was given
  double total_time_s = 0.0;  ///< including the sampling
};

using WaypointCallback = std::function<void(const WaypointResult&)>;

/// Algorithm 4 over `waypoints` (#waypoints x 3, mm), solving from options.first_waypoint on.
/// Calls on_waypoint (if set) after each waypoint. Throws std::invalid_argument for invalid
/// options, an unknown point, non-finite waypoints or a warm start of the wrong size / outside
/// the box; IK failures are reported per waypoint (a kinematics failure at a waypoint keeps the
/// previous actuation for the next one).
TrajectoryResult FollowTrajectory(Kinematics& kin,
                                  const Eigen::Ref<const Eigen::MatrixX3d>& waypoints,
                                  const TrajectoryOptions& options,
                                  const WaypointCallback& on_waypoint = {});

}  // namespace softkin
