// Progressive chamber remeshing (thesis Sec. 3.3.2, Algorithm 2; remesh.hpp): the remesh checks
// and RemeshChamber. The driver, SolveProgressive, is in progressive.cpp.
#include "softkin/solver/remesh/remesh.hpp"

#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/common/text_format.hpp"

#include "softkin/solver/collision/collision.hpp"
#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace softkin {

namespace {

using Clock = std::chrono::steady_clock;
using Rows4 = Eigen::Matrix<double, 4, 3>;

Rows4 TetRows(const Element& e, const Eigen::Ref<const Eigen::MatrixX3d>& X) {
  Rows4 r;
  for (int j = 0; j < 4; ++j) r.row(j) = X.row(e.v[j]);
  return r;
}

Eigen::Matrix3d EdgeMatrix(const Rows4& r) {
  Eigen::Matrix3d E;
  for (int j = 0; j < 3; ++j) E.col(j) = (r.row(j + 1) - r.row(0)).transpose();
  return E;
}

bool InRegions(int tag, const std::vector<int>& regions) {
  return std::find(regions.begin(), regions.end(), tag) != regions.end();
}

/// Point location in a set of tets (by uniform grid over their bounding boxes).
class TetLocator {
 public:
  TetLocator(const Mesh& mesh, const Eigen::Ref<const Eigen::MatrixX3d>& X, std::vector<int> tets)
      : mesh_(mesh), X_(X), tets_(std::move(tets)) {
    lo_ = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo_;
    double mean_extent = 0;
    for (int t : tets_) {
      const Rows4 r = TetRows(mesh_.elements[t], X_);
      lo_ = lo_.cwiseMin(r.colwise().minCoeff().transpose());
      hi = hi.cwiseMax(r.colwise().maxCoeff().transpose());
      mean_extent += (r.colwise().maxCoeff() - r.colwise().minCoeff()).maxCoeff();
    }
    h_ = tets_.empty() ? 1.0 : std::max(1e-9, mean_extent / tets_.size());
    for (int d = 0; d < 3; ++d)
      n_[d] = std::max(1, static_cast<int>(std::ceil((hi[d] - lo_[d]) / h_)) + 1);
    for (int t : tets_) {
      const Rows4 r = TetRows(mesh_.elements[t], X_);
      const Eigen::Vector3i a = Cell(r.colwise().minCoeff().transpose()),
                            b = Cell(r.colwise().maxCoeff().transpose());
      for (int i = a[0]; i <= b[0]; ++i)
        for (int j = a[1]; j <= b[1]; ++j)
          for (int k = a[2]; k <= b[2]; ++k) grid_[Key(i, j, k)].push_back(t);
    }
  }

  /// The tet whose smallest barycentric coordinate of p is largest (p inside it if >= 0) and
  /// those coordinates.
  int Locate(const Eigen::Vector3d& p, Eigen::Vector4d* bary) const {
    int best = -1;
    double best_min = -std::numeric_limits<double>::infinity();
    auto test = [&](int t) {
      const Rows4 r = TetRows(mesh_.elements[t], X_);
      const Eigen::Vector3d l = EdgeMatrix(r).partialPivLu().solve(p - r.row(0).transpose());
      const Eigen::Vector4d b(1.0 - l.sum(), l[0], l[1], l[2]);
      if (b.minCoeff() > best_min) {
        best_min = b.minCoeff();
        best = t;
        *bary = b;
      }
    };
    const Eigen::Vector3i c = Cell(p);
    auto it = grid_.find(Key(c[0], c[1], c[2]));
    if (it != grid_.end())
      for (int t : it->second) test(t);
    if (best_min < -1e-9)
      for (int t : tets_) test(t);  // outside every candidate: search all (rare)
    return best;
  }

 private:
  Eigen::Vector3i Cell(const Eigen::Vector3d& p) const {
    Eigen::Vector3i c;
    for (int d = 0; d < 3; ++d)
      c[d] = std::clamp(static_cast<int>(std::floor((p[d] - lo_[d]) / h_)), 0, n_[d] - 1);
    return c;
  }
  long long Key(int i, int j, int k) const {
    return (static_cast<long long>(k) * n_[1] + j) * n_[0] + i;
  }
  const Mesh& mesh_;
  Eigen::Ref<const Eigen::MatrixX3d> X_;
  std::vector<int> tets_;
  Eigen::Vector3d lo_;
  double h_ = 1.0;
  int n_[3] = {1, 1, 1};
  std::unordered_map<long long, std::vector<int>> grid_;
};

std::vector<int> Remap(const std::vector<int>& ids, const std::vector<int>& new_of_old,
                       const std::string& what) {
  std::vector<int> out;
  out.reserve(ids.size());
  for (int v : ids) {
    if (new_of_old[v] < 0)
      throw std::runtime_error(
          "RemeshChamber: " + what + " uses vertex " + std::to_string(v) +
          ", which the chamber remesh removed; expected it outside the chamber's interior");
    out.push_back(new_of_old[v]);
  }
  return out;
}

}  // namespace

// ---- checks
// --------------------------------------------------------------------------------------

