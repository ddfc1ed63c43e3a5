#include "softkin/solver/mesh/mesh_gen.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>

namespace softkin {

namespace {

// Signed volume of the tet (a, b, c, d): ((b-a) x (c-a)) . (d-a) / 6.
double TetVolume(const Eigen::MatrixX3d& X, int a, int b, int c, int d) {
  const Eigen::Vector3d p = X.row(a).transpose();
  const Eigen::Vector3d u = X.row(b).transpose() - p;
  const Eigen::Vector3d v = X.row(c).transpose() - p;
  const Eigen::Vector3d w = X.row(d).transpose() - p;
  return u.cross(v).dot(w) / 6.0;
}

Element MakeTet(int a, int b, int c, int d, int region) {
  Element e;
  e.type = ElementType::Tet;
  e.v = {{a, b, c, d, -1, -1}};
  e.region = region;
  return e;
}

// The arguments of a regular voxel grid, checked before any line is made; `who` names the caller.
void CheckVoxelGrid(const char* who, double h, const Eigen::Vector3i& cells,
                    const VoxelClassifier& classify) {
  if (!(h > 0.0) || !std::isfinite(h))
    throw std::invalid_argument(std::string(who) + ": cell size h must be > 0, got " +
                                std::to_string(h));
  if (cells.minCoeff() < 1)
    throw std::invalid_argument(std::string(who) + ": every cell count must be >= 1");
  if (!classify) throw std::invalid_argument(std::string(who) + ": no cell classifier given");
  if (std::int64_t(cells[0] + 1) * (cells[1] + 1) * (cells[2] + 1) > std::int64_t(1) << 30)
    throw std::invalid_argument(std::string(who) + ": grid too large");
}

}  // namespace

// ------------------------------------------------------------------------------------------------
// VoxelTetMesh
// ------------------------------------------------------------------------------------------------

Mesh VoxelTetMesh(const Eigen::Vector3d& origin, double h, const Eigen::Vector3i& cells,
                  const VoxelClassifier& classify) {
  CheckVoxelGrid("VoxelTetMesh", h, cells, classify);
  std::array<std::vector<double>, 3> lines;
  for (int d = 0; d < 3; ++d)
    for (int i = 0; i <= cells[d]; ++i) lines[d].push_back(origin[d] + h * double(i));
  return RectilinearTetMesh(lines[0], lines[1], lines[2], classify);
}

Mesh SymmetricVoxelTetMesh(const Eigen::Vector3d& origin, double h, const Eigen::Vector3i& cells,
                           const std::array<bool, 3>& even, const VoxelClassifier& classify) {
  CheckVoxelGrid("SymmetricVoxelTetMesh", h, cells, classify);
  std::array<std::vector<double>, 3> lines;
  for (int d = 0; d < 3; ++d) {
    const int n = cells[d], m = even[d] ? n + n % 2 : n;
    for (int i = 0; i <= m; ++i)  // an axis left as it is gets VoxelTetMesh's lines exactly
      lines[d].push_back(origin[d] + (m == n ? h * double(i) : h * n * double(i) / m));
  }
  // The original cell holding a new cell's centre. With m = n + 1 even and n odd, a centre sits at
  // (2i + 1) n / (2m) cells, never on a line, so mirrored cells map to mirrored cells.
  return RectilinearTetMesh(
      lines[0], lines[1], lines[2], [&](const Eigen::Vector3d& c, const Eigen::Vector3i& g) {
        Eigen::Vector3i k;
        Eigen::Vector3d centre;  // of the original cell, as VoxelTetMesh computes it
        for (int d = 0; d < 3; ++d) {
          k[d] = static_cast<int>(lines[d].size()) - 1 == cells[d]
                     ? g[d]
                     : std::clamp(static_cast<int>(std::floor((c[d] - origin[d]) / h)), 0,
                                  cells[d] - 1);
          centre[d] = 0.5 * ((origin[d] + h * double(k[d])) + (origin[d] + h * double(k[d] + 1)));
        }
        return classify(centre, k);
      });
}

Mesh RectilinearTetMesh(const std::vector<double>& xs, const std::vector<double>& ys,
                        const std::vector<double>& zs, const VoxelClassifier& classify) {
  const std::vector<double>* axes[3] = {&xs, &ys, &zs};
  for (int d = 0; d < 3; ++d) {
    const auto& l = *axes[d];
    if (l.size() < 2)
      throw std::invalid_argument(std::string("RectilinearTetMesh: axis ") + "xyz"[d] +
                                  " needs at least 2 grid lines");
    for (size_t q = 0; q + 1 < l.size(); ++q)
      if (!(l[q + 1] > l[q]) || !std::isfinite(l[q + 1]) || !std::isfinite(l[q]))
        throw std::invalid_argument(std::string("RectilinearTetMesh: the grid lines of axis ") +
                                    "xyz"[d] + " must be finite and increasing (line " +
                                    std::to_string(q + 1) + ")");
  }
  if (!classify) throw std::invalid_argument("RectilinearTetMesh: no cell classifier given");
  const std::int64_t nx = xs.size() - 1, ny = ys.size() - 1, nz = zs.size() - 1;
  const std::int64_t vx = nx + 1, vy = ny + 1, vz = nz + 1;
  if (vx * vy * vz > std::int64_t(1) << 30)
    throw std::invalid_argument("RectilinearTetMesh: grid too large");

  // 1. Classify the cells (grid order: x fastest).
  std::vector<int> tag(static_cast<size_t>(nx * ny * nz), -1);
  std::vector<char> used(static_cast<size_t>(vx * vy * vz), 0);
  auto vid = [&](std::int64_t i, std::int64_t j, std::int64_t k) { return i + vx * (j + vy * k); };
  std::int64_t kept = 0;
  for (std::int64_t k = 0; k < nz; ++k)
    for (std::int64_t j = 0; j < ny; ++j)
      for (std::int64_t i = 0; i < nx; ++i) {
        const Eigen::Vector3d centre(0.5 * (xs[i] + xs[i + 1]), 0.5 * (ys[j] + ys[j + 1]),
                                     0.5 * (zs[k] + zs[k + 1]));
        const int t = classify(centre, Eigen::Vector3i(int(i), int(j), int(k)));
        tag[i + nx * (j + ny * k)] = t < 0 ? -1 : t;
        if (t < 0) continue;
        ++kept;
        for (int c = 0; c < 8; ++c)
          used[vid(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))] = 1;
      }

