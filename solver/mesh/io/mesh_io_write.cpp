/// \file mesh_io_write.cpp
/// ReadMesh (dispatch by extension), ParaView output (.vtu, .pvd), the boundary surface as .obj and
/// the per-element strain measure.
#include <algorithm>
#include <Eigen/Dense>
#include <climits>
#include <cmath>
#include <limits>

#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/mesh/io/mesh_io_detail.hpp"
#include "softkin/solver/mesh/element_faces.hpp"

namespace softkin {

namespace {

void CheckPositions(const std::string& path, const Mesh& mesh,
                    const Eigen::Ref<const Eigen::MatrixX3d>& X) {
  if (X.rows() != mesh.num_vertices())
    detail::Fail(path, "positions have " + std::to_string(X.rows()) + " rows",
                 std::to_string(mesh.num_vertices()) + " rows (one per mesh vertex)");
}

std::string XmlEscape(const std::string& s) {
  std::string r;
  r.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&':
        r += "&amp;";
        break;
      case '<':
        r += "&lt;";
        break;
      case '>':
        r += "&gt;";
        break;
      case '"':
        r += "&quot;";
        break;
      case '\'':
        r += "&apos;";
        break;
      default:
        r += c;
    }
  }
  return r;
}

}  // namespace

void PrintMeshReport(const MeshReport& report, std::ostream& os) {
  for (const auto& n : report.notes) os << "softkin: note: " << n << '\n';
  for (const auto& w : report.warnings) os << "softkin: warning: " << w << '\n';
}

Mesh ReadMesh(const std::string& path, MeshReport* report) {
  const std::string ext = detail::LowerExtension(path);
  if (ext == ".tet") return ReadTet(path, "", report);
  if (ext == ".node" || ext == ".ele")
    return ReadTetGen(path.substr(0, path.size() - ext.size()), report);
  if (ext == ".msh") return ReadGmsh(path, report);
  if (ext == ".vtk") return ReadVtk(path, "", report);
  if (ext == ".vtu") return ReadVtu(path, "", report);
  detail::Fail(path, "unknown mesh file extension " + detail::Quote(ext.empty() ? "(none)" : ext),
               ".tet, .node/.ele (TetGen), .msh (Gmsh 2.2/4.1), .vtk (legacy VTK) or .vtu (VTK "
               "XML)");
}

std::vector<double> ElementStrain(const Mesh& mesh, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                                  const std::vector<int>& rest_regions,
                                  const Eigen::MatrixX3d* rest_positions) {
  if (X.rows() != mesh.num_vertices())
    throw std::invalid_argument("ElementStrain: positions have " + std::to_string(X.rows()) +
                                " rows; expected " + std::to_string(mesh.num_vertices()));
  if (!rest_regions.empty() && (!rest_positions || rest_positions->rows() != mesh.num_vertices()))
    throw std::invalid_argument("ElementStrain: expected rest positions with one row per vertex (" +
                                std::to_string(mesh.num_vertices()) +
                                ") for regions with their own rest shape");
  std::vector<double> strain(mesh.elements.size());
  for (std::size_t i = 0; i < mesh.elements.size(); ++i) {
    const Element& e = mesh.elements[i];
    const int k = e.k();
    const bool own =
        std::find(rest_regions.begin(), rest_regions.end(), e.region) != rest_regions.end();
    const Eigen::MatrixX3d& rest = own ? *rest_positions : mesh.vertices;
    // Centred rest (P) and deformed (Q) positions; F minimises sum ||F p - q||^2:
    // F = (Q^T P) (P^T P)^{-1}. For a tet the affine map is exact, so this is the exact F.
    Eigen::Vector3d pc = Eigen::Vector3d::Zero(), qc = Eigen::Vector3d::Zero();
    for (int a = 0; a < k; ++a) {
      pc += rest.row(e.v[a]).transpose();
      qc += X.row(e.v[a]).transpose();
    }
    pc /= k;
    qc /= k;
    Eigen::Matrix3d PtP = Eigen::Matrix3d::Zero(), QtP = Eigen::Matrix3d::Zero();
    for (int a = 0; a < k; ++a) {
      const Eigen::Vector3d p = rest.row(e.v[a]).transpose() - pc;
      const Eigen::Vector3d q = X.row(e.v[a]).transpose() - qc;
      PtP.noalias() += p * p.transpose();
      QtP.noalias() += q * p.transpose();
    }
    Eigen::Matrix3d inv;
    bool ok = false;
    double det = 0.0;
    PtP.computeInverseAndDetWithCheck(inv, det, ok, 1e-300);
    const double scale = PtP.trace();
    if (!ok || !(std::abs(det) > 1e-14 * scale * scale * scale)) {
      strain[i] = std::numeric_limits<double>::quiet_NaN();  // degenerate rest element
      continue;
    }
    const Eigen::Matrix3d F = QtP * inv;
    strain[i] = 0.5 * (F.transpose() * F - Eigen::Matrix3d::Identity()).norm();
  }
  return strain;
}

