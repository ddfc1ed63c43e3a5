#pragma once
/// \file mesh.hpp
/// One volumetric mesh type for SoftKin: tetrahedra (k = 4) and prisms (k = 6), each with an
/// integer region tag. Units are millimetres unless a file says otherwise.
#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace softkin {

/// Element kinds, valued by their vertex count k.
enum class ElementType : std::uint8_t { Tet = 4, Prism = 6 };

/// "tet" / "prism".
const char* ElementTypeToString(ElementType t);

/// One element. Tet vertices: v[0..3], positive orientation means
/// ((v1-v0) x (v2-v0)) . (v3-v0) > 0. Prism vertices: bottom triangle v[0..2], top triangle v[3..5]
/// with v[3+j] above v[j]; positive orientation means the bottom triangle's normal
/// (v1-v0) x (v2-v0) points towards the top triangle (Gmsh's convention).
struct Element {
  std::array<int, 6> v{{-1, -1, -1, -1, -1, -1}};
  ElementType type = ElementType::Tet;
  int region = 0;  ///< integer region tag (physical group, attribute, label)
  int k() const { return static_cast<int>(type); }
};

/// Vertices (#V x 3, mm) and elements with region tags.
struct Mesh {
  Eigen::MatrixX3d vertices;  ///< #V x 3 rest positions, mm
  std::vector<Element> elements;

  int num_vertices() const { return static_cast<int>(vertices.rows()); }
  int num_elements() const { return static_cast<int>(elements.size()); }
  int num_tets() const;
  int num_prisms() const;
  /// Sorted distinct region tags.
  std::vector<int> regions() const;
  /// Axis-aligned bounding-box diagonal length (the model's size), mm.
  double size() const;
};

/// Signed volume of element `e` with vertex positions `X` (#V x 3). Prisms use a fixed
/// three-tet split, exact for planar quad faces.
double SignedVolume(const Element& e, const Eigen::Ref<const Eigen::MatrixX3d>& X);

/// Number of elements of `mesh` whose signed volume at positions X (#V x 3) is not positive
/// (inverted or flat): a state's tangles, as opposed to contacts between its surfaces.
int CountInvertedElements(const Mesh& mesh, const Eigen::Ref<const Eigen::MatrixX3d>& X);

/// Messages produced while checking a mesh: notes (e.g. flipped elements, dropped vertices) and
/// warnings (cracks, disconnected parts). Errors are thrown, never collected here.
struct MeshReport {
  int flipped = 0;
  int unused_vertices = 0;  ///< vertices used by no element, dropped by ValidateAndOrient
  int components = 0;
  /// source_vertex[j]: the 0-based position in the file's vertex list (before unused vertices were
  /// dropped) of the mesh's vertex j. For Gmsh files this is the position in $Nodes, not the node
  /// tag; for 1-based TetGen files it is the point index minus 1.
  std::vector<int> source_vertex;
  std::vector<std::string> notes;
  std::vector<std::string> warnings;
};

/// Where a reader found each element and vertex, for error messages: 1-based lines of a text file,
/// or 0-based byte offsets of a binary one (`bytes`). Empty vectors or values <= 0 (lines) / < 0
/// (offsets): unknown, the message names the element or vertex by index instead.
struct MeshOrigin {
  std::vector<long long> element_at;
  std::vector<long long> vertex_at;
  bool bytes = false;
};

/// Reverses the orientation of an element in place (tet: swap v1,v2; prism: swap 1<->2 and 4<->5).
void FlipElement(Element& e);

/// Checks and repairs a freshly read mesh (every reader calls it):
///  - throws std::runtime_error naming `source` and the element (its line when known, see
///    MeshOrigin) for indices out of range, repeated vertices in one element, NaN/Inf coordinates
///    of used vertices, degenerate elements (|vol| <= 1e-12 * size^3), two elements with the same
///    vertex set (naming both lines and region tags) and folds: face neighbours that overlap
///    after each element is oriented positively (naming both elements);
///  - drops vertices that no element uses, with a note; report.source_vertex maps kept vertices
///    to their file positions;
///  - flips negatively oriented elements (all of them, or some: both are fine) and records a note;
///  - warns about cracks (coincident vertices both used by elements, named by file position) and
///    disconnected parts (element vertex connectivity).
MeshReport ValidateAndOrient(Mesh& mesh, const std::string& source, const MeshOrigin& origin);
/// Same, with 1-based element and vertex lines of a text file.
MeshReport ValidateAndOrient(Mesh& mesh, const std::string& source,
                             const std::vector<int>& element_lines = {},
                             const std::vector<int>& vertex_lines = {});

/// Pairs (i, j), i < j, of elements that share a face and lie on the same side of it, i.e. the
/// face is oriented the same way by both (elements must be positively oriented); also pairs of
/// any two of three or more elements sharing one face. Empty for a consistent mesh.
std::vector<std::pair<int, int>> FoldedElementPairs(const Mesh& mesh);

/// Pairs (a, b), a < b, of distinct vertices used by elements that lie within `tol` (mm) of each
/// other: a crack (the mesh is cut there).
std::vector<std::pair<int, int>> CoincidentVertexPairs(const Mesh& mesh, double tol);

/// Pairs (i, j), i < j, of elements with the same vertex set (in any order).
std::vector<std::pair<int, int>> DuplicateElementPairs(const Mesh& mesh);

/// Connected components of the element graph (elements sharing a vertex); returns the component id
/// per element and sets *count.
std::vector<int> ElementComponents(const Mesh& mesh, int* count);

}  // namespace softkin
