// T(S_c, S_b) with CGAL Mesh_3 and the re-tessellation of one region's interior with CGAL's
// tetrahedral remeshing (tessellation.hpp). All of SoftKin's CGAL meshing lives in this file so
// that only one translation unit pays for Mesh_3's compile time.
#include "softkin/solver/remesh/tessellation.hpp"

#include "softkin/solver/common/memory_guard.hpp"
#include "softkin/solver/common/text_format.hpp"
#include "softkin/solver/fk/actuation.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_cell_base_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_polyhedron_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Polyhedral_complex_mesh_domain_3.h>
#include <CGAL/make_mesh_3.h>

#include <CGAL/Polygon_mesh_processing/intersection.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Random.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>

#include <CGAL/Mesh_3/tet_soup_to_c3t3.h>
#include <CGAL/Tetrahedral_remeshing/Remeshing_triangulation_3.h>
#include <CGAL/tetrahedral_remeshing.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace softkin {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using CPoint = K::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<CPoint>;
using Polyhedron = CGAL::Mesh_polyhedron_3<K>::type;
using Domain = CGAL::Polyhedral_complex_mesh_domain_3<K, Polyhedron>;
// Mesh_cell_base_3 instead of the default compact cell: its cells carry time stamps, so Mesh_3
// orders cells by creation, not by address.
using MeshGt = CGAL::details::Mesh_geom_traits_generator<K>::type;
using MeshTr = CGAL::Mesh_triangulation_3<Domain, K, CGAL::Sequential_tag, CGAL::Default,
                                          CGAL::Mesh_cell_base_3<MeshGt, Domain>>::type;
using C3t3 =
    CGAL::Mesh_complex_3_in_triangulation_3<MeshTr, Domain::Corner_index, Domain::Curve_index>;
using Criteria = CGAL::Mesh_criteria_3<MeshTr>;
using RemeshTr = CGAL::Tetrahedral_remeshing::Remeshing_triangulation_3<K>;
using Clock = std::chrono::steady_clock;

std::string SourceOf(const TriangleSurface& s, const char* role) {
  return s.source.empty() ? std::string(role) : s.source;
}

template <class PolygonMesh>
void ToPolygonMesh(const TriangleSurface& s, PolygonMesh* out) {
  std::vector<CPoint> pts;
  pts.reserve(s.vertices.rows());
  for (int i = 0; i < s.vertices.rows(); ++i)
    pts.emplace_back(s.vertices(i, 0), s.vertices(i, 1), s.vertices(i, 2));
  std::vector<std::vector<std::size_t>> polys(s.faces.rows());
  for (int f = 0; f < s.faces.rows(); ++f)
    polys[f] = {static_cast<std::size_t>(s.faces(f, 0)), static_cast<std::size_t>(s.faces(f, 1)),
                static_cast<std::size_t>(s.faces(f, 2))};
  CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(pts, polys, *out);
}

/// Signed volume of the tet (a, b, c, d): ((b - a) x (c - a)) . (d - a) / 6.
double TetVolume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                 const Eigen::Vector3d& d) {
  return (b - a).cross(c - a).dot(d - a) / 6.0;
}

/// Mesh_3 cell sizing field: the chamber's bound (subdomain 2) and the body's.
struct CellSize {
  double body, chamber;
  typedef K::FT FT;
  FT operator()(const CPoint&, const int dim, const Domain::Index& index) const {
    return dim == 3 && index == 2 ? chamber : body;
  }
};

/// Swaps std::cout's buffer for a null one while alive: CGAL's remesher prints progress lines to
/// std::cout in some configurations, and SoftKin's stdout carries JSON.
class SilenceCout {
 public:
  SilenceCout() : old_(std::cout.rdbuf(&null_)) {}
  ~SilenceCout() { std::cout.rdbuf(old_); }

 private:
  struct NullBuf : std::streambuf {
    int overflow(int c) override { return c; }
  } null_;
  std::streambuf* old_;
};

}  // namespace

// ---- options ------------------------------------------------------------------------------------

