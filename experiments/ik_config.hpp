#pragma once
/// \file ik_config.hpp
/// The config keys shared by the Chapter 4 (IK) experiments, and the waypoint paths they follow.
///
/// Common keys (all optional except where an experiment says so):
///   robot ("cable_finger"), res (robot default), robot_params ({}), solver (FK options),
///   point ("tip"), method ("softls"), jacobian ("implicit"), fd_step (1/160 of the range),
///   lambda_mm (0.2: stop a point-tracking waypoint within 0.2 mm, i.e. O <= 0.04 mm^2),
///   max_iterations (30, thesis i_max), max_evaluations (300), max_time_s (600 per
///   waypoint or stage), samples_per_axis (5: 5^3 samples), first_waypoint_starts (3: the first
///   waypoint of a path is solved from up to 3 closest samples until one converges).
///
/// A path is a JSON object {"name", "type", ...}:
///   "polyline": "vertices" [[x,y,z],...] (mm), "n" waypoints spread evenly by arc length over the
///               polyline (both ends included), "closed" (false) to return to the first vertex;
///   "flame":    a closed teardrop with a flickering side (the thesis's flame, Fig. 4.2) in the
///               plane of two axes "axes" ([0, 2]: x and z), centred at "center" [x,y,z], "width"
///               and "height" (mm), turned by "tilt_deg" (0) in that plane, "n" waypoints evenly by
///               arc length, starting at its bottom;
///   "file":     a waypoint file "file" (ik/trajectory_io.hpp; relative paths are taken from the
///               source tree), every "stride"-th waypoint (1: all; the first is always kept, and
///               the mapping uses the file's first waypoint), optionally mapped into the robot's
///               workspace with "map" {axis, anchor_actuation, profile_steps, lift} (see
///               MapToWorkspace in ik_config.cpp and docs/ik.md).
/// Every path may carry "thesis": {...}, the thesis's numbers for it (e.g. {"total_time_s": 38}),
/// copied into the summary beside ours.
#include "softkin/experiments/config.hpp"
#include "softkin/ik/ik_solver.hpp"
#include "softkin/ik/simulator_kinematics.hpp"
#include "softkin/ik/trajectory.hpp"
#include "softkin/solver/scene/scene.hpp"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace softkin {

struct IkExperimentSetup {
  std::string robot;
  int res = 0;
  Scene scene;
  FkOptions fk;
  SimulatorKinematicsOptions kin;  ///< jacobian and fd_step from the config; points left empty
  std::string point = "tip";
  IkOptions ik;
  double lambda_mm = 0.2;
  int samples_per_axis = 5;
  int first_waypoint_starts = 3;
  /// robot, res, sizes, method, jacobian, lambda, i_max: for the summary.
  nlohmann::json Json() const;
  /// Kinematics options tracking `points`.
  SimulatorKinematicsOptions KinematicsFor(const std::vector<std::string>& points) const;
};

/// Reads the common keys (see the file comment); errors name the config and the key.
IkExperimentSetup ReadIkSetup(const Config& cfg, const std::string& default_robot);

/// A path to follow: its waypoints and what the summary reports about it.
struct IkPath {
  std::string name;
  Eigen::MatrixX3d waypoints;  ///< #waypoints x 3, mm
  nlohmann::json info;         ///< the spec, plus the mapping applied (for "file")
  nlohmann::json thesis = nlohmann::json::object();  ///< the thesis's numbers, from the spec
};

/// Builds a path from its JSON spec; `where` names it in errors ("config.json: paths[1]").
/// For "map", kin (tracking the path's point first) and the configuration-space samples are used.
IkPath MakeIkPath(const nlohmann::json& spec, const std::string& where, Kinematics& kin,
                  const ConfigurationSamples& samples);

/// n points spread evenly by arc length over the polyline `v` (closed: back to v[0], and the
/// last point is not repeated). Throws std::invalid_argument for fewer than 2 vertices, n < 2 or a
/// zero-length polyline.
Eigen::MatrixX3d ResamplePolyline(const std::vector<Eigen::Vector3d>& v, int n, bool closed);

}  // namespace softkin