bool RemeshCriteria::IsValid(std::string* why) const {
  if (!(alpha_max > 1) || !std::isfinite(alpha_max)) {
    if (why) *why = "alpha_max: expected a finite volume ratio > 1, got " + FormatNumber(alpha_max);
    return false;
  }
  if (!(d_max > 1) || !std::isfinite(d_max)) {
    if (why) *why = "d_max: expected a finite distortion > 1, got " + FormatNumber(d_max);
    return false;
  }
  return true;
}

TetChangeInfo TetChange(const Rows4& reference, const Rows4& current) {
  TetChangeInfo c;
  const Eigen::Matrix3d P = EdgeMatrix(reference), D = EdgeMatrix(current);
  const double vp = P.determinant();
  c.volume_ratio = D.determinant() / vp;
  const Eigen::Matrix3d F = D * P.inverse();
  const Eigen::Vector3d s = Eigen::JacobiSVD<Eigen::Matrix3d>(F).singularValues();
  c.distortion = s[2] > 0 ? std::max(s[0], 1.0 / s[2]) : std::numeric_limits<double>::infinity();
  return c;
}

RemeshCheck CheckRemesh(const Mesh& mesh, const Eigen::Ref<const Eigen::MatrixX3d>& reference,
                        const Eigen::Ref<const Eigen::MatrixX3d>& current,
                        const std::vector<int>& regions, const RemeshCriteria& criteria) {
  if (reference.rows() != mesh.num_vertices() || current.rows() != mesh.num_vertices())
    throw std::invalid_argument("CheckRemesh: positions have " + std::to_string(reference.rows()) +
                                " and " + std::to_string(current.rows()) + " rows; expected " +
                                std::to_string(mesh.num_vertices()) + " (one per vertex)");
  std::string why;
  if (!criteria.IsValid(&why)) throw std::invalid_argument("remesh criteria " + why);
  RemeshCheck out;
  for (int i = 0; i < mesh.num_elements(); ++i) {
    const Element& e = mesh.elements[i];
    if (!InRegions(e.region, regions)) continue;
    if (e.type != ElementType::Tet)
      throw std::invalid_argument("CheckRemesh: chamber element " + std::to_string(i) + " is a " +
                                  ElementTypeToString(e.type) + "; expected tets");
    const TetChangeInfo c = TetChange(TetRows(e, reference), TetRows(e, current));
    ++out.checked;
    // An inverted element counts as infinitely distorted.
    const double d = c.volume_ratio > 0 ? c.distortion : std::numeric_limits<double>::infinity();
    if (c.volume_ratio > criteria.alpha_max) ++out.over_volume;
    if (d > criteria.d_max) ++out.over_distortion;
    out.max_volume_ratio = std::max(out.max_volume_ratio, c.volume_ratio);
    if (d > out.max_distortion || out.worst_element < 0) {
      out.max_distortion = std::max(out.max_distortion, d);
      out.worst_element = i;
    }
  }
  out.needed = out.over_volume > 0 || out.over_distortion > 0;
  return out;
}

bool NeedsRemesh(const Mesh& mesh, const Eigen::Ref<const Eigen::MatrixX3d>& reference,
                 const Eigen::Ref<const Eigen::MatrixX3d>& current, const std::vector<int>& regions,
                 const RemeshCriteria& criteria) {
  return CheckRemesh(mesh, reference, current, regions, criteria).needed;
}

double RegionVolume(const Mesh& mesh, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                    const std::vector<int>& regions) {
  double v = 0;
  for (const auto& e : mesh.elements)
    if (InRegions(e.region, regions)) v += SignedVolume(e, X);
  return v;
}

int ChamberActuator(const Scene& scene) {
  int found = -1;
  for (int a = 0; a < scene.num_actuators(); ++a) {
    const Actuator& act = scene.actuators[a];
    if (act.type != ActuatorType::Pneumatic || act.is_signed() || act.regions.size() != 1 ||
        found >= 0)
      throw std::invalid_argument(
          "scene '" + scene.name +
          "': progressive remeshing needs exactly one actuator, an unsigned "
          "pneumatic chamber on one region; actuator '" +
          act.name + "' (" + ActuatorTypeToString(act.type) + (act.is_signed() ? ", signed" : "") +
          ", " + std::to_string(act.regions.size()) + " region(s)) is " +
          (found >= 0 ? "a second actuator" : "not one"));
    found = a;
  }
  if (found < 0)
    throw std::invalid_argument("scene '" + scene.name +
                                "': progressive remeshing needs one pneumatic chamber "
                                "actuator; the scene has none");
  return found;
}

// ---- RemeshChamber
// -------------------------------------------------------------------------------

const char* RemeshMethodToString(RemeshMethod m) {
  switch (m) {
    case RemeshMethod::Auto:
      return "auto";
    case RemeshMethod::ChamberOnly:
      return "chamber";
    case RemeshMethod::Whole:
      return "whole";
  }
  return "?";
}

bool RemeshMethodFromString(const std::string& s, RemeshMethod* m) {
  for (RemeshMethod x : {RemeshMethod::Auto, RemeshMethod::ChamberOnly, RemeshMethod::Whole})
    if (s == RemeshMethodToString(x)) {
      *m = x;
      return true;
    }
  return false;
}

const char* ChamberRestToString(ChamberRest r) {
  return r == ChamberRest::Remeshed ? "remeshed" : "original";
}

