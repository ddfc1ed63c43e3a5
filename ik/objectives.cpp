#include "softkin/ik/objectives.hpp"

#include "softkin/ik/circle_fit.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <sstream>

namespace softkin {
namespace {

// O = |r|^2 and dO/dp = 2 (dr/dp)^T r, reshaped to #points x 3, from the residual form.
double EvaluateFromResiduals(const Objective& o, const Eigen::Ref<const Eigen::MatrixX3d>& p,
                             Eigen::MatrixX3d* grad) {
  Eigen::VectorXd r;
  Eigen::MatrixXd dr;
  o.Residuals(p, &r, grad ? &dr : nullptr);
  if (grad) {
    const Eigen::VectorXd g = 2.0 * dr.transpose() * r;
    grad->resize(p.rows(), 3);
    for (int i = 0; i < p.rows(); ++i)
      for (int d = 0; d < 3; ++d) (*grad)(i, d) = g[3 * i + d];
  }
  return r.squaredNorm();
}

void CheckFinite(const Eigen::Vector3d& v, const std::string& who, const std::string& what) {
  if (!v.allFinite()) throw std::invalid_argument(who + ": " + what + " must be finite");
}

void CheckNonNegative(double v, const std::string& who, const std::string& what) {
  if (!std::isfinite(v) || v < 0.0) {
    std::ostringstream s;
    s << who << ": " << what << " must be a finite number >= 0, got " << v;
    throw std::invalid_argument(s.str());
  }
}

// The unit normal of PlaneNormalSpec's points and, if g_n is given, the gradient of g_n . n with
// respect to those points (added into grad rows, scaled by `scale`).
Eigen::Vector3d NormalFromPoints(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                                 const std::vector<int>& kn) {
  const Eigen::Vector3d a = p.row(kn[0]).transpose(), b = p.row(kn[1]).transpose();
  Eigen::Vector3d v = kn.size() == 2 ? Eigen::Vector3d(b - a)
                                     : Eigen::Vector3d((b - a).cross(p.row(kn[2]).transpose() - a));
  const double len = v.norm();
  const double size = std::max({a.norm(), b.norm(), 1.0});
  if (!(len > 1e-12 * size)) throw ObjectiveError("pick: the plane normal's points are degenerate");
  return v / len;
}

// d(g_n . n)/d(points), one 3-vector per normal point, for n = v/|v|.
std::vector<Eigen::Vector3d> NormalPullback(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                                            const std::vector<int>& kn,
                                            const Eigen::Vector3d& g_n) {
  const Eigen::Vector3d a = p.row(kn[0]).transpose(), b = p.row(kn[1]).transpose();
  if (kn.size() == 2) {
    const Eigen::Vector3d v = b - a;
    const Eigen::Vector3d n = v.normalized();
    const Eigen::Vector3d gv = (g_n - n * n.dot(g_n)) / v.norm();
    return {-gv, gv};
  }
  const Eigen::Vector3d c = p.row(kn[2]).transpose();
  const Eigen::Vector3d u = b - a, w = c - a, v = u.cross(w);
  const Eigen::Vector3d n = v.normalized();
  const Eigen::Vector3d gv = (g_n - n * n.dot(g_n)) / v.norm();
  // dv = db x w + u x dc - da x w - u x da; g.(db x w) = db.(w x g), g.(u x dc) = dc.(g x u).
  const Eigen::Vector3d gb = w.cross(gv), gc = gv.cross(u);
  return {-gb - gc, gb, gc};
}

}  // namespace

void Objective::CheckPoints(const Eigen::Ref<const Eigen::MatrixX3d>& p) const {
  if (p.rows() != num_points_) {
    std::ostringstream s;
    s << name() << ": got " << p.rows() << " tracked points, expected " << num_points_;
    throw std::invalid_argument(s.str());
  }
}

Eigen::VectorXd GradientWrtActuation(const Eigen::Ref<const Eigen::MatrixXd>& J,
                                     const Eigen::Ref<const Eigen::MatrixX3d>& dO_dp) {
  assert(J.rows() == 3 * dO_dp.rows());
  Eigen::VectorXd g = Eigen::VectorXd::Zero(J.cols());
  for (int i = 0; i < dO_dp.rows(); ++i)
    for (int d = 0; d < 3; ++d)
      if (dO_dp(i, d) != 0.0) g += dO_dp(i, d) * J.row(3 * i + d).transpose();
  return g;
}

int ResolvePoint(const std::vector<std::string>& point_names, const std::string& name,
                 const std::string& who) {
  for (size_t i = 0; i < point_names.size(); ++i)
    if (point_names[i] == name) return static_cast<int>(i);
  std::ostringstream s;
  s << who << ": the kinematics tracks no point named '" << name << "' (it tracks:";
  for (size_t i = 0; i < point_names.size() && i < 20; ++i) s << " " << point_names[i];
  if (point_names.size() > 20) s << " ... (" << point_names.size() << " in all)";
  s << ")";
  throw std::invalid_argument(s.str());
}

std::vector<int> ResolvePointGroup(const std::vector<std::string>& point_names,
                                   const std::string& group, const std::string& who) {
  for (size_t i = 0; i < point_names.size(); ++i)
    if (point_names[i] == group) return {static_cast<int>(i)};
  std::vector<std::pair<long, int>> found;  // (index in the group, row)
  const std::string prefix = group + "[";
  for (size_t i = 0; i < point_names.size(); ++i) {
    const std::string& n = point_names[i];
    if (n.size() <= prefix.size() + 1 || n.compare(0, prefix.size(), prefix) != 0 ||
        n.back() != ']')
      continue;
    const std::string num = n.substr(prefix.size(), n.size() - prefix.size() - 1);
    if (num.empty() || !std::all_of(num.begin(), num.end(), ::isdigit)) continue;
    found.emplace_back(std::stol(num), static_cast<int>(i));
  }
  if (found.empty()) {
    std::ostringstream s;
    s << who << ": the kinematics tracks neither a point '" << group << "' nor points '" << group
      << "[i]'";
    throw std::invalid_argument(s.str());
  }
  std::sort(found.begin(), found.end());
  std::vector<int> out;
  for (const auto& f : found) out.push_back(f.second);
  return out;
}

// ---- point tracking ----------------------------------------------------------------------------

PointTrackingObjective::PointTrackingObjective(const std::vector<std::string>& point_names,
                                               const std::string& point,
                                               const Eigen::Vector3d& target)
    : Objective(static_cast<int>(point_names.size())),
      point_(point),
      k_(ResolvePoint(point_names, point, "point objective")),
      target_(target) {
  CheckFinite(target, "point objective", "the target");
}

double PointTrackingObjective::Evaluate(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                                        Eigen::MatrixX3d* grad) const {
  CheckPoints(p);
  const Eigen::RowVector3d d = p.row(k_) - target_.transpose();
  if (grad) {
    grad->setZero(p.rows(), 3);
    grad->row(k_) = 2.0 * d;
  }
  return d.squaredNorm();
}

bool PointTrackingObjective::Residuals(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                                       Eigen::VectorXd* r, Eigen::MatrixXd* dr_dp) const {
  CheckPoints(p);
  *r = p.row(k_).transpose() - target_;
  if (dr_dp) {
    dr_dp->setZero(3, 3 * p.rows());
    dr_dp->block<3, 3>(0, 3 * k_).setIdentity();
  }
  return true;
}

// ---- several points ----------------------------------------------------------------------------

MultiPointTrackingObjective::MultiPointTrackingObjective(
    const std::vector<std::string>& point_names, std::vector<PointTarget> targets)
    : Objective(static_cast<int>(point_names.size())), targets_(std::move(targets)) {
  if (targets_.empty()) throw std::invalid_argument("multi-point objective: no targets");
  for (const PointTarget& t : targets_) {
    index_.push_back(ResolvePoint(point_names, t.point, "multi-point objective"));
    CheckFinite(t.target, "multi-point objective", "the target of '" + t.point + "'");
    CheckNonNegative(t.weight, "multi-point objective", "the weight of '" + t.point + "'");
  }
}

std::string MultiPointTrackingObjective::name() const {
  std::string s = "points(";
  for (size_t j = 0; j < targets_.size(); ++j) s += (j ? "," : "") + targets_[j].point;
  return s + ")";
}

double MultiPointTrackingObjective::Evaluate(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                                             Eigen::MatrixX3d* grad) const {
  CheckPoints(p);
  if (grad) grad->setZero(p.rows(), 3);
  double o = 0.0;
  for (size_t j = 0; j < targets_.size(); ++j) {
    const Eigen::RowVector3d d = p.row(index_[j]) - targets_[j].target.transpose();
    o += targets_[j].weight * d.squaredNorm();
    if (grad) grad->row(index_[j]) += 2.0 * targets_[j].weight * d;
  }
  return o;
}

bool MultiPointTrackingObjective::Residuals(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                                            Eigen::VectorXd* r, Eigen::MatrixXd* dr_dp) const {
  CheckPoints(p);
  const int m = num_residuals();
  r->resize(m);
  if (dr_dp) dr_dp->setZero(m, 3 * p.rows());
  for (size_t j = 0; j < targets_.size(); ++j) {
    const double sw = std::sqrt(targets_[j].weight);
    r->segment<3>(3 * j) = sw * (p.row(index_[j]).transpose() - targets_[j].target);
    if (dr_dp) dr_dp->block<3, 3>(3 * j, 3 * index_[j]) += sw * Eigen::Matrix3d::Identity();
  }
  return true;
}

// ---- pick --------------------------------------------------------------------------------------

PickObjective::PickObjective(const std::vector<std::string>& point_names, PickParams params)
    : Objective(static_cast<int>(point_names.size())), params_(std::move(params)) {
  const std::string who = "pick objective";
  k0_ = ResolvePoint(point_names, params_.p0, who);
  if (params_.normal.points.size() != 2 && params_.normal.points.size() != 3)
    throw std::invalid_argument(who + ": the plane normal needs 2 or 3 tracked point names, got " +
                                std::to_string(params_.normal.points.size()));
  for (const std::string& n : params_.normal.points)
    kn_.push_back(ResolvePoint(point_names, n, who));
  CheckFinite(params_.center, who, "the object centre p1");
  CheckNonNegative(params_.object_radius, who, "the object radius R");
  CheckNonNegative(params_.half_width, who, "the half width d");
  CheckNonNegative(params_.omega1, who, "omega1");
}

Eigen::Vector3d PickObjective::Normal(const Eigen::Ref<const Eigen::MatrixX3d>& p) const {
  CheckPoints(p);
  return NormalFromPoints(p, kn_);
}

double PickObjective::Evaluate(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                               Eigen::MatrixX3d* grad) const {
  return EvaluateFromResiduals(*this, p, grad);
}

bool PickObjective::Residuals(const Eigen::Ref<const Eigen::MatrixX3d>& p, Eigen::VectorXd* r,
                              Eigen::MatrixXd* dr_dp) const {
  CheckPoints(p);
  const Eigen::Vector3d p0 = p.row(k0_).transpose();
  const Eigen::Vector3d v = params_.center - p0;
  const double dist = v.norm();
  const Eigen::Vector3d n = NormalFromPoints(p, kn_);
  const double sw = std::sqrt(params_.omega1);
  r->resize(2);
  (*r)[0] = dist - (params_.object_radius + params_.half_width);
  (*r)[1] = sw * n.dot(v);
  if (!dr_dp) return true;
  dr_dp->setZero(2, 3 * p.rows());
  // d|v|/dp0 = -v/|v| (0 at |v| = 0, a subgradient).
  if (dist > 0.0) dr_dp->block<1, 3>(0, 3 * k0_) = -(v / dist).transpose();
  dr_dp->block<1, 3>(1, 3 * k0_) += -sw * n.transpose();
  const std::vector<Eigen::Vector3d> gn = NormalPullback(p, kn_, sw * v);
  for (size_t j = 0; j < kn_.size(); ++j) dr_dp->block<1, 3>(1, 3 * kn_[j]) += gn[j].transpose();
  return true;
}

// ---- place -------------------------------------------------------------------------------------

PlaceObjective::PlaceObjective(const std::vector<std::string>& point_names, PlaceParams params)
    : Objective(static_cast<int>(point_names.size())), params_(std::move(params)) {
  const std::string who = "place objective";
  k0_ = ResolvePoint(point_names, params_.p0, who);
  CheckFinite(params_.target_center, who, "the target centre p1t");
  CheckNonNegative(params_.object_radius, who, "the object radius R");
  CheckNonNegative(params_.half_width, who, "the half width d");
}

double PlaceObjective::Evaluate(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                                Eigen::MatrixX3d* grad) const {
  return EvaluateFromResiduals(*this, p, grad);
}

bool PlaceObjective::Residuals(const Eigen::Ref<const Eigen::MatrixX3d>& p, Eigen::VectorXd* r,
                               Eigen::MatrixXd* dr_dp) const {
  CheckPoints(p);
  const Eigen::Vector3d v = params_.target_center - p.row(k0_).transpose();
  const double dist = v.norm();
  r->resize(1);
  (*r)[0] = dist - (params_.object_radius + params_.half_width);
  if (dr_dp) {
    dr_dp->setZero(1, 3 * p.rows());
    if (dist > 0.0) dr_dp->block<1, 3>(0, 3 * k0_) = -(v / dist).transpose();
  }
  return true;
}

// ---- grasp -------------------------------------------------------------------------------------

GraspObjective::GraspObjective(const std::vector<std::string>& point_names, GraspParams params)
    : Objective(static_cast<int>(point_names.size())), params_(std::move(params)) {
  const std::string who = "grasp objective";
  idx_ = ResolvePointGroup(point_names, params_.group, who);
  if (idx_.size() < 3)
    throw std::invalid_argument(who + ": the group '" + params_.group + "' has " +
                                std::to_string(idx_.size()) + " points, a circle needs 3");
  if (!(std::isfinite(params_.object_diameter) && params_.object_diameter > 0.0))
    throw std::invalid_argument(who + ": the object diameter must be > 0");
  CheckFinite(params_.plane_normal, who, "the plane normal");
}

double GraspObjective::FittedDiameter(const Eigen::Ref<const Eigen::MatrixX3d>& p) const {
  Eigen::VectorXd r;
  Residuals(p, &r, nullptr);
  return r[0] + params_.object_diameter;
}

double GraspObjective::Evaluate(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                                Eigen::MatrixX3d* grad) const {
  return EvaluateFromResiduals(*this, p, grad);
}

bool GraspObjective::Residuals(const Eigen::Ref<const Eigen::MatrixX3d>& p, Eigen::VectorXd* r,
                               Eigen::MatrixXd* dr_dp) const {
  CheckPoints(p);
  Eigen::MatrixX3d pts(idx_.size(), 3);
  for (size_t j = 0; j < idx_.size(); ++j) pts.row(j) = p.row(idx_[j]);
  const CircleFit fit = FitCircle(pts, params_.plane_normal, dr_dp != nullptr);
  if (!fit.ok) throw ObjectiveError("grasp: " + fit.message);
  r->resize(1);
  (*r)[0] = fit.diameter - params_.object_diameter;
  if (dr_dp) {
    dr_dp->setZero(1, 3 * p.rows());
    for (size_t j = 0; j < idx_.size(); ++j)
      dr_dp->block<1, 3>(0, 3 * idx_[j]) += fit.d_diameter.row(j);
  }
  return true;
}

// ---- shape matching ----------------------------------------------------------------------------

ShapeMatchingObjective::ShapeMatchingObjective(int num_points, std::vector<int> idx,
                                               Eigen::MatrixX3d target)
    : Objective(num_points), idx_(std::move(idx)), target_(std::move(target)) {
  if (static_cast<int>(idx_.size()) != target_.rows())
    throw std::invalid_argument("shape objective: the region has " + std::to_string(idx_.size()) +
                                " points but the target shape has " +
                                std::to_string(target_.rows()) + " rows");
  if (idx_.empty()) throw std::invalid_argument("shape objective: empty region");
  if (!target_.allFinite())
    throw std::invalid_argument("shape objective: the target must be finite");
}

ShapeMatchingObjective::ShapeMatchingObjective(const std::vector<std::string>& point_names,
                                               const std::vector<std::string>& region_points,
                                               const Eigen::Ref<const Eigen::MatrixX3d>& target)
    : ShapeMatchingObjective(
          static_cast<int>(point_names.size()),
          [&] {
            std::vector<int> idx;
            for (const std::string& n : region_points)
              idx.push_back(ResolvePoint(point_names, n, "shape objective"));
            return idx;
          }(),
          target) {}

ShapeMatchingObjective ShapeMatchingObjective::ForGroup(
    const std::vector<std::string>& point_names, const std::string& group,
    const Eigen::Ref<const Eigen::MatrixX3d>& target) {
  return ShapeMatchingObjective(static_cast<int>(point_names.size()),
                                ResolvePointGroup(point_names, group, "shape objective"), target);
}

double ShapeMatchingObjective::Evaluate(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                                        Eigen::MatrixX3d* grad) const {
  CheckPoints(p);
  if (grad) grad->setZero(p.rows(), 3);
  double o = 0.0;
  for (size_t j = 0; j < idx_.size(); ++j) {
    const Eigen::RowVector3d d = p.row(idx_[j]) - target_.row(j);
    o += d.squaredNorm();
    if (grad) grad->row(idx_[j]) += 2.0 * d;
  }
  return o;
}

bool ShapeMatchingObjective::Residuals(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                                       Eigen::VectorXd* r, Eigen::MatrixXd* dr_dp) const {
  CheckPoints(p);
  const int m = num_residuals();
  r->resize(m);
  if (dr_dp) dr_dp->setZero(m, 3 * p.rows());
  for (size_t j = 0; j < idx_.size(); ++j) {
    r->segment<3>(3 * j) = (p.row(idx_[j]) - target_.row(j)).transpose();
    if (dr_dp) dr_dp->block<3, 3>(3 * j, 3 * idx_[j]) += Eigen::Matrix3d::Identity();
  }
  return true;
}

// ---- weighted sums -----------------------------------------------------------------------------

WeightedSumObjective& WeightedSumObjective::Add(double weight,
                                                std::shared_ptr<const Objective> term) {
  CheckNonNegative(weight, "weighted sum", "a weight");
  if (!term) throw std::invalid_argument("weighted sum: null term");
  if (term->num_points() != num_points())
    throw std::invalid_argument("weighted sum: the term " + term->name() + " expects " +
                                std::to_string(term->num_points()) + " points, the sum " +
                                std::to_string(num_points()));
  terms_.emplace_back(weight, std::move(term));
  return *this;
}

std::string WeightedSumObjective::name() const {
  std::ostringstream s;
  s << "sum(";
  for (size_t j = 0; j < terms_.size(); ++j)
    s << (j ? " + " : "") << terms_[j].first << " " << terms_[j].second->name();
  s << ")";
  return s.str();
}

double WeightedSumObjective::Evaluate(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                                      Eigen::MatrixX3d* grad) const {
  CheckPoints(p);
  if (grad) grad->setZero(p.rows(), 3);
  double o = 0.0;
  Eigen::MatrixX3d g;
  for (const auto& [w, term] : terms_) {
    o += w * term->Evaluate(p, grad ? &g : nullptr);
    if (grad) *grad += w * g;
  }
  return o;
}

int WeightedSumObjective::num_residuals() const {
  int m = 0;
  for (const auto& t : terms_) {
    if (t.second->num_residuals() == 0) return 0;
    m += t.second->num_residuals();
  }
  return m;
}

bool WeightedSumObjective::Residuals(const Eigen::Ref<const Eigen::MatrixX3d>& p,
                                     Eigen::VectorXd* r, Eigen::MatrixXd* dr_dp) const {
  CheckPoints(p);
  const int m = num_residuals();
  if (m == 0) return false;
  r->resize(m);
  if (dr_dp) dr_dp->resize(m, 3 * p.rows());
  int row = 0;
  Eigen::VectorXd rj;
  Eigen::MatrixXd dj;
  for (const auto& [w, term] : terms_) {
    term->Residuals(p, &rj, dr_dp ? &dj : nullptr);
    const double sw = std::sqrt(w);
    r->segment(row, rj.size()) = sw * rj;
    if (dr_dp) dr_dp->middleRows(row, rj.size()) = sw * dj;
    row += static_cast<int>(rj.size());
  }
  return true;
}

}  // namespace softkin
