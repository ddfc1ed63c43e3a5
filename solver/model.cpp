#include "solver/model.hpp"

#include "solver/actuation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace softkin {

Model::Model(const Scene& scene) : scene_(scene) {
  scene_.validate();
  const Mesh& m = scene_.mesh;
  const int nv = m.num_vertices();
  const int ne = m.num_elements();
  size_ = m.size();
  if (!(size_ > 0)) throw std::invalid_argument("scene '" + scene_.name + "': the mesh has zero size");

  // Region -> role lookup.
  std::map<int, std::pair<ElementRole, int>> role;  // region -> (role, actuator or -1)
  std::map<int, const Material*> material;
  for (const auto& [tag, mat] : scene_.body) {
    role[tag] = {ElementRole::Body, -1};
    material[tag] = &mat;
  }
  actuator_elements_.assign(scene_.num_actuators(), {});
  actuator_rest_measure_.assign(scene_.num_actuators(), 0.0);
  actuator_offset_.assign(scene_.num_actuators(), 0.0);
  for (int a = 0; a < scene_.num_actuators(); ++a) {
    const Actuator& act = scene_.actuators[a];
    const ElementRole r = act.type == ActuatorType::Pneumatic ? ElementRole::Pneumatic
                          : act.type == ActuatorType::Cable   ? ElementRole::Cable
                                                              : ElementRole::Dea;
    for (int reg : act.regions) role[reg] = {r, a};
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
    for (int j = 0; j < me.k; ++j) P.row(j) = m.vertices.row(e.v[j]);
    me.rest_volume = RowsVolume(P, me.k);
    if (!(me.rest_volume > 0))
      throw std::invalid_argument("scene '" + scene_.name + "': element " + std::to_string(i) +
                                  " has non-positive rest volume; expected an oriented mesh");
    CenterRows(P, me.k);
    me.rest = P;
    if (r == ElementRole::Body) {
      const Material& mat = *material.at(e.region);
      me.r_omega = mat.r_omega;
      me.wv = mat.weight * me.rest_volume;
    } else {
      me.r_omega = 1.0;
      me.wv = scene_.actuators[grp].weight * me.rest_volume;
      actuator_elements_[grp].push_back(i);
      if (r == ElementRole::Pneumatic) {
        me.measure0 = me.rest_volume;
      } else if (r == ElementRole::Dea) {
        me.axis = PrismNormal(me.rest);
        me.measure0 = ActuationMeasure(me, me.rest);
      }
      // Cable elements get their direction and length share below, per cable.
    }
  }
  for (int a = 0; a < scene_.num_actuators(); ++a) {
    if (scene_.actuators[a].type == ActuatorType::Cable) SetUpCable(a);
    for (int i : actuator_elements_[a]) actuator_rest_measure_[a] += elements_[i].measure0;
    if (!(actuator_rest_measure_[a] > 0))
      throw std::invalid_argument("actuator '" + scene_.actuators[a].name +
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

  free_index_.assign(nv, -1);
  std::vector<int> fixed_index(nv, -1);
  for (size_t c = 0; c < scene_.fixed.size(); ++c) fixed_index[scene_.fixed[c]] = static_cast<int>(c);
  for (int v = 0; v < nv; ++v)
    if (fixed_index[v] < 0) {
      free_index_[v] = static_cast<int>(free_vertices_.size());
      free_vertices_.push_back(v);
    }
  std::vector<Eigen::Triplet<double>> tff, tfc;
  for (int col = 0; col < A_.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(A_, col); it; ++it) {
      const int fr = free_index_[it.row()];
      if (fr < 0) continue;
      if (free_index_[col] >= 0) {
        tff.emplace_back(fr, free_index_[col], it.value());
      } else {
        tfc.emplace_back(fr, fixed_index[col], it.value());
      }
    }
  A_ff_.resize(num_free(), num_free());
  A_ff_.setFromTriplets(tff.begin(), tff.end());
  A_ff_.makeCompressed();
  A_fc_.resize(num_free(), static_cast<int>(scene_.fixed.size()));
  A_fc_.setFromTriplets(tfc.begin(), tfc.end());
  A_fc_.makeCompressed();

  const auto t0 = std::chrono::steady_clock::now();
  // Simplicial LL^T: for these sparse 3D meshes its 3-RHS solve is faster than the supernodal one
  // (3.4 vs 5.3 ms at 47k tets, bench_fk BM_GlobalSolve) and it calls no BLAS, whose own threads
  // would compete with the OpenMP local step on a small machine.
  chol_.setMode(Eigen::CholmodSimplicialLLt);
  chol_.compute(A_ff_);
  factor_time_s_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (chol_.info() != Eigen::Success)
    throw std::runtime_error("scene '" + scene_.name +
                             "': CHOLMOD could not factor the global matrix; is every part of the "
                             "mesh connected to a fixed vertex?");
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

void Model::SetUpCable(int a) {
  const Actuator& act = scene_.actuators[a];
  const Mesh& m = scene_.mesh;
  const auto& path = act.path;
  const auto& ids = actuator_elements_[a];
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
  actuator_offset_[a] = std::max(0.0, L - inside);
}

Eigen::MatrixX3d Model::SolveFree(const Eigen::Ref<const Eigen::MatrixX3d>& rhs) const {
  return chol_.solve(rhs);
}

}  // namespace softkin