bool TessellationOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!(cell_size > 0) || !std::isfinite(cell_size))
    return fail("cell_size: expected a finite size > 0 mm, got " + FormatNumber(cell_size));
  if (!(chamber_cell_size >= 0) || !std::isfinite(chamber_cell_size))
    return fail("chamber_cell_size: expected >= 0 mm (0: cell_size), got " +
                FormatNumber(chamber_cell_size));
  if (!(facet_size >= 0) || !std::isfinite(facet_size))
    return fail("facet_size: expected >= 0 mm (0: cell_size), got " + FormatNumber(facet_size));
  if (!(facet_distance >= 0) || !std::isfinite(facet_distance))
    return fail("facet_distance: expected >= 0 mm (0: cell_size / 10), got " +
                FormatNumber(facet_distance));
  if (!(facet_angle > 0 && facet_angle <= 30))
    return fail(
        "facet_angle: expected an angle in (0, 30] degrees (Mesh_3 terminates only up to 30), "
        "got " +
        FormatNumber(facet_angle));
  if (!(radius_edge_ratio >= 2) || !std::isfinite(radius_edge_ratio))
    return fail("radius_edge_ratio: expected a finite ratio >= 2, got " +
                FormatNumber(radius_edge_ratio));
  if (!(feature_angle >= 0 && feature_angle < 180))
    return fail("feature_angle: expected an angle in [0, 180) degrees (0: no protection), got " +
                FormatNumber(feature_angle));
  if (body_region == chamber_region)
    return fail("body_region and chamber_region: expected two different tags, both are " +
                std::to_string(body_region));
  return true;
}

bool RegionRemeshOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!(target_edge >= 0) || !std::isfinite(target_edge))
    return fail("target_edge: expected >= 0 mm (0: the region boundary's mean edge), got " +
                FormatNumber(target_edge));
  if (iterations < 1)
    return fail("iterations: expected an integer >= 1, got " + std::to_string(iterations));
  return true;
}

// ---- surfaces
// -------------------------------------------------------------------------------------

double EnclosedVolume(const TriangleSurface& s) {
  double v = 0;
  for (int f = 0; f < s.faces.rows(); ++f) {
    const Eigen::Vector3d a = s.vertices.row(s.faces(f, 0)).transpose();
    const Eigen::Vector3d b = s.vertices.row(s.faces(f, 1)).transpose();
    const Eigen::Vector3d c = s.vertices.row(s.faces(f, 2)).transpose();
    v += a.dot(b.cross(c));
  }
  return v / 6.0;
}

double EstimateTessellationTets(const TriangleSurface& chamber, const TriangleSurface& body,
                                const TessellationOptions& opt) {
  // A regular tet of circumradius R has edge 4 R / sqrt(6) and volume (edge)^3 / (6 sqrt(2));
  // Mesh_3's tets are smaller than the bound: 2.2-2.5 times as many (a box at sizes 2 and 0.5).
  auto tet_volume = [](double r) {
    const double a = 4.0 * r / std::sqrt(6.0);
    return a * a * a / (6.0 * std::sqrt(2.0));
  };
  const double ccs = opt.chamber_cell_size > 0 ? opt.chamber_cell_size : opt.cell_size;
  const double fs = opt.facet_size > 0 ? opt.facet_size : opt.cell_size;
  const double vc = std::abs(EnclosedVolume(chamber)), vb = std::abs(EnclosedVolume(body)) - vc;
  double area = 0;  // one tet per surface facet of circumradius fs (equilateral: 3 sqrt(3)/4 fs^2)
  for (const TriangleSurface* s : {&chamber, &body})
    for (int f = 0; f < s->faces.rows(); ++f)
      area += TriangleArea(s->vertices.row(s->faces(f, 0)), s->vertices.row(s->faces(f, 1)),
                           s->vertices.row(s->faces(f, 2)));
  return 2.5 * (std::max(vb, 0.0) / tet_volume(opt.cell_size) + vc / tet_volume(ccs)) +
         area / (0.75 * std::sqrt(3.0) * fs * fs);
}