bool ChamberRestFromString(const std::string& s, ChamberRest* r) {
  for (ChamberRest x : {ChamberRest::Remeshed, ChamberRest::Original})
    if (s == ChamberRestToString(x)) {
      *r = x;
      return true;
    }
  return false;
}

bool ChamberRemeshOptions::IsValid(std::string* why) const {
  if (!region.IsValid(why)) return false;
  if (tessellation.cell_size > 0) {
    TessellationOptions t = tessellation;
    t.body_region = 0;
    t.chamber_region = 1;
    if (!t.IsValid(why)) return false;
  }
  return true;
}

namespace {

/// Outward faces of a positively oriented tet (v0..v3): the face opposite v_j.
constexpr int kOutFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

/// The deformed outer surface (faces of the whole mesh used once) and chamber surface (faces of
/// the chamber region used once within it), oriented outwards by the tets' vertex order, with
/// compact vertex numbering; *_old maps a surface vertex to its mesh vertex.
void DeformedSurfaces(const Mesh& mesh, const Eigen::Ref<const Eigen::MatrixX3d>& X, int region,
                      TriangleSurface* chamber, std::vector<int>* chamber_old,
                      TriangleSurface* outer, std::vector<int>* outer_old) {
  struct Use {
    int count = 0, chamber_count = 0;
    std::array<int, 3> outer_face{}, chamber_face{};
  };
  std::map<std::array<int, 3>, Use> faces;
  for (const auto& e : mesh.elements) {
    const bool ch = e.region == region;
    for (const auto& f : kOutFace) {
      const std::array<int, 3> oriented = {e.v[f[0]], e.v[f[1]], e.v[f[2]]};
      std::array<int, 3> key = oriented;
      std::sort(key.begin(), key.end());
      Use& u = faces[key];
      ++u.count;
      u.outer_face = oriented;
      if (ch) {
        ++u.chamber_count;
        u.chamber_face = oriented;
      }
    }
  }
  auto build = [&](bool want_chamber, TriangleSurface* s, std::vector<int>* old,
                   const std::string& name) {
    std::map<int, int> index;
    std::vector<Eigen::Vector3i> F;
    for (const auto& [key, u] : faces) {
      const bool take = want_chamber ? u.chamber_count == 1 : u.count == 1;
      if (!take) continue;
      if (!want_chamber && u.chamber_count == 1)
        throw std::invalid_argument(
            "RemeshChamber: the chamber reaches the outer surface; expected it inside the body");
      const std::array<int, 3>& f = want_chamber ? u.chamber_face : u.outer_face;
      Eigen::Vector3i t;
      for (int k = 0; k < 3; ++k) {
        auto [it, fresh] = index.emplace(f[k], static_cast<int>(index.size()));
        (void)fresh;
        t[k] = it->second;
      }
      F.push_back(t);
    }
    old->assign(index.size(), -1);
    s->vertices.resize(static_cast<int>(index.size()), 3);
    for (const auto& [v, i] : index) {
      (*old)[i] = v;
      s->vertices.row(i) = X.row(v);
    }
    s->faces.resize(static_cast<int>(F.size()), 3);
    for (size_t f = 0; f < F.size(); ++f) s->faces.row(f) = F[f].transpose();
    s->source = name;
  };
  build(true, chamber, chamber_old, "deformed chamber surface S_c^k");
  build(false, outer, outer_old, "deformed outer surface S_b^k");
}

/// Largest distance from a vertex of `from` to the surface `to`, by closest-point queries of a
/// CGAL AABB tree over `to`'s triangles (MovingSurface).
double OneSidedDeviation(const TriangleSurface& from, const TriangleSurface& to) {
  std::vector<std::array<int, 3>> faces(static_cast<size_t>(to.faces.rows()));
  for (int f = 0; f < to.faces.rows(); ++f)
    faces[f] = {to.faces(f, 0), to.faces(f, 1), to.faces(f, 2)};
  MovingSurface tree(std::move(faces));
  tree.Update(to.vertices);
  double worst = 0;
  for (int i = 0; i < from.vertices.rows(); ++i) {
    const Eigen::Vector3d p = from.vertices.row(i).transpose();
    worst = std::max(worst, (tree.ClosestPoint(p) - p).norm());
  }
  return worst;
}

/// Height (relative to the square root of the face's area) UntangleTets wants a vertex above the
/// plane of its opposite face: a small positive margin.
constexpr double kUntangleHeight = 0.05;

/// Moves free (not `held`) vertices of `m` until every tet has a positive volume (positions in
/// m.vertices): each moved vertex must lie on the inner side of the plane of the face opposite it
/// in every incident tet, at a height of at least kUntangleHeight of that face's size; its violated
/// half-spaces are projected onto simultaneously (averaged). The moved set is the free vertices of
/// inverted tets, grown by one ring of neighbours every 50 passes while some remain (at most 400
/// passes, and none after 100 passes without a new low in the number of inverted tets). Returns
/// the number of vertex moves; the caller checks the result.
int UntangleTets(Mesh& m, const std::vector<char>& held) {
  const int nv = m.num_vertices(), ne = m.num_elements();
  std::vector<std::vector<std::pair<int, int>>> star(nv);  // (element, local slot)
  for (int i = 0; i < ne; ++i)
    for (int j = 0; j < 4; ++j) star[m.elements[i].v[j]].emplace_back(i, j);
  // The inverted tets, kept up to date incrementally: a tet's volume changes only when one of its
  // vertices moves, so after the first full scan only the stars of the moved vertices are
  // re-examined (the passes and moves are those of a full scan per pass).
  std::vector<char> inverted(ne, 0);
  std::vector<int> bad;
  for (int i = 0; i < ne; ++i)
    if (!(SignedVolume(m.elements[i], m.vertices) > 0)) {
      inverted[i] = 1;
      bad.push_back(i);
    }
  int moves = 0;
  std::vector<int> active, grown, moved, touched, next;
  std::vector<char> listed(ne, 0);
  auto sort_unique = [](std::vector<int>& v) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
  };
  size_t best = bad.size();
  int best_pass = 0;
  for (int pass = 0; pass < 400; ++pass) {
    if (bad.empty()) break;
    if (bad.size() < best) {
      best = bad.size();
      best_pass = pass;
    }
    // Give up once the count of inverted tets has not reached a new low for 100 passes (two ring
    // growths): on the twisting robot's failing remeshes it creeps from 186 to 167 in the first 200
    // passes and then stays there until pass 400 (about 0.2 s of futile passes per attempt).
    if (pass - best_pass >= 100) break;
    // The free vertices of the inverted tets, ascending and unique (the order they move in).
    active.clear();
    for (int t : bad)
      for (int j = 0; j < 4; ++j)
        if (!held[m.elements[t].v[j]]) active.push_back(m.elements[t].v[j]);
    sort_unique(active);
    if (active.empty()) break;
    for (int ring = 0; ring < pass / 50; ++ring) {
      grown = active;
      for (int v : active)
        for (const auto& [t, j] : star[v])
          for (int k = 0; k < 4; ++k)
            if (!held[m.elements[t].v[k]]) grown.push_back(m.elements[t].v[k]);
      sort_unique(grown);
      active.swap(grown);
    }
    moved.clear();
    for (int v : active) {
      Eigen::Vector3d p = m.vertices.row(v).transpose(), shift = Eigen::Vector3d::Zero();
      int violated = 0;
      for (const auto& [t, j] : star[v]) {
        const Element& e = m.elements[t];
        const Eigen::Vector3d a = m.vertices.row(e.v[kOutFace[j][0]]).transpose();
        const Eigen::Vector3d b = m.vertices.row(e.v[kOutFace[j][1]]).transpose();
        const Eigen::Vector3d c = m.vertices.row(e.v[kOutFace[j][2]]).transpose();
        const Eigen::Vector3d n = (b - a).cross(c - a);  // points away from v_j when positive
        const double nn = n.norm();
        if (!(nn > 0)) continue;
        const double need =
            kUntangleHeight * std::sqrt(0.5 * nn);  // wanted height of v above the face
        const double height = -n.dot(p - a) / nn;
        if (height < need) {
          shift -= (need - height) * n / nn;
          ++violated;
        }
      }
      if (violated == 0) continue;
      m.vertices.row(v) = (p + shift / violated).transpose();
      moved.push_back(v);
      ++moves;
    }
    // Re-examine the tets around the moved vertices.
    touched.clear();
    for (int v : moved)
      for (const auto& [t, j] : star[v]) touched.push_back(t);
    sort_unique(touched);
    for (int t : touched) inverted[t] = SignedVolume(m.elements[t], m.vertices) > 0 ? 0 : 1;
    // bad <- every inverted tet: the listed ones still inverted, and the newly inverted touched
    // ones.
    for (int t : bad) listed[t] = 1;
    next.clear();
    for (int t : bad)
      if (inverted[t]) next.push_back(t);
    for (int t : touched)
      if (inverted[t] && !listed[t]) next.push_back(t);
    for (int t : bad) listed[t] = 0;
    bad.swap(next);
  }
  return moves;
}

