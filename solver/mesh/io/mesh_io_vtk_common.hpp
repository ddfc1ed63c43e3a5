#pragma once
/// \file mesh_io_vtk_common.hpp
/// Private helpers shared by the legacy VTK (.vtk) and VTK XML (.vtu) readers (not public API):
/// which cell types are kept, how the region array is chosen and how cells become elements.
#include <cmath>
#include <string>
#include <string_view>
#include <vector>

#include "softkin/solver/mesh/io/mesh_io_detail.hpp"

namespace softkin {
namespace detail {

/// Points of a kept cell type: 10 tetra (4), 13 wedge (6), 24 quadratic tetra (10) and 26
/// quadratic wedge (15), whose corner points come first; 0 for other types.
inline int KeptPoints(long long t) {
  return t == 10 ? 4 : t == 13 ? 6 : t == 24 ? 10 : t == 26 ? 15 : 0;
}

/// A single-component cell-data array: a region tag candidate.
struct CellArray {
  std::string name;
  long long line = 0;  ///< line of the array header (or tag)
  bool integer_type = false;
  std::vector<double> values;  ///< one per cell
};

/// Whether a VTK data type name (legacy or XML) is an integer type.
inline bool IsIntegerType(std::string_view t) {
  std::string n(t);
  for (char& c : n) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return n.find("float") == std::string::npos && n.find("double") == std::string::npos;
}

inline bool NameSuggestsTag(std::string_view name) {
  std::string n(name);
  for (char& c : n) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (const char* w :
       {"region", "tag", "label", "material", "physical", "attribute", "domain", "entity"})
    if (n.find(w) != std::string::npos) return true;
  return false;
}

/// The region array: the one named `tag_array` (fails naming `path` if there is none), else the
/// first integer-typed array, else the first array with a tag-like name and integral values;
/// nullptr: every region is 0.
inline const CellArray* ChooseRegionArray(const std::string& path,
                                          const std::vector<CellArray>& arrays,
                                          const std::string& tag_array) {
  if (!tag_array.empty()) {
    for (const auto& a : arrays)
      if (a.name == tag_array) return &a;
    std::string names;
    for (const auto& a : arrays) names += (names.empty() ? "" : ", ") + a.name;
    Fail(path, "no single-component cell data array named " + Quote(tag_array),
         names.empty() ? std::string("a cell data array of that name (the file has none)")
                       : "one of: " + names);
  }
  for (const auto& a : arrays)
    if (a.integer_type) return &a;
  for (const auto& a : arrays) {
    if (!NameSuggestsTag(a.name)) continue;
    bool integral = true;
    for (double v : a.values) integral = integral && v == std::round(v) && std::abs(v) <= INT_MAX;
    if (integral) return &a;
  }
  return nullptr;
}

/// Appends the kept cells (KeptPoints) as elements of *mesh: cell c has the points
/// conn[offsets[c] .. offsets[c+1]), its region from `tags` (may be null) and its location
/// cell_at[c] in *element_at. VTK wedges are converted to SoftKin prisms. Returns how many
/// quadratic cells were read by their corners.
template <typename Types, typename Conn, typename Locs>
int AddVtkElements(const std::string& path, const Types& cell_types,
                   const std::vector<long long>& offsets, const Conn& conn, const CellArray* tags,
                   const Locs& cell_at, Mesh* mesh, std::vector<long long>* element_at) {
  const std::size_t n = cell_types.size();
  if (tags && tags->values.size() != n)
    Fail(At(path, static_cast<int>(tags->line)),
         "array " + Quote(tags->name) + " has " + std::to_string(tags->values.size()) + " values",
         std::to_string(n) + " (one per cell)");
  int higher_order = 0;
  for (std::size_t c = 0; c < n; ++c) {
    const long long t = cell_types[c];
    if (KeptPoints(t) == 0) continue;
    Element e;
    e.type = t == 10 || t == 24 ? ElementType::Tet : ElementType::Prism;
    for (int a = 0; a < e.k(); ++a)
      e.v[a] = static_cast<int>(conn[static_cast<std::size_t>(offsets[c] + a)]);
    if (e.type == ElementType::Prism) VtkWedgeSwap(e.v);
    higher_order += t == 24 || t == 26;
    if (tags) {
      const double v = tags->values[c];
      if (!(v == std::round(v) && std::abs(v) <= INT_MAX))
        Fail(At(path, static_cast<int>(tags->line)),
             "array " + Quote(tags->name) + " holds the non-integer region " + std::to_string(v) +
                 " for cell " + std::to_string(c),
             "integer region tags");
      e.region = static_cast<int>(v);
    }
    mesh->elements.push_back(e);
    element_at->push_back(c < cell_at.size() ? static_cast<long long>(cell_at[c]) : 0);
  }
  return higher_order;
}

}  // namespace detail
}  // namespace softkin
