#pragma once
/// \file mesh_io_gmsh_types.hpp
/// Private: Gmsh element types (node count, dimension, name) shared by the ASCII and binary .msh
/// readers (not public API).

namespace softkin {
namespace detail {

struct GmshType {
  int nodes = 0;  ///< 0: unknown type
  int dim = 0;
  const char* name = "";
};

inline GmshType LookupGmshType(long long t) {
  switch (t) {
    case 1:
      return {2, 1, "2-node line"};
    case 2:
      return {3, 2, "3-node triangle"};
    case 3:
      return {4, 2, "4-node quadrangle"};
    case 4:
      return {4, 3, "4-node tetrahedron"};
    case 5:
      return {8, 3, "8-node hexahedron"};
    case 6:
      return {6, 3, "6-node prism"};
    case 7:
      return {5, 3, "5-node pyramid"};
    case 8:
      return {3, 1, "3-node line"};
    case 9:
      return {6, 2, "6-node triangle"};
    case 10:
      return {9, 2, "9-node quadrangle"};
    case 11:
      return {10, 3, "10-node tetrahedron"};
    case 12:
      return {27, 3, "27-node hexahedron"};
    case 13:
      return {18, 3, "18-node prism"};
    case 14:
      return {14, 3, "14-node pyramid"};
    case 15:
      return {1, 0, "1-node point"};
    case 16:
      return {8, 2, "8-node quadrangle"};
    case 17:
      return {20, 3, "20-node hexahedron"};
    case 18:
      return {15, 3, "15-node prism"};
    case 19:
      return {13, 3, "13-node pyramid"};
    case 20:
      return {9, 2, "9-node triangle"};
    case 21:
      return {10, 2, "10-node triangle"};
    case 22:
      return {12, 2, "12-node triangle"};
    case 23:
      return {15, 2, "15-node triangle"};
    case 24:
      return {15, 2, "15-node triangle"};
    case 25:
      return {21, 2, "21-node triangle"};
    case 26:
      return {4, 1, "4-node line"};
    case 27:
      return {5, 1, "5-node line"};
    case 28:
      return {6, 1, "6-node line"};
    case 29:
      return {20, 3, "20-node tetrahedron"};
    case 30:
      return {35, 3, "35-node tetrahedron"};
    case 31:
      return {56, 3, "56-node tetrahedron"};
    case 92:
      return {64, 3, "64-node hexahedron"};
    case 93:
      return {125, 3, "125-node hexahedron"};
    default:
      return {};
  }
}

/// Corner count (4 tet, 6 prism) of a kept Gmsh type: Gmsh lists an element's corner nodes first,
/// so a higher-order element is read as its linear one. 0 for other types.
inline int Corners(long long type) {
  switch (type) {
    case 4:
    case 11:
    case 29:
    case 30:
    case 31:
      return 4;
    case 6:
    case 13:
    case 18:
      return 6;
    default:
      return 0;
  }
}

}  // namespace detail
}  // namespace softkin