/// Mesh_3 sizing of the whole re-tessellation: opt.tessellation, or where it leaves the cell size
/// unset, a facet size of the mean edge length of the deformed outer surface `sb` (cell size
/// twice that, facet distance 0.05 of the cell size). Tags body 0, chamber 1: temporary ones, the
/// body tets' final regions come from the old tets containing them.
TessellationOptions WholeTessellationOptions(const TriangleSurface& sb,
                                             const ChamberRemeshOptions& opt) {
  TessellationOptions topt = opt.tessellation;
  if (!(topt.cell_size > 0)) {
    double sum = 0;
    int n = 0;
    for (int f = 0; f < sb.faces.rows(); ++f)
      for (int k = 0; k < 3; ++k, ++n)
        sum += (sb.vertices.row(sb.faces(f, k)) - sb.vertices.row(sb.faces(f, (k + 1) % 3))).norm();
    topt.facet_size = sum / std::max(1, n);
    topt.cell_size = 2.0 * topt.facet_size;
    topt.facet_distance = 0.05 * topt.cell_size;
  }
  topt.body_region = 0;
  topt.chamber_region = 1;
  return topt;
}

/// The new vertices' rest positions, pulled back through the old deformation (PullBack).
struct PulledBack {
  Eigen::MatrixX3d rest;                  ///< #V' x 3, mm (rows of unknown vertices 0)
  std::vector<char> known;                ///< per new vertex: whether `rest` holds its position
  std::vector<int> fixed;                 ///< new vertices held: on faces of old fixed vertices
  std::vector<std::vector<int>> markers;  ///< per marker: new vertices on faces of its vertices
};

