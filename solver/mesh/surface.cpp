#include "softkin/solver/mesh/surface.hpp"
#include "softkin/solver/common/input_file.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace softkin {

namespace {

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

[[noreturn]] void Fail(const std::string& where, const std::string& what) {
  throw std::invalid_argument(where + ": " + what);
}

TriangleSurface ReadObj(const std::string& path) {
  CheckInputFile(path, "a surface file (.obj)");
  std::ifstream in(path);
  if (!in) Fail(path, "cannot open the file");
  TriangleSurface s;
  s.source = path;
  std::vector<Eigen::Vector3d> V;
  std::vector<Eigen::Vector3i> F;
  std::string line;
  int no = 0;
  while (std::getline(in, line)) {
    ++no;
    const std::string at = path + ":" + std::to_string(no);
    std::istringstream ss(line);
    std::string tag;
    if (!(ss >> tag)) continue;
    if (tag == "v") {
      Eigen::Vector3d p;
      if (!(ss >> p.x() >> p.y() >> p.z())) Fail(at, "expected 'v x y z' with three numbers");
      if (!p.allFinite()) Fail(at, "vertex coordinates must be finite");
      V.push_back(p);
    } else if (tag == "f") {
      std::vector<int> ids;
      std::string tok;
      while (ss >> tok) {
        const std::string first = tok.substr(0, tok.find('/'));
        char* end = nullptr;
        const long v = std::strtol(first.c_str(), &end, 10);
        if (first.empty() || *end != '\0' || v == 0)
          Fail(at, "expected face vertex indices (1-based, or negative from the end), got '" + tok +
                       "'");
        const long idx = v > 0 ? v - 1 : static_cast<long>(V.size()) + v;
        if (idx < 0 || idx >= static_cast<long>(V.size()))
          Fail(at, "face index " + std::to_string(v) + " refers to no vertex defined so far (" +
                       std::to_string(V.size()) + " vertices)");
        ids.push_back(static_cast<int>(idx));
      }
      if (ids.size() < 3) Fail(at, "expected a face with at least 3 vertices");
      for (size_t k = 1; k + 1 < ids.size(); ++k) F.emplace_back(ids[0], ids[k], ids[k + 1]);
    }
  }
  if (F.empty()) Fail(path, "no faces ('f' lines) found; expected a closed triangle surface");
  s.vertices.resize(V.size(), 3);
  for (size_t i = 0; i < V.size(); ++i) s.vertices.row(i) = V[i].transpose();
  s.faces.resize(F.size(), 3);
  for (size_t i = 0; i < F.size(); ++i) s.faces.row(i) = F[i].transpose();
  return s;
}

/// Appends a triangle of three points, merging exactly equal points.
struct PointMerger {
  std::map<std::array<double, 3>, int> index;
  std::vector<Eigen::Vector3d> V;
  int Add(const Eigen::Vector3d& p) {
    const std::array<double, 3> key{p.x(), p.y(), p.z()};
    auto [it, fresh] = index.emplace(key, static_cast<int>(V.size()));
    if (fresh) V.push_back(p);
    return it->second;
  }
};

TriangleSurface ReadStl(const std::string& path) {
  CheckInputFile(path, "a surface file (.stl)");
  std::ifstream in(path, std::ios::binary);
  if (!in) Fail(path, "cannot open the file");
  std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  PointMerger pm;
  std::vector<Eigen::Vector3i> F;
  bool binary = false;
  if (data.size() >= 84) {
    std::uint32_t n = 0;
    std::memcpy(&n, data.data() + 80, 4);
    binary = data.size() == 84 + 50ull * n;
  }
  if (binary) {
    std::uint32_t n = 0;
    std::memcpy(&n, data.data() + 80, 4);
    for (std::uint32_t t = 0; t < n; ++t) {
      const char* rec = data.data() + 84 + 50ull * t;
      Eigen::Vector3i f;
      for (int k = 0; k < 3; ++k) {
        float xyz[3];
        std::memcpy(xyz, rec + 12 + 12 * k, 12);
        const Eigen::Vector3d p(xyz[0], xyz[1], xyz[2]);
        if (!p.allFinite())
          Fail(path, "triangle " + std::to_string(t) + " has a non-finite coordinate");
        f[k] = pm.Add(p);
      }
      F.push_back(f);
    }
  } else {
    std::istringstream ss(data);
    std::string line;
    int no = 0, corners = 0;
    Eigen::Vector3i f;
    while (std::getline(ss, line)) {
      ++no;
      std::istringstream ls(line);
      std::string tag;
      if (!(ls >> tag)) continue;
      tag = Lower(tag);
      const std::string at = path + ":" + std::to_string(no);
      if (tag == "facet") {
        if (corners != 0) Fail(at, "a facet starts before the previous one has 3 vertices");
      } else if (tag == "vertex") {
        Eigen::Vector3d p;
        if (!(ls >> p.x() >> p.y() >> p.z()))
          Fail(at, "expected 'vertex x y z' with three numbers");
        if (!p.allFinite()) Fail(at, "vertex coordinates must be finite");
        if (corners == 3) Fail(at, "a facet has more than 3 vertices; expected triangles");
        f[corners++] = pm.Add(p);
      } else if (tag == "endloop") {
        if (corners != 3)
          Fail(at, "a facet has " + std::to_string(corners) + " vertices; expected 3");
        F.push_back(f);
        corners = 0;
      } else if (tag != "solid" && tag != "endsolid" && tag != "outer" && tag != "endfacet") {
        Fail(at, "unexpected '" + tag +
                     "' in an ASCII STL file (binary STL: its size must be 84 + 50 n bytes)");
      }
    }
    if (corners != 0) Fail(path, "the file ends inside a facet");
  }
  if (F.empty()) Fail(path, "no triangles found; expected a closed triangle surface");
  TriangleSurface s;
  s.source = path;
  s.vertices.resize(pm.V.size(), 3);
  for (size_t i = 0; i < pm.V.size(); ++i) s.vertices.row(i) = pm.V[i].transpose();
  s.faces.resize(F.size(), 3);
  for (size_t i = 0; i < F.size(); ++i) s.faces.row(i) = F[i].transpose();
  return s;
}
}  // namespace