void CheckChamberInBody(TriangleSurface* chamber, TriangleSurface* body) {
  const std::string sc = SourceOf(*chamber, "chamber surface"),
                    sb = SourceOf(*body, "body surface");
  if (chamber->source.empty()) chamber->source = sc;
  if (body->source.empty()) body->source = sb;
  CheckClosedSurface(chamber);
  CheckClosedSurface(body);
  SurfaceMesh mc, mb;
  ToPolygonMesh(*chamber, &mc);
  ToPolygonMesh(*body, &mb);
  namespace PMP = CGAL::Polygon_mesh_processing;
  if (PMP::does_self_intersect(mc))
    throw std::invalid_argument(sc +
                                ": the chamber surface intersects itself; expected a closed "
                                "surface without self-intersections");
  if (PMP::does_self_intersect(mb))
    throw std::invalid_argument(sb +
                                ": the body surface intersects itself; expected a closed surface "
                                "without self-intersections");
  if (PMP::do_intersect(mc, mb))
    throw std::invalid_argument(sc + ": the chamber surface intersects the body surface " + sb +
                                "; expected the chamber strictly inside the body");
  CGAL::Side_of_triangle_mesh<SurfaceMesh, K> inside(mb);
  for (int i = 0; i < chamber->vertices.rows(); ++i) {
    const CPoint p(chamber->vertices(i, 0), chamber->vertices(i, 1), chamber->vertices(i, 2));
    if (inside(p) != CGAL::ON_BOUNDED_SIDE) {
      std::ostringstream os;
      os << sc << ": chamber vertex " << i << " (" << p << ") is not inside the body surface " << sb
         << "; expected the chamber strictly inside the body";
      throw std::invalid_argument(os.str());
    }
  }
}

// ---- T(S_c, S_b)
// ------------------------------------------------------------------------------------

Mesh Tessellate(const TriangleSurface& chamber_in, const TriangleSurface& body_in,
                const TessellationOptions& opt, TessellationReport* report) {
  const auto t0 = Clock::now();
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument("tessellation option " + why);
  TriangleSurface chamber = chamber_in, body = body_in;
  CheckChamberInBody(&chamber, &body);
  const double tets = EstimateTessellationTets(chamber, body, opt);
  CheckMemoryEstimate("tessellation cell size " + FormatNumber(opt.cell_size) + " mm",
                      tets * kTessellationBytesPerTet,
                      "about " + std::to_string(std::llround(tets)) + " tets at " +
                          std::to_string(kTessellationBytesPerTet) + " bytes each",
                      "use a larger cell size");

  // Mesh_3's randomness: the domain's generator and CGAL's default one (used by the refinement
  // and exudation steps). Sliver perturbation is off: it is time-limited, hence not reproducible.
  CGAL::get_default_random() = CGAL::Random(opt.seed);
  CGAL::Random rng(opt.seed);
  std::vector<Polyhedron> patches(2);
  ToPolygonMesh(body, &patches[0]);
  ToPolygonMesh(chamber, &patches[1]);
  // (subdomain on the positive, outer side; subdomain on the negative side) per patch.
  const std::pair<int, int> incident[2] = {{1, 0}, {2, 1}};
  Domain domain(patches.begin(), patches.end(), incident, incident + 2, &rng);
  if (opt.feature_angle > 0) domain.detect_features(opt.feature_angle);

  const double facet_size = opt.facet_size > 0 ? opt.facet_size : opt.cell_size;
  const double facet_distance = opt.facet_distance > 0 ? opt.facet_distance : 0.1 * opt.cell_size;
  namespace P = CGAL::parameters;
  const CellSize cell_size{opt.cell_size,
                           opt.chamber_cell_size > 0 ? opt.chamber_cell_size : opt.cell_size};
  Criteria criteria(P::edge_size = facet_size, P::facet_angle = opt.facet_angle,
                    P::facet_size = facet_size, P::facet_distance = facet_distance,
                    P::cell_radius_edge_ratio = opt.radius_edge_ratio, P::cell_size = cell_size);
  // time_limit = 0: no limit (the default limit is the refinement's wall time, not reproducible).
  const auto perturb = opt.perturb ? P::perturb(P::time_limit = 0) : P::no_perturb();
  const auto exude = opt.exude ? P::exude(P::time_limit = 0) : P::no_exude();
  C3t3 c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria, perturb, exude);

  const MeshTr& tr = c3t3.triangulation();
  auto cp = tr.geom_traits().construct_point_3_object();
  Mesh mesh;
  std::map<MeshTr::Vertex_handle, int> index;
  std::vector<Eigen::Vector3d> verts;
  int body_tets = 0, chamber_tets = 0;
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
    const int sub = c3t3.subdomain_index(c);
    if (sub != 1 && sub != 2) continue;
    Element e;
    e.type = ElementType::Tet;
    e.region = sub == 1 ? opt.body_region : opt.chamber_region;
    for (int j = 0; j < 4; ++j) {
      const auto vh = c->vertex(j);
      auto [it, fresh] = index.emplace(vh, static_cast<int>(verts.size()));
      if (fresh) {
        const CPoint p = cp(tr.point(c, j));
        verts.emplace_back(p.x(), p.y(), p.z());
      }
      e.v[j] = it->second;
    }
    (sub == 1 ? body_tets : chamber_tets)++;
    mesh.elements.push_back(e);
  }
  mesh.vertices.resize(static_cast<int>(verts.size()), 3);
  for (size_t i = 0; i < verts.size(); ++i) mesh.vertices.row(i) = verts[i].transpose();
  if (body_tets == 0 || chamber_tets == 0)
    throw std::runtime_error("T(S_c, S_b): Mesh_3 produced " + std::to_string(body_tets) +
                             " body and " + std::to_string(chamber_tets) + " chamber tets for " +
                             body.source + " and " + chamber.source + " at cell_size " +
                             FormatNumber(opt.cell_size) +
                             " mm; expected both regions meshed (use smaller sizes)");
  // CGAL's cells are positively oriented; orient explicitly anyway (a no-op then) and reject
  // degenerate tets with the mesh module's checks.
  ValidateAndOrient(mesh, "T(" + chamber.source + ", " + body.source + ")");

  if (report) {
    report->vertices = mesh.num_vertices();
    report->tets = mesh.num_tets();
    report->body_tets = body_tets;
    report->chamber_tets = chamber_tets;
    report->body_volume = report->chamber_volume = 0;
    for (const auto& e : mesh.elements)
      (e.region == opt.body_region ? report->body_volume : report->chamber_volume) +=
          SignedVolume(e, mesh.vertices);
    report->chamber_enclosed = EnclosedVolume(chamber);
    report->body_enclosed = EnclosedVolume(body) - report->chamber_enclosed;
    report->seconds = SecondsSince(t0);
  }
  return mesh;
}