/// Pulls the new mesh `fresh` (deformed positions *positions) back into the old rest frame. A
/// vertex of a body tet goes through the old body tet `locate` finds for it; it is fixed (and
/// moved to its rest position) or in a marker if every old vertex with a barycentric weight
/// above kSupport is. A chamber-interior vertex goes through an old chamber tet that is not
/// inverted at X, where one covers it; the rest stay unknown.
PulledBack PullBack(const Scene& scene, const Eigen::Ref<const Eigen::MatrixX3d>& X, int region,
                    const Mesh& fresh, const TetLocator& locate, Eigen::MatrixX3d* positions) {
  const Mesh& mesh = scene.mesh;
  const int nv = fresh.num_vertices();
  // Which new vertices touch a body tet.
  std::vector<char> in_body(nv, 0);
  for (const auto& e : fresh.elements)
    if (e.region == 0)
      for (int j = 0; j < 4; ++j) in_body[e.v[j]] = 1;
  // The old chamber tets that are not inverted at X: where they cover a new chamber vertex, it is
  // pulled back through them like the body's; the rest (inside tangled parts) are extended
  // harmonically (ExtendHarmonically).
  std::vector<int> old_chamber_ok;
  for (int i = 0; i < mesh.num_elements(); ++i)
    if (mesh.elements[i].region == region && SignedVolume(mesh.elements[i], X) > 0)
      old_chamber_ok.push_back(i);
  TetLocator locate_chamber(mesh, X, old_chamber_ok);
  std::vector<char> fixed_old(mesh.num_vertices(), 0);
  for (int v : scene.fixed) fixed_old[v] = 1;
  std::vector<std::vector<char>> marker_old(scene.markers.size(),
                                            std::vector<char>(mesh.num_vertices(), 0));
  for (size_t m = 0; m < scene.markers.size(); ++m)
    for (int v : scene.markers[m].vertices) marker_old[m][v] = 1;

  PulledBack out;
  out.rest = Eigen::MatrixX3d::Zero(nv, 3);
  out.known.assign(nv, 0);
  out.markers.resize(scene.markers.size());
  constexpr double kSupport = 1e-7;  // barycentric weights below this are "on the face"
  for (int v = 0; v < nv; ++v) {
    if (!in_body[v]) {
      Eigen::Vector4d b;
      const int t =
          old_chamber_ok.empty() ? -1 : locate_chamber.Locate(positions->row(v).transpose(), &b);
      if (t >= 0 && b.minCoeff() >= -1e-9) {
        Eigen::RowVector3d r = Eigen::RowVector3d::Zero();
        for (int j = 0; j < 4; ++j) r += b[j] * mesh.vertices.row(mesh.elements[t].v[j]);
        out.rest.row(v) = r;
        out.known[v] = 1;
      }
      continue;
    }
    Eigen::Vector4d b;
    const int t = locate.Locate(positions->row(v).transpose(), &b);
    const Element& e = mesh.elements[t];
    Eigen::RowVector3d r = Eigen::RowVector3d::Zero();
    bool all_fixed = true;
    std::vector<char> all_marker(scene.markers.size(), 1);
    for (int j = 0; j < 4; ++j) {
      r += b[j] * mesh.vertices.row(e.v[j]);
      if (b[j] > kSupport) {
        all_fixed = all_fixed && fixed_old[e.v[j]];
        for (size_t m = 0; m < out.markers.size(); ++m)
          all_marker[m] = all_marker[m] && marker_old[m][e.v[j]];
      }
    }
    out.rest.row(v) = r;
    out.known[v] = 1;
    if (all_fixed) {
      out.fixed.push_back(v);
      positions->row(v) = r;  // a held vertex sits at its rest position
    }
    for (size_t m = 0; m < out.markers.size(); ++m)
      if (all_marker[m]) out.markers[m].push_back(v);
  }
  return out;
}

/// Chamber-interior vertices not covered by an untangled old chamber tet: harmonic extension of
/// the known rest positions (uniform weights over the edges of `fresh`) into the unknown rows of
/// *rest.
void ExtendHarmonically(const Mesh& fresh, const std::vector<char>& known, Eigen::MatrixX3d* rest) {
  const int nv = fresh.num_vertices();
  std::vector<int> unknown_index(nv, -1);
  int nu = 0;
  for (int v = 0; v < nv; ++v)
    if (!known[v]) unknown_index[v] = nu++;
  if (nu == 0) return;
  std::set<std::pair<int, int>> edges;
  for (const auto& e : fresh.elements)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) edges.insert(std::minmax(e.v[a], e.v[b]));
  std::vector<Eigen::Triplet<double>> trip;
  Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Zero(nu, 3);
  for (const auto& [p, q] : edges)
    for (auto [u, w] : {std::make_pair(p, q), std::make_pair(q, p)}) {
      const int iu = unknown_index[u];
      if (iu < 0) continue;
      trip.emplace_back(iu, iu, 1.0);
      if (unknown_index[w] >= 0)
        trip.emplace_back(iu, unknown_index[w], -1.0);
      else
        rhs.row(iu) += rest->row(w);
    }
  Eigen::SparseMatrix<double> L(nu, nu);
  L.setFromTriplets(trip.begin(), trip.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(L);
  if (ldlt.info() != Eigen::Success)
    throw std::runtime_error(
        "RemeshChamber (whole): a part of the new chamber has no vertex on its boundary");
  const Eigen::MatrixX3d r = ldlt.solve(rhs);
  for (int v = 0; v < nv; ++v)
    if (unknown_index[v] >= 0) rest->row(v) = r.row(unknown_index[v]);
}

