#pragma once
/// \file mesh_gen.hpp
/// Structured tetrahedral mesh generators used by the embedded robots (solver/robots/):
///  - VoxelTetMesh: cubic cells on a regular grid, each kept cell split into 6 tets (Kuhn split);
///  - MakeConcentricDisk + ExtrudedDiskTetMesh: a disk triangulated in concentric rings, exactly
///    invariant under rotation by 120 degrees, extruded into layers of prisms split into 3 tets.
/// Both produce conforming meshes (every interior triangle is shared by exactly two tets), with all
/// tets positively oriented (mesh.hpp) and no unused vertices. Units are millimetres.
#include "softkin/solver/mesh/mesh.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <functional>
#include <vector>

namespace softkin {

// ------------------------------------------------------------------------------------------------
// Voxel grid
// ------------------------------------------------------------------------------------------------

/// Classifies one grid cell. Arguments: the cell centre (3-vector, mm) and its integer index
/// (i, j, k), 0 <= i < cells[0] etc. Returns the region tag of the cell's six tets (>= 0), or any
/// negative value to leave the cell empty.
using VoxelClassifier =
    std::function<int(const Eigen::Vector3d& centre, const Eigen::Vector3i& cell)>;

/// Regular grid of cubic cells of edge `h` (mm) covering the box
/// [origin, origin + h * cells] (cells = number of cells along x, y, z; each >= 1).
/// Every cell for which `classify` returns a tag >= 0 is split into 6 tets by the Kuhn
/// (Freudenthal) split, mirrored in each axis whose cell index is odd (so the mesh keeps the
/// grid's reflection symmetries): all 6 tets share the cell's main diagonal (for an unmirrored
/// cell from corner (0,0,0) to (1,1,1)),
/// and each follows one monotone path (0,0,0) -> +e_a -> +e_a+e_b -> (1,1,1) over the 6 axis
/// orders (a, b, c). The same split in every cell makes shared faces match, so the mesh is
/// conforming. Grid vertices not used by any kept cell are removed and the remaining ones are
/// numbered in grid order (x fastest, then y, then z), so the result is deterministic.
/// Output: #V x 3 vertex positions (mm; vertex (i,j,k) at origin + h * (i,j,k)) and
/// 6 * (#kept cells) tets, cell by cell in grid order, all positively oriented.
/// Throws std::invalid_argument if h <= 0 or any cell count < 1.
Mesh VoxelTetMesh(const Eigen::Vector3d& origin, double h, const Eigen::Vector3i& cells,
                  const VoxelClassifier& classify);

/// VoxelTetMesh made mirror-symmetric about the box's mid-plane normal to each axis d with
/// `even[d]`. The mirrored split is symmetric about a mid-plane only over an even count of cells
/// across it; over an odd count every tet leans the same way and a symmetric design bends out of
/// its plane. So an odd cells[d] is cut into cells[d] + 1 cells of equal size over the same length
/// h * cells[d] (non-cubic cells). Each new cell takes the tag of the original cell that holds its
/// centre: `classify` is called with that original cell's centre and index, so a classifier
/// symmetric in the original cells stays symmetric, and the box does not change; a feature's
/// width changes by less than one cell (a wall of one cell of 5 becomes one of 6 equal cells, the
/// middle cell becomes two). An even count is left as it is.
Mesh SymmetricVoxelTetMesh(const Eigen::Vector3d& origin, double h, const Eigen::Vector3i& cells,
                           const std::array<bool, 3>& even, const VoxelClassifier& classify);

/// The same split on a rectilinear grid: cell (i, j, k) spans [xs[i], xs[i+1]] x [ys[j], ys[j+1]]
/// x [zs[k], zs[k+1]], so grid lines can sit on a design's dimensions (walls, layers) whatever
/// the cell size; `classify` gets the cell's centre and index. Each axis needs at least 2
/// strictly increasing finite lines (std::invalid_argument otherwise). VoxelTetMesh is this grid
/// with equally spaced lines.
Mesh RectilinearTetMesh(const std::vector<double>& xs, const std::vector<double>& ys,
                        const std::vector<double>& zs, const VoxelClassifier& classify);

// ------------------------------------------------------------------------------------------------
// Prism grid (thin shells and membranes)
// ------------------------------------------------------------------------------------------------

/// Classifies one prism cell: its centre (mm) and index (i, j, layer). Returns the region tag of
/// the cell's two prisms (>= 0), or a negative value to leave it empty.
using PrismClassifier =
    std::function<int(const Eigen::Vector3d& centre, const Eigen::Vector3i& cell)>;

/// A grid of cx x cy rectangular cells of size hx x hy (mm) in the x-y plane, from `origin`,
/// extruded between the increasing z levels `z` (layer l spans z[l] .. z[l+1]; z.size() >= 2).
/// Each kept cell is split into two triangles and extruded into two prisms (bottom triangle
/// v[0..2] counter-clockwise seen from +z, top copy v[3..5]: positively oriented). The diagonal
/// alternates with the parity of i + j (from (i, j) to (i+1, j+1) when even, else the other one),
/// so the triangulation is symmetric under reflection about any grid line. Unused grid vertices
/// are removed; vertices are numbered in grid order (x fastest, then y, then level).
/// Throws std::invalid_argument on bad sizes or non-increasing levels.
Mesh PrismGridMesh(const Eigen::Vector3d& origin, double hx, double hy,
                   const Eigen::Vector2i& cells, const std::vector<double>& z,
                   const PrismClassifier& classify);

// ------------------------------------------------------------------------------------------------
// Concentric-ring disk and its extrusion
// ------------------------------------------------------------------------------------------------

/// A disk triangulated in concentric rings: ring 0 is the centre point, ring j (1 <= j <= rings)
/// has 6j points at radius radius * j / rings and angles 2*pi*i / (6j), i = 0 .. 6j-1, measured
/// from the first in-plane axis towards the second. Point i of ring j owns the angles
/// (i -+ 1/2) / (6j) turns; consecutive rings are joined where those intervals overlap (exact
/// integer comparison, never a tie), giving 6 * (2j - 1) triangles between rings j-1 and j and
/// 6 * rings^2 triangles in all. The rule depends only on angles, so the triangle set is mapped
/// exactly onto itself by rotation by 120 degrees, point (j, i) -> (j, i + 2j mod 6j), and by the
/// reflection across the first in-plane axis, (j, i) -> (j, -i mod 6j): the dihedral symmetry of
/// three chambers on the axes 0, 120 and 240 degrees (or 60, 180 and 300).
struct ConcentricDisk {
  double radius = 0.0;  ///< mm
  int rings = 0;
  Eigen::MatrixX2d points;                    ///< #P x 2 in-plane positions, mm; #P = 1 + 3 r (r+1)
  std::vector<int> ring;                      ///< #P: ring index j of each point (0 = centre)
  std::vector<int> index;                     ///< #P: angular index i in [0, 6j) (0 for the centre)
  std::vector<std::array<int, 3>> triangles;  ///< #T point triples, counter-clockwise

