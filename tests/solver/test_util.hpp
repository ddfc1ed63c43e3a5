#pragma once
/// \file test_util.hpp
/// Small helpers shared by the energy and local-global tests: scene builders (voxel bars with
/// chosen regions and materials, a hand-built prism slab), random rotations and matrix comparisons
/// that report the first failing (row, col) entry.
#include "softkin/solver/mesh/mesh_gen.hpp"
#include "softkin/solver/scene/scene.hpp"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace softkin {
namespace test {

/// Region tag of voxel cell (i, j, k); negative leaves the cell empty.
using CellRegionFn = std::function<int(const Eigen::Vector3i& cell)>;

/// A pneumatic actuator on `regions`.
inline Actuator Pneumatic(const std::string& name, std::vector<int> regions, double weight = 5.0,
                          double min = 1.0, double max = 3.0) {
  Actuator a;
  a.name = name;
  a.type = ActuatorType::Pneumatic;
  a.regions = std::move(regions);
  a.min = min;
  a.max = max;
  a.rest = 1.0;
  a.weight = weight;
  return a;
}

/// A cable actuator on `regions` along `path`, shortening ratio in [min, max], rest 1.
inline Actuator Cable(const std::string& name, std::vector<int> regions,
                      std::vector<Eigen::Vector3d> path, double min = 0.3, double max = 1.0) {
  Actuator a;
  a.name = name;
  a.type = ActuatorType::Cable;
  a.regions = std::move(regions);
  a.path = std::move(path);
  a.min = min;
  a.max = max;
  a.rest = 1.0;
  return a;
}

/// A DEA actuator on `regions` (prism elements), area ratio in [min, max], rest 1.
inline Actuator Dea(const std::string& name, std::vector<int> regions, double min = 0.5,
                    double max = 2.0) {
  Actuator a;
  a.name = name;
  a.type = ActuatorType::Dea;
  a.regions = std::move(regions);
  a.min = min;
  a.max = max;
  a.rest = 1.0;
  return a;
}

/// Fills in the common parts of a test scene: x = 0 face fixed, markers "tip" (the x = xmax face)
/// and "all" (every vertex), then validates.
inline void FinishScene(Scene* s) {
  const Mesh& m = s->mesh;
  const double xmin = m.vertices.col(0).minCoeff(), xmax = m.vertices.col(0).maxCoeff();
  const double eps = 1e-9 * m.size();
  s->fixed = VerticesOnPlane(m, Eigen::Vector3d(xmin, 0, 0), Eigen::Vector3d::UnitX(), eps);
  s->markers.clear();
  s->markers.push_back(
      {"tip", VerticesOnPlane(m, Eigen::Vector3d(xmax, 0, 0), Eigen::Vector3d::UnitX(), eps)});
  std::vector<int> all(m.num_vertices());
  for (int i = 0; i < m.num_vertices(); ++i) all[i] = i;
  s->markers.push_back({"all", all});
  s->validate();
}

/// Voxel bar of cells[0] x cells[1] x cells[2] cubes of edge h (origin 0), tets tagged by
/// `region`, with the given body materials and actuators; x = 0 face fixed.
inline Scene VoxelScene(const Eigen::Vector3i& cells, double h, const CellRegionFn& region,
                        const std::map<int, Material>& body, const std::vector<Actuator>& acts,
                        const std::string& name = "voxel_test") {
  Scene s;
  s.name = name;
  s.mesh = VoxelTetMesh(
      Eigen::Vector3d::Zero(), h, cells,
      [&region](const Eigen::Vector3d&, const Eigen::Vector3i& c) { return region(c); });
  s.body = body;
  s.actuators = acts;
  FinishScene(&s);
  return s;
}

/// Prism slab: an nx x ny grid of squares of edge h, each split into two counter-clockwise
/// triangles (seen from +z), extruded into `layers` layers of thickness h. Prisms are positively
/// oriented (bottom normal towards the top). region(i, j, layer) gives the tag of both prisms of a
/// square.
inline Mesh PrismSlab(int nx, int ny, int layers, double h,
                      const std::function<int(int, int, int)>& region) {
  Mesh m;
  const int vx = nx + 1, vy = ny + 1;
  auto vid = [&](int i, int j, int l) { return i + vx * (j + vy * l); };
  m.vertices.resize(vx * vy * (layers + 1), 3);
  for (int l = 0; l <= layers; ++l)
    for (int j = 0; j < vy; ++j)
      for (int i = 0; i < vx; ++i) m.vertices.row(vid(i, j, l)) = h * Eigen::RowVector3d(i, j, l);
  for (int l = 0; l < layers; ++l)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const int tris[2][3] = {{vid(i, j, l), vid(i + 1, j, l), vid(i + 1, j + 1, l)},
                                {vid(i, j, l), vid(i + 1, j + 1, l), vid(i, j + 1, l)}};
        const int up = vx * vy;
        for (const auto& t : tris) {
          Element e;
          e.type = ElementType::Prism;
          e.v = {{t[0], t[1], t[2], t[0] + up, t[1] + up, t[2] + up}};
          e.region = region(i, j, l);
          m.elements.push_back(e);
        }
      }
  return m;
}

