#include "softkin/solver/fk/model.hpp"

#include "softkin/solver/fk/actuation.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace softkin {

void Model::CheckRotationsHeld(const std::vector<int>& part,
                               const std::array<std::vector<char>, 3>& held) const {
  // A small rigid motion u(x) = t + w x (x - o) leaves every prescribed coordinate in place iff
  // e_d . t + (r_v x e_d) . w = 0 for each held (v, d), r_v = x_v - o. Stack these rows a = [e_d,
  // r_v x e_d] (r in units of the part's size) into M = sum a a^T (6 x 6): a (near) zero
  // eigenvalue is a rigid motion the held coordinates do not stop. The energy is invariant under
  // rotations, so the solve would then "converge" to an arbitrary one.
  const Eigen::MatrixX3d& X = scene_.mesh.vertices;
  Eigen::Vector3d lo = X.row(part.front()).transpose(), hi = lo, o = Eigen::Vector3d::Zero();
  int n_held = 0, first_held = -1;
  for (int v : part) {
    lo = lo.cwiseMin(X.row(v).transpose());
    hi = hi.cwiseMax(X.row(v).transpose());
    if (held[0][v] || held[1][v] || held[2][v]) {
      o += X.row(v).transpose();
      if (n_held++ == 0) first_held = v;
    }
  }
  const double size = (hi - lo).norm();
  if (n_held == 0 || !(size > 0)) return;  // translations: reported per axis before
  o /= n_held;
  Eigen::Matrix<double, 6, 6> M = Eigen::Matrix<double, 6, 6>::Zero();
  for (int v : part)
    for (int d = 0; d < 3; ++d) {
      if (!held[d][v]) continue;
      const Eigen::Vector3d r = (X.row(v).transpose() - o) / size;
      Eigen::Matrix<double, 6, 1> a;
      a.head<3>() = Eigen::Vector3d::Unit(d);
      a.tail<3>() = r.cross(Eigen::Vector3d::Unit(d));
      M += a * a.transpose();
    }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(M);
  // The rows have norm ~1; a gap of 1e-10 to the largest eigenvalue separates a genuinely held
  // set (a fixed face: ~(width / size)^2 per vertex) from a collinear one (rounding only).
  if (eig.eigenvalues()[0] > 1e-10 * eig.eigenvalues()[5]) return;
  const Eigen::Matrix<double, 6, 1> z = eig.eigenvectors().col(0);
  Eigen::Vector3d w = z.tail<3>();
  std::string what;
  char buf[200];
  if (w.norm() > 1e-6) {
    w.normalize();
    std::snprintf(buf, sizeof(buf), "rotate about the axis [%.3g, %.3g, %.3g]", w.x(), w.y(),
                  w.z());
    what = buf;
  } else {
    const Eigen::Vector3d t = z.head<3>().normalized();
    std::snprintf(buf, sizeof(buf), "slide along [%.3g, %.3g, %.3g]", t.x(), t.y(), t.z());
    what = buf;
  }
  throw std::invalid_argument(
      "scene '" + scene_.name + "': the connected part of the mesh with vertex " +
      std::to_string(part.front()) + " has " + std::to_string(n_held) +
      " held vertex(es) (first: vertex " + std::to_string(first_held) +
      "), which leave a rigid motion free: it could " + what +
      " (a rigid-motion null space: the energy does not change, so the answer would be "
      "arbitrary). Hold at least three non-collinear points of each part, e.g. a whole face");
}