void CheckClosedSurface(TriangleSurface* s) {
  const std::string& src = s->source.empty() ? std::string("surface") : s->source;
  const int nv = static_cast<int>(s->vertices.rows()), nf = static_cast<int>(s->faces.rows());
  if (nf < 4) Fail(src, "a closed surface needs at least 4 triangles, got " + std::to_string(nf));
  if (!s->vertices.allFinite()) Fail(src, "vertex coordinates must be finite");
  const double diag = (s->vertices.colwise().maxCoeff() - s->vertices.colwise().minCoeff()).norm();
  std::map<std::pair<int, int>, int> directed;
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k)
      if (s->faces(f, k) < 0 || s->faces(f, k) >= nv)
        Fail(src, "triangle " + std::to_string(f) + " has vertex index " +
                      std::to_string(s->faces(f, k)) + ", expected 0.." + std::to_string(nv - 1));
    const Eigen::Vector3d a = s->vertices.row(s->faces(f, 0)), b = s->vertices.row(s->faces(f, 1)),
                          c = s->vertices.row(s->faces(f, 2));
    if (!((b - a).cross(c - a).norm() > 1e-12 * diag * diag))
      Fail(src, "triangle " + std::to_string(f) + " is degenerate (zero area)");
    for (int k = 0; k < 3; ++k) ++directed[{s->faces(f, k), s->faces(f, (k + 1) % 3)}];
  }
  for (const auto& [e, n] : directed) {
    const std::string edge =
        "edge (" + std::to_string(e.first) + ", " + std::to_string(e.second) + ")";
    if (n > 1)
      Fail(src, edge + " is traversed in the same direction by " + std::to_string(n) +
                    " triangles; expected a closed, consistently oriented, manifold surface");
    auto r = directed.find({e.second, e.first});
    if (r == directed.end())
      Fail(src, edge + " belongs to one triangle only; expected a closed surface (no holes)");
  }
  double vol = 0;
  for (int f = 0; f < nf; ++f) {
    const Eigen::Vector3d a = s->vertices.row(s->faces(f, 0)), b = s->vertices.row(s->faces(f, 1)),
                          c = s->vertices.row(s->faces(f, 2));
    vol += a.dot(b.cross(c)) / 6.0;
  }
  if (!(std::abs(vol) > 1e-12 * diag * diag * diag)) Fail(src, "the surface encloses no volume");
  if (vol < 0) s->faces.col(1).swap(s->faces.col(2));  // inside-out: make the normals point out
}