/// Interpolated rest shapes of thin new tets can come out inverted where the old deformation
/// bends sharply (near old inverted tets). Untangles them locally (UntangleTets) with the fixed
/// vertices held, and checks every rest volume; returns the number of vertex moves. With
/// ChamberRest::Remeshed (chamber_too false) the chamber's tets take their new (deformed) shapes
/// as rest shapes, so only the body's interpolated rest shapes need to be valid; the
/// chamber-interior vertices' pulled-back positions in fresh->vertices are then only a picture of
/// the chamber in the original frame.
int UntangleRestShapes(const std::vector<int>& fixed, int region, bool chamber_too, Mesh* fresh) {
  const int nv = fresh->num_vertices();
  int untangled = 0;
  {
    std::vector<char> held(nv, 0);
    for (int v : fixed) held[v] = 1;
    if (chamber_too) {
      untangled = UntangleTets(*fresh, held);
    } else {
      Mesh body;
      body.vertices = std::move(fresh->vertices);
      for (const auto& e : fresh->elements)
        if (e.region != region) body.elements.push_back(e);
      untangled = UntangleTets(body, held);
      fresh->vertices = std::move(body.vertices);
    }
  }
  const Eigen::MatrixX3d rest = fresh->vertices;
  for (int i = 0; i < fresh->num_elements(); ++i) {
    if (!chamber_too && fresh->elements[i].region == region) continue;
    const double v = SignedVolume(fresh->elements[i], rest);
    if (!(v > 0))
      throw std::runtime_error("RemeshChamber (whole): new tet " + std::to_string(i) + " (region " +
                               std::to_string(fresh->elements[i].region) +
                               ") has interpolated rest volume " + FormatNumber(v) +
                               " mm^3; expected positive");
  }
  return untangled;
}

/// The whole re-tessellation T(S_c^k, S_b^k) and the interpolated state (remesh.hpp).
void RemeshWhole(const Scene& scene, const Eigen::Ref<const Eigen::MatrixX3d>& X, int region,
                 const ChamberRemeshOptions& opt, ChamberRemesh* out) {
  const Mesh& mesh = scene.mesh;
  if (!scene.fixed_axis[0].empty() || !scene.fixed_axis[1].empty() || !scene.fixed_axis[2].empty())
    throw std::invalid_argument(
        "RemeshChamber: the whole re-tessellation does not support fixed_axis "
        "constraints (scene '" +
        scene.name + "')");
  TriangleSurface sc, sb;
  std::vector<int> sc_old, sb_old;
  DeformedSurfaces(mesh, X, region, &sc, &sc_old, &sb, &sb_old);
  const TessellationOptions topt = WholeTessellationOptions(sb, opt);
  Mesh fresh;
  try {
    fresh = Tessellate(sc, sb, topt);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(
        std::string("RemeshChamber (whole): the deformed surfaces cannot be meshed: ") + e.what());
  }
  const int nv = fresh.num_vertices();
  out->positions = fresh.vertices;

  std::vector<int> old_body;
  for (int i = 0; i < mesh.num_elements(); ++i)
    if (mesh.elements[i].region != region) old_body.push_back(i);
  TetLocator locate(mesh, X, old_body);
  PulledBack pb = PullBack(scene, X, region, fresh, locate, &out->positions);
  ExtendHarmonically(fresh, pb.known, &pb.rest);
  // Body tets take the region (material) of the old tet containing their centroid.
  for (auto& e : fresh.elements) {
    if (e.region == 1) {
      e.region = region;
      continue;
    }
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int j = 0; j < 4; ++j) c += out->positions.row(e.v[j]).transpose() / 4.0;
    Eigen::Vector4d b;
    e.region = mesh.elements[locate.Locate(c, &b)].region;
  }
  fresh.vertices = pb.rest;
  out->untangled_vertices =
      UntangleRestShapes(pb.fixed, region, opt.rest == ChamberRest::Original, &fresh);
  out->scene = scene;
  out->scene.mesh = std::move(fresh);
  out->scene.fixed = pb.fixed;
  std::vector<std::vector<int>>& markers = pb.markers;
  for (size_t m = 0; m < markers.size(); ++m) {
    if (markers[m].empty()) {
      // No new vertex on the old marker's faces (e.g. a single-vertex marker): the new vertex
      // nearest to where the marker was.
      Eigen::RowVector3d p = Eigen::RowVector3d::Zero();
      for (int v : scene.markers[m].vertices)
        p += X.row(v) / static_cast<double>(scene.markers[m].vertices.size());
      int best = 0;
      for (int v = 1; v < nv; ++v)
        if ((out->positions.row(v) - p).squaredNorm() <
            (out->positions.row(best) - p).squaredNorm())
          best = v;
      markers[m] = {best};
    }
    out->scene.markers[m].vertices = markers[m];
  }
  out->old_index.assign(nv, -1);
  out->outer_volume_before = EnclosedVolume(sb);
  {
    TriangleSurface nc, nb;
    std::vector<int> a, b;
    DeformedSurfaces(out->scene.mesh, out->positions, region, &nc, &a, &nb, &b);
    out->outer_volume_after = EnclosedVolume(nb);
    out->outer_deviation = std::max(OneSidedDeviation(nb, sb), OneSidedDeviation(sb, nb));
  }
}

