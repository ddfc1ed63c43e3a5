#pragma once
/// \file mesh_io_gmsh_binary.hpp
/// Private: the binary Gmsh 4.1 reader's entry point (mesh_io_gmsh_binary.cpp), called by ReadGmsh
/// once it has read a "4.1 1 <data-size>" format line (not public API).
#include "softkin/solver/mesh/io/mesh_io_detail.hpp"

namespace softkin {
namespace detail {

/// What the binary body holds: the mesh (tets and prisms, by their corners), where each element
/// and vertex was found (byte offsets) and how many higher-order elements were read.
struct GmshBody {
  Mesh mesh;
  MeshOrigin origin;
  int higher_order = 0;
};

/// Reads the rest of a binary .msh 4.1 file from the line after its format line; `data_size` is
/// the format line's size_t width (4 or 8).
void ReadGmshBinaryBody(Scanner& s, int data_size, GmshBody* out);

}  // namespace detail
}  // namespace softkin