/// Uniformly distributed random rotation (normalised Gaussian quaternion).
inline Eigen::Matrix3d RandomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return q.toRotationMatrix();
}

/// Matrix with entries uniform in [-1, 1].
inline Eigen::MatrixXd RandomMatrix(std::mt19937& rng, int rows, int cols) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd M(rows, cols);
  for (int j = 0; j < cols; ++j)
    for (int i = 0; i < rows; ++i) M(i, j) = u(rng);
  return M;
}

/// |a(i,j) - b(i,j)| <= tol for all entries; on failure names the worst (i, j) and both values.
inline ::testing::AssertionResult MatrixNear(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b,
                                             double tol) {
  if (a.rows() != b.rows() || a.cols() != b.cols())
    return ::testing::AssertionFailure() << "size mismatch: " << a.rows() << "x" << a.cols()
                                         << " vs " << b.rows() << "x" << b.cols();
  double worst = -1.0;
  Eigen::Index wi = 0, wj = 0;
  int bad = 0;
  for (Eigen::Index j = 0; j < a.cols(); ++j)
    for (Eigen::Index i = 0; i < a.rows(); ++i) {
      const double d = std::abs(a(i, j) - b(i, j));
      const bool fail = !(d <= tol);  // NaN fails
      if (fail) ++bad;
      if (fail && (worst < 0 || !(d <= worst))) {
        worst = d;
        wi = i;
        wj = j;
      }
    }
  if (bad == 0) return ::testing::AssertionSuccess();
  std::ostringstream os;
  os.precision(17);
  os << bad << " entr" << (bad == 1 ? "y" : "ies") << " differ by more than " << tol
     << "; worst at (" << wi << ", " << wj << "): " << a(wi, wj) << " vs " << b(wi, wj) << " (diff "
     << worst << ")";
  return ::testing::AssertionFailure() << os.str();
}

/// Component-wise relative comparison: |a - b| <= rel * max(|b(i,j)|, floor * max|b|). Reports
/// the worst (i, j). `max_rel` (optional) receives the largest relative error found.
inline ::testing::AssertionResult MatrixRelNear(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b,
                                                double rel, double floor,
                                                double* max_rel = nullptr) {
  if (a.rows() != b.rows() || a.cols() != b.cols())
    return ::testing::AssertionFailure() << "size mismatch";
  const double bmax = b.cwiseAbs().maxCoeff();
  double worst = -1.0;
  Eigen::Index wi = 0, wj = 0;
  for (Eigen::Index j = 0; j < a.cols(); ++j)
    for (Eigen::Index i = 0; i < a.rows(); ++i) {
      const double den = std::max(std::abs(b(i, j)), floor * bmax);
      double r = std::abs(a(i, j) - b(i, j)) / (den > 0 ? den : 1.0);
      if (!std::isfinite(r)) r = std::numeric_limits<double>::infinity();
      if (r > worst) {
        worst = r;
        wi = i;
        wj = j;
      }
    }
  if (max_rel) *max_rel = worst;
  if (worst <= rel) return ::testing::AssertionSuccess();
  std::ostringstream os;
  os.precision(17);
  os << "relative error " << worst << " > " << rel << " at (" << wi << ", " << wj
     << "): " << a(wi, wj) << " vs " << b(wi, wj);
  return ::testing::AssertionFailure() << os.str();
}

/// Radius of curvature (inverse) of the circle through three points: 4 * area / (|ab| |bc| |ca|).
inline double Curvature3(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                         const Eigen::Vector3d& c) {
  const double area2 = (b - a).cross(c - a).norm();  // twice the triangle area
  return 2.0 * area2 / ((b - a).norm() * (c - b).norm() * (a - c).norm());
}

}  // namespace test
}  // namespace softkin