  // 2. Compact the used grid vertices, in grid order.
  std::vector<int> newid(used.size(), -1);
  int nv = 0;
  for (size_t g = 0; g < used.size(); ++g)
    if (used[g]) newid[g] = nv++;
  Mesh mesh;
  mesh.vertices.resize(nv, 3);
  for (std::int64_t k = 0; k < vz; ++k)
    for (std::int64_t j = 0; j < vy; ++j)
      for (std::int64_t i = 0; i < vx; ++i) {
        const int id = newid[vid(i, j, k)];
        if (id >= 0) mesh.vertices.row(id) << xs[i], ys[j], zs[k];
      }

  // 3. Kuhn split. Corner c of a cell has offset (c&1, c>>1&1, c>>2&1). For the axis order
  // (a, b, c) the tet is (000, e_a, e_a+e_b, 111); its orientation is the sign of the permutation
  // (det[e_a, e_a+e_b, e_a+e_b+e_c] = det[e_a, e_b, e_c]), so odd orders swap v1 and v2.
  static const int kOrders[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1},   // even
                                    {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};  // odd
  mesh.elements.reserve(static_cast<size_t>(6 * kept));
  for (std::int64_t k = 0; k < nz; ++k)
    for (std::int64_t j = 0; j < ny; ++j)
      for (std::int64_t i = 0; i < nx; ++i) {
        const int t = tag[i + nx * (j + ny * k)];
        if (t < 0) continue;
        // Mirror the split in every axis whose cell index is odd: corner c maps to c ^ mirror.
        // Opposite faces of the Kuhn cube carry the same diagonal pattern, so the mirrored
        // cells still match their neighbours, and the mesh gains the reflection symmetries of
        // the grid (a single unmirrored diagonal biases large deformations towards (1,1,1)).
        const int mirror = int(i & 1) | int(j & 1) << 1 | int(k & 1) << 2;
        const bool odd_mirror = ((mirror & 1) ^ ((mirror >> 1) & 1) ^ ((mirror >> 2) & 1)) != 0;
        auto corner = [&](int c) {
          c ^= mirror;
          return newid[vid(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))];
        };
        for (int o = 0; o < 6; ++o) {
          const int c1 = 1 << kOrders[o][0];
          const int c2 = c1 | (1 << kOrders[o][1]);
          int v1 = corner(c1), v2 = corner(c2);
          if ((o >= 3) != odd_mirror) std::swap(v1, v2);
          mesh.elements.push_back(MakeTet(corner(0), v1, v2, corner(7), t));
        }
      }
  return mesh;
}