// ---- re-tessellation of one region's interior
// -------------------------------------------------------

std::vector<std::array<int, 3>> RegionBoundaryFaces(const Mesh& mesh, int region) {
  static const int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  std::map<std::array<int, 3>, int> count;
  for (const auto& e : mesh.elements) {
    if (e.region != region || e.type != ElementType::Tet) continue;
    for (const auto& f : kFace) {
      std::array<int, 3> t = {e.v[f[0]], e.v[f[1]], e.v[f[2]]};
      std::sort(t.begin(), t.end());
      ++count[t];
    }
  }
  std::vector<std::array<int, 3>> out;
  for (const auto& [t, n] : count)
    if (n == 1) out.push_back(t);
  return out;
}

namespace {

/// Exact coordinates as a hashable key (bit patterns; -0.0 folded to 0.0).
struct CoordKey {
  std::array<std::uint64_t, 3> b;
  bool operator==(const CoordKey& o) const { return b == o.b; }
};
struct CoordHash {
  size_t operator()(const CoordKey& k) const {
    size_t h = 1469598103934665603ull;
    for (auto x : k.b) h = (h ^ x) * 1099511628211ull;
    return h;
  }
};
CoordKey KeyOf(double x, double y, double z) {
  CoordKey k;
  const double v[3] = {x == 0.0 ? 0.0 : x, y == 0.0 ? 0.0 : y, z == 0.0 ? 0.0 : z};
  for (int d = 0; d < 3; ++d) std::memcpy(&k.b[d], &v[d], sizeof(double));
  return k;
}

/// Cell selector for CGAL's remesher: the cells of one subdomain.
struct SubdomainSelector {
  int subdomain;
  bool operator()(RemeshTr::Cell_handle c) const { return c->subdomain_index() == subdomain; }
};

using CoordIndex = std::unordered_map<CoordKey, int, CoordHash>;

/// Throws std::invalid_argument unless the options are valid, X has one finite row per vertex of
/// `mesh`, the mesh has only tets and some of them have region tag `region`.
void CheckRegionRemeshInput(const Mesh& mesh, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                            int region, const RegionRemeshOptions& opt) {
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument("region remesh option " + why);
  const int nv = mesh.num_vertices();
  if (X.rows() != nv)
    throw std::invalid_argument("RemeshRegionInterior: positions have " + std::to_string(X.rows()) +
                                " rows; expected one per mesh vertex (" + std::to_string(nv) + ")");
  if (!X.allFinite()) throw std::invalid_argument("RemeshRegionInterior: positions must be finite");
  if (mesh.num_prisms() > 0)
    throw std::invalid_argument("RemeshRegionInterior: the mesh has prisms; expected a tet mesh");
  const std::vector<int> tags = mesh.regions();
  const auto tag_it = std::find(tags.begin(), tags.end(), region);
  if (tag_it == tags.end())
    throw std::invalid_argument("RemeshRegionInterior: no element has region tag " +
                                std::to_string(region));
}

/// The points of X for CGAL's triangulation, and *by_coord: each position's vertex (throws
/// std::invalid_argument if two vertices share a position).
std::vector<RemeshTr::Point> TriangulationPoints(const Eigen::Ref<const Eigen::MatrixX3d>& X,
                                                 CoordIndex* by_coord) {
  const int nv = static_cast<int>(X.rows());
  by_coord->reserve(nv * 2);
  std::vector<RemeshTr::Point> pts;
  pts.reserve(nv);
  for (int i = 0; i < nv; ++i) {
    pts.emplace_back(X(i, 0), X(i, 1), X(i, 2));
    const CoordKey key = KeyOf(X(i, 0), X(i, 1), X(i, 2));
    if (!by_coord->emplace(key, i).second)
      throw std::invalid_argument("RemeshRegionInterior: vertices " +
                                  std::to_string((*by_coord)[key]) + " and " + std::to_string(i) +
                                  " are at the same position; expected distinct positions");
  }
  return pts;
}

/// The tets as CGAL cells (4 vertices and a subdomain index: 1 for the region, 0 for every other
/// tet); *region_tets counts the region's. Throws std::invalid_argument for a non-tet element or
/// a region tet not positively oriented at X.
std::vector<std::array<int, 5>> TriangulationCells(const Mesh& mesh,
                                                   const Eigen::Ref<const Eigen::MatrixX3d>& X,
                                                   int region, int* region_tets) {
  std::vector<std::array<int, 5>> cells;
  cells.reserve(mesh.elements.size());
  *region_tets = 0;
  for (int i = 0; i < mesh.num_elements(); ++i) {
    const Element& e = mesh.elements[i];
    if (e.type != ElementType::Tet)
      throw std::invalid_argument("RemeshRegionInterior: element " + std::to_string(i) +
                                  " is not a tet");
    const double vol = TetVolume(X.row(e.v[0]).transpose(), X.row(e.v[1]).transpose(),
                                 X.row(e.v[2]).transpose(), X.row(e.v[3]).transpose());
    if (e.region == region && !(vol > 0))
      throw std::invalid_argument(
          "RemeshRegionInterior: tet " + std::to_string(i) + " (region " +
          std::to_string(e.region) + ") has volume " + FormatNumber(vol) +
          " mm^3 at the given positions; expected the region's tets positively oriented");
    cells.push_back({e.v[0], e.v[1], e.v[2], e.v[3], e.region == region ? 1 : 0});
    if (e.region == region) ++*region_tets;
  }
  return cells;
}

/// The remeshed region's cells read back from CGAL's triangulation.
struct RemeshedCells {
  std::vector<Eigen::Vector3d> fresh;    ///< positions of created vertices
  std::vector<std::array<int, 4>> tets;  ///< old vertex index >= 0, or -(1 + fresh id)
  std::map<int, int> other_count;        ///< cells per subdomain index outside the region
};

/// Reads the cells of subdomain `selected` back from `tr`: vertices at a position of the input
/// (by_coord) keep their index, the others are created (in the order of first use).
RemeshedCells ReadRemeshedCells(const RemeshTr& tr, int selected, const CoordIndex& by_coord) {
  RemeshedCells out;
  std::map<RemeshTr::Vertex_handle, int> fresh_index;
  for (auto c : tr.finite_cell_handles()) {
    const int sub = c->subdomain_index();
    if (sub != selected) {
      ++out.other_count[sub];
      continue;
    }
    std::array<int, 4> t{};
    for (int j = 0; j < 4; ++j) {
      const auto vh = c->vertex(j);
      const auto& p = vh->point();
      auto it = by_coord.find(KeyOf(p.x(), p.y(), p.z()));
      if (it != by_coord.end()) {
        t[j] = it->second;
      } else {
        auto [f, isnew] = fresh_index.emplace(vh, static_cast<int>(out.fresh.size()));
        if (isnew) out.fresh.emplace_back(p.x(), p.y(), p.z());
        t[j] = -(1 + f->second);
      }
    }
    out.tets.push_back(t);
  }
  return out;
}

/// Back to a Mesh: the vertices still used (kept, in their order) and the created ones, the other
/// regions' elements as they were, then the region's new tets (each checked positive).
void AssembleRemeshedMesh(const Mesh& mesh, const Eigen::Ref<const Eigen::MatrixX3d>& X, int region,
                          const RemeshedCells& cells, RegionRemeshResult* out) {
  const int nv = mesh.num_vertices();
  std::vector<int> new_of_old(nv, -1);
  std::vector<char> used(nv, 0);
  for (const auto& e : mesh.elements)
    if (e.region != region)
      for (int j = 0; j < 4; ++j) used[e.v[j]] = 1;
  for (const auto& t : cells.tets)
    for (int j = 0; j < 4; ++j)
      if (t[j] >= 0) used[t[j]] = 1;
  int n = 0;
  for (int i = 0; i < nv; ++i)
    if (used[i]) {
      new_of_old[i] = n++;
      out->old_index.push_back(i);
    }
  out->kept_vertices = n;
  out->removed_vertices = nv - n;
  out->new_vertices = static_cast<int>(cells.fresh.size());
  for (int f = 0; f < out->new_vertices; ++f) out->old_index.push_back(-1);
  out->mesh.vertices.resize(n + out->new_vertices, 3);
  for (int i = 0; i < nv; ++i)
    if (new_of_old[i] >= 0) out->mesh.vertices.row(new_of_old[i]) = X.row(i);
  for (int f = 0; f < out->new_vertices; ++f)
    out->mesh.vertices.row(n + f) = cells.fresh[f].transpose();
  for (const auto& e : mesh.elements) {
    if (e.region == region) continue;
    Element m = e;
    for (int j = 0; j < 4; ++j) m.v[j] = new_of_old[e.v[j]];
    out->mesh.elements.push_back(m);
  }
  for (const auto& t : cells.tets) {
    Element m;
    m.type = ElementType::Tet;
    m.region = region;
    for (int j = 0; j < 4; ++j) m.v[j] = t[j] >= 0 ? new_of_old[t[j]] : n + (-t[j] - 1);
    const Eigen::MatrixX3d& V = out->mesh.vertices;
    const double vol = TetVolume(V.row(m.v[0]).transpose(), V.row(m.v[1]).transpose(),
                                 V.row(m.v[2]).transpose(), V.row(m.v[3]).transpose());
    if (!(vol > 0))
      throw std::runtime_error("RemeshRegionInterior: CGAL's remesher produced a tet of volume " +
                               FormatNumber(vol) + " mm^3 in region " + std::to_string(region) +
                               "; expected positive volumes");
    out->mesh.elements.push_back(m);
  }
  out->region_tets_after = static_cast<int>(cells.tets.size());
}

}  // namespace