Model::Model(const Scene& scene) : scene_(scene) {
  scene_.validate();
  const Mesh& m = scene_.mesh;
  const int nv = m.num_vertices();
  const int ne = m.num_elements();
  size_ = m.size();
  if (!(size_ > 0))
    throw std::invalid_argument("scene '" + scene_.name + "': the mesh has zero size");

  // Region -> role lookup.
  std::map<int, std::pair<ElementRole, int>> role;  // region -> (role, actuator or -1)
  std::map<int, const Material*> material;
  for (const auto& [tag, mat] : scene_.body) {
    role[tag] = {ElementRole::Body, -1};
    material[tag] = &mat;
    if (mat.hyperelastic())
      curves_.emplace(tag, FitMooneyRivlinROmega(MooneyRivlin{mat.c1, mat.c2}, mat.r_omega));
  }
  first_group_.assign(scene_.num_actuators(), -1);
  for (int a = 0; a < scene_.num_actuators(); ++a) {
    const Actuator& act = scene_.actuators[a];
    if (act.is_motion()) continue;
    const ElementRole r = act.type == ActuatorType::Pneumatic ? ElementRole::Pneumatic
                          : act.type == ActuatorType::Cable   ? ElementRole::Cable
                                                              : ElementRole::Dea;
    first_group_[a] = num_groups();
    groups_.push_back(Group{a, act.is_signed() ? 1 : 0, {}, 0.0, 0.0});
    for (int reg : act.regions) role[reg] = {r, num_groups() - 1};
    if (act.is_signed()) {
      groups_.push_back(Group{a, -1, {}, 0.0, 0.0});
      for (int reg : act.negative_regions) role[reg] = {r, num_groups() - 1};
    }
  }

  elements_.resize(ne);
  for (int i = 0; i < ne; ++i) {
    const Element& e = m.elements[i];
    ModelElement& me = elements_[i];
    me.v = e.v;
    me.k = e.k();
    auto [r, grp] = role.at(e.region);
    me.role = r;
    me.group = grp;
    ElemRows P = ElemRows::Zero();
    const Eigen::MatrixX3d& rest = scene_.rest_positions_of(e.region);
    for (int j = 0; j < me.k; ++j) P.row(j) = rest.row(e.v[j]);
    me.rest_volume = RowsVolume(P, me.k);
    if (!(me.rest_volume > 0))
      throw std::invalid_argument("scene '" + scene_.name + "': element " + std::to_string(i) +
                                  " has non-positive rest volume; expected an oriented mesh");
    CenterRows(P, me.k);
    me.rest = P;
    if (r == ElementRole::Body) {
      const Material& mat = *material.at(e.region);
      me.r_omega = mat.r_omega;
      me.curve = curve(e.region);
      me.wv = mat.weight * me.rest_volume;
    } else {
      me.r_omega = 1.0;
      me.wv = scene_.actuators[groups_[grp].actuator].weight * me.rest_volume;
      groups_[grp].elements.push_back(i);
      if (r == ElementRole::Pneumatic) {
        me.measure0 = me.rest_volume;
      } else if (r == ElementRole::Dea) {
        me.axis = PrismNormal(me.rest);
        me.measure0 = ActuationMeasure(me, me.rest);
      }
      // Cable elements get their direction and length share below, per cable.
    }
    // "strain" (scene.hpp, ElementEnergy): the term per unit of strain, not of vertex motion.
    if (scene_.element_energy == ElementEnergy::kStrain)
      me.wv /= P.topRows(me.k).squaredNorm() / 3.0;
  }
  for (int g = 0; g < num_groups(); ++g) {
    const Actuator& act = scene_.actuators[groups_[g].actuator];
    if (act.type == ActuatorType::Cable) SetUpCable(g);
    for (int i : groups_[g].elements) groups_[g].rest_measure += elements_[i].measure0;
    if (!(groups_[g].rest_measure > 0))
      throw std::invalid_argument("actuator '" + act.name +
                                  "': its elements have zero rest measure");
  }

  // Incidence (CSR).
  inc_offset_.assign(nv + 1, 0);
  for (const auto& me : elements_)
    for (int j = 0; j < me.k; ++j) ++inc_offset_[me.v[j] + 1];
  for (int v = 0; v < nv; ++v) inc_offset_[v + 1] += inc_offset_[v];
  inc_.resize(inc_offset_[nv]);
  {
    std::vector<int> fill(inc_offset_.begin(), inc_offset_.end() - 1);
    for (int i = 0; i < ne; ++i)
      for (int j = 0; j < elements_[i].k; ++j) inc_[fill[elements_[i].v[j]]++] = i * 6 + j;
  }

  // Global matrix A = sum_i wv_i S_i^T (I - 1/k) S_i.
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(static_cast<size_t>(ne) * 36);
  for (const auto& me : elements_) {
    const double invk = 1.0 / me.k;
    for (int a = 0; a < me.k; ++a)
      for (int b = 0; b < me.k; ++b)
        trip.emplace_back(me.v[a], me.v[b], me.wv * ((a == b ? 1.0 : 0.0) - invk));
  }
  A_.resize(nv, nv);
  A_.setFromTriplets(trip.begin(), trip.end());
  A_.makeCompressed();

  SetUpConstraints();
}