/// Positions the chamber-only re-tessellation can start from: X with the chamber's interior
/// vertices (those no body tet uses) moved by UntangleTets so that no chamber tet is inverted.
/// They carry no physics (the chamber is the gas inside its boundary), and the chamber's volume,
/// being that of its boundary, does not change. Sets *Xc to them if that succeeded and
/// *untangled to the number of vertex moves; returns the number of chamber tets still inverted.
int UntangleChamberInterior(const Mesh& mesh, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                            int region, Eigen::MatrixX3d* Xc, int* untangled) {
  Mesh ch;
  ch.vertices = X;
  std::vector<char> held(mesh.num_vertices(), 0);
  for (const auto& e : mesh.elements) {
    if (e.region == region)
      ch.elements.push_back(e);
    else
      for (int j = 0; j < e.k(); ++j) held[e.v[j]] = 1;
  }
  *untangled = UntangleTets(ch, held);
  int still_inverted = 0;
  for (const auto& e : ch.elements) still_inverted += SignedVolume(e, ch.vertices) > 0 ? 0 : 1;
  if (still_inverted == 0) *Xc = ch.vertices;
  return still_inverted;
}

/// Rest positions of the re-tessellated chamber's vertices (`fresh`, new numbering, deformed
/// positions `positions`): kept vertices keep theirs (old_index); created ones are pulled back
/// through the old piecewise-linear deformation of the chamber at Xc.
void PullBackChamberVertices(const Mesh& mesh, const Eigen::MatrixX3d& Xc, int region,
                             const std::vector<int>& old_index, const Eigen::MatrixX3d& positions,
                             Mesh* fresh) {
  std::vector<int> old_chamber;
  for (int i = 0; i < mesh.num_elements(); ++i)
    if (mesh.elements[i].region == region) old_chamber.push_back(i);
  TetLocator locate(mesh, Xc, old_chamber);
  double worst_outside = 0;
  for (int v = 0; v < fresh->num_vertices(); ++v) {
    const int o = old_index[v];
    if (o >= 0) {
      fresh->vertices.row(v) = mesh.vertices.row(o);
      continue;
    }
    Eigen::Vector4d b;
    const int t = locate.Locate(positions.row(v).transpose(), &b);
    if (t < 0)
      throw std::runtime_error(
          "RemeshChamber: the old chamber has no tets to locate a new vertex in");
    worst_outside = std::min(worst_outside, b.minCoeff());
    const Element& e = mesh.elements[t];
    Eigen::RowVector3d r = Eigen::RowVector3d::Zero();
    for (int j = 0; j < 4; ++j) r += b[j] * mesh.vertices.row(e.v[j]);
    fresh->vertices.row(v) = r;
  }
  if (worst_outside < -1e-6)
    throw std::runtime_error(
        "RemeshChamber: a created vertex lies outside the old chamber (barycentric " +
        FormatNumber(worst_outside) + "); expected every created vertex inside it");
}

/// The chamber-only re-tessellation (RemeshRegionInterior of the chamber at Xc) and the state on
/// it: rest positions, the scene's vertex lists renumbered, the outer surface's volume.
void RemeshChamberOnly(const Scene& scene, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                       const Eigen::MatrixX3d& Xc, int region, const ChamberRemeshOptions& options,
                       ChamberRemesh* out) {
  const Mesh& mesh = scene.mesh;
  RegionRemeshResult rr = RemeshRegionInterior(mesh, Xc, region, options.region);
  out->old_index = rr.old_index;
  out->new_vertices = rr.new_vertices;
  out->removed_vertices = rr.removed_vertices;
  out->target_edge = rr.target_edge;
  out->positions = rr.mesh.vertices;

  Mesh fresh = rr.mesh;
  PullBackChamberVertices(mesh, Xc, region, out->old_index, out->positions, &fresh);
  // With ChamberRest::Remeshed the new chamber tets' rest shapes are their shapes at X (set
  // by RemeshChamber), and the pulled-back positions are only a picture of the chamber in the
  // original frame; they need not be valid tets.
  if (options.rest == ChamberRest::Original) {
    // Where the old deformation bends sharply, a thin new tet's pulled-back rest shape can come
    // out inverted: untangle by moving created vertices only (UntangleTets).
    // Held: the vertices of body tets (their rest positions are the body's memory). The
    // chamber's own vertices, kept or created, may move.
    std::vector<char> held(fresh.num_vertices(), 0);
    for (const auto& e : fresh.elements)
      if (e.region != region)
        for (int j = 0; j < 4; ++j) held[e.v[j]] = 1;
    out->untangled_vertices = UntangleTets(fresh, held);
    for (int i = 0; i < fresh.num_elements(); ++i) {
      const Element& e = fresh.elements[i];
      if (e.region != region) continue;
      const double v = SignedVolume(e, fresh.vertices);
      if (!(v > 0))
        throw std::runtime_error(
            "RemeshChamber: the pulled-back rest shape of new chamber tet " + std::to_string(i) +
            " has volume " + FormatNumber(v) +
            " mm^3; expected positive (the previous deformation "
            "varies too much across it; remesh earlier, i.e. lower alpha_max / d_max)");
    }
  }
  std::vector<int> new_of_old(mesh.num_vertices(), -1);
  for (int v = 0; v < fresh.num_vertices(); ++v)
    if (out->old_index[v] >= 0) new_of_old[out->old_index[v]] = v;
  out->scene = scene;
  out->scene.mesh = std::move(fresh);
  out->scene.fixed = Remap(scene.fixed, new_of_old, "the fixed set");
  for (int d = 0; d < 3; ++d)
    out->scene.fixed_axis[d] = Remap(scene.fixed_axis[d], new_of_old, "fixed_axis");
  for (auto& m : out->scene.markers)
    m.vertices = Remap(m.vertices, new_of_old, "marker '" + m.name + "'");
  for (auto& act : out->scene.actuators)
    if (act.is_motion())
      act.vertices = Remap(act.vertices, new_of_old, "actuator '" + act.name + "'");
  for (auto* ids : {&out->scene.fixed, &out->scene.fixed_axis[0], &out->scene.fixed_axis[1],
                    &out->scene.fixed_axis[2]})
    std::sort(ids->begin(), ids->end());
  TriangleSurface sc, sb;
  std::vector<int> u, w;
  DeformedSurfaces(mesh, X, region, &sc, &u, &sb, &w);
  out->outer_volume_before = out->outer_volume_after = EnclosedVolume(sb);
}

}  // namespace