  int num_points() const { return static_cast<int>(ring.size()); }
  /// Point id of ring j, angular index i (taken modulo 6j); the centre is (0, 0).
  int id(int j, int i) const;
  /// Sector s in {0, 1, 2} of a non-centre point: i / (2j). The centre has sector 0.
  int sector(int p) const;
  /// Ordering key invariant under the 120-degree rotation and the reflection: ring * (2*rings + 1)
  /// + min(u, 2j - u) with u = i mod 2j. Distinct for the vertices of any one triangle.
  long key(int p) const;
  /// Point id of the image of point p under rotation by s * 120 degrees (s may be negative).
  int rotated(int p, int s) const;
};

/// Builds the concentric-ring disk of radius `radius` (mm, > 0) with `rings` rings (>= 1). The
/// points of sector 0 (0 <= i < 2j) are computed with cos/sin; sectors 1 and 2 are the sector-0
/// points rotated by the fixed 120-degree rotation matrix, so the 3-fold symmetry holds to
/// rounding (~1e-15 relative). Throws std::invalid_argument on bad arguments.
ConcentricDisk MakeConcentricDisk(double radius, int rings);

/// Parameters of ExtrudedDiskTetMesh.
struct DiskExtrusion {
  double radius = 1.0;  ///< disk radius, mm
  int rings = 4;        ///< number of rings (>= 1)
  double length = 1.0;  ///< extent along the axis, mm
  int layers = 4;       ///< number of prism layers along the axis (>= 1)
  /// Extrusion axis (0 = x, 1 = y, 2 = z). The disk lies in the other two coordinates taken in
  /// increasing order (axis 1: the x-z plane, angles measured from +x towards +z).
  int axis = 2;
  double base = 0.0;  ///< axis coordinate of the bottom face, mm (top = base + length)
};

/// What the region callback of ExtrudedDiskTetMesh sees for one tet.
struct DiskElementInfo {
  Eigen::Vector3d centroid;  ///< the tet's centroid, mm (world coordinates)
  /// Centroid of the canonical copy of this tet: the tet rotated by -sector * 120 degrees, computed
  /// from the canonical vertices' stored positions, hence bit-identical for the three rotated
  /// copies of a tet. Classify on it to get exactly 3-fold symmetric region tags.
  Eigen::Vector3d canonical_centroid;
  int sector = 0;  ///< this tet = canonical tet rotated by sector * 120 degrees
};

/// Region callback: returns the region tag (>= 0) of one tet.
using DiskRegionFn = std::function<int(const DiskElementInfo&)>;

/// Extrudes MakeConcentricDisk(radius, rings) along `axis` into `layers` equal layers of prisms
/// and splits each prism into 3 tets with a rule that is conforming and as symmetric as the disk:
/// the triangle's vertices are ordered a < b < c by ConcentricDisk::key (invariant under the
/// rotation and the reflection), every vertical quad face gets the diagonal from the lower-key
/// vertex's bottom copy to the higher-key vertex's top copy (a property of the edge alone, so
/// both prisms sharing a face agree), and the tets are (a_b,b_b,c_b,c_t), (a_b,b_b,b_t,c_t),
/// (a_b,a_t,b_t,c_t) (b = bottom, t = top), flipped where needed to be positively oriented.
/// Output: #V = (layers+1) * #P vertices (mm; vertex id = layer * #P + disk point id) and
/// 18 * rings^2 * layers tets with regions from `region` (a null function tags everything 0).
/// Rotation by 120 degrees about the axis and the reflection across the first in-plane axis map
/// vertices and tets onto themselves. Throws std::invalid_argument on bad parameters or a negative
/// region tag.
Mesh ExtrudedDiskTetMesh(const DiskExtrusion& params, const DiskRegionFn& region = nullptr);

/// In-plane axes (first, second) used for `axis` by ExtrudedDiskTetMesh: axis 0 -> (1, 2),
/// axis 1 -> (0, 2), axis 2 -> (0, 1).
std::array<int, 2> DiskPlaneAxes(int axis);

}  // namespace softkin
