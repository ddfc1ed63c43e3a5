#pragma once
/// \file fem_trajectory.hpp
/// The pressure-driven FEM (solver/baselines/calculix_pressure.hpp) as the experiments use it:
/// its options read from one set of config keys, and a pressure ramp read back as a bending
/// trajectory, one point per converged increment, comparable with a SoftKin sweep at the same
/// chamber volume ratio (the FEM's cavity ratio).
///
/// Config keys (all optional): fem_element ("C3D10" or "C3D4"), young_mpa (E0), poisson (nu),
/// max_increment (largest increment, fraction of the ramp), fem_time_limit_s (0: none); and, read
/// by the caller with CheckFemLaw, the law or laws ("linear": FEM 1, "neo-hooke": FEM 2).
#include "softkin/experiments/config.hpp"
#include "softkin/experiments/results.hpp"
#include "softkin/solver/baselines/calculix_pressure.hpp"
#include "softkin/solver/scene/scene.hpp"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace softkin {

/// Reads the FEM keys above into options (law left at its default), checking each; a bad value
/// fails naming the key and what was expected.
PressureFemOptions ReadPressureFemOptions(const Config& cfg, double default_max_increment,
                                          double default_time_limit_s);

/// Fails on `key` unless law is "linear" or "neo-hooke".
void CheckFemLaw(const Config& cfg, const std::string& key, const std::string& law);
/// Fails on `key` unless element is "C3D10" or "C3D4".
void CheckFemElement(const Config& cfg, const std::string& key, const std::string& element);
/// Fails on `key` unless the largest increment is a fraction of the ramp in (0, 1].
void CheckMaxIncrement(const Config& cfg, const std::string& key, double max_increment);

/// Fails on `key`, before any work, if ccx is missing (with the install hint) or the FEM cannot
/// mesh the scene with `element` (naming the chamber or actuator).
void CheckPressureFemCanRun(const Config& cfg, const std::string& key, const Scene& scene,
                            const std::string& element);

/// One converged FEM increment, measured.
struct FemTrajectoryPoint {
  double load = 0;          ///< fraction of the pressure ramp
  double pressure = 0;      ///< on the measured actuator's chambers, MPa
  double cavity_ratio = 1;  ///< the measured actuator's cavity volume / rest volume
  double bend_deg = 0;      ///< BendAngle (0 if the scene has no tip_top / tip_bottom markers)
  double wall_s = 0;        ///< wall-clock time since the ccx run started
  Eigen::Vector3d tip = Eigen::Vector3d::Zero();  ///< the 'tip' marker
};

struct FemTrajectory {
  std::string law;
  PressureFemRun run;  ///< the ccx run: status, message, counts, increments with positions
  std::vector<FemTrajectoryPoint> points;  ///< the rest state first, then each increment
  double max_bend_deg = 0;
};

/// Ramps the pressure of the actuators in `pressure` (MPa per actuator) with `options` and
/// measures every converged increment on actuator `measured` and the scene's markers. A run that
/// could not start (no ccx, a scene the FEM cannot mesh) has run.ok = false and its message.
FemTrajectory RunFemTrajectory(const Scene& scene, const Model& model,
                               const Eigen::Ref<const Eigen::VectorXd>& pressure, int measured,
                               const PressureFemOptions& options);

/// Header of the rows AppendFemRows writes.
std::vector<std::string> FemTrajectoryColumns();
/// One row per point: law, increment, load, pressure_mpa, cavity_ratio, bend_deg, tip x/y/z,
/// wall_s.
void AppendFemRows(const FemTrajectory& t, CsvWriter* csv);

/// What a summary reports of a trajectory: the run's status ("reached_end", "stopped" or
/// "not_run"), its message (why it stopped), size, time, end pressure and cavity ratio, largest
/// bend, and the wall-clock time to each milestone angle (null where not reached).
nlohmann::json FemTrajectorySummary(const FemTrajectory& t, const std::vector<double>& milestones);

/// Wall-clock time of the first point at or beyond `deg`, or -1.
double FemTimeToBend(const FemTrajectory& t, double deg);

}  // namespace softkin