// ------------------------------------------------------------------------------------------------
// ConcentricDisk
// ------------------------------------------------------------------------------------------------

int ConcentricDisk::id(int j, int i) const {
  if (j == 0) return 0;
  const int n = 6 * j;
  return 1 + 3 * j * (j - 1) + ((i % n) + n) % n;
}

int ConcentricDisk::sector(int p) const {
  const int j = ring[p];
  return j == 0 ? 0 : index[p] / (2 * j);
}

long ConcentricDisk::key(int p) const {
  const int j = ring[p];
  if (j == 0) return 0L;
  const int u = index[p] % (2 * j);  // the angular index within the sector
  return long(j) * (2L * rings + 1) + std::min(u, 2 * j - u);  // folded: mirror invariant
}

int ConcentricDisk::rotated(int p, int s) const {
  const int j = ring[p];
  return j == 0 ? p : id(j, index[p] + 2 * j * s);
}

ConcentricDisk MakeConcentricDisk(double radius, int rings) {
  if (!(radius > 0.0) || !std::isfinite(radius))
    throw std::invalid_argument("MakeConcentricDisk: radius must be > 0");
  if (rings < 1 || rings > 2000)
    throw std::invalid_argument("MakeConcentricDisk: rings must be in [1, 2000], got " +
                                std::to_string(rings));
  ConcentricDisk d;
  d.radius = radius;
  d.rings = rings;
  const int np = 1 + 3 * rings * (rings + 1);
  d.points.setZero(np, 2);
  d.ring.assign(np, 0);
  d.index.assign(np, 0);
  const double pi = std::acos(-1.0);
  const double c120 = -0.5, s120 = std::sqrt(3.0) / 2.0;
  for (int j = 1; j <= rings; ++j) {
    const double r = radius * j / rings;
    for (int i0 = 0; i0 < 2 * j; ++i0) {
      const double a = 2.0 * pi * i0 / (6.0 * j);
      const double x = r * std::cos(a), y = r * std::sin(a);
      for (int s = 0; s < 3; ++s) {
        const int p = d.id(j, i0 + 2 * j * s);
        d.ring[p] = j;
        d.index[p] = i0 + 2 * j * s;
        if (s == 0) {
          d.points.row(p) << x, y;
        } else {
          const double sn = (s == 1) ? s120 : -s120;  // rotation by +120 (s=1) or -120 (s=2)
          d.points.row(p) << c120 * x - sn * y, sn * x + c120 * y;
        }
      }
    }
  }
  // Ring 1 fan around the centre.
  for (int o = 0; o < 6; ++o) d.triangles.push_back({0, d.id(1, o), d.id(1, o + 1)});
  // Rings j-1, j: point i of a ring of n points owns the angles (i -+ 1/2) / n turns, and two
  // points of consecutive rings are joined where their intervals overlap: the strip advances on
  // the ring whose current interval ends first, (2i + 1) / 2n (compared exactly as integers).
  // The rule is symmetric under reflection i -> -i as well as under rotation, and it never ties:
  // (2i + 1) j and (2o + 1) (j - 1) differ in parity.
  for (int j = 2; j <= rings; ++j) {
    const long n0 = 6L * (j - 1), n1 = 6L * j;
    long i = 0, o = 0;
    while (i < n0 || o < n1) {
      const bool inner = (o == n1) || (i < n0 && (2 * i + 1) * n1 < (2 * o + 1) * n0);
      if (inner) {
        d.triangles.push_back({d.id(j - 1, int(i)), d.id(j, int(o)), d.id(j - 1, int(i + 1))});
        ++i;
      } else {
        d.triangles.push_back({d.id(j - 1, int(i)), d.id(j, int(o)), d.id(j, int(o + 1))});
        ++o;
      }
    }
  }
  return d;
}

std::array<int, 2> DiskPlaneAxes(int axis) {
  switch (axis) {
    case 0:
      return {{1, 2}};
    case 1:
      return {{0, 2}};
    case 2:
      return {{0, 1}};
  }
  throw std::invalid_argument("DiskPlaneAxes: axis must be 0, 1 or 2, got " + std::to_string(axis));
}

