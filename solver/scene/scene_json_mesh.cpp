/// \file scene_json_mesh.cpp
/// Scene JSON: the mesh section (format, file, labels, tag array, scale) and the mesh reader it
/// picks (mesh_io.hpp).
#include "softkin/solver/common/text_format.hpp"
#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/scene/scene_parser.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>

namespace softkin {
namespace scene_json_detail {

namespace fs = std::filesystem;

void SceneParser::ReadMeshSection(const json& m, Scene* scene) {
  CheckObject(m, "mesh", "mesh");
  const std::string file_key = m.at("file").get<std::string>();
  if (file_key.empty()) Fail("mesh.file: expected a file name, got \"\"");
  const fs::path file = Resolve(file_key);
  std::string format = Get(m, "mesh", "format").get<std::string>();
  const std::string labels = Get(m, "mesh", "labels").get<std::string>();
  const std::string tag_array = Get(m, "mesh", "tag_array").get<std::string>();
  if (format == "auto") {
    std::string ext = file.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return std::tolower(c); });
    if (ext == ".tet")
      format = "tet";
    else if (ext == ".node" || ext == ".ele")
      format = "tetgen";
    else if (ext == ".msh")
      format = "gmsh";
    else if (ext == ".vtk")
      format = "vtk";
    else if (ext == ".vtu")
      format = "vtu";
    else if (ext.empty() && fs::exists(file.string() + ".node"))
      format = "tetgen";
    else
      Fail("mesh.format: cannot tell the mesh format of '" + file.string() +
           "' from its extension; expected a .tet, .node, .ele, .msh, .vtk or .vtu file, or "
           "mesh.format set to one of: tet, tetgen, gmsh, vtk, vtu");
  }
  if (!labels.empty() && format != "tet")
    Fail("mesh.labels: only used by the tet format (the mesh is read as " + format + ")");
  if (!tag_array.empty() && format != "vtk" && format != "vtu")
    Fail("mesh.tag_array: only used by the vtk and vtu formats (the mesh is read as " + format +
         ")");

  fs::path read_path = file;
  if (format == "tetgen") {
    const std::string ext = file.extension().string();
    fs::path base = (ext == ".node" || ext == ".ele") ? fs::path(file).replace_extension() : file;
    for (const char* e : {".node", ".ele"})
      if (!fs::is_regular_file(base.string() + e))
        Fail("mesh.file: file not found: '" + base.string() + e + "' (from mesh.file \"" +
             file_key + "\"; expected an existing TetGen .node and .ele pair)");
    read_path = base;
  } else if (!fs::is_regular_file(file)) {
    Fail("mesh.file: file not found: '" + file.string() + "' (from mesh.file \"" + file_key +
         "\", relative to '" + (base_.empty() ? std::string(".") : base_) + "')");
  }
  fs::path labels_path;
  if (!labels.empty()) {
    labels_path = Resolve(labels);
    if (!fs::is_regular_file(labels_path))
      Fail("mesh.labels: file not found: '" + labels_path.string() + "' (from mesh.labels \"" +
           labels + "\")");
  }

  MeshReport report;
  try {
    if (format == "tet")
      scene->mesh = ReadTet(read_path.string(), labels_path.string(), &report);
    else if (format == "tetgen")
      scene->mesh = ReadTetGen(read_path.string(), &report);
    else if (format == "gmsh")
      scene->mesh = ReadGmsh(read_path.string(), &report);
    else if (format == "vtu")
      scene->mesh = ReadVtu(read_path.string(), tag_array, &report);
    else
      scene->mesh = ReadVtk(read_path.string(), tag_array, &report);
  } catch (const std::exception& e) {
    // Keep the reader's "<file>:<line>: ..." message intact; add the key it came from.
    const std::string what = e.what();
    const bool from_labels = !labels_path.empty() && what.rfind(labels_path.string(), 0) == 0;
    Fail(std::string(from_labels ? "mesh.labels" : "mesh.file") + ": cannot read the " + format +
         " mesh: " + what);
  }
  PrintMeshReport(report, std::cerr);
  scene->mesh_source_vertex = report.source_vertex;
  MapFileVertices(report, scene->mesh.num_vertices());
  const double scale = Get(m, "mesh", "scale").get<double>();
  if (scale != 1.0) {
    scene->mesh.vertices *= scale;
    // Volumes (size^3) and the energy's terms (size^5) must stay within double precision: a
    // scale that puts the mesh's size outside [1e-30, 1e30] mm would overflow or underflow them.
    const double size = scene->mesh.num_vertices() > 0 ? scene->mesh.size() : 1.0;
    if (!scene->mesh.vertices.allFinite() || !(size >= 1e-30 && size <= 1e30))
      Fail("mesh.scale: " + FormatNumber(scale) + " makes the mesh " +
           (std::isfinite(size) ? FormatNumber(size) + " mm" : std::string("infinitely")) +
           " across; expected a scale that keeps its size within [1e-30, 1e30] mm (volumes and "
           "energies must stay within double precision)");
  }
}

void SceneParser::MapFileVertices(const MeshReport& report, int num_vertices) {
  const int file_vertices = num_vertices + report.unused_vertices;
  file_to_mesh_.assign(static_cast<std::size_t>(file_vertices), -1);
  for (int j = 0; j < num_vertices; ++j) {
    const int f = report.source_vertex.empty() ? j : report.source_vertex[j];
    file_to_mesh_[static_cast<std::size_t>(f)] = j;
  }
}

}  // namespace scene_json_detail
}  // namespace softkin
