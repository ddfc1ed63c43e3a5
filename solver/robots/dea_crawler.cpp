/// \file dea_crawler.cpp
/// dea_crawler (thesis Fig. 2.10): a DEA membrane under a bendable frame, on two legs.
#include "softkin/solver/robots/robot_parts.hpp"

#include "softkin/solver/mesh/mesh_gen.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <vector>

namespace softkin {
namespace robots_detail {
namespace {

// ================================================================================================
// dea_crawler (thesis Fig. 2.10, after [83]): a thin strip of prism elements, a DEA membrane under
// a bendable frame, with a leg under each end.
//
// Axes: x = long axis [0, 60], y = width [0, 20], z = up. Prism layers (mm): legs z in [0, 5] under
// x in [0, 5] and [55, 60] (region 3, weight 20: rigid); the membrane layer z in [5, 5.5], whose
// part x in [10, 50] is the DEA actuator "dea" (region 1) and the rest passive elastomer
// (region 2); the frame layer z in [5.5, 6.5] over the whole strip (region 0, R_omega 1).
// The mesh is the flat, pre-stretched state of fabrication (area ratio 1). Releasing the stretch
// gives the robot's rest state, lambda_init = 0.7: the membrane shrinks, the bilayer arches up and
// the legs are pulled together. A voltage relaxes the membrane (lambda towards 1), flattening the
// arch and spreading the legs. Range lambda in [0.7, 1], rest 0.7.
// Supports: the legs stay on the x-y plane (thesis): the bottom of the rear leg (x in [0, 5]) is
// pinned (the stance foot), the bottom of the front leg has only z held (it slides on the
// ground). Markers: tip (front face x = 60), rear_foot / front_foot (centroids of the leg
// bottoms), apex (the frame's top surface at x = 30). The leg spacing is front_foot - rear_foot.
// Resolution: prisms per 20 mm of width (in-plane cell 20 / res mm); an odd res has res + 1 across
// the width, so that the mesh is mirror-symmetric about y = 10.
// ================================================================================================

constexpr int kCrawlMinRes = 4, kCrawlMaxRes = 40, kCrawlDefaultRes = 8;
constexpr double kCrawlLength = 60.0, kCrawlWidth = 20.0, kCrawlLeg = 5.0, kCrawlLegHeight = 5.0,
                 kCrawlMembrane = 0.5, kCrawlFrame = 1.0, kCrawlDea0 = 10.0, kCrawlDea1 = 50.0,
                 kCrawlInit = 0.7;

Scene MakeDeaCrawler(int res, const RobotParams& P) {
  // PrismGridMesh's triangulation is symmetric about every grid line, and the mid-width y = 10 is
  // one only over an even number of cells: an odd res is cut into res + 1 across the same width.
  const double h = kCrawlWidth / res;
  const int nx = static_cast<int>(std::lround(kCrawlLength / h)), ny = res + (res & 1);
  const double hy = kCrawlWidth / ny;
  // Layers: legs split into cells of about h, then the membrane and the frame.
  const int leg_layers = std::max(1, static_cast<int>(std::lround(kCrawlLegHeight / h)));
  std::vector<double> z;
  for (int l = 0; l <= leg_layers; ++l) z.push_back(kCrawlLegHeight * l / leg_layers);
  z.push_back(kCrawlLegHeight + kCrawlMembrane);
  z.push_back(kCrawlLegHeight + kCrawlMembrane + P.at("frame_thickness"));
  auto cell = [&](const Eigen::Vector3d& ctr, const Eigen::Vector3i& c) {
    const double xc = ctr.x();
    if (c[2] < leg_layers) return (xc < kCrawlLeg || xc > kCrawlLength - kCrawlLeg) ? 3 : -1;
    if (c[2] == leg_layers) return (xc > kCrawlDea0 && xc < kCrawlDea1) ? 1 : 2;
    return 0;
  };
  Scene s;
  s.name = "dea_crawler";
  s.mesh = PrismGridMesh(Eigen::Vector3d::Zero(), h, hy, Eigen::Vector2i(nx, ny), z, cell);
  s.body[0] = Material{"frame", 1.0, P.at("frame_weight")};
  s.body[2] = Material{"elastomer", 1.0, 1.0};
  s.body[3] = Material{"leg", 1.0, 20.0};
  Actuator a;
  a.name = "dea";
  a.type = ActuatorType::Dea;
  a.regions = {1};
  a.min = a.rest = kCrawlInit;
  a.max = 1.0;
  s.actuators.push_back(a);
  const double eps = 1e-6 * h, xmax = nx * h;
  const std::vector<int> rear = VerticesInBox(s.mesh, Eigen::Vector3d(-kInf, -kInf, -eps),
                                              Eigen::Vector3d(kCrawlLeg + eps, kInf, eps));
  const std::vector<int> front =
      VerticesInBox(s.mesh, Eigen::Vector3d(xmax - kCrawlLeg - eps, -kInf, -eps),
                    Eigen::Vector3d(kInf, kInf, eps));
  s.fixed = rear;
  s.fixed_axis[2] = front;
  s.markers.push_back(
      {"tip", VerticesOnPlane(s.mesh, Eigen::Vector3d(xmax, 0, 0), Eigen::Vector3d::UnitX(), eps)});
  s.markers.push_back({"rear_foot", rear});
  s.markers.push_back({"front_foot", front});
  const double ztop = z.back();
  const int mid = NearestVertex(s.mesh, Eigen::Vector3d(0.5 * xmax, 0, ztop));
  const double xmid = s.mesh.vertices(mid, 0);
  s.markers.push_back({"apex", VerticesInBox(s.mesh, Eigen::Vector3d(xmid - eps, -kInf, ztop - eps),
                                             Eigen::Vector3d(xmid + eps, kInf, kInf))});
  s.validate();
  return s;
}

}  // namespace

RobotEntry DeaCrawlerEntry() {
  const RobotInfo info = {
      "dea_crawler",
      "DEA crawling robot (thesis Fig. 2.10): a 60 x 20 mm strip of prism elements, a 0.5 mm DEA "
      "membrane (actuator 'dea', area ratio in [0.7, 1], rest 0.7 = the released pre-stretch "
      "lambda_init) under a bendable frame, with a 5 mm leg under each end. The mesh is the flat "
      "pre-stretched state. The rear foot is pinned, the front foot slides on the x-y plane (z "
      "held). Markers: tip, rear_foot, front_foot, apex (top of the frame at mid-length).",
      kCrawlDefaultRes,
      "prisms per 20 mm (in-plane cell 20/res mm; an odd res has res + 1 across the 20 mm "
      "width, for mirror symmetry about y = 10), integer in [4, 40]",
      {{"frame_thickness", kCrawlFrame, 0.2, 5.0, "thickness of the frame layer, mm"},
       {"frame_weight", 1.0, 0.01, 100.0, "element weight of the frame (membrane: 1, DEA: 5)"}}};
  return {info, kCrawlMinRes, kCrawlMaxRes, &MakeDeaCrawler};
}

}  // namespace robots_detail
}  // namespace softkin