// ------------------------------------------------------------------------------------------------
// ExtrudedDiskTetMesh
// ------------------------------------------------------------------------------------------------

Mesh ExtrudedDiskTetMesh(const DiskExtrusion& p, const DiskRegionFn& region) {
  if (!(p.length > 0.0) || !std::isfinite(p.length))
    throw std::invalid_argument("ExtrudedDiskTetMesh: length must be > 0");
  if (p.layers < 1) throw std::invalid_argument("ExtrudedDiskTetMesh: layers must be >= 1");
  const std::array<int, 2> plane = DiskPlaneAxes(p.axis);
  const ConcentricDisk disk = MakeConcentricDisk(p.radius, p.rings);
  const int np = disk.num_points();
  if (static_cast<std::int64_t>(np) * (p.layers + 1) > (std::int64_t(1) << 30))
    throw std::invalid_argument("ExtrudedDiskTetMesh: mesh too large");

  Mesh mesh;
  mesh.vertices.setZero(static_cast<Eigen::Index>(np) * (p.layers + 1), 3);
  for (int l = 0; l <= p.layers; ++l) {
    const double w = p.base + p.length * l / p.layers;
    for (int q = 0; q < np; ++q) {
      const Eigen::Index v = static_cast<Eigen::Index>(l) * np + q;
      mesh.vertices(v, plane[0]) = disk.points(q, 0);
      mesh.vertices(v, plane[1]) = disk.points(q, 1);
      mesh.vertices(v, p.axis) = w;
    }
  }

  const Eigen::MatrixX3d& X = mesh.vertices;
  auto centroid = [&](const std::array<int, 4>& t) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int v : t) c += X.row(v).transpose();
    return Eigen::Vector3d(c / 4.0);
  };
  mesh.elements.reserve(disk.triangles.size() * 3 * p.layers);
  for (int l = 0; l < p.layers; ++l) {
    const int bot = l * np, top = (l + 1) * np;
    for (const auto& tri : disk.triangles) {
      std::array<int, 3> s = tri;  // order a < b < c by the rotation-invariant key
      for (int x = 0; x < 2; ++x)
        for (int y = 0; y + 1 < 3 - x; ++y)
          if (disk.key(s[y]) > disk.key(s[y + 1])) std::swap(s[y], s[y + 1]);
      const int a = s[0], b = s[1], c = s[2];
      // Sector of this triangle: that of its lowest-key non-centre vertex (rotation-equivariant).
      const int sec = disk.sector(disk.ring[a] == 0 ? b : a);
      const int ca = disk.rotated(a, -sec), cb = disk.rotated(b, -sec), cc = disk.rotated(c, -sec);
      const std::array<std::array<int, 4>, 3> tets = {{{{bot + a, bot + b, bot + c, top + c}},
                                                       {{bot + a, bot + b, top + b, top + c}},
                                                       {{bot + a, top + a, top + b, top + c}}}};
      const std::array<std::array<int, 4>, 3> canon = {
          {{{bot + ca, bot + cb, bot + cc, top + cc}},
           {{bot + ca, bot + cb, top + cb, top + cc}},
           {{bot + ca, top + ca, top + cb, top + cc}}}};
      for (int t = 0; t < 3; ++t) {
        int tag = 0;
        if (region) {
          DiskElementInfo info;
          info.centroid = centroid(tets[t]);
          info.canonical_centroid = centroid(canon[t]);
          info.sector = sec;
          tag = region(info);
          if (tag < 0)
            throw std::invalid_argument("ExtrudedDiskTetMesh: the region callback returned " +
                                        std::to_string(tag) + " (tags must be >= 0)");
        }
        std::array<int, 4> v = tets[t];
        if (TetVolume(X, v[0], v[1], v[2], v[3]) < 0.0) std::swap(v[1], v[2]);
        mesh.elements.push_back(MakeTet(v[0], v[1], v[2], v[3], tag));
      }
    }
  }
  return mesh;
}