ChamberRemesh RemeshChamber(const Scene& scene, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                            const ChamberRemeshOptions& options) {
  const auto t0 = Clock::now();
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("chamber remesh option " + why);
  const int a = ChamberActuator(scene);
  const int region = scene.actuators[a].regions[0];
  const Mesh& mesh = scene.mesh;
  if (X.rows() != mesh.num_vertices() || !X.allFinite())
    throw std::invalid_argument("RemeshChamber: expected finite positions, one row per vertex (" +
                                std::to_string(mesh.num_vertices()) + "), got " +
                                std::to_string(X.rows()) + " rows");
  const std::vector<int> regions = {region};
  ChamberRemesh out;
  for (const auto& e : mesh.elements)
    if (e.region == region) {
      ++out.chamber_tets_before;
      if (!(SignedVolume(e, X) > 0)) ++out.inverted_chamber_tets;
    }
  out.chamber_rest_volume_before = RegionVolume(mesh, scene.rest_positions_of(region), regions);
  out.chamber_volume_before = RegionVolume(mesh, X, regions);

  // Positions the chamber-only re-tessellation starts from (UntangleChamberInterior).
  Eigen::MatrixX3d Xc = X;
  int still_inverted = out.inverted_chamber_tets;
  if (options.method != RemeshMethod::Whole && out.inverted_chamber_tets > 0)
    still_inverted = UntangleChamberInterior(mesh, X, region, &Xc, &out.untangled_chamber_vertices);
  RemeshMethod method = options.method;
  if (method == RemeshMethod::Auto) {
    method = still_inverted > 0 ? RemeshMethod::Whole : RemeshMethod::ChamberOnly;
    if (method == RemeshMethod::Whole)
      out.reason = std::to_string(out.inverted_chamber_tets) + " of " +
                   std::to_string(out.chamber_tets_before) + " chamber tets are inverted, " +
                   std::to_string(still_inverted) +
                   " of them cannot be untangled by moving the chamber's interior vertices";
  }
  out.method = method;
  if (method == RemeshMethod::ChamberOnly && options.method == RemeshMethod::Auto) {
    // Auto: if the chamber-only re-tessellation fails, re-tessellate the whole robot.
    ChamberRemeshOptions only = options;
    only.method = RemeshMethod::ChamberOnly;
    try {
      ChamberRemesh r = RemeshChamber(scene, X, only);
      r.seconds = SecondsSince(t0);
      return r;
    } catch (const std::runtime_error& e) {
      method = out.method = RemeshMethod::Whole;
      out.reason = std::string("chamber-only failed: ") + e.what();
    }
  }
  if (method == RemeshMethod::Whole)
    RemeshWhole(scene, X, region, options, &out);
  else
    RemeshChamberOnly(scene, X, Xc, region, options, &out);
  // The chamber's rest shape (ChamberRest): its shape at the remesh, or the pulled-back one now in
  // mesh.vertices.
  out.scene.region_rest = {};
  if (options.rest == ChamberRest::Remeshed) out.scene.region_rest = {{region}, out.positions};
  out.scene.validate();
  out.chamber_tets_after = 0;
  for (const auto& e : out.scene.mesh.elements)
    if (e.region == region) ++out.chamber_tets_after;
  out.chamber_rest_volume_after =
      RegionVolume(out.scene.mesh, out.scene.rest_positions_of(region), regions);
  out.chamber_volume_after = RegionVolume(out.scene.mesh, out.positions, regions);
  out.seconds = SecondsSince(t0);
  return out;
}

}  // namespace softkin