void WriteVtu(const std::string& path, const Mesh& mesh,
              const Eigen::Ref<const Eigen::MatrixX3d>& X, const std::vector<int>& rest_regions,
              const Eigen::MatrixX3d* rest_positions, const VtuSolveInfo* info) {
  CheckPositions(path, mesh, X);
  const std::vector<double> strain = ElementStrain(mesh, X, rest_regions, rest_positions);
  OutputFile out_file(path);
  std::ostream& out = detail::ForWrite(out_file);
  const int nv = mesh.num_vertices(), ne = mesh.num_elements();
  out << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
         "header_type=\"UInt64\">\n"
      << "  <UnstructuredGrid>\n";
  if (info)
    out << "    <FieldData>\n"
        << "      <DataArray type=\"UInt8\" Name=\"converged\" NumberOfTuples=\"1\" "
           "format=\"ascii\">"
        << (info->converged ? 1 : 0) << "</DataArray>\n"
        << "      <DataArray type=\"Int32\" Name=\"iterations\" NumberOfTuples=\"1\" "
           "format=\"ascii\">"
        << info->iterations << "</DataArray>\n"
        << "      <DataArray type=\"Float64\" Name=\"residual_ratio\" NumberOfTuples=\"1\" "
           "format=\"ascii\">"
        << detail::Num{std::isfinite(info->residual_ratio) ? info->residual_ratio : -1.0}
        << "</DataArray>\n"
        << "      <DataArray type=\"Int32\" Name=\"inverted_elements\" NumberOfTuples=\"1\" "
           "format=\"ascii\">"
        << info->inverted_elements << "</DataArray>\n"
        << "    </FieldData>\n";
  out << "    <Piece NumberOfPoints=\"" << nv << "\" NumberOfCells=\"" << ne << "\">\n";
  out << "      <PointData Vectors=\"displacement\">\n"
      << "        <DataArray type=\"Float64\" Name=\"displacement\" NumberOfComponents=\"3\" "
         "format=\"ascii\">\n";
  for (int j = 0; j < nv; ++j)
    out << "          " << detail::Num{X(j, 0) - mesh.vertices(j, 0)} << ' '
        << detail::Num{X(j, 1) - mesh.vertices(j, 1)} << ' '
        << detail::Num{X(j, 2) - mesh.vertices(j, 2)} << '\n';
  out << "        </DataArray>\n      </PointData>\n";
  out << "      <CellData Scalars=\"region\">\n"
      << "        <DataArray type=\"Int32\" Name=\"region\" format=\"ascii\">\n";
  for (const auto& e : mesh.elements) out << "          " << e.region << '\n';
  out << "        </DataArray>\n"
      << "        <DataArray type=\"UInt8\" Name=\"element_type\" format=\"ascii\">\n";
  for (const auto& e : mesh.elements)
    out << "          " << (e.type == ElementType::Tet ? 10 : 13) << '\n';
  out << "        </DataArray>\n"
      << "        <DataArray type=\"Float64\" Name=\"strain\" format=\"ascii\">\n";
  // -1: undefined (degenerate rest shape, or overflow); never NaN, which readers treat unevenly.
  for (double s : strain) out << "          " << detail::Num{std::isfinite(s) ? s : -1.0} << '\n';
  out << "        </DataArray>\n      </CellData>\n";
  out << "      <Points>\n"
      << "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" "
         "format=\"ascii\">\n";
  for (int j = 0; j < nv; ++j) detail::WriteRow(out << "          ", X, j) << '\n';
  out << "        </DataArray>\n      </Points>\n";
  out << "      <Cells>\n"
      << "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (const auto& e : mesh.elements) {
    std::array<int, 6> v = e.v;
    if (e.type == ElementType::Prism) detail::VtkWedgeSwap(v);
    out << "         ";
    for (int a = 0; a < e.k(); ++a) out << ' ' << v[a];
    out << '\n';
  }
  out << "        </DataArray>\n"
      << "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  long long off = 0;
  for (const auto& e : mesh.elements) {
    off += e.k();
    out << "          " << off << '\n';
  }
  out << "        </DataArray>\n"
      << "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (const auto& e : mesh.elements)
    out << "          " << (e.type == ElementType::Tet ? 10 : 13) << '\n';
  out << "        </DataArray>\n      </Cells>\n";
  out << "    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
  out_file.Commit();
}

