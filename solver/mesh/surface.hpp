#pragma once
/// \file surface.hpp
/// Closed triangle surfaces: obstacles of a scene and the inputs of tessellation (S_c, S_b). The
/// readers (OBJ, STL), the closed-surface check and two generated shapes (box, cylinder).
#include <Eigen/Core>

#include <string>

namespace softkin {

/// A triangle surface: #V x 3 vertices (mm), #F x 3 vertex indices (counter-clockwise seen from
/// outside), and where it came from (for messages).
struct TriangleSurface {
  Eigen::MatrixX3d vertices;
  Eigen::MatrixX3i faces;
  std::string source;
};

/// Reads an obstacle surface from Wavefront OBJ (`v` and `f` lines; polygons are split into
/// fans; `f 1/2/3` forms and negative indices accepted; other lines ignored) or STL (ASCII or
/// binary; duplicate corner points are merged exactly), by extension (.obj, .stl). Then checks it
/// with CheckClosedSurface. Throws std::invalid_argument naming the file (and line, for text
/// formats) and what was expected.
TriangleSurface ReadSurfaceMesh(const std::string& path);

/// Checks a surface for use as an obstacle: finite coordinates, indices in range, no degenerate
/// triangle, every edge shared by exactly two triangles with opposite directions (closed and
/// consistently oriented), and positive enclosed volume (outward normals; an inside-out surface
/// is flipped). Throws std::invalid_argument naming `s.source` and the first offending element.
void CheckClosedSurface(TriangleSurface* s);

/// An axis-aligned box obstacle [lo, hi] (12 triangles).
TriangleSurface MakeBoxSurface(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);
/// A closed cylinder obstacle: axis from `base` along unit `axis` for `height`, with `segments`
/// sides (>= 3).
TriangleSurface MakeCylinderSurface(const Eigen::Vector3d& base, const Eigen::Vector3d& axis,
                                    double radius, double height, int segments = 48);

}  // namespace softkin
