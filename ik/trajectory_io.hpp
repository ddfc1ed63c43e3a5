#pragma once
/// \file
/// Files of trajectory following: the waypoint file read by `softkin ik --trajectory`, and the
/// per-waypoint CSV it writes (streamed row by row, and read back to resume a run).
///
/// Waypoint file: one waypoint per line, "x y z" in mm separated by whitespace (spaces, tabs)
/// and/or commas; '#' starts a comment (to the end of the line); blank lines are skipped; an
/// optional header line "x y z" (any case, same separators) before the first waypoint. This reads
/// data/thesis/flower_trajectory.txt (120 tab-separated lines, no header) as it is.
///
/// Waypoint CSV: the header from WaypointCsvHeader, then one WaypointCsvRow per waypoint:
///   index,target_x,target_y,target_z,c0..c{n-1},reached_x,reached_y,reached_z,error_mm,
///   objective,converged,termination,iterations,evaluations,fk_solves,time_s,jump,
///   inverted_elements
/// (numbers with 17 significant digits for the actuation, so a resumed run continues exactly).

#include "softkin/ik/trajectory.hpp"

#include <Eigen/Core>

#include <string>

namespace softkin {

/// Reads a waypoint file into #waypoints x 3 (mm). Throws std::invalid_argument naming the file
/// and line (and the column where it applies) for a missing file, a line with other than 3
/// values, a value that does not parse fully as a number, NaN or infinity, or a file without
/// waypoints.
Eigen::MatrixX3d ReadWaypoints(const std::string& path);

/// The CSV header line (no newline) for #actuators actuators.
std::string WaypointCsvHeader(int num_actuators);
/// One CSV row (no newline).
std::string WaypointCsvRow(const WaypointResult& w);

/// Where a partly written waypoint CSV leaves off.
struct WaypointCsvResume {
  int next_index = 0;      ///< the index after the last complete row (0 for a header-only file)
  Eigen::VectorXd last_c;  ///< that row's actuation (empty for a header-only file)
};
/// Reads a waypoint CSV written with WaypointCsvHeader(num_actuators) for resuming. A last line
/// without its newline (a run killed mid-write) is ignored. Throws std::invalid_argument naming
/// the file and line for a missing file, another header or a malformed row.
WaypointCsvResume ReadWaypointCsvForResume(const std::string& path, int num_actuators);

}  // namespace softkin