void Model::SetUpConstraints() {
  const int nv = num_vertices();
  // Per axis: which coordinates are prescribed.
  std::array<std::vector<char>, 3> held;
  for (int d = 0; d < 3; ++d) {
    held[d].assign(nv, 0);
    for (int v : scene_.fixed) held[d][v] = 1;
    for (int v : scene_.fixed_axis[d]) held[d][v] = 1;
    for (const auto& a : scene_.actuators)
      if (a.is_motion())
        for (int v : a.vertices) held[d][v] = 1;
  }
  fully_held_.clear();
  num_fully_free_ = 0;
  for (int v = 0; v < nv; ++v) {
    if (held[0][v] && held[1][v] && held[2][v]) fully_held_.push_back(v);
    if (!held[0][v] && !held[1][v] && !held[2][v]) ++num_fully_free_;
  }
  free_offset_[0] = 0;
  for (int d = 0; d < 3; ++d) {
    free_[d].clear();
    free_index_[d].assign(nv, -1);
    for (int v = 0; v < nv; ++v)
      if (!held[d][v]) {
        free_index_[d][v] = static_cast<int>(free_[d].size());
        free_[d].push_back(v);
      }
    free_offset_[d + 1] = free_offset_[d] + static_cast<int>(free_[d].size());
  }

  // Per axis, the global matrix is a weighted graph Laplacian of the mesh (the same for x, y, z):
  // singular exactly when a connected part of the mesh has no prescribed coordinate on that axis
  // (CHOLMOD may not notice a singular Laplacian in floating point). Check it up front.
  {
    std::vector<int> parent(nv);
    for (int v = 0; v < nv; ++v) parent[v] = v;
    auto find = [&](int v) {
      while (parent[v] != v) v = parent[v] = parent[parent[v]];
      return v;
    };
    for (const auto& me : elements_)
      for (int j = 1; j < me.k; ++j) parent[find(me.v[j])] = find(me.v[0]);
    for (int d = 0; d < 3; ++d) {
      std::vector<char> anchored(nv, 0);
      for (int v = 0; v < nv; ++v)
        if (held[d][v]) anchored[find(v)] = 1;
      for (int v = 0; v < nv; ++v) {
        const int root = find(v);
        if (!anchored[root] && !inc_offset_.empty() && inc_offset_[v + 1] > inc_offset_[v])
          throw std::invalid_argument(
              "scene '" + scene_.name + "': vertex " + std::to_string(v) +
              " lies in a connected part of the mesh with nothing fixed, moved or held on axis " +
              std::string(1, "xyz"[d]) + "; that part could drift freely along " +
              std::string(1, "xyz"[d]) + " (a rigid-motion null space)");
      }
    }
    std::vector<std::vector<int>> parts(nv);
    for (int v = 0; v < nv; ++v)
      if (!inc_offset_.empty() && inc_offset_[v + 1] > inc_offset_[v]) parts[find(v)].push_back(v);
    for (const std::vector<int>& part : parts)
      if (!part.empty()) CheckRotationsHeld(part, held);
  }

  const auto t0 = std::chrono::steady_clock::now();
  factors_.clear();
  for (int d = 0; d < 3; ++d) {
    // Axes with the same free set share one factorisation (the usual case: only whole vertices
    // are fixed).
    int same = -1;
    for (int e = 0; e < d && same < 0; ++e)
      if (held[e] == held[d]) same = factor_of_axis_[e];
    if (same >= 0) {
      factor_of_axis_[d] = same;
      continue;
    }
    const int nf = static_cast<int>(free_[d].size());
    if (nf == 0)
      throw std::invalid_argument("scene '" + scene_.name + "': every " + std::string(1, "xyz"[d]) +
                                  " coordinate is prescribed; nothing to solve for");
    std::vector<Eigen::Triplet<double>> tff;
    for (int col = 0; col < A_.outerSize(); ++col) {
      const int fc = free_index_[d][col];
      if (fc < 0) continue;
      for (Eigen::SparseMatrix<double>::InnerIterator it(A_, col); it; ++it) {
        const int fr = free_index_[d][it.row()];
        if (fr >= 0) tff.emplace_back(fr, fc, it.value());
      }
    }
    Factor f;
    f.A_ff = std::make_unique<Eigen::SparseMatrix<double>>(nf, nf);
    f.A_ff->setFromTriplets(tff.begin(), tff.end());
    f.A_ff->makeCompressed();
    f.chol = std::make_unique<CholmodFactorization>();
    // Simplicial LL^T: for these sparse 3D meshes its 3-RHS solve is faster than the supernodal
    // one (3.4 vs 5.3 ms at 47k tets, bench_fk BM_GlobalSolve) and it calls no BLAS, whose own
    // threads would compete with the OpenMP local step on a small machine.
    f.chol->setMode(Eigen::CholmodSimplicialLLt);
    f.chol->compute(*f.A_ff);
    if (f.chol->info() != Eigen::Success)
      throw std::runtime_error(
          "scene '" + scene_.name + "': CHOLMOD could not factor the global matrix of axis " +
          std::string(1, "xyz"[d]) +
          "; is every part of the mesh held in that coordinate (fixed, held or moved vertices)?");
    factor_of_axis_[d] = static_cast<int>(factors_.size());
    factors_.push_back(std::move(f));
  }
  factor_time_s_ = SecondsSince(t0);
}

