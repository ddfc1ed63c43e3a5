#pragma once
/// \file tessellation.hpp
/// Volume tessellation T(S_c, S_b) of thesis Sec. 3.2.1 (Fig. 3.2) with CGAL Mesh_3, and the
/// re-tessellation of one region's interior used by the progressive remeshing of Algorithm 2
/// (remesh.hpp) with CGAL's tetrahedral remeshing.
///
/// T(S_c, S_b): two closed, outward-oriented triangle surfaces, the chamber S_c strictly inside
/// the body S_b, become one labelled tet mesh. The domain is a CGAL
/// Polyhedral_complex_mesh_domain_3 with two surface patches: S_b between the outside (subdomain 0)
/// and the body (1), S_c between the body (1) and the chamber (2). Mesh_3 meshes every patch once
/// and both incident subdomains use the same restricted-Delaunay facets, so the chamber-body
/// interface is conforming: every interface triangle is a face of exactly one body tet and one
/// chamber tet. Edges of the input surfaces whose dihedral angle exceeds `feature_angle` (a
/// cylinder's rims, a box's edges) are protected, so sharp edges and flat faces are reproduced.
/// Mesh_3 is randomised; the seed sets both the domain's random generator and CGAL's default one,
/// and the sliver perturbation and exudation run without a time limit, so the same input and
/// options give the same mesh. Units: millimetres throughout.
#include "softkin/solver/mesh/surface.hpp"
#include "softkin/solver/mesh/mesh.hpp"

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace softkin {

/// Sizing of T(S_c, S_b) (CGAL Mesh_3 criteria, all lengths in mm).
struct TessellationOptions {
  /// Largest tet: upper bound on a tet's circumradius (Mesh_3 cell_size), mm.
  double cell_size = 2.0;
  /// The same bound inside the chamber, mm; 0: cell_size. A smaller value gives a thin chamber
  /// interior vertices (otherwise its tets tend to span it from wall to wall).
  double chamber_cell_size = 0.0;
  /// Upper bound on the radius of a surface facet's surface Delaunay ball (facet_size), mm;
  /// 0: cell_size. Also the size of the segments of protected sharp edges.
  double facet_size = 0.0;
  /// Largest distance between a facet's circumcentre and the input surface (facet_distance), mm;
  /// 0: cell_size / 10. Smaller values refine curved parts (a thin tube) more.
  double facet_distance = 0.0;
  /// Smallest angle of a surface facet, degrees (facet_angle; Mesh_3 terminates for <= 30).
  double facet_angle = 25.0;
  /// Largest circumradius / shortest edge of a tet (cell_radius_edge_ratio; >= 2).
  double radius_edge_ratio = 3.0;
  /// Input edges whose two triangles' normals differ by more than this angle (degrees) are
  /// protected as sharp features; 0 disables feature protection.
  double feature_angle = 60.0;
  /// Run Mesh_3's sliver perturbation / exudation after refinement, both with no time limit
  /// (make_mesh_3's default limit, the refinement's own duration, makes them stop at a point that
  /// depends on the machine's speed: the mesh would not be reproducible). Perturbation is off by
  /// default: without a limit it is slow (24 s instead of 0.3 s for the twisting robot at res 1).
  bool perturb = false;
  bool exude = true;
  /// Seed of Mesh_3's random choices.
  unsigned seed = 1;
  /// Region tags of the output mesh.
  int body_region = 0;
  int chamber_region = 1;

  /// False with the reason (naming the field and what was expected) if an option is invalid.
  bool IsValid(std::string* why) const;
};

/// What T(S_c, S_b) produced and how long it took.
struct TessellationReport {
  int vertices = 0, tets = 0, body_tets = 0, chamber_tets = 0;
  double body_volume = 0, chamber_volume = 0;  ///< sums of the tets' volumes, mm^3
  double body_enclosed = 0,
         chamber_enclosed = 0;  ///< volumes enclosed by the inputs: |S_b| - |S_c| and |S_c|, mm^3
  double seconds = 0;           ///< wall time of the whole call, s
};

/// Volume enclosed by a closed triangle surface (divergence theorem; positive when the faces are
/// counter-clockwise seen from outside), mm^3.
double EnclosedVolume(const TriangleSurface& s);

/// Checks two surfaces for T(S_c, S_b): each closed, consistently oriented, finite and free of
/// self-intersections (inside-out surfaces are flipped, see CheckClosedSurface), and the chamber
/// strictly inside the body (no intersection of the two surfaces, every chamber vertex inside the
/// body). Throws std::invalid_argument naming the surface's `source` and what was expected.
void CheckChamberInBody(TriangleSurface* chamber, TriangleSurface* body);

/// Roughly the number of tets Tessellate makes for these surfaces and sizes (within ~30 % on
/// boxes): 2.5 times the volumes over that of a regular tet of the cell size's circumradius, plus
/// one tet per surface facet. Tessellate refuses a mesh whose estimate, at
/// kTessellationBytesPerTet (Mesh_3's peak: ~0.55 KiB per tet measured), would not fit in memory.
double EstimateTessellationTets(const TriangleSurface& chamber, const TriangleSurface& body,
                                const TessellationOptions& options);
constexpr int kTessellationBytesPerTet = 1024;

/// T(S_c, S_b): the labelled tet mesh of the body S_b with the chamber S_c inside it.
/// chamber, body: closed triangle surfaces (#V x 3 mm, #F x 3 indices; checked with
/// CheckChamberInBody). Returns the tets of the body (tag options.body_region) and of the chamber
/// (tag options.chamber_region), positively oriented (mesh.hpp), vertices numbered in order of
/// first use, no unused vertices. Throws std::invalid_argument for bad surfaces or options and
/// std::runtime_error if Mesh_3 produces no tets of a region (e.g. sizes far larger than the
/// chamber); std::invalid_argument before meshing if the estimated mesh would not fit in memory
/// (CheckMemoryEstimate).
Mesh Tessellate(const TriangleSurface& chamber, const TriangleSurface& body,
                const TessellationOptions& options = {}, TessellationReport* report = nullptr);

/// Options of RemeshRegionInterior.
struct RegionRemeshOptions {
  /// Target edge length of the re-tessellated interior, mm; 0: the mean edge length of the
  /// region's boundary triangles at the given positions (the re-tessellation then matches the
  /// boundary's density).
  double target_edge = 0.0;
  /// Iterations of CGAL's tetrahedral isotropic remeshing (split, collapse, flip, smooth).
  int iterations = 3;
  /// Seed of CGAL's default random generator during remeshing.
  unsigned seed = 1;
  bool IsValid(std::string* why) const;
};

/// Result of RemeshRegionInterior.
struct RegionRemeshResult {
  /// The new mesh: vertices are positions (mm, the `X` given for kept vertices), the elements of
  /// the other regions first (the input's, in input order, renumbered), then the region's new tets.
  Mesh mesh;
  /// Per new vertex: the input vertex it is, or -1 for a vertex created inside the region.
  std::vector<int> old_index;
  int kept_vertices = 0, new_vertices = 0, removed_vertices = 0;
  int region_tets_before = 0, region_tets_after = 0;
  double target_edge = 0;  ///< the target edge length used, mm
  double seconds = 0;
};

/// Re-tessellates the interior of region `region` of a tet mesh at positions X (#V x 3, mm) with
/// CGAL::tetrahedral_isotropic_remeshing restricted to that region's cells, with every boundary
/// between regions (and the outer boundary) kept: the tets of all other regions and the region's
/// boundary triangles are unchanged, so the result is conforming to them exactly. Only vertices
/// strictly inside the region can move, disappear or appear. The tet soup is turned into a
/// CGAL triangulation (the outer boundary's facets are closed by infinite cells). Every element
/// of `mesh` must be a tet; the region's tets must be positively oriented at X (the others are
/// never examined or changed by the remesher, and may be inverted). Throws
/// std::invalid_argument for prisms, an unknown region, mismatched sizes, non-finite X or an
/// inverted tet of the region at X, and std::runtime_error if CGAL cannot build the
/// triangulation or the result is not conforming.
RegionRemeshResult RemeshRegionInterior(const Mesh& mesh,
                                        const Eigen::Ref<const Eigen::MatrixX3d>& X, int region,
                                        const RegionRemeshOptions& options = {});

/// Boundary triangles of the tets with region tag `region` (faces not shared by two of them), each
/// with sorted vertex ids. For checks of conformity.
std::vector<std::array<int, 3>> RegionBoundaryFaces(const Mesh& mesh, int region);

}  // namespace softkin
