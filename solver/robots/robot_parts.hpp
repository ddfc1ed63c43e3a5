#pragma once
/// \file robot_parts.hpp
/// What the embedded robot generators share, private to solver/robots (not public API;
/// robots.hpp is): the registry entry each robot's file exports (listed by robots.cpp), the
/// nominal PneuNet finger dimensions of pneumatic_finger and selfcollision_finger, and helpers
/// that lay out cells, chamber rows, markers, Mooney-Rivlin materials and slits.
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/scene/scene.hpp"

#include <Eigen/Core>

#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace softkin {
namespace robots_detail {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// One robot of the registry: its documentation (ListRobots), its resolution range and its
/// generator, called with a resolution in that range and every parameter of info.params.
struct RobotEntry {
  RobotInfo info;
  int min_res, max_res;
  Scene (*make)(int, const RobotParams&);
};

// The registry entries, one per robot file, in ListRobots() order.
RobotEntry PneumaticFingerEntry();      // pneumatic_finger.cpp
RobotEntry ThreeChamberEntry();         // three_chamber.cpp
RobotEntry CableFingerEntry();          // cable_finger.cpp
RobotEntry FingerManipulatorEntry();    // finger_manipulator.cpp
RobotEntry MultiSegmentGripperEntry();  // multi_segment_gripper.cpp
RobotEntry DeaCrawlerEntry();           // dea_crawler.cpp
RobotEntry BimaterialBarEntry();        // bimaterial_bar.cpp
RobotEntry CableGripperEntry();         // cable_gripper.cpp
RobotEntry SelfCollisionFingerEntry();  // selfcollision_finger.cpp
RobotEntry MembraneEntry();             // membrane.cpp
RobotEntry TwistingRobotEntry();        // robot_twisting.cpp
RobotEntry BilayerStripEntry();         // bilayer_strip.cpp

// ---- The PneuNet finger's nominal dimensions (mm): pneumatic_finger, selfcollision_finger ----

constexpr double kFingerLength = 120.0, kFingerWidth = 20.0, kFingerHeight = 15.0;
constexpr double kFingerBase = 1.5, kFingerFloor = 1.5, kFingerWall = 1.5, kFingerCavity = 5.0;
constexpr double kFingerProximal = 8.0;
/// Weight of the inextensible layer relative to the body: it resists stretching; being one cell
/// thin it still bends.
constexpr double kFingerLayerWeight = 20.0;

// ---- Helpers ----

/// The number of cells of size h (mm) closest to a length of `mm`, at least one.
int Cells(double mm, double h);

/// Grid lines through the breakpoints `b` (increasing: a design's dimensions along one axis),
/// each interval cut into about len / h cells (at least 1; an even number where `even` says so).
/// Meshes on these lines keep the design's dimensions at every resolution.
std::vector<double> DesignLines(const std::vector<double>& b, double h,
                                const std::vector<bool>& even = {});

/// A 0/1 robot parameter `key` of `robot` as a flag; any other value throws
/// std::invalid_argument naming the robot, the key and what 0 (`off`) and 1 (`on`) mean.
bool FlagParam(const std::string& robot, const RobotParams& P, const std::string& key,
               const std::string& off, const std::string& on);

/// The robot parameter design_grid of `robot` as a flag: 0 snaps the features to whole cells, 1
/// puts grid lines on the design's dimensions (DesignLines). Any other value throws
/// std::invalid_argument naming the robot, the key and the accepted values.
bool DesignGridFlag(const std::string& robot, const RobotParams& P);

/// The robot parameter chamber_weight of the pneumatic robots whose chamber fill can be
/// softened (pneumatic_finger, multi_segment_gripper): the weight of the chamber elements in
/// Eq. 2.10 against the body's 1; default Actuator{}.weight (5, Sec. 2.5), range [0.01, 100].
RobotParam ChamberWeightParam();

/// Markers of a finger whose distal face is the plane x = xmax: "tip" (the face's centroid),
/// "tip_top" / "tip_bottom" (its top and bottom quarters in z, used for the bend angle).
void AddDistalFaceMarkers(double xmax, double zmax, double eps, Scene* s);

// Chamber rows shared by the multi-segment robots (finger_manipulator, multi_segment_gripper):
// along x, a solid proximal part, then cavities of `cavity` cells between walls of `wall` cells,
// the last wall closing the segment.

struct ChamberRow {
  int x0 = 0, x1 = 0;        // the segment's cells [x0, x1)
  int wall = 1, cavity = 1;  // cells
  int first = 0;             // first cavity wall cell (after the solid proximal part)
  int chambers = 0;
};

/// The row over cells [x0, x1) with as many chambers as fit after a solid part of at least
/// `min_solid` cells.
ChamberRow MakeChamberRow(int x0, int x1, int wall, int cavity, int min_solid);

/// Whether cell column i lies in a cavity of the row.
bool InCavity(const ChamberRow& r, int i);

/// A first-order Mooney-Rivlin body material (Eq. 3.6-3.7) named `name`, with the constants of
/// the built-in material `named` (hyperelastic.hpp), R_omega 1 at zero strain and weight `weight`.
Material MooneyRivlinMaterial(const std::string& name, const std::string& named, double weight);

/// Cuts a slit through a tet mesh along a set of vertices: every vertex with on_cut(position)
/// that is used by tets on both sides (far_side(tet centroid) true and false) is doubled, and
/// the far-side tets take the copy; a vertex used by far-side tets only is simply moved. The
/// far side's vertices of the cut are then moved by `shift` (mm), opening the slit.
void CutSlit(Mesh* mesh, const std::function<bool(const Eigen::Vector3d&)>& on_cut,
             const std::function<bool(const Eigen::Vector3d&)>& far_side,
             const Eigen::Vector3d& shift);

}  // namespace robots_detail
}  // namespace softkin