double Model::GroupRatio(int g, const Eigen::Ref<const Eigen::VectorXd>& c) const {
  const Group& gr = groups_[g];
  return scene_.actuators[gr.actuator].SideRatio(gr.side, c[gr.actuator]);
}

double Model::ActuatorValue(int a, const std::vector<double>& group_ratios,
                            const Eigen::Ref<const Eigen::VectorXd>& c) const {
  const Actuator& act = scene_.actuators[a];
  if (act.is_motion()) return c[a];
  const int g = first_group_[a];
  if (!act.is_signed()) return group_ratios[g];
  // The active side's volume ratio 1 + gain |v|, inverted; the other side is vented.
  if (c[a] > 0.0) return (group_ratios[g] - 1.0) / act.gain;
  if (c[a] < 0.0) return -(group_ratios[g + 1] - 1.0) / act.gain;
  return 0.0;
}

namespace {
const std::vector<int> kNoElements;
}

const std::vector<int>& Model::actuator_elements(int a) const {
  return first_group_[a] < 0 ? kNoElements : groups_[first_group_[a]].elements;
}
double Model::actuator_rest_measure(int a) const {
  return first_group_[a] < 0 ? 0.0 : groups_[first_group_[a]].rest_measure;
}
double Model::actuator_offset(int a) const {
  return first_group_[a] < 0 ? 0.0 : groups_[first_group_[a]].offset;
}

void Model::GatherFree(const Eigen::Ref<const Eigen::MatrixX3d>& X, Eigen::VectorXd* x) const {
  x->resize(num_free_dofs());
  for (int d = 0; d < 3; ++d) {
    const auto& fv = free_[d];
    double* out = x->data() + free_offset_[d];
    for (size_t i = 0; i < fv.size(); ++i) out[i] = X(fv[i], d);
  }
}

void Model::ScatterFree(const Eigen::VectorXd& x, Eigen::MatrixX3d* X) const {
  for (int d = 0; d < 3; ++d) {
    const auto& fv = free_[d];
    const double* in = x.data() + free_offset_[d];
    for (size_t i = 0; i < fv.size(); ++i) (*X)(fv[i], d) = in[i];
  }
}

void Model::ApplyConstraints(const Eigen::Ref<const Eigen::VectorXd>& c,
                             Eigen::MatrixX3d* X) const {
  const Eigen::MatrixX3d& R = rest_positions();
  for (int v : scene_.fixed) X->row(v) = R.row(v);
  for (int d = 0; d < 3; ++d)
    for (int v : scene_.fixed_axis[d]) (*X)(v, d) = R(v, d);
  // Motion actuators compose in actuator order: each moves the position left by the previous ones
  // (e.g. a twist listed before a displacement: rotate about the rest axis, then translate).
  for (const auto& act : scene_.actuators)
    if (act.is_motion())
      for (int v : act.vertices) X->row(v) = R.row(v);
  for (int a = 0; a < scene_.num_actuators(); ++a) {
    const Actuator& act = scene_.actuators[a];
    if (!act.is_motion()) continue;
    for (int v : act.vertices) X->row(v) = act.Move(X->row(v).transpose(), c[a]).transpose();
  }
}

namespace {

/// Barycentric point-in-tet test (inclusive, with a small tolerance).
bool InTet(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
           const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
  Eigen::Matrix3d T;
  T << b - a, c - a, d - a;
  const Eigen::Vector3d l = T.partialPivLu().solve(p - a);
  const double tol = 1e-9;
  return l.allFinite() && l.minCoeff() >= -tol && l.sum() <= 1.0 + tol;
}

bool InElement(const Eigen::Vector3d& p, const Element& e, const Eigen::MatrixX3d& V) {
  auto x = [&](int j) { return Eigen::Vector3d(V.row(e.v[j]).transpose()); };
  if (e.k() == 4) return InTet(p, x(0), x(1), x(2), x(3));
  // The prism's three tets (as in RowsVolume).
  return InTet(p, x(0), x(1), x(2), x(5)) || InTet(p, x(0), x(1), x(5), x(4)) ||
         InTet(p, x(0), x(4), x(5), x(3));
}

}  // namespace

