#pragma once
/// \file remesh.hpp
/// Progressive chamber remeshing (thesis Sec. 3.3.2, Algorithm 2, Fig. 3.7): a large chamber
/// inflation is applied in steps alpha_k = k * alpha_max, and whenever a chamber element has grown
/// or distorted too much since the chamber was last meshed, the chamber's interior is
/// re-tessellated in its current (deformed) shape.
///
/// Two ways to re-tessellate (RemeshMethod; docs/remeshing.md):
///  - chamber-only (preferred): RemeshRegionInterior re-tessellates only the chamber's interior
///    with CGAL's tetrahedral remeshing; the body's tets, the chamber-body interface triangles
///    and every body vertex are kept exactly, so the body keeps its rest shape (its material
///    memory) and the new chamber mesh is conforming to it. CGAL needs a valid triangulation to
///    start from: inverted chamber tets are first untangled by moving the chamber's interior
///    vertices (their positions carry no physics: the chamber is the gas inside its boundary;
///    each violated "vertex above its opposite face" half-space is projected onto, repeatedly).
///    This fails when an inverted tet has all four vertices on the chamber's boundary.
///  - whole: the chamber tets of a solved state are often inverted (the chamber's elements follow
///    their current volume, Sec. 2.3.3, and thin slivers across a tube flip; the twisting robot
///    has 1 inverted chamber tet of 1,164 at alpha = 2 and 24 at alpha = 4), while its surface is
///    still valid. Then the whole robot is re-tessellated, T(S_c^k, S_b^k), from the deformed
///    chamber surface (the chamber's boundary triangles) and the deformed outer surface, and the
///    body's state is carried by interpolation: each new vertex inside the old body gets the rest
///    position given by its barycentric coordinates in the old deformed body tet containing it
///    (the inverse of the previous piecewise-linear deformation; where that makes a thin new tet's
///    rest shape inverted, its free vertices are moved above the planes of their opposite faces,
///    repeatedly, until no tet is inverted), each new body tet the region
///    (material) of the old tet containing its centroid. Vertices inside the new chamber are pulled
///    back the same way through the old chamber tets that are not inverted; those inside tangled
///    parts get rest positions by harmonic (graph-Laplacian) extension of their neighbours'. Fixed
///    vertices and markers are new vertices lying on the old ones' faces (the barycentric support
///    rule in RemeshChamber). The outer surface is re-sampled by Mesh_3: its enclosed volume and
///    its distance to the old one are reported (ChamberRemesh).
///  - auto: chamber-only when the chamber has no inverted tet at the positions after untangling
///    its interior vertices (and the chamber-only re-tessellation succeeds), else whole.
/// In both, the deformed positions are where the vertices are (kept, or created by CGAL in the
/// deformed shape). The chamber's rest shape after a remesh (ChamberRest):
///  - remeshed (default, Algorithm 2, line 11): the new chamber tets' shapes at the remesh, kept in
///    Scene::region_rest (the body tets sharing the interface vertices keep their rest positions in
///    mesh.vertices). The chamber's rest volume becomes its volume at the remesh, M_k, and
///    SolveProgressive asks for alpha V_c^0 / M_k of it, so alpha stays a ratio of the original
///    chamber volume V_c^0. The chamber's elements start well shaped, their targets are their
///    current shapes scaled, and their weights (w Vol) follow their volumes at the remesh.
///  - original: vertices created inside the old chamber get their rest positions pulled back
///    through the old chamber tets (then untangled where a thin new tet's pulled-back shape comes
///    out inverted), so the chamber's rest volume stays the original chamber's (exactly for
///    chamber-only; up to Mesh_3's re-sampling for whole). The new elements' targets then carry the
///    old mesh's deformation, which is what the thesis's remeshing is there to drop; kept for
///    comparison (exp fig3_7 `chamber_rest`).
/// mesh.vertices always holds the original frame: with "remeshed" the chamber-interior vertices'
/// pulled-back positions there are only a picture of the chamber in that frame (not used by the
/// Model, and not required to form valid tets).
/// The remeshing checks compare each chamber element with its shape when the chamber was last
/// meshed (the "reference" positions, = the deformed positions at the last remesh), which is the
/// reference Algorithm 2's tests use.
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/scene/scene.hpp"
#include "softkin/solver/remesh/tessellation.hpp"

#include <Eigen/Core>

