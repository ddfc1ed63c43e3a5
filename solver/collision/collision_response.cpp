#include "softkin/solver/collision/collision_response.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace softkin {

namespace {
using Clock = std::chrono::steady_clock;
// Face j of a positively oriented tet (the face opposite vertex j), ordered so that its normal
// (x1 - x0) x (x2 - x0) points out of the tet.
constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

bool AllTets(const Mesh& m) {
  for (const auto& e : m.elements)
    if (e.type != ElementType::Tet) return false;
  return true;
}

SpringSystem::Method UpdateMethod(const CollisionOptions& o) {
  return o.update == SpringUpdate::kRefactor ? SpringSystem::Method::kRefactor
                                             : SpringSystem::Method::kUpdown;
}
}  // namespace

CollisionResponse::CollisionResponse(const Model& model, const CollisionOptions& options)
    : model_(model), options_(options), system_(model, UpdateMethod(options)) {
  std::string why;
  if (!options_.IsValid(&why)) throw std::invalid_argument("solver." + why);
  const Mesh& mesh = model.mesh();
  const bool tets = AllTets(mesh);
  if (options_.self && !tets)
    throw std::invalid_argument("scene '" + model.scene().name +
                                "': solver.collision.self needs a tet-only mesh (it has prisms)");
  if (options_.obstacles)
    for (const auto& s : model.scene().obstacles) obstacles_.emplace_back(s);
  if (options_.self) detector_ = std::make_unique<SelfCollisionDetector>(mesh);

  const int nv = mesh.num_vertices();
  if (tets) {
    // Tet adjacency and boundary faces from the sorted list of all faces.
    const int nt = mesh.num_elements();
    struct FaceRef {
      std::array<int, 3> key;
      int slot;  // 4 t + j
    };
    std::vector<FaceRef> faces;
    faces.reserve(static_cast<size_t>(nt) * 4);
    for (int t = 0; t < nt; ++t)
      for (int j = 0; j < 4; ++j) {
        const auto& v = mesh.elements[t].v;
        std::array<int, 3> k = {v[kFace[j][0]], v[kFace[j][1]], v[kFace[j][2]]};
        std::sort(k.begin(), k.end());
        faces.push_back({k, 4 * t + j});
      }
    std::sort(faces.begin(), faces.end(), [](const FaceRef& a, const FaceRef& b) {
      return a.key != b.key ? a.key < b.key : a.slot < b.slot;
    });
    adj_.assign(static_cast<size_t>(nt) * 4, -1);
    for (size_t i = 0; i < faces.size();) {
      size_t j = i + 1;
      while (j < faces.size() && faces[j].key == faces[i].key) ++j;
      if (j - i == 2) {
        adj_[faces[i].slot] = faces[i + 1].slot / 4;
        adj_[faces[i + 1].slot] = faces[i].slot / 4;
      } else if (j - i == 1) {
        const int t = faces[i].slot / 4, f = faces[i].slot % 4;
        const auto& v = mesh.elements[t].v;
        bfaces_.push_back({v[kFace[f][0]], v[kFace[f][1]], v[kFace[f][2]]});
        bface_slot_.push_back(faces[i].slot);
      }  // a face shared by > 2 tets is non-manifold: left without a neighbour
      i = j;
    }
    vface_offset_.assign(nv + 1, 0);
    for (const auto& f : bfaces_)
      for (int v : f) ++vface_offset_[v + 1];
    for (int v = 0; v < nv; ++v) vface_offset_[v + 1] += vface_offset_[v];
    vface_.resize(vface_offset_[nv]);
    std::vector<int> fill(vface_offset_.begin(), vface_offset_.end() - 1);
    for (int f = 0; f < static_cast<int>(bfaces_.size()); ++f)
      for (int v : bfaces_[f]) vface_[fill[v]++] = f;
    for (int v = 0; v < nv; ++v)
      if (vface_offset_[v + 1] > vface_offset_[v]) check_vertices_.push_back(v);
  } else {
    check_vertices_.resize(nv);
    for (int v = 0; v < nv; ++v) check_vertices_[v] = v;
  }

  // Bodies: connected components of the elements (union-find over their vertices).
  {
    std::vector<int> parent(nv);
    for (int v = 0; v < nv; ++v) parent[v] = v;
    auto find = [&](int v) {
      while (parent[v] != v) v = parent[v] = parent[parent[v]];
      return v;
    };
    for (const auto& e : mesh.elements)
      for (int a = 1; a < e.k(); ++a) {
        const int r0 = find(e.v[0]), r1 = find(e.v[a]);
        if (r0 != r1) parent[std::max(r0, r1)] = std::min(r0, r1);
      }
    std::vector<int> label(nv, -1);
    body_.assign(nv, -1);
    for (int v = 0; v < nv; ++v) {
      const int r = find(v);
      if (label[r] < 0) label[r] = num_bodies_++;
      body_[v] = label[r];
    }
  }
  if (tets && num_bodies_ > 1) {
    body_faces_.resize(num_bodies_);
    for (int f = 0; f < static_cast<int>(bfaces_.size()); ++f)
      body_faces_[body_[bfaces_[f][0]]].push_back(f);
  }

  // k: stiffness times the median diagonal entry of A over the tested vertices.
  const Eigen::VectorXd diag = model.A().diagonal();
  std::vector<double> d;
  d.reserve(check_vertices_.size());
  for (int v : check_vertices_)
    if (diag[v] > 0) d.push_back(diag[v]);
  if (d.empty())
    throw std::invalid_argument("collision response: the global matrix has no positive diagonal");
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  k_ = k0_ = options_.stiffness * d[d.size() / 2];
}