Mesh PrismGridMesh(const Eigen::Vector3d& origin, double hx, double hy,
                   const Eigen::Vector2i& cells, const std::vector<double>& z,
                   const PrismClassifier& classify) {
  if (!(hx > 0.0 && hy > 0.0) || !std::isfinite(hx) || !std::isfinite(hy))
    throw std::invalid_argument("PrismGridMesh: cell sizes must be > 0");
  if (cells.minCoeff() < 1)
    throw std::invalid_argument("PrismGridMesh: every cell count must be >= 1");
  if (z.size() < 2) throw std::invalid_argument("PrismGridMesh: expected at least 2 z levels");
  for (size_t l = 1; l < z.size(); ++l)
    if (!(z[l] > z[l - 1])) throw std::invalid_argument("PrismGridMesh: z levels must increase");
  if (!classify) throw std::invalid_argument("PrismGridMesh: no cell classifier given");
  const std::int64_t nx = cells[0], ny = cells[1], nl = static_cast<std::int64_t>(z.size()) - 1;
  const std::int64_t vx = nx + 1, vy = ny + 1;
  if (vx * vy * (nl + 1) > std::int64_t(1) << 30)
    throw std::invalid_argument("PrismGridMesh: grid too large");
  auto vid = [&](std::int64_t i, std::int64_t j, std::int64_t l) { return i + vx * (j + vy * l); };
  std::vector<int> tag(static_cast<size_t>(nx * ny * nl), -1);
  std::vector<char> used(static_cast<size_t>(vx * vy * (nl + 1)), 0);
  for (std::int64_t l = 0; l < nl; ++l)
    for (std::int64_t j = 0; j < ny; ++j)
      for (std::int64_t i = 0; i < nx; ++i) {
        const Eigen::Vector3d centre =
            origin + Eigen::Vector3d((i + 0.5) * hx, (j + 0.5) * hy, 0.5 * (z[l] + z[l + 1]));
        const int t = classify(centre, Eigen::Vector3i(int(i), int(j), int(l)));
        if (t < 0) continue;
        tag[i + nx * (j + ny * l)] = t;
        for (int c = 0; c < 8; ++c)
          used[vid(i + (c & 1), j + ((c >> 1) & 1), l + ((c >> 2) & 1))] = 1;
      }
  std::vector<int> newid(used.size(), -1);
  int nv = 0;
  for (size_t g = 0; g < used.size(); ++g)
    if (used[g]) newid[g] = nv++;
  Mesh mesh;
  mesh.vertices.resize(nv, 3);
  for (std::int64_t l = 0; l <= nl; ++l)
    for (std::int64_t j = 0; j < vy; ++j)
      for (std::int64_t i = 0; i < vx; ++i)
        if (const int id = newid[vid(i, j, l)]; id >= 0)
          mesh.vertices.row(id) =
              (origin + Eigen::Vector3d(double(i) * hx, double(j) * hy, z[l])).transpose();
  for (std::int64_t l = 0; l < nl; ++l)
    for (std::int64_t j = 0; j < ny; ++j)
      for (std::int64_t i = 0; i < nx; ++i) {
        const int t = tag[i + nx * (j + ny * l)];
        if (t < 0) continue;
        auto v = [&](int di, int dj, int dl) { return newid[vid(i + di, j + dj, l + dl)]; };
        // Corners: a = (0,0), b = (1,0), c = (1,1), d = (0,1); both triangles counter-clockwise.
        int tri[2][2][3];  // [triangle][corner][di, dj, unused]
        if (((i + j) & 1) == 0) {
          const int t0[3][2] = {{0, 0}, {1, 0}, {1, 1}}, t1[3][2] = {{0, 0}, {1, 1}, {0, 1}};
          for (int q = 0; q < 3; ++q) {
            tri[0][0][q] = t0[q][0];
            tri[0][1][q] = t0[q][1];
            tri[1][0][q] = t1[q][0];
            tri[1][1][q] = t1[q][1];
          }
        } else {
          const int t0[3][2] = {{0, 0}, {1, 0}, {0, 1}}, t1[3][2] = {{1, 0}, {1, 1}, {0, 1}};
          for (int q = 0; q < 3; ++q) {
            tri[0][0][q] = t0[q][0];
            tri[0][1][q] = t0[q][1];
            tri[1][0][q] = t1[q][0];
            tri[1][1][q] = t1[q][1];
          }
        }
        for (int s = 0; s < 2; ++s) {
          Element e;
          e.type = ElementType::Prism;
          for (int q = 0; q < 3; ++q) {
            e.v[q] = v(tri[s][0][q], tri[s][1][q], 0);
            e.v[q + 3] = v(tri[s][0][q], tri[s][1][q], 1);
          }
          e.region = t;
          mesh.elements.push_back(e);
        }
      }
  return mesh;
}

}  // namespace softkin