#include <functional>
#include <string>
#include <vector>

namespace softkin {

/// Thresholds of Algorithm 2 (thesis Sec. 3.3.2: alpha_max = d_max = 4.0).
struct RemeshCriteria {
  /// Remesh when a chamber element's volume exceeds alpha_max times its reference volume.
  double alpha_max = 4.0;
  /// ... or its distortion exceeds d_max (TetChange).
  double d_max = 4.0;
  bool IsValid(std::string* why) const;
};

/// Change of one tet from a reference shape to its current shape.
struct TetChangeInfo {
  double volume_ratio = 1.0;  ///< Vol(current) / Vol(reference), signed (< 0: inverted)
  /// norm(Sigma): the largest singular value of the affine map between the two shapes in either
  /// direction, max(sigma_max(F), 1 / sigma_min(F)) with F = D P^-1 (D, P the 3 x 3 edge matrices
  /// [v1 - v0, v2 - v0, v3 - v0] of the current and reference shapes). The thesis takes the SVD of
  /// "the affine transformation from V^d to V", i.e. F^-1, whose largest singular value is
  /// 1 / sigma_min(F) (compression); including sigma_max(F) also catches a stretch. 1 for a rigid
  /// motion; cbrt(a) for a uniform expansion by volume ratio a >= 1. Infinite for a flat tet.
  double distortion = 1.0;
};

/// TetChange of tet rows (4 x 3 vertex positions, mm) `reference` -> `current`.
TetChangeInfo TetChange(const Eigen::Matrix<double, 4, 3>& reference,
                        const Eigen::Matrix<double, 4, 3>& current);

/// What CheckRemesh found over the chamber elements.
struct RemeshCheck {
  bool needed = false;          ///< any element past a threshold
  int checked = 0;              ///< chamber tets examined
  int over_volume = 0;          ///< of them, volume_ratio > alpha_max
  int over_distortion = 0;      ///< of them, distortion > d_max
  double max_volume_ratio = 0;  ///< largest volume_ratio
  double max_distortion = 0;    ///< largest distortion
  int worst_element = -1;       ///< the element with the largest distortion
};

/// Algorithm 2, lines 9-12: the chamber tets (region tag in `regions`) of `mesh` at positions
/// `current` against `reference` (both #V x 3, mm). Throws std::invalid_argument for mismatched
/// sizes or a chamber element that is not a tet.
RemeshCheck CheckRemesh(const Mesh& mesh, const Eigen::Ref<const Eigen::MatrixX3d>& reference,
                        const Eigen::Ref<const Eigen::MatrixX3d>& current,
                        const std::vector<int>& regions, const RemeshCriteria& criteria = {});
/// CheckRemesh(...).needed.
bool NeedsRemesh(const Mesh& mesh, const Eigen::Ref<const Eigen::MatrixX3d>& reference,
                 const Eigen::Ref<const Eigen::MatrixX3d>& current, const std::vector<int>& regions,
                 const RemeshCriteria& criteria = {});

/// The scene's pneumatic chamber actuator for remeshing: the index of its only element actuator,
/// which must be an unsigned pneumatic actuator on one region. Throws std::invalid_argument naming
/// the scene and what was expected otherwise (other actuators, signed, several regions).
int ChamberActuator(const Scene& scene);

/// How RemeshChamber re-tessellates (file comment).
enum class RemeshMethod { Auto, ChamberOnly, Whole };
/// "auto" / "chamber" / "whole".
const char* RemeshMethodToString(RemeshMethod m);
/// Parses the names of RemeshMethodToString; false if unknown.
bool RemeshMethodFromString(const std::string& s, RemeshMethod* m);

/// The rest shape a re-tessellated chamber takes (file comment).
enum class ChamberRest {
  /// Its shape when it was re-tessellated (Algorithm 2, line 11: M^k = M_b^k + T(S_c^k)), kept in
  /// Scene::region_rest: the new elements start well shaped and the actuation scales their
  /// current shapes, and the chamber's rest volume becomes its volume at the remesh.
  Remeshed,
  /// The original chamber's rest shape: created vertices' rest positions are pulled back through
  /// the previous deformation, so the rest volume stays the original chamber's.
  Original
};
/// "remeshed" / "original".
const char* ChamberRestToString(ChamberRest r);
/// Parses the names of ChamberRestToString; false if unknown.
bool ChamberRestFromString(const std::string& s, ChamberRest* r);

/// Options of RemeshChamber.
struct ChamberRemeshOptions {
  RemeshMethod method = RemeshMethod::Auto;
  ChamberRest rest = ChamberRest::Remeshed;
  /// The chamber-only re-tessellation.
  RegionRemeshOptions region;
  /// Sizing of the whole re-tessellation T(S_c^k, S_b^k). cell_size <= 0: derived from the
  /// deformed outer surface (facet_size = its mean edge length, cell_size twice that,
  /// facet_distance 0.05 cell_size). Its region tags are ignored (the scene's are used).
  TessellationOptions tessellation;
  bool IsValid(std::string* why) const;
};

/// Result of RemeshChamber.
struct ChamberRemesh {
  RemeshMethod method = RemeshMethod::ChamberOnly;  ///< the method used
  std::string reason;             ///< why auto chose the whole re-tessellation ("" otherwise)
  int inverted_chamber_tets = 0;  ///< at the input positions
  /// Chamber-only: vertex moves made to untangle the chamber at X before re-tessellating it (only
  /// vertices strictly inside the chamber move; see RemeshChamber).
  int untangled_chamber_vertices = 0;
  /// Rest positions of created vertices moved to untangle interpolated rest shapes that came out
  /// inverted (the vertex is moved above the planes of its tets' opposite faces, repeatedly).
  int untangled_vertices = 0;
  Scene scene;                 ///< the scene on the new mesh (rest positions as described above)
  Eigen::MatrixX3d positions;  ///< #V' x 3 deformed positions on the new mesh, mm
  std::vector<int> old_index;  ///< per new vertex: its vertex in the input scene, or -1 if created
  int chamber_tets_before = 0, chamber_tets_after = 0;
  int new_vertices = 0, removed_vertices = 0;
  double chamber_rest_volume_before = 0, chamber_rest_volume_after = 0;  ///< mm^3
  double chamber_volume_before = 0, chamber_volume_after = 0;            ///< at the positions, mm^3
  /// Volume enclosed by the outer surface before / after, mm^3 (equal for chamber-only).
  double outer_volume_before = 0, outer_volume_after = 0;
  /// Symmetric Hausdorff distance between the old and new outer surfaces, measured from each
  /// one's vertices to the other surface, mm (0 for chamber-only).
  double outer_deviation = 0;
  double target_edge = 0;  ///< chamber-only: the target edge length, mm
  double seconds = 0;      ///< wall time, s
};

/// Re-tessellates the chamber of `scene` (ChamberActuator) in its deformed shape X (#V x 3, mm)
/// and carries the state across (file comment). Chamber-only needs every tet positively oriented
/// at X; whole needs the deformed chamber and outer surfaces to be closed, free of
/// self-intersections and nested, and supports fixed vertices and markers but not fixed_axis.
/// Fixed vertices and markers are renumbered (chamber-only) or re-found (whole). Throws
/// std::invalid_argument for a bad scene, X or options, std::runtime_error if CGAL fails, the
/// deformed surfaces are unusable, or a new tet gets a non-positive rest volume.
ChamberRemesh RemeshChamber(const Scene& scene, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                            const ChamberRemeshOptions& options = {});

/// One ladder value of SolveProgressive.
struct ProgressiveStep {
  int k = 0;                ///< 1-based ladder index
  double alpha = 1.0;       ///< chamber volume ratio asked for (of the original chamber)
  int remeshes = 0;         ///< remeshes done at this value
  std::string methods;      ///< the methods used by them, joined by '+' ("" if none)
  int remesh_failures = 0;  ///< remeshes that threw std::runtime_error (the step went on without)
  int tets = 0, chamber_tets = 0;  ///< after the step
  double mesh_seconds = 0;         ///< time in RemeshChamber at this step (failed attempts too), s
  double solver_seconds = 0;       ///< time in FkSolver::Solve (and Model builds) at this step, s
  int iterations = 0;              ///< solver iterations summed over the step's solves
  FkStatus status = FkStatus::Converged;  ///< of the step's last solve
  double chamber_volume_ratio = 1.0;      ///< chamber volume / original chamber volume, reached
  double max_volume_ratio = 1.0, max_distortion = 1.0;  ///< CheckRemesh after the first solve
  /// Of the step's solves (summed): collision detection and response time (0 without collision
  /// handling) and the local and global steps' time, s.
  double check_seconds = 0, response_seconds = 0, local_global_seconds = 0;
  /// With collision handling: the exact check of the step's last solve, and its springs.
  bool collision_active = false;
  CollisionCheck collision;
  int springs = 0;
};

/// Options of SolveProgressive.
struct ProgressiveOptions {
  RemeshCriteria criteria;
  /// Step of the actuation ladder alpha_k = k * step; 0: criteria.alpha_max (Algorithm 2).
  double step = 0.0;
  /// Explicit ladder values (increasing, in (1, alpha_target]); when given they replace the
  /// k * step values (the target and the snapshots are still added).
  std::vector<double> ladder;
  /// false: the same ladder of solves without remeshing (for comparisons).
  bool remesh = true;
  /// Remesh-and-re-solve rounds allowed at one ladder value.
  int max_remeshes_per_step = 2;
  /// How to re-tessellate.
  ChamberRemeshOptions remesh_options;
  /// Extra ladder values (in (1, alpha_target]) at which the state is kept in
  /// ProgressiveResult::snapshots (e.g. the shapes of Fig. 3.7).
  std::vector<double> snapshots;
  /// Called after each ladder value with its record and the state reached (scene, #V x 3
  /// positions), e.g. for progress output or measurements; may be empty.
  std::function<void(const ProgressiveStep&, const Scene&, const Eigen::MatrixX3d&)> on_step;
  bool IsValid(std::string* why) const;
};

/// A kept state.
struct ProgressiveSnapshot {
  double alpha = 1.0;
  Scene scene;
  Eigen::MatrixX3d positions;
  double chamber_volume_ratio = 1.0;
};

struct ProgressiveResult {
  /// converged if every solve converged; else the first other status (the ladder stops at
  /// diverged or invalid_input and keeps going otherwise).
  FkStatus status = FkStatus::Converged;
  /// False if the ladder stopped before alpha_target (a diverged or invalid solve).
  bool completed = true;
  std::string message;  ///< why a solve did not converge or the ladder stopped, "" if none
  /// Remeshes that failed (RemeshChamber threw std::runtime_error, e.g. a self-intersecting
  /// deformed chamber surface); the ladder then goes on without remeshing at that step.
  int remesh_failures = 0;
  std::string first_remesh_failure;
  Scene scene;                 ///< the final scene (remeshed)
  Eigen::MatrixX3d positions;  ///< final positions on it, #V x 3 mm
  std::vector<ProgressiveStep> steps;
  std::vector<ProgressiveSnapshot> snapshots;
  int remeshes = 0;
  double chamber_volume_ratio = 1.0;  ///< reached at the end
  double mesh_seconds = 0, solver_seconds = 0;
  /// One line: status, steps, remeshes, volume ratio, tets, times.
  std::string BriefReport() const;
};

/// Algorithm 2's outer loop for a scene with one pneumatic chamber actuator (ChamberActuator):
/// solves at alpha_k = k * step (k = 1, 2, ...; plus the snapshot values) up to alpha_target,
/// each warm-started from the previous state, with MakeFkSolver and the scene's solver options
/// (so whatever the solver does, e.g. collision response, applies); after each solve, if
/// CheckRemesh (against the state at the last remesh) fires and remeshing is on, RemeshChamber
/// and solve again at the same alpha. alpha is a ratio of the original chamber volume V_c^0:
/// the actuator gets alpha V_c^0 / M_k, M_k the current chamber rest volume (ChamberRest: the
/// chamber's volume at the last remesh, or V_c^0 up to a whole re-tessellation's re-sampling; the
/// actuator's range is widened to match). A remesh
/// that throws std::runtime_error is counted (remesh_failures) and the step keeps its state on the
/// current mesh; a diverged or invalid solve ends the ladder (completed = false), and so does a
/// runaway (a solution whose bounding box exceeds 5 times the rest one or whose chamber volume
/// ratio exceeds twice alpha, reported as diverged; the state before it is kept). Throws
/// std::invalid_argument for a bad scene, options or an alpha_target outside the actuator's
/// range.
ProgressiveResult SolveProgressive(const Scene& scene, double alpha_target,
                                   const ProgressiveOptions& options = {});

/// Sum of the signed volumes of the tets with a region tag in `regions` at positions X, mm^3.
double RegionVolume(const Mesh& mesh, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                    const std::vector<int>& regions);

}  // namespace softkin
