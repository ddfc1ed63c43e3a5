#pragma once
/// \file robot_twisting.hpp
/// The plant-inspired twisting robot of thesis Sec. 3.4.1 (Fig. 3.7, 3.8): a silicone cylinder
/// with a spiral (helical) tube chamber inside, meshed with T(S_c, S_b) (tessellation.hpp) from
/// generated surfaces, and helpers to measure how far a cross-section has turned about the axis.
///
/// Geometry (mm): body = cylinder of radius 10 about the z axis, z in [0, 100]; z = 0 is fixed, the
/// tip face is z = 100. Chamber = a closed tube of radius `tube_radius` (default 2.5) around the
/// right-handed helix (helix_radius cos phi, helix_radius sin phi, z), phi = 2 pi turns t,
/// z = 8 + 84 t, t in [0, 1] (default helix radius 5, 6 turns: a 14 mm pitch), closed by
/// hemispherical caps. Why 6 turns: the inflated tube lengthens along the helix, and the flatter
/// the helix the more of that becomes twist (measured at res 1 with R_omega = 1 bodies: 8 deg of
/// tip twist at alpha = 4 with 6 turns; with 3 turns the tip turned by less than 6 deg and
/// changed direction as alpha grew).
/// Material (parameter hyperelastic = 1, default): Ecoflex 00-30, first-order Mooney-Rivlin
/// c1 = 0.0418, c2 = 0.0106 MPa (law "mooney-rivlin", R_omega 1 at zero strain, weight 1);
/// hyperelastic = 0: Ch. 2 shape blending with R_omega = 1 (as-rigid-as-possible). Actuator
/// "chamber": pneumatic, volume ratio in [1, 120]. Markers: tip (the z = 100 face), tip_rim (the
/// tip-face vertex nearest (10, 0, 100)). Body region 0, chamber region 1.
#include "softkin/solver/mesh/surface.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/scene/scene.hpp"
#include "softkin/solver/remesh/tessellation.hpp"

#include <Eigen/Core>

#include <vector>

namespace softkin {

constexpr double kTwistBodyRadius = 10.0, kTwistLength = 100.0;
constexpr double kTwistHelixZ0 = 8.0, kTwistHelixZ1 = 92.0;
constexpr int kTwistMinRes = 1, kTwistMaxRes = 12, kTwistDefaultRes = 1;
/// The chamber's volume ratio: the largest the robot_param max_ratio may set (the thesis's range,
/// reached with progressive remeshing), and its default (what the initial mesh reaches without
/// inverted elements).
constexpr double kTwistMaxAlpha = 120.0, kTwistDefaultMaxRatio = 3.0;
constexpr double kTwistDefaultTurns = 6.0;

/// A closed tube surface around a helix about the z axis: centreline
/// c(t) = (r cos(2 pi n t), r sin(2 pi n t), z0 + (z1 - z0) t), t in [0, 1], with circular
/// cross-sections of radius `tube_radius` in the helix's normal planes (Frenet frame), closed at
/// both ends by hemispherical caps. `around` segments around the tube, `along` segments along
/// it, `cap_rings` rings per cap. Outward-oriented (CheckClosedSurface). Throws
/// std::invalid_argument for non-positive sizes, tube_radius >= helix_radius or a pitch that
/// makes neighbouring turns overlap (pitch <= 2 tube_radius).
TriangleSurface MakeHelicalTubeSurface(double helix_radius, double turns, double z0, double z1,
                                       double tube_radius, int around = 24, int along = 192,
                                       int cap_rings = 6);

/// The body S_b and chamber S_c surfaces of the twisting robot with design parameters
/// `params` (helix_radius, tube_radius, turns; defaults as in the file comment; others ignored).
void TwistingRobotSurfaces(const RobotParams& params, TriangleSurface* chamber,
                           TriangleSurface* body);

/// Mesh_3 sizing of the twisting robot at resolution res (1..6): cell_size = facet_size =
/// 8 / res mm, chamber_cell_size = min(cell_size, 0.8 tube_radius) (so the tube has interior
/// vertices), facet_distance = 0.05 * cell_size, seed 1.
TessellationOptions TwistingRobotTessellation(int res, double tube_radius = 2.5);
/// The same for the robot built with `params` (its tube_radius, default 2.5) at res (<= 0: the
/// default resolution): the sizing MakeTwistingRobot uses, e.g. for re-tessellating its chamber.
TessellationOptions TwistingRobotTessellation(int res, const RobotParams& params);

/// Builds the twisting robot (res <= 0: default). Parameters: helix_radius, tube_radius, turns,
/// hyperelastic (full defaults in ListRobots()). Deterministic.
Scene MakeTwistingRobot(int res, const RobotParams& params);

/// The angle (degrees, in (-180, 180]) of the twist part of the best-fit rotation taking the
/// centred rest points P (n x 3, n >= 3, mm) to the centred deformed points Q: the rotation R
/// (Kabsch) is split as R = R_swing R_twist with R_twist about `axis` (unit, rest frame), and the
/// angle of R_twist is returned (right-hand rule about `axis`).
double TwistAboutAxisDegrees(const Eigen::Ref<const Eigen::MatrixX3d>& P,
                             const Eigen::Ref<const Eigen::MatrixX3d>& Q,
                             const Eigen::Vector3d& axis);

/// Twist profile of a robot along the z axis: the body-region vertices (region `body_region`)
/// whose rest z lies within each of `sections` equal slabs of [0, length] are fitted with
/// TwistAboutAxisDegrees about +z; the last entry uses the vertices of marker `tip` instead of the
/// last slab. Angles are unwrapped from the fixed base (0) upwards, so neighbouring sections
/// differ by at most 180 degrees: the result can exceed one turn. Returns `sections` angles
/// (degrees); X: #V x 3 positions (mm). Throws std::invalid_argument if a slab has < 3 vertices
/// or the marker is missing.
std::vector<double> TwistProfileDegrees(const Scene& scene,
                                        const Eigen::Ref<const Eigen::MatrixX3d>& X, double length,
                                        int sections = 20, int body_region = 0,
                                        const std::string& tip = "tip");

}  // namespace softkin