void WritePvd(const std::string& path, const std::vector<std::pair<double, std::string>>& steps) {
  OutputFile out_file(path);
  std::ostream& out = detail::ForWrite(out_file);
  out << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      << "  <Collection>\n";
  for (const auto& [t, file] : steps)
    out << "    <DataSet timestep=\"" << detail::Num{t} << "\" group=\"\" part=\"0\" file=\""
        << XmlEscape(file) << "\"/>\n";
  out << "  </Collection>\n</VTKFile>\n";
  out_file.Commit();
}

void WriteSurfaceObj(const std::string& path, const Mesh& mesh,
                     const Eigen::Ref<const Eigen::MatrixX3d>& X) {
  CheckPositions(path, mesh, X);
  // Faces that occur once are on the boundary.
  const std::vector<MeshFace> faces = SortedMeshFaces(mesh);

  std::vector<int> new_index(mesh.num_vertices(), -1);
  std::vector<const MeshFace*> boundary;
  int nused = 0;
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j == i + 1) {
      boundary.push_back(&faces[i]);
      for (int a = 0; a < 4; ++a) {
        const int v = faces[i].key[a];
        if (v != INT_MAX && new_index[v] < 0) new_index[v] = nused++;
      }
    }
    i = j;
  }
  // Keep the original vertex order among the used vertices.
  std::vector<int> order;
  order.reserve(nused);
  nused = 0;
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (new_index[v] >= 0) {
      new_index[v] = nused++;
      order.push_back(v);
    }
  std::sort(boundary.begin(), boundary.end(), [](const MeshFace* a, const MeshFace* b) {
    return a->element != b->element ? a->element < b->element : a->local < b->local;
  });

  OutputFile out_file(path);
  std::ostream& out = detail::ForWrite(out_file);
  out << "# SoftKin boundary surface: " << order.size() << " vertices, " << boundary.size()
      << " faces\n";
  for (int v : order) detail::WriteRow(out << "v ", X, v) << '\n';
  for (const MeshFace* r : boundary) {
    const Element& e = mesh.elements[r->element];
    const LocalFace& lf = (e.type == ElementType::Tet ? kTetFaces : kPrismFaces)[r->local];
    out << "f " << new_index[e.v[lf.a]] + 1 << ' ' << new_index[e.v[lf.b]] + 1 << ' '
        << new_index[e.v[lf.c]] + 1;
    if (lf.d >= 0) out << ' ' << new_index[e.v[lf.d]] + 1;
    out << '\n';
  }
  out_file.Commit();
}

}  // namespace softkin
