#pragma once
/// \file element_faces.hpp
/// The faces of tet and prism elements: their local corner lists (outward normals on a positively
/// oriented element, mesh.hpp), and every face of a mesh sorted by its vertex set, so that the
/// faces two elements share sit side by side. The topology checks (mesh_topology.cpp: folds) and
/// the boundary surface writer (WriteSurfaceObj: faces that occur once) both read them here.
#include "softkin/solver/mesh/mesh.hpp"

#include <array>
#include <vector>

namespace softkin {

/// Corners of one face, in the order whose right-hand normal points out of the element; d = -1 for
/// a triangle.
struct LocalFace {
  int a, b, c, d;
};
inline constexpr LocalFace kTetFaces[4] = {
    {0, 2, 1, -1}, {0, 1, 3, -1}, {1, 2, 3, -1}, {0, 3, 2, -1}};
inline constexpr LocalFace kPrismFaces[5] = {
    {0, 2, 1, -1}, {3, 4, 5, -1}, {0, 1, 4, 3}, {1, 2, 5, 4}, {2, 0, 3, 5}};

/// The local faces of an element of type t (4 for a tet, 5 for a prism) into *count.
const LocalFace* LocalFaces(ElementType t, int* count);

/// One face of one element.
struct MeshFace {
  std::array<int, 4> key;  ///< its vertices sorted (INT_MAX pads a triangle)
  int element;             ///< the element it belongs to
  int local;               ///< its index in LocalFaces(element type)
  /// Which way its cycle turns: true when, from its smallest vertex, the next vertex is smaller
  /// than the previous one. Two faces with the same key and the same turn are oriented alike, so
  /// two elements on the same side of their shared face (a fold) give equal turns.
  bool turn;
};

/// Every face of every element, sorted by (key, element): a face shared by two elements appears
/// twice in a row, a boundary face once.
std::vector<MeshFace> SortedMeshFaces(const Mesh& mesh);

/// The vertices on the mesh's outer surface (of faces that belong to one element), sorted.
std::vector<int> BoundaryVertices(const Mesh& mesh);

}  // namespace softkin
