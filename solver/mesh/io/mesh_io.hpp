#pragma once
/// \file mesh_io.hpp
/// Mesh readers and writers. Every reader validates and orients the mesh (ValidateAndOrient) and
/// throws std::runtime_error("<file>:<line>: <what was wrong>; expected <what>") on bad input:
/// truncated files, indices out of range, NaN/Inf, degenerate elements, unknown element types.
#include "softkin/solver/mesh/mesh.hpp"

#include <iosfwd>
#include <string>
#include <vector>

namespace softkin {

/// The thesis group's `.tet` format ("N vertices", "M tets", N lines "x y z", M lines "4 a b c d",
/// 0-based). A file that looks 1-based (no tet uses vertex 0, and a tet uses vertex N, or the
/// tets only form a clean mesh when read 1-based) is refused with an error that says so.
/// If `labels_path` is non-empty it holds one integer per tet (region tag).
Mesh ReadTet(const std::string& path, const std::string& labels_path = "",
             MeshReport* report = nullptr);
void WriteTet(const std::string& path, const Mesh& mesh, const std::string& labels_path = "");

/// TetGen `.node` + `.ele` (`base` without extension), 4 or 10 (tetgen -o2, read by the corners)
/// nodes per tet. The first element attribute is the region.
Mesh ReadTetGen(const std::string& base, MeshReport* report = nullptr);
void WriteTetGen(const std::string& base, const Mesh& mesh);

/// Gmsh `.msh` 2.2 (ASCII) and 4.1 (ASCII or binary, either byte order): tetrahedra (type 4) and
/// prisms (type 6), and higher-order ones (11, 29-31; 13, 18) read by their corner nodes; the
/// physical group is the region tag. Lower-dimensional elements are skipped.
Mesh ReadGmsh(const std::string& path, MeshReport* report = nullptr);
/// Writes Gmsh 2.2 ASCII (version 2.2 or 4.1 accepted as `version`).
void WriteGmsh(const std::string& path, const Mesh& mesh, const std::string& version = "2.2");

/// Legacy VTK unstructured grid, ASCII or BINARY (big-endian, as VTK and meshio write it): cell
/// types 10 tet, 13 wedge, 24 quadratic tet and 26 quadratic wedge (read by their corners);
/// the region is the cell-data array named `tag_array` (or, if empty, the first integer
/// cell-data array, else the first one with a tag-like name and integer values).
Mesh ReadVtk(const std::string& path, const std::string& tag_array = "",
             MeshReport* report = nullptr);
void WriteVtk(const std::string& path, const Mesh& mesh);

/// VTK XML UnstructuredGrid `.vtu` (one Piece): DataArrays in ascii, inline base64 `binary` or
/// raw appended format, either byte order, UInt32 or UInt64 headers; compressed files are
/// refused. Cell types and the region array as for ReadVtk. WriteVtu's output reads back as the
/// mesh at the positions it was written at (its Points; the displacement array is not used).
Mesh ReadVtu(const std::string& path, const std::string& tag_array = "",
             MeshReport* report = nullptr);

/// Prints a reader's notes and warnings as "softkin: note: ..." / "softkin: warning: ..." lines
/// (what every reader does when it is given no MeshReport).
void PrintMeshReport(const MeshReport& report, std::ostream& os);

/// Picks the reader by extension: .tet, .node/.ele, .msh, .vtk, .vtu.
Mesh ReadMesh(const std::string& path, MeshReport* report = nullptr);

/// The outcome of the solve that produced a `.vtu`, written as its field data (ParaView: the
/// Information panel; VTK / meshio: field data), so that a frame of a failed solve says so.
struct VtuSolveInfo {
  bool converged = false;
  int iterations = 0;
  double residual_ratio = 0.0;  ///< FkResult::gradient_ratio
  int inverted_elements = 0;
};

/// ParaView `.vtu` (ASCII XML) of the mesh at positions X (#V x 3): the points are the deformed
/// positions; point data "displacement" is X - rest (so ParaView's Warp By Vector would move them
/// twice: colour by it, or warp the rest mesh); cell data "region", "element_type" (VTK type id)
/// and "strain" (||F^T F - I||_F / 2 of the best-fit deformation gradient; -1 where it is
/// undefined: a degenerate rest shape, or a deformation too large for double precision — never
/// NaN). `rest_regions` / `rest_positions` (#V x 3): elements of those regions measure their
/// strain from rest_positions instead of mesh.vertices (a Scene's region_rest, e.g. a remeshed
/// chamber). `info`: the solve's outcome as field data "converged", "iterations",
/// "residual_ratio" and "inverted_elements".
void WriteVtu(const std::string& path, const Mesh& mesh,
              const Eigen::Ref<const Eigen::MatrixX3d>& X,
              const std::vector<int>& rest_regions = {},
              const Eigen::MatrixX3d* rest_positions = nullptr, const VtuSolveInfo* info = nullptr);
/// `.pvd` collection listing (time, file) pairs, files relative to the pvd's folder.
void WritePvd(const std::string& path, const std::vector<std::pair<double, std::string>>& steps);
/// Boundary surface (faces used by one element) as Wavefront `.obj` at positions X.
void WriteSurfaceObj(const std::string& path, const Mesh& mesh,
                     const Eigen::Ref<const Eigen::MatrixX3d>& X);

/// Per-element strain measure used by WriteVtu (#E values; NaN for an element whose rest shape is
/// degenerate). Elements of `rest_regions` take their rest shapes from `rest_positions` (#V x 3).
std::vector<double> ElementStrain(const Mesh& mesh, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                                  const std::vector<int>& rest_regions = {},
                                  const Eigen::MatrixX3d* rest_positions = nullptr);

}  // namespace softkin