void Model::SetUpCable(int g) {
  const Actuator& act = scene_.actuators[groups_[g].actuator];
  const Mesh& m = scene_.mesh;
  const auto& path = act.path;
  const auto& ids = groups_[g].elements;
  double L = 0;
  for (size_t q = 1; q < path.size(); ++q) L += (path[q] - path[q - 1]).norm();

  // Direction: tangent of the path segment nearest to the element's centroid.
  // Bounding boxes of the elements (for the path sampling below) and of the whole cable region.
  double total_volume = 0;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> boxes;
  boxes.reserve(ids.size());
  for (int i : ids) {
    ModelElement& me = elements_[i];
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    Eigen::Vector3d blo = Eigen::Vector3d::Constant(1e300), bhi = -blo;
    for (int j = 0; j < me.k; ++j) {
      const Eigen::Vector3d x = m.vertices.row(me.v[j]).transpose();
      c += x / me.k;
      blo = blo.cwiseMin(x);
      bhi = bhi.cwiseMax(x);
    }
    boxes.emplace_back(blo, bhi);
    lo = lo.cwiseMin(blo);
    hi = hi.cwiseMax(bhi);
    double best = 1e300;
    for (size_t q = 1; q < path.size(); ++q) {
      const Eigen::Vector3d s = path[q] - path[q - 1];
      const double len2 = s.squaredNorm();
      if (!(len2 > 0)) continue;
      const double t = std::clamp((c - path[q - 1]).dot(s) / len2, 0.0, 1.0);
      const double dist = (path[q - 1] + t * s - c).squaredNorm();
      if (dist < best) {
        best = dist;
        me.axis = s.normalized();
      }
    }
    // Q d with Q = P (P^T P)^-1: F d = D^T Q d for the element's best-fit deformation gradient.
    const Eigen::MatrixXd P = me.rest.topRows(me.k);
    const Eigen::VectorXd qd = P * (P.transpose() * P).ldlt().solve(me.axis);
    for (int j = 0; j < me.k; ++j) me.qd[j] = qd[j];
    total_volume += me.rest_volume;
  }

  // Length of the path inside the actuation elements (sum l_i): sampled at ~L / 4000 spacing,
  // each sample tested against the elements whose bounding box holds it.
  double inside = 0;
  for (size_t q = 1; q < path.size(); ++q) {
    const Eigen::Vector3d s = path[q] - path[q - 1];
    const double len = s.norm();
    const int n = std::max(1, static_cast<int>(std::ceil(4000.0 * len / L)));
    for (int t = 0; t < n; ++t) {
      const Eigen::Vector3d p = path[q - 1] + (t + 0.5) / n * s;
      if ((p.array() < lo.array()).any() || (p.array() > hi.array()).any()) continue;
      for (size_t b = 0; b < ids.size(); ++b) {
        if ((p.array() < boxes[b].first.array()).any() ||
            (p.array() > boxes[b].second.array()).any())
          continue;
        if (InElement(p, m.elements[ids[b]], m.vertices)) {
          inside += len / n;
          break;
        }
      }
    }
  }
  if (!(inside > 0))
    throw std::invalid_argument("cable '" + act.name +
                                "': its path does not pass through its actuation elements");
  // l_i: the inside length shared by volume; L_R: the rest of the path.
  for (int i : ids) elements_[i].measure0 = inside * elements_[i].rest_volume / total_volume;
  groups_[g].offset = std::max(0.0, L - inside);
}

Eigen::VectorXd Model::SolveFree(const Eigen::VectorXd& rhs) const {
  Eigen::VectorXd y(num_free_dofs());
  if (factor_of_axis_[0] == factor_of_axis_[1] && factor_of_axis_[1] == factor_of_axis_[2]) {
    // One factor: solve the three axes as one 3-column right-hand side.
    const int nf = static_cast<int>(free_[0].size());
    Eigen::Map<const Eigen::MatrixXd> B(rhs.data(), nf, 3);
    Eigen::Map<Eigen::MatrixXd> Y(y.data(), nf, 3);
    Y = factors_[factor_of_axis_[0]].chol->solve(B);
    return y;
  }
  for (int d = 0; d < 3; ++d) {
    const int n = free_offset_[d + 1] - free_offset_[d];
    y.segment(free_offset_[d], n) =
        factors_[factor_of_axis_[d]].chol->solve(rhs.segment(free_offset_[d], n));
  }
  return y;
}

}  // namespace softkin