CollisionResponse::~CollisionResponse() = default;

Eigen::Vector3d CollisionResponse::VertexNormal(const Eigen::Ref<const Eigen::MatrixX3d>& X,
                                                int v) const {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  if (vface_offset_.empty()) return n;
  for (int q = vface_offset_[v]; q < vface_offset_[v + 1]; ++q) {
    const auto& f = bfaces_[vface_[q]];
    const Eigen::Vector3d a = X.row(f[0]), b = X.row(f[1]), c = X.row(f[2]);
    n += (b - a).cross(c - a);
  }
  const double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

bool CollisionResponse::WalkOut(const Eigen::Ref<const Eigen::MatrixX3d>& X, int v, int tet,
                                const Eigen::Vector3d& dir, Eigen::Vector3d* exit,
                                int* exit_face) const {
  if (adj_.empty() || !(dir.norm() > 0)) return false;
  const Mesh& mesh = model_.mesh();
  const Eigen::Vector3d p0 = X.row(v);
  const double slack = 1e-9 * model_.size();
  int cur = tet;
  // Round-off at an edge or a vertex that the ray runs along can bounce the walk between the
  // tets around it; it usually gets out, so revisits are allowed, but the walk is capped. A
  // straight ray crosses far fewer tets than 4096; the cap was 4 x #tets, and bouncing walks then
  // held one check of a 30k-tet membrane for minutes. A walk whose exit parameter has not
  // advanced in 64 tets is bouncing in place and is given up as well: at 4096 steps each, the
  // failed walks of ~200 contacts took seconds per check on the full-size membrane.
  const int max_steps = std::min(4 * mesh.num_elements() + 16, 4096);
  double t_far = -std::numeric_limits<double>::infinity();
  int last_progress = 0;
  for (int step = 0; step < max_steps; ++step) {
    const auto& e = mesh.elements[cur].v;
    const Eigen::Vector3d x0 = X.row(e[0]);
    Eigen::Matrix3d M;
    M.col(0) = X.row(e[1]).transpose() - x0;
    M.col(1) = X.row(e[2]).transpose() - x0;
    M.col(2) = X.row(e[3]).transpose() - x0;
    const Eigen::PartialPivLU<Eigen::Matrix3d> lu(M);
    if (!(std::abs(M.determinant()) > 0)) return false;
    const Eigen::Vector3d l123 = lu.solve(p0 - x0), g123 = lu.solve(dir);
    const double lam[4] = {1.0 - l123.sum(), l123[0], l123[1], l123[2]};
    const double g[4] = {-g123.sum(), g123[0], g123[1], g123[2]};
    // The ray leaves the tet where the first decreasing barycentric coordinate reaches zero.
    int jout = -1;
    double tout = std::numeric_limits<double>::infinity();
    for (int j = 0; j < 4; ++j) {
      if (!(g[j] < 0)) continue;
      const double t = -lam[j] / g[j];
      if (t < tout) {
        tout = t;
        jout = j;
      }
    }
    if (jout < 0 || !std::isfinite(tout) || tout < -slack) return false;
    if (tout > t_far + slack) {
      t_far = tout;
      last_progress = step;
    } else if (step - last_progress > 64) {
      return false;
    }
    const int next = adj_[4 * cur + jout];
    if (next < 0) {
      *exit = p0 + std::max(0.0, tout) * dir;
      if (exit_face) *exit_face = 4 * cur + jout;
      return true;
    }
    const auto& ne = mesh.elements[next].v;
    if (ne[0] == v || ne[1] == v || ne[2] == v || ne[3] == v) return false;
    cur = next;
  }
  return false;
}

std::vector<MovingSurface> CollisionResponse::MakeBodySurfaces() const {
  std::vector<MovingSurface> out;
  for (const auto& list : body_faces_) {
    std::vector<std::array<int, 3>> tri;
    tri.reserve(list.size());
    for (int f : list) tri.push_back(bfaces_[f]);
    if (tri.empty()) tri.push_back({0, 0, 0});  // a body without a boundary (never queried)
    out.emplace_back(std::move(tri));
  }
  return out;
}

bool CollisionResponse::BodyTarget(const MovingSurface& surface, int b,
                                   const Eigen::Ref<const Eigen::MatrixX3d>& X, int v,
                                   CollisionSpring* s) const {
  if (body_faces_[b].empty()) return false;
  const Eigen::Vector3d p = X.row(v);
  // The closest point among the faces of b that face v's own surface (their outward normals
  // against n(v)): a vertex of a face pressed onto b's top goes back up, not out through a side
  // face of b that it happens to lie on. Without such a face, the closest point of all.
  int tri = -1;
  Eigen::Vector3d c;
  const Eigen::Vector3d n = VertexNormal(X, v);
  if (!(n.norm() > 0) || !surface.ClosestFacing(p, n, &c, &tri)) c = surface.ClosestPoint(p, &tri);
  const int face = body_faces_[b][tri];
  Eigen::Vector3d dir = c - p;
  const double depth = dir.norm();
  // Out of body b through its surface: towards the closest point or, with v on the surface,
  // along the face's outward normal.
  if (depth > 1e-9 * model_.size()) {
    dir /= depth;
  } else {
    const auto& f = bfaces_[face];
    const Eigen::Vector3d x0 = X.row(f[0]), x1 = X.row(f[1]), x2 = X.row(f[2]);
    dir = (x1 - x0).cross(x2 - x0);
    if (!(dir.norm() > 0)) return false;
    dir.normalize();
  }
  s->vertex = v;
  s->kind = CollisionSpring::Kind::Self;
  s->other = -1;
  s->normal = dir;
  s->depth = depth;
  s->exit_face = bface_slot_[face];
  SetSelfTarget(X, c, bfaces_[face], s);
  return true;
}

bool CollisionResponse::SelfTarget(const Eigen::Ref<const Eigen::MatrixX3d>& X, int v, int tet,
                                   CollisionSpring* s) const {
  const auto& e = model_.mesh().elements[tet].v;
  const Eigen::Vector3d centroid =
      (X.row(e[0]) + X.row(e[1]) + X.row(e[2]) + X.row(e[3])).transpose() / 4.0;
  const Eigen::Vector3d p = X.row(v);
  // -n(v) first (the thesis's rule); if that walk fails (the ray turns back into v's own part),
  // the shortest exit among the direction away from the collided tet's centroid and the axes.
  std::vector<Eigen::Vector3d> dirs = {-VertexNormal(X, v), p - centroid};
  double best = std::numeric_limits<double>::infinity();
  for (size_t q = 0; q < dirs.size() + 6; ++q) {
    Eigen::Vector3d dir =
        q < dirs.size() ? dirs[q] : (q % 2 ? 1.0 : -1.0) * Eigen::Vector3d::Unit((q - 2) / 2);
    const double len = dir.norm();
    if (!(len > 0)) continue;
    dir /= len;
    Eigen::Vector3d exit;
    int face = -1;
    if (!WalkOut(X, v, tet, dir, &exit, &face)) continue;
    const double depth = (exit - p).norm();
    if (depth >= best) continue;
    best = depth;
    s->exit_face = face;
    s->vertex = v;
    s->kind = CollisionSpring::Kind::Self;
    s->other = tet;
    s->normal = dir;
    s->depth = depth;
    const auto& fe = model_.mesh().elements[face / 4].v;
    const int j = face % 4;
    SetSelfTarget(X, exit, {fe[kFace[j][0]], fe[kFace[j][1]], fe[kFace[j][2]]}, s);
    if (q == 0) break;  // -n(v) worked
  }
  return std::isfinite(best);
}

void CollisionResponse::SetSelfTarget(const Eigen::Ref<const Eigen::MatrixX3d>& X,
                                      const Eigen::Vector3d& exit, const std::array<int, 3>& face,
                                      CollisionSpring* s) const {
  const Eigen::Vector3d p = X.row(s->vertex);
  const Eigen::Vector3d off = options_.epsilon * s->normal;
  s->face = {-1, -1, -1};
  if (options_.self_spring == SelfSpring::kPair) {
    // Barycentric coordinates of the exit point in the face (clamped into it: the walk's exit
    // lies on the face up to round-off, the closest point on it exactly).
    const Eigen::Vector3d a = X.row(face[0]), b = X.row(face[1]), c = X.row(face[2]);
    const Eigen::Vector3d e1 = b - a, e2 = c - a, r = exit - a;
    const double d11 = e1.dot(e1), d12 = e1.dot(e2), d22 = e2.dot(e2);
    const double det = d11 * d22 - d12 * d12;
    if (det > 1e-12 * d11 * d22) {
      Eigen::Vector3d w;
      w[1] = (d22 * r.dot(e1) - d12 * r.dot(e2)) / det;
      w[2] = (d11 * r.dot(e2) - d12 * r.dot(e1)) / det;
      w[0] = 1.0 - w[1] - w[2];
      w = w.cwiseMax(0.0);
      w /= w.sum();
      s->face = face;
      s->weights = w;
      // The whole overlap: the face moves towards v as v moves out.
      s->target = exit + off;
      s->offset = s->target - s->FacePoint(X);
      return;
    }
    // A degenerate (flat) face: a fixed target, as below.
  }
  // Both sides of a face-to-face contact have vertices inside the other: each spring takes half
  // the overlap (the targets are refreshed at every check, so a one-sided contact still closes,
  // halving each time), plus the offset.
  s->target = p + 0.5 * (exit - p) + off;
}

std::vector<SpringStencil> CollisionResponse::Stencils() const {
  std::vector<SpringStencil> st;
  st.reserve(springs_.size());
  for (const auto& s : springs_)
    if (!IsPlane(s)) st.push_back(s.Stencil());
  return st;
}

void CollisionResponse::RebuildPlanes(bool system_changed) {
  plane_.clear();
  for (const auto& s : springs_)
    if (IsPlane(s)) plane_.push_back({s.vertex, s.normal, s.normal.dot(s.target)});
  if (system_changed) plane_solve_.clear();
  const int m = static_cast<int>(plane_.size());
  const int nf = model_.num_free_dofs();
  // Keep the cached solves of vertices that still have a plane spring; solve for new ones.
  std::vector<std::pair<int, Eigen::VectorXd>> cache;
  plane_solve_of_.assign(m, -1);
  for (int s = 0; s < m; ++s) {
    const int v = plane_[s].vertex;
    if (!cache.empty() && cache.back().first == v) {  // a vertex inside two obstacles
      plane_solve_of_[s] = static_cast<int>(cache.size()) - 1;
      continue;
    }
    auto it = std::lower_bound(
        plane_solve_.begin(), plane_solve_.end(), v,
        [](const std::pair<int, Eigen::VectorXd>& a, int b) { return a.first < b; });
    if (it != plane_solve_.end() && it->first == v) {
      cache.push_back(std::move(*it));
    } else {
      Eigen::VectorXd e = Eigen::VectorXd::Zero(nf);
      for (int d = 0; d < 3; ++d) {
        const int fi = model_.free_index(d)[v];
        if (fi >= 0) e[model_.free_offset(d) + fi] = 1.0;
      }
      cache.emplace_back(v, system_.Solve(e));
    }
    plane_solve_of_[s] = static_cast<int>(cache.size()) - 1;
  }
  plane_solve_ = std::move(cache);
  if (m == 0) return;
  // Capacitance I / k + U^T W: (U^T W)_st = sum_d n_s,d n_t,d (S^-1 e_(v_t,d))_(v_s,d).
  Eigen::MatrixXd C = Eigen::MatrixXd::Identity(m, m) / k_;
  for (int t = 0; t < m; ++t) {
    const Eigen::VectorXd& g = plane_solve_[plane_solve_of_[t]].second;
    for (int s = 0; s < m; ++s)
      for (int d = 0; d < 3; ++d) {
        const int fi = model_.free_index(d)[plane_[s].vertex];
        if (fi >= 0)
          C(s, t) += plane_[s].normal[d] * plane_[t].normal[d] * g[model_.free_offset(d) + fi];
      }
  }
  plane_capacitance_.compute(0.5 * (C + C.transpose()));
}

Eigen::VectorXd CollisionResponse::PlaneDot(const Eigen::VectorXd& x) const {
  Eigen::VectorXd r = Eigen::VectorXd::Zero(plane_.size());
  for (size_t s = 0; s < plane_.size(); ++s)
    for (int d = 0; d < 3; ++d) {
      const int fi = model_.free_index(d)[plane_[s].vertex];
      if (fi >= 0) r[s] += plane_[s].normal[d] * x[model_.free_offset(d) + fi];
    }
  return r;
}

void CollisionResponse::AddPlaneProduct(const Eigen::VectorXd& x, Eigen::VectorXd* y) const {
  if (plane_.empty()) return;
  const Eigen::VectorXd r = PlaneDot(x);
  for (size_t s = 0; s < plane_.size(); ++s)
    for (int d = 0; d < 3; ++d) {
      const int fi = model_.free_index(d)[plane_[s].vertex];
      if (fi >= 0) (*y)[model_.free_offset(d) + fi] += k_ * plane_[s].normal[d] * r[s];
    }
}

void CollisionResponse::AddSpringProduct(const Eigen::VectorXd& x, Eigen::VectorXd* y) const {
  system_.AddSpringProduct(x, y);
  AddPlaneProduct(x, y);
}

Eigen::VectorXd CollisionResponse::Multiply(const Eigen::VectorXd& x) const {
  Eigen::VectorXd y = system_.Multiply(x);
  AddPlaneProduct(x, &y);
  return y;
}

Eigen::VectorXd CollisionResponse::Solve(const Eigen::VectorXd& rhs) const {
  Eigen::VectorXd y = system_.Solve(rhs);
  if (plane_.empty()) return y;
  const Eigen::VectorXd z = plane_capacitance_.solve(PlaneDot(y));
  // y - W z, W's column s = n_s spread over the axis blocks of S^-1 sum_d e_(v_s, d).
  for (size_t s = 0; s < plane_.size(); ++s) {
    const Eigen::VectorXd& g = plane_solve_[plane_solve_of_[s]].second;
    for (int d = 0; d < 3; ++d) {
      const int a = model_.free_offset(d), len = model_.free_offset(d + 1) - a;
      y.segment(a, len).noalias() -= (z[s] * plane_[s].normal[d]) * g.segment(a, len);
    }
  }
  return y;
}

void CollisionResponse::ObstacleTarget(const Eigen::Vector3d& p, int obstacle,
                                       CollisionSpring* s) const {
  Eigen::Vector3d n;
  const Eigen::Vector3d c = obstacles_[obstacle].ClosestPoint(p, &n);
  s->kind = CollisionSpring::Kind::Obstacle;
  s->other = obstacle;
  s->normal = n;
  s->target = c + options_.epsilon * n;
}

namespace {

/// Springs for the obstacle contacts (target: the closest point pushed epsilon out along the
/// obstacle's normal), appended to *next; *obst_vertex receives their vertices, sorted.
void AddObstacleSprings(const std::vector<ObstacleContact>& obst, double epsilon,
                        std::vector<CollisionSpring>* next, std::vector<int>* obst_vertex) {
  obst_vertex->reserve(obst.size());
  for (const auto& c : obst) {
    CollisionSpring s;
    s.vertex = c.vertex;
    s.kind = CollisionSpring::Kind::Obstacle;
    s.other = c.obstacle;
    s.normal = c.normal;
    s.target = c.closest + epsilon * c.normal;
    s.depth = c.depth;
    next->push_back(s);
    obst_vertex->push_back(c.vertex);
  }
  std::sort(obst_vertex->begin(), obst_vertex->end());
}

/// A pair spring of *next (sorted by vertex) whose contact persists on the same face of
/// `springs` (the previous set, sorted by vertex), its point moved by less than a fifth of the
/// face, keeps its weights (so its column of the matrix): the offset takes up the refreshed
/// target.
void KeepPairWeights(const std::vector<CollisionSpring>& springs,
                     const Eigen::Ref<const Eigen::MatrixX3d>& X,
                     std::vector<CollisionSpring>* next) {
  for (auto& s : *next) {
    if (!s.pair()) continue;
    const auto it = std::lower_bound(springs.begin(), springs.end(), s.vertex,
                                     [](const CollisionSpring& a, int v) { return a.vertex < v; });
    if (it == springs.end() || it->vertex != s.vertex || it->face != s.face) continue;
    if ((it->weights - s.weights).cwiseAbs().maxCoeff() > 0.2) continue;
    s.weights = it->weights;
    s.offset = s.target - s.FacePoint(X);
  }
}

/// Where the release test (Eq. 3.8) of self spring s, whose vertex is at p, finds the contact
/// surface: p moved along s.normal onto the current plane of the face it was pushed out through
/// (s.exit_face), plus epsilon; its fixed target if that face is (nearly) parallel to s.normal.
Eigen::Vector3d ExitFaceTarget(const Mesh& mesh, const Eigen::Ref<const Eigen::MatrixX3d>& X,
                               const CollisionSpring& s, const Eigen::Vector3d& p, double epsilon) {
  const auto& e = mesh.elements[s.exit_face / 4].v;
  const int j = s.exit_face % 4;
  const Eigen::Vector3d a = X.row(e[kFace[j][0]]), b = X.row(e[kFace[j][1]]),
                        c = X.row(e[kFace[j][2]]);
  const Eigen::Vector3d m = (b - a).cross(c - a);
  const double mn = m.dot(s.normal);
  if (std::abs(mn) > 1e-3 * m.norm()) return p + (m.dot(a - p) / mn + epsilon) * s.normal;
  return s.target;
}

}  // namespace

bool CollisionResponse::Update(const Eigen::Ref<const Eigen::MatrixX3d>& X) {
  const auto t0 = Clock::now();
  std::vector<SelfContact> self;
  if (detector_) {
    detector_->Update(X);
    self = detector_->Detect();
  }
  std::vector<ObstacleContact> obst;
  if (!obstacles_.empty()) obst = DetectObstacleContacts(obstacles_, X, check_vertices_);
  stats_.check_s += SecondsSince(t0);
  ++stats_.checks;

  const auto t1 = Clock::now();
  std::vector<CollisionSpring> next;
  next.reserve(self.size() + obst.size() + springs_.size());
  // An obstacle contact wins over a self contact of the same vertex: the obstacle does not move.
  std::vector<int> obst_vertex;
  AddObstacleSprings(obst, options_.epsilon, &next, &obst_vertex);
  std::vector<char> fresh(body_faces_.size(), 0);
  for (const auto& c : self) {
    if (std::binary_search(obst_vertex.begin(), obst_vertex.end(), c.vertex)) continue;
    CollisionSpring s;
    const int b = body_[model_.mesh().elements[c.tet].v[0]];
    bool ok;
    if (options_.self_target == SelfTarget::kAuto && !body_faces_.empty() && b != body_[c.vertex]) {
      // Between two bodies: the closest point of the other body's surface.
      if (body_surface_.empty()) body_surface_ = MakeBodySurfaces();
      if (!fresh[b]) {
        body_surface_[b].Update(X);
        fresh[b] = 1;
      }
      ok = BodyTarget(body_surface_[b], b, X, c.vertex, &s);
      s.other = c.tet;
    } else {
      ok = SelfTarget(X, c.vertex, c.tet, &s);
    }
    if (ok)
      next.push_back(s);
    else
      ++stats_.unresolved;
  }
  std::sort(next.begin(), next.end(),
            [](const CollisionSpring& a, const CollisionSpring& b) { return a.vertex < b.vertex; });
  KeepPairWeights(springs_, X, &next);
  // Springs of vertices no longer in collision: release by Eq. 3.8, else keep (obstacle targets
  // follow the closest point as the vertex slides).
  std::vector<CollisionSpring> kept;
  int added = static_cast<int>(next.size());
  for (auto s : springs_) {
    const auto it = std::lower_bound(next.begin(), next.end(), s.vertex,
                                     [](const CollisionSpring& a, int v) { return a.vertex < v; });
    if (it != next.end() && it->vertex == s.vertex) {
      --added;  // still in collision: its spring stays (with a fresh target)
      continue;
    }
    const Eigen::Vector3d p = X.row(s.vertex);
    // Eq. 3.8 is tested against where the contact surface is now. An obstacle spring's target
    // follows the closest point as the vertex slides. A self spring keeps its target while the
    // vertex is out of collision (both parts' springs chasing each other's moving faces would
    // make a slow, lagged iteration); the release test uses the current plane of the face the
    // vertex was pushed out through (the other part may have moved away).
    Eigen::Vector3d surface_target = s.target;
    if (s.kind == CollisionSpring::Kind::Obstacle) {
      ObstacleTarget(p, s.other, &s);
      surface_target = s.target;
    } else if (s.exit_face >= 0) {
      surface_target = ExitFaceTarget(model_.mesh(), X, s, p, options_.epsilon);
    }
    if (s.normal.dot(p - surface_target) > options_.epsilon) {
      ++stats_.springs_released;
      continue;
    }
    s.depth = 0;
    kept.push_back(s);
  }
  stats_.springs_added += added;
  next.insert(next.end(), kept.begin(), kept.end());
  std::sort(next.begin(), next.end(),
            [](const CollisionSpring& a, const CollisionSpring& b) { return a.vertex < b.vertex; });
  springs_ = std::move(next);
  bool changed = system_.SetSprings(Stencils(), k_);
  // The plane springs' normals and offsets follow the refreshed closest points at every check;
  // a changed set of plane-spring vertices changes the matrix too.
  const std::vector<PlaneSpring> planes_before = std::move(plane_);
  RebuildPlanes(changed);
  changed =
      changed ||
      !std::equal(plane_.begin(), plane_.end(), planes_before.begin(), planes_before.end(),
                  [](const PlaneSpring& a, const PlaneSpring& b) { return a.vertex == b.vertex; });
  stats_.max_springs = std::max(stats_.max_springs, static_cast<int>(springs_.size()));
  stats_.response_s += SecondsSince(t1);
  return changed;
}

void CollisionResponse::AddToRhs(const Eigen::Ref<const Eigen::MatrixX3d>& X,
                                 Eigen::VectorXd* Bf) const {
  for (const auto& s : springs_) {
    if (IsPlane(s)) {
      // k n (n . v_c - n . x_prescribed) on the vertex's free coordinates.
      double b = s.normal.dot(s.target);
      for (int d = 0; d < 3; ++d)
        if (model_.free_index(d)[s.vertex] < 0) b -= s.normal[d] * X(s.vertex, d);
      for (int d = 0; d < 3; ++d) {
        const int fi = model_.free_index(d)[s.vertex];
        if (fi >= 0) (*Bf)[model_.free_offset(d) + fi] += k_ * s.normal[d] * b;
      }
      continue;
    }
    const SpringStencil st = s.Stencil();
    const Eigen::Vector3d delta = s.pair() ? s.offset : s.target;
    for (int d = 0; d < 3; ++d) {
      const std::vector<int>& fi = model_.free_index(d);
      // k c (delta - c . x_prescribed) on the free entries of c.
      double a = delta[d];
      for (int j = 0; j < 4; ++j)
        if (st.vertex[j] >= 0 && fi[st.vertex[j]] < 0) a -= st.coef[j] * X(st.vertex[j], d);
      for (int j = 0; j < 4; ++j)
        if (st.vertex[j] >= 0 && fi[st.vertex[j]] >= 0)
          (*Bf)[model_.free_offset(d) + fi[st.vertex[j]]] += k_ * st.coef[j] * a;
    }
  }
}

void CollisionResponse::Reset() {
  springs_.clear();
  k_ = k0_;
  raises_ = 0;
  system_.SetSprings(std::vector<SpringStencil>(), k_);
  RebuildPlanes(true);
  stats_ = CollisionStats();
}

bool CollisionResponse::Stiffen(int max_raises) {
  if (raises_ >= max_raises || springs_.empty()) return false;
  ++raises_;
  ++stats_.stiffenings;
  k_ *= 4.0;
  const auto t0 = Clock::now();
  system_.SetSprings(Stencils(), k_);
  RebuildPlanes(true);
  stats_.response_s += SecondsSince(t0);
  return true;
}

double CollisionResponse::Energy(const Eigen::Ref<const Eigen::MatrixX3d>& X) const {
  double e = 0;
  for (const auto& s : springs_) {
    const Eigen::Vector3d r = X.row(s.vertex).transpose() - s.TargetAt(X);
    e += IsPlane(s) ? k_ * std::pow(s.normal.dot(r), 2) : k_ * r.squaredNorm();
  }
  return e;
}

CollisionCheck CollisionResponse::Check(const Eigen::Ref<const Eigen::MatrixX3d>& X) const {
  CollisionCheck r;
  // Inverted elements (as CountInvertedElements counts them), and the vertices that belong to one.
  const Mesh& mesh = model_.mesh();
  std::vector<char> inverted(mesh.num_elements(), 0), at_inverted(mesh.num_vertices(), 0);
  for (int t = 0; t < mesh.num_elements(); ++t) {
    const Element& e = mesh.elements[t];
    if (SignedVolume(e, X) > 0) continue;
    inverted[t] = 1;
    ++r.inverted_elements;
    if (model_.elements()[t].role == ElementRole::Body) ++r.inverted_body_elements;
    for (int j = 0; j < e.k(); ++j) at_inverted[e.v[j]] = 1;
  }
  std::unique_ptr<SelfCollisionDetector> own;
  SelfCollisionDetector* det = detector_.get();
  if (!det && !adj_.empty()) {
    own = std::make_unique<SelfCollisionDetector>(model_.mesh());
    det = own.get();
  }
  if (det) {
    det->Update(X);
    std::vector<MovingSurface> surfaces;
    std::vector<char> fresh(body_faces_.size(), 0);
    for (const auto& c : det->Detect()) {
      ++r.self_contacts;
      if (at_inverted[c.vertex] || inverted[c.tet]) ++r.tangled_contacts;
      const Eigen::Vector3d p = X.row(c.vertex);
      const int b = body_[model_.mesh().elements[c.tet].v[0]];
      if (!body_faces_.empty() && b != body_[c.vertex] && !body_faces_[b].empty()) {
        // Between two bodies the penetration is the distance to the other body's surface.
        if (surfaces.empty()) surfaces = MakeBodySurfaces();
        if (!fresh[b]) {
          surfaces[b].Update(X);
          fresh[b] = 1;
        }
        r.self_penetration = std::max(r.self_penetration, (surfaces[b].ClosestPoint(p) - p).norm());
        continue;
      }
      const auto& e = model_.mesh().elements[c.tet].v;
      const Eigen::Vector3d centroid =
          (X.row(e[0]) + X.row(e[1]) + X.row(e[2]) + X.row(e[3])).transpose() / 4.0;
      std::vector<Eigen::Vector3d> dirs = {-VertexNormal(X, c.vertex), p - centroid};
      for (int d = 0; d < 3; ++d) {
        dirs.push_back(Eigen::Vector3d::Unit(d));
        dirs.push_back(-Eigen::Vector3d::Unit(d));
      }
      double depth = std::numeric_limits<double>::infinity();
      for (auto dir : dirs) {
        if (!(dir.norm() > 0)) continue;
        dir.normalize();
        Eigen::Vector3d exit;
        if (WalkOut(X, c.vertex, c.tet, dir, &exit)) depth = std::min(depth, (exit - p).norm());
      }
      if (std::isfinite(depth)) r.self_penetration = std::max(r.self_penetration, depth);
    }
  }
  if (!model_.scene().obstacles.empty()) {
    std::vector<Obstacle> local;
    const std::vector<Obstacle>* obs = &obstacles_;
    if (obstacles_.empty()) {  // response to obstacles is off: still report them
      for (const auto& s : model_.scene().obstacles) local.emplace_back(s);
      obs = &local;
    }
    for (const auto& c : DetectObstacleContacts(*obs, X, check_vertices_)) {
      ++r.obstacle_contacts;
      r.obstacle_penetration = std::max(r.obstacle_penetration, c.depth);
    }
  }
  r.max_penetration = std::max(r.self_penetration, r.obstacle_penetration);
  return r;
}

}  // namespace softkin
