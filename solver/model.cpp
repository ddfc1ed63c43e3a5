#include "solver/model.hpp"

#include <chrono>
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
  actuator_rest_volume_.assign(scene_.num_actuators(), 0.0);
  for (int a = 0; a < scene_.num_actuators(); ++a) {
    const Actuator& act = scene_.actuators[a];
    if (act.type != ActuatorType::Pneumatic)
      throw std::invalid_argument("actuator '" + act.name + "': " +
                                  ActuatorTypeToString(act.type) +
                                  " actuation elements are not supported by this build; "
                                  "expected type 'pneumatic'");
    for (int r : act.regions) role[r] = {ElementRole::Pneumatic, a};
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
      actuator_rest_volume_[grp] += me.rest_volume;
    }
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

Eigen::MatrixX3d Model::SolveFree(const Eigen::Ref<const Eigen::MatrixX3d>& rhs) const {
  return chol_.solve(rhs);
}

}  // namespace softkin
