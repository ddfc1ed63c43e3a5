#pragma once
/// \file constraints_test_util.hpp
/// Helpers of the boundary-condition and actuator tests (test_constraints.cpp,
/// test_motion_signed.cpp): tight solves, mirror partners of vertices, planes of a grid mesh and
/// a chamber bar.
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/energy.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/mesh/mesh_gen.hpp"
#include "tests/solver/test_util.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace softkin {
namespace constraints_test {

/// Tight solver options: stop when no vertex moves more than 1e-9 of the model size per iteration
/// and the local-global residual has dropped by 1e10. Single-threaded for stable timings.
inline FkOptions Tight() {
  FkOptions o;
  o.tolerance = 1e-9;
  o.gradient_tolerance = 1e-10;
  o.max_iterations = 20000;
  o.threads = 1;
  return o;
}

inline FkResult SolveTight(const std::shared_ptr<const Model>& model, const Eigen::VectorXd& c) {
  return MakeFkSolver(model, Tight())->Solve(c);
}

/// Solves the rest actuation with the default gradient tolerance (1e-6): at rest the residual is
/// pure round-off and a tighter gradient tolerance is never met (see
/// Motion.RestValueConvergesAtOnceUnderTightTolerance).
inline FkResult SolveRest(const std::shared_ptr<const Model>& model) {
  FkOptions o = Tight();
  o.gradient_tolerance = 1e-6;
  o.max_iterations = 50;
  return MakeFkSolver(model, o)->Solve(model->scene().rest_actuation());
}

inline Eigen::VectorXd Vec1(double v) {
  Eigen::VectorXd c(1);
  c << v;
  return c;
}

/// Key of a grid position (all test coordinates are multiples of 1/4 mm, exact in binary).
inline std::array<long long, 3> Key(const Eigen::RowVector3d& p) {
  return {std::llround(p.x() * 1024.0), std::llround(p.y() * 1024.0), std::llround(p.z() * 1024.0)};
}

/// For every vertex of `from`, the vertex of `to` whose rest position is its image under `map`,
/// or -1.
template <class F>
std::vector<int> Partner(const Mesh& from, const Mesh& to, const F& map) {
  std::map<std::array<long long, 3>, int> at;
  for (int v = 0; v < to.num_vertices(); ++v) at[Key(to.vertices.row(v))] = v;
  std::vector<int> out(from.num_vertices(), -1);
  for (int v = 0; v < from.num_vertices(); ++v) {
    const Eigen::RowVector3d p = from.vertices.row(v);
    auto it = at.find(Key(map(p)));
    if (it != at.end()) out[v] = it->second;
  }
  return out;
}
template <class F>
std::vector<int> Partner(const Mesh& m, const F& map) {
  return Partner(m, m, map);
}
/// For every vertex of `sub`, the vertex of `full` at the same rest position, or -1.
inline std::vector<int> SamePosition(const Mesh& sub, const Mesh& full) {
  return Partner(sub, full, [](const Eigen::RowVector3d& p) { return p; });
}

/// Partner of each vertex under the reflection of coordinate d about the plane x_d = centre.
inline std::vector<int> MirrorPartner(const Mesh& m, int d, double centre) {
  return Partner(m, [d, centre](Eigen::RowVector3d p) {
    p[d] = 2.0 * centre - p[d];
    return p;
  });
}

/// Largest |X(v) - reflect_d(X(partner(v)))| over all vertices: zero for a configuration that is
/// mirror-symmetric about x_d = centre.
inline double MirrorDefect(const Eigen::MatrixX3d& X, const std::vector<int>& partner, int d,
                           double centre) {
  double worst = 0;
  for (int v = 0; v < X.rows(); ++v) {
    Eigen::RowVector3d q = X.row(partner[v]);
    q[d] = 2.0 * centre - q[d];
    worst = std::max(worst, (X.row(v) - q).norm());
  }
  return worst;
}

/// Largest |X(v) - reflect_d(Y(partner(v)))|: zero when Y is the mirror image of X.
inline double MirrorDistance(const Eigen::MatrixX3d& X, const Eigen::MatrixX3d& Y,
                             const std::vector<int>& partner, int d, double centre) {
  double worst = 0;
  for (int v = 0; v < X.rows(); ++v) {
    Eigen::RowVector3d q = Y.row(partner[v]);
    q[d] = 2.0 * centre - q[d];
    worst = std::max(worst, (X.row(v) - q).norm());
  }
  return worst;
}

inline std::vector<int> Plane(const Mesh& m, int d, double value) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  p[d] = value;
  return VerticesOnPlane(m, p, Eigen::Vector3d::Unit(d), 1e-9 * m.size());
}

/// Sum of the rest-normalised volume of the elements with region `region` at positions X.
inline double RegionVolumeRatio(const Mesh& m, const Eigen::MatrixX3d& X, int region) {
  double v = 0, v0 = 0;
  for (const auto& e : m.elements)
    if (e.region == region) {
      v += SignedVolume(e, X);
      v0 += SignedVolume(e, m.vertices);
    }
  return v / v0;
}

inline Material Rigid(double weight = 1.0) { return Material{"arap", 1.0, weight}; }

/// 10 x 4 x 4 bar of unit cubes, x = 0 face fixed. Region 1 (a pneumatic chamber, weight 5) is the
/// quadrant y >= 2, z >= 2 for x >= 1, so inflating it bends the bar towards -y and -z.
inline Scene QuadrantChamberBar() {
  return test::VoxelScene(
      {10, 4, 4}, 1.0,
      [](const Eigen::Vector3i& c) { return (c.x() >= 1 && c.y() >= 2 && c.z() >= 2) ? 1 : 0; },
      {{0, Rigid()}}, {test::Pneumatic("p", {1})}, "quadrant_chamber_bar");
}

/// Expects s.validate() to throw std::invalid_argument whose message contains `fragment`.
inline void ExpectValidateRejects(const Scene& s, const std::string& fragment) {
  try {
    s.validate();
    ADD_FAILURE() << "accepted; expected an error containing '" << fragment << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

}  // namespace constraints_test
}  // namespace softkin
