/// \file bimaterial_bar.cpp
/// bimaterial_bar (thesis Fig. 2.6): the two-material specimen of the elongation and twisting
/// tests.
#include "softkin/solver/robots/robot_parts.hpp"

#include "softkin/solver/mesh/mesh_gen.hpp"

#include <Eigen/Core>

#include <vector>

namespace softkin {
namespace robots_detail {
namespace {

// ================================================================================================
// bimaterial_bar (thesis Fig. 2.6): the two-material specimen of the elongation and twisting
// tests used to calibrate R_omega.
//
// Axes: x = long axis [0, 80], cross-section y, z in [0, 12] x [0, 12]. Material A (region 0) for
// x < interface * 80, material B (region 1) beyond; the x = 0 face is fixed. The x = 80 face is
// moved by two motion actuators, composed in this order: "twist" (degrees about the bar's axis
// y = z = 6, range [-180, 180]) and "stretch" (mm along +x, range [0, 40]). Each material's
// R_omega and weight are parameters. Markers: tip (end face), interface (the cells' face nearest
// the interface plane), a_mid / b_mid (the cross-sections midway through each material).
// Resolution: cells across the 12 mm side (cell about 12 / res mm). Grid lines sit on the ends,
// the interface and the two mid-sections at every res, so the bar is 80 mm long, the interface
// where the parameter puts it and every marker on its nominal plane, whatever the cell size; an
// even count of cells across each side keeps the mesh mirror-symmetric about y = 6 and z = 6.
// ================================================================================================

constexpr int kBarMinRes = 2, kBarMaxRes = 24, kBarDefaultRes = 4;
constexpr double kBarLength = 80.0, kBarSide = 12.0;

Scene MakeBimaterialBar(int res, const RobotParams& P) {
  const double h = kBarSide / res;
  const double xi = P.at("interface") * kBarLength;
  const double xa = 0.5 * xi, xb = 0.5 * (xi + kBarLength);
  const auto side = DesignLines({0.0, kBarSide}, h, {true});
  auto cell = [&](const Eigen::Vector3d& c, const Eigen::Vector3i&) { return c.x() < xi ? 0 : 1; };
  Scene s;
  s.name = "bimaterial_bar";
  s.mesh = RectilinearTetMesh(DesignLines({0.0, xa, xi, xb, kBarLength}, h), side, side, cell);
  s.body[0] = Material{"A", P.at("r_omega_a"), P.at("weight_a")};
  s.body[1] = Material{"B", P.at("r_omega_b"), P.at("weight_b")};
  const double eps = 1e-6 * h;
  auto plane = [&](double x) {
    return VerticesOnPlane(s.mesh, Eigen::Vector3d(x, 0, 0), Eigen::Vector3d::UnitX(), eps);
  };
  const std::vector<int> end = plane(kBarLength);
  Actuator tw;
  tw.name = "twist";
  tw.type = ActuatorType::Twist;
  tw.vertices = end;
  tw.axis = Eigen::Vector3d::UnitX();
  tw.centre = Eigen::Vector3d(0, 0.5 * kBarSide, 0.5 * kBarSide);
  tw.rest = 0.0;
  tw.min = -180.0;
  tw.max = 180.0;
  Actuator st = tw;
  st.name = "stretch";
  st.type = ActuatorType::Displacement;
  st.min = 0.0;
  st.max = 40.0;
  s.actuators = {tw, st};
  s.fixed = plane(0.0);
  s.markers.push_back({"tip", end});
  s.markers.push_back({"interface", plane(xi)});
  s.markers.push_back({"a_mid", plane(xa)});
  s.markers.push_back({"b_mid", plane(xb)});
  s.validate();
  return s;
}

}  // namespace

RobotEntry BimaterialBarEntry() {
  const RobotInfo info = {
      "bimaterial_bar",
      "Two-material specimen of the elongation and twisting tests (thesis Fig. 2.6): an "
      "80 x 12 x 12 mm bar, material A (region 0) up to the interface and B (region 1) beyond; "
      "x = 0 fixed; the x = 80 face is driven by the motion actuators 'twist' (degrees about the "
      "bar's axis, [-180, 180]) and 'stretch' (mm along +x, [0, 40]). Markers: tip, interface, "
      "a_mid, b_mid.",
      kBarDefaultRes,
      "cells across the 12 mm side (cell size about 12/res mm; an odd res gets one more), integer "
      "in [2, 24]",
      {{"interface", 0.5, 0.05, 0.95,
        "interface position as a fraction of the length (a grid line at every res)"},
       {"r_omega_a", 1.0, 0.0, 1.0, "R_omega of material A"},
       {"r_omega_b", 1.0, 0.0, 1.0, "R_omega of material B"},
       {"weight_a", 1.0, 1e-3, 1e3, "element weight of material A"},
       {"weight_b", 1.0, 1e-3, 1e3, "element weight of material B"}}};
  return {info, kBarMinRes, kBarMaxRes, &MakeBimaterialBar};
}

}  // namespace robots_detail
}  // namespace softkin
