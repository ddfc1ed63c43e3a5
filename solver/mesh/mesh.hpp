#pragma once
/// \file mesh.hpp
/// One volumetric mesh type for SoftKin: tetrahedra (k = 4) and prisms (k = 6), each with an
/// integer region tag. Units are millimetres unless a file says otherwise.
#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <string>
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

/// Messages produced while checking a mesh: notes (e.g. flipped elements) and warnings
/// (unused vertices, disconnected parts). Errors are thrown, never collected here.
struct MeshReport {
  int flipped = 0;
  int unused_vertices = 0;
  int components = 0;
  std::vector<std::string> notes;
  std::vector<std::string> warnings;
};

/// Reverses the orientation of an element in place (tet: swap v1,v2; prism: swap 1<->2 and 4<->5).
void FlipElement(Element& e);

/// Checks and repairs a freshly read mesh:
///  - throws std::runtime_error naming `source` and the element (its `lines[i]` when given, 1-based
///    file line of element i) for indices out of range, repeated vertices in one element, NaN/Inf
///    coordinates (`vertex_lines[j]` for vertex j) and degenerate elements (|vol| <= 1e-12 *
///    size^3);
///  - flips negatively oriented elements consistently and records a note;
///  - warns about unused vertices and disconnected parts (element face/vertex connectivity).
MeshReport ValidateAndOrient(Mesh& mesh, const std::string& source,
                             const std::vector<int>& element_lines = {},
                             const std::vector<int>& vertex_lines = {});

/// Connected components of the element graph (elements sharing a vertex); returns the component id
/// per element and sets *count.
std::vector<int> ElementComponents(const Mesh& mesh, int* count);

}  // namespace softkin