TriangleSurface ReadSurfaceMesh(const std::string& path) {
  const std::string ext = Lower(path.substr(
      path.find_last_of('.') == std::string::npos ? path.size() : path.find_last_of('.')));
  TriangleSurface s;
  if (ext == ".obj")
    s = ReadObj(path);
  else if (ext == ".stl")
    s = ReadStl(path);
  else
    Fail(path, "unknown surface format '" + ext + "'; expected .obj or .stl");
  CheckClosedSurface(&s);
  return s;
}

TriangleSurface MakeBoxSurface(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  if (!(lo.array() < hi.array()).all())
    throw std::invalid_argument("box obstacle: expected min < max on every axis");
  TriangleSurface s;
  s.source = "box";
  s.vertices.resize(8, 3);
  for (int i = 0; i < 8; ++i)
    s.vertices.row(i) << (i & 1 ? hi.x() : lo.x()), (i & 2 ? hi.y() : lo.y()),
        (i & 4 ? hi.z() : lo.z());
  s.faces.resize(12, 3);
  s.faces << 0, 2, 1, 1, 2, 3,  // z = lo
      4, 5, 6, 5, 7, 6,         // z = hi
      0, 1, 4, 1, 5, 4,         // y = lo
      2, 6, 3, 3, 6, 7,         // y = hi
      0, 4, 2, 2, 4, 6,         // x = lo
      1, 3, 5, 3, 7, 5;         // x = hi
  CheckClosedSurface(&s);
  return s;
}

TriangleSurface MakeCylinderSurface(const Eigen::Vector3d& base, const Eigen::Vector3d& axis_in,
                                    double radius, double height, int segments) {
  if (!(radius > 0) || !(height > 0) || segments < 3 || !(axis_in.norm() > 0))
    throw std::invalid_argument(
        "cylinder obstacle: expected radius > 0, height > 0, segments >= 3, a non-zero axis");
  const Eigen::Vector3d a = axis_in.normalized();
  const Eigen::Vector3d u = a.unitOrthogonal(), w = a.cross(u);
  TriangleSurface s;
  s.source = "cylinder";
  const int n = segments;
  s.vertices.resize(2 * n + 2, 3);
  for (int i = 0; i < n; ++i) {
    const double t = 2.0 * M_PI * i / n;
    const Eigen::Vector3d r = radius * (std::cos(t) * u + std::sin(t) * w);
    s.vertices.row(i) = (base + r).transpose();
    s.vertices.row(n + i) = (base + height * a + r).transpose();
  }
  s.vertices.row(2 * n) = base.transpose();
  s.vertices.row(2 * n + 1) = (base + height * a).transpose();
  s.faces.resize(4 * n, 3);
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    s.faces.row(4 * i) << i, j, n + j;
    s.faces.row(4 * i + 1) << i, n + j, n + i;
    s.faces.row(4 * i + 2) << 2 * n, j, i;              // bottom, facing -a
    s.faces.row(4 * i + 3) << 2 * n + 1, n + i, n + j;  // top, facing +a
  }
  CheckClosedSurface(&s);
  return s;
}

}  // namespace softkin