RegionRemeshResult RemeshRegionInterior(const Mesh& mesh,
                                        const Eigen::Ref<const Eigen::MatrixX3d>& X, int region,
                                        const RegionRemeshOptions& opt) {
  const auto t0 = Clock::now();
  CheckRegionRemeshInput(mesh, X, region, opt);
  // Subdomain indices of the CGAL triangulation: 1 for the region, 0 ("outside the domain", like
  // the cells Mesh_3 leaves outside) for every other tet. CGAL's remesher treats every cell with a
  // non-zero index as part of the complex and remeshes it whatever the cell selector says
  // (measured with CGAL 5.5: a box body around a remeshed box chamber went from 2,075 to 72,112
  // tets), so the other regions must not carry one (TriangulationCells).
  auto subdomain_of = [region](int tag) { return tag == region ? 1 : 0; };
  const int selected = 1;

  CoordIndex by_coord;
  const std::vector<RemeshTr::Point> pts = TriangulationPoints(X, &by_coord);
  int region_before = 0;
  const std::vector<std::array<int, 5>> cells = TriangulationCells(mesh, X, region, &region_before);

  const std::vector<std::array<int, 3>> boundary_before = RegionBoundaryFaces(mesh, region);
  double target = opt.target_edge;
  if (!(target > 0)) {
    std::set<std::pair<int, int>> edges;
    for (const auto& f : boundary_before)
      for (int k = 0; k < 3; ++k) edges.insert(std::minmax(f[k], f[(k + 1) % 3]));
    double sum = 0;
    for (const auto& [a, b] : edges) sum += (X.row(a) - X.row(b)).norm();
    target = edges.empty() ? 1.0 : sum / edges.size();
  }

  CGAL::get_default_random() = CGAL::Random(opt.seed);
  RemeshTr tr;
  std::vector<RemeshTr::Vertex_handle> handles;
  const std::map<std::array<int, 3>, RemeshTr::Cell::Surface_patch_index> no_patches;
  if (!CGAL::build_triangulation<RemeshTr, false>(tr, pts, cells, no_patches, handles, false,
                                                  false))
    throw std::runtime_error(
        "RemeshRegionInterior: CGAL could not build a triangulation from the tets "
        "(is the mesh conforming and its boundary a manifold surface?)");
  {
    SilenceCout quiet;
    namespace P = CGAL::parameters;
    CGAL::tetrahedral_isotropic_remeshing(tr, target,
                                          P::number_of_iterations(opt.iterations)
                                              .remesh_boundaries(false)
                                              .cell_is_selected_map(SubdomainSelector{selected}));
  }

  const RemeshedCells remeshed = ReadRemeshedCells(tr, selected, by_coord);
  // The other regions' cells must be untouched.
  std::map<int, int> other_before;
  for (const auto& e : mesh.elements)
    if (e.region != region) ++other_before[subdomain_of(e.region)];
  if (remeshed.other_count != other_before) {
    std::ostringstream os;
    os << "RemeshRegionInterior: CGAL's remesher changed tets outside region " << region
       << "; expected them kept (tets per subdomain before:";
    for (const auto& [k, n] : other_before) os << " " << k << ":" << n;
    os << ", after:";
    for (const auto& [k, n] : remeshed.other_count) os << " " << k << ":" << n;
    os << ")";
    throw std::runtime_error(os.str());
  }

  RegionRemeshResult out;
  out.target_edge = target;
  out.region_tets_before = region_before;
  AssembleRemeshedMesh(mesh, X, region, remeshed, &out);

  // Conformity: the region's boundary triangles are exactly the ones it had.
  std::vector<std::array<int, 3>> after = RegionBoundaryFaces(out.mesh, region);
  for (auto& f : after) {
    for (int& v : f) v = out.old_index[v];
    std::sort(f.begin(), f.end());
  }
  std::sort(after.begin(), after.end());
  if (after != boundary_before)
    throw std::runtime_error(
        "RemeshRegionInterior: the re-tessellated region " + std::to_string(region) + " has " +
        std::to_string(after.size()) + " boundary triangles, not the " +
        std::to_string(boundary_before.size()) + " it had; expected its boundary kept");
  out.seconds = SecondsSince(t0);
  return out;
}

}  // namespace softkin
