#include "softkin/ik/simulator_kinematics.hpp"

#include "softkin/solver/factory/fk_factory.hpp"

#include "softkin/solver/mesh/mesh.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace softkin {

const char* JacobianModeToString(JacobianMode m) {
  switch (m) {
    case JacobianMode::kFd:
      return "fd";
    case JacobianMode::kFdWarm:
      return "fd-warm";
    case JacobianMode::kImplicit:
      return "implicit";
  }
  return "unknown";
}

bool JacobianModeFromString(const std::string& s, JacobianMode* m) {
  for (JacobianMode x : {JacobianMode::kFd, JacobianMode::kFdWarm, JacobianMode::kImplicit})
    if (s == JacobianModeToString(x)) {
      *m = x;
      return true;
    }
  return false;
}

std::string JacobianModeNames() { return "fd, fd-warm, implicit"; }

bool SimulatorKinematicsOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!(fd_step > 0.0 && fd_step <= 0.25))
    return bad("fd_step: expected a fraction of the actuator range in (0, 0.25]");
  if (warm_max_iterations < 0)
    return bad("warm_max_iterations: expected >= 0 (0: the solver's max_iterations)");
  if (!(predict_max_step > 0.0) || std::isnan(predict_max_step))
    return bad("predict_max_step: expected a range-scaled step length > 0");
  if (!implicit.IsValid(why)) return false;
  return true;
}

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

SimulatorKinematics::SimulatorKinematics(const Scene& scene,
                                         const SimulatorKinematicsOptions& options,
                                         const FkOptions* fk)
    : model_(std::make_shared<const Model>(scene)) {
  Init(options, fk);
}

SimulatorKinematics::SimulatorKinematics(std::shared_ptr<const Model> model,
                                         const SimulatorKinematicsOptions& options,
                                         const FkOptions* fk)
    : model_(std::move(model)) {
  if (!model_) throw std::invalid_argument("SimulatorKinematics: null model");
  Init(options, fk);
}

void SimulatorKinematics::Init(const SimulatorKinematicsOptions& options, const FkOptions* fk) {
  options_ = options;
  std::string why;
  if (!options_.IsValid(&why)) throw std::invalid_argument("kinematics options: " + why);
  const Scene& scene = model_->scene();
  fk_ = fk ? *fk : scene.solver;
  if (!fk_.IsValid(&why)) throw std::invalid_argument("solver options: " + why);
  // lg, lg-aa, newton and auto stop at the same local-global equilibrium, which 'implicit'
  // differentiates; the other solvers minimise other problems.
  if (options_.jacobian == JacobianMode::kImplicit && fk_.solver != FkSolverType::kLg &&
      fk_.solver != FkSolverType::kLgAa && fk_.solver != FkSolverType::kNewton &&
      fk_.solver != FkSolverType::kAuto)
    throw std::invalid_argument(
        "jacobian 'implicit' differentiates the local-global equilibrium; it needs solver lg, "
        "lg-aa, newton or auto, got '" +
        ToString(fk_.solver) + "' (use fd or fd-warm with other solvers)");
  solver_ = MakeFkSolver(model_, fk_);
  warm_solver_.reset();
  if (options_.warm_max_iterations > 0 && options_.warm_max_iterations < fk_.max_iterations) {
    FkOptions warm = fk_;
    warm.max_iterations = options_.warm_max_iterations;
    warm_solver_ = MakeFkSolver(model_, warm);  // shares the model (and its factor)
  }

  // Tracked points.
  std::vector<std::string> spec = options_.points;
  if (spec.empty())
    for (const auto& m : scene.markers) spec.push_back(m.name);
  offset_.assign(1, 0);
  auto add = [&](const std::string& name, const std::vector<int>& verts) {
    names_.push_back(name);
    for (int v : verts) {
      vertex_.push_back(v);
      weight_.push_back(1.0 / static_cast<double>(verts.size()));
    }
    offset_.push_back(static_cast<int>(vertex_.size()));
  };
  for (const std::string& s : spec) {
    const size_t br = s.find('[');
    const std::string base = s.substr(0, br);
    const int mi = scene.marker_index(base);
    if (mi < 0) {
      std::string known;
      for (const auto& m : scene.markers) known += (known.empty() ? "" : ", ") + m.name;
      throw std::invalid_argument("tracked point '" + s + "': scene '" + scene.name +
                                  "' has no marker '" + base + "'; its markers: " + known);
    }
    const auto& verts = scene.markers[mi].vertices;
    if (br == std::string::npos) {
      add(base, verts);
      continue;
    }
    if (s.back() != ']')
      throw std::invalid_argument("tracked point '" + s + "': expected name, name[*] or name[i]");
    const std::string inner = s.substr(br + 1, s.size() - br - 2);
    if (inner == "*") {
      for (size_t i = 0; i < verts.size(); ++i)
        add(base + "[" + std::to_string(i) + "]", {verts[i]});
      continue;
    }
    size_t used = 0;
    int idx = -1;
    try {
      idx = std::stoi(inner, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != inner.size() || inner.empty() || idx < 0 || idx >= static_cast<int>(verts.size()))
      throw std::invalid_argument("tracked point '" + s + "': expected an index in [0, " +
                                  std::to_string(verts.size() - 1) +
                                  "] or '*' inside [] (marker '" + base + "' has " +
                                  std::to_string(verts.size()) + " vertices)");
    add(base + "[" + std::to_string(idx) + "]", {verts[idx]});
  }

  const int na = model_->num_actuators();
  lower_.resize(na);
  upper_.resize(na);
  for (int a = 0; a < na; ++a) {
    lower_[a] = scene.actuators[a].min;
    upper_[a] = scene.actuators[a].max;
  }
}

std::string SimulatorKinematics::name() const {
  return std::string("simulator(") + JacobianModeToString(options_.jacobian) + ")";
}

void SimulatorKinematics::Reset() {
  last_X_.resize(0, 3);
  last_c_.resize(0);
  last_start_.resize(0, 3);
  jac_dXdc_.resize(0, 0);
  jac_c_.resize(0);
  jac_columns_.clear();
  // The implicit mode's preconditioner (factor, and whether its blocks are projected) too: after
  // Reset the next evaluations are those of a new object, bit for bit (a dataset's blocks).
  workspace_ = std::make_unique<EquilibriumJacobianWorkspace>();
  last_implicit_ = EquilibriumJacobianResult();
}

double SimulatorKinematics::fd_step(int a) const {
  return options_.fd_step * (upper_[a] - lower_[a]);
}

Eigen::MatrixX3d SimulatorKinematics::Points(const Eigen::Ref<const Eigen::MatrixX3d>& X) const {
  const int np = num_points();
  Eigen::MatrixX3d P = Eigen::MatrixX3d::Zero(np, 3);
  for (int q = 0; q < np; ++q)
    for (int t = offset_[q]; t < offset_[q + 1]; ++t) P.row(q) += weight_[t] * X.row(vertex_[t]);
  return P;
}

std::string SimulatorKinematics::Solve(const Eigen::VectorXd& c, const Eigen::MatrixX3d* start,
                                       FkResult* r, std::string* note, const char* kind,
                                       int* solves, bool* from_rest) {
  auto run = [&](FkSolver& solver, const Eigen::MatrixX3d* from, const char* what) {
    *r = solver.Solve(c, from);
    ++total_fk_solves_;
    if (solves) ++*solves;
    if (options_.trace) {
      std::ostringstream t;
      t << "fk #" << total_fk_solves_ << " " << what << (from ? "" : " (from rest)") << " c = ("
        << c.transpose() << "): " << FkStatusToString(r->status) << ", " << r->iterations
        << " iterations, " << r->time_s << " s\n";
      std::fputs(t.str().c_str(), stderr);
    }
  };
  if (from_rest) *from_rest = start == nullptr;
  run(start && warm_solver_ ? *warm_solver_ : *solver_, start, kind);
  // A stored state can sit where the iterations crawl (cable_finger: 10000 lg-aa iterations
  // without converging from a neighbouring sample's state, 79 from rest; plain lg needed
  // 15804): give such a start warm_max_iterations, then solve c as a cold FK solve would.
  if (start && options_.retry_from_rest &&
      (r->status == FkStatus::IterationCap || r->status == FkStatus::Diverged)) {
    ++rest_retries_;
    if (from_rest) *from_rest = true;
    run(*solver_, nullptr, "rest retry");
  }
  // An inverted state is the solver's fixed point: IK sees it and reports its inverted elements
  // (KinematicsEval::inverted_elements), so that no waypoint counts it as reached.
  if (r->status == FkStatus::Converged || r->status == FkStatus::Inverted) return "";
  std::ostringstream s;
  s << "forward solve at c = (" << c.transpose() << ") ended with status "
    << FkStatusToString(r->status) << (r->message.empty() ? "" : ": ") << r->message;
  if (r->status == FkStatus::IterationCap && options_.accept_iteration_cap &&
      r->positions.allFinite()) {
    if (note) *note += (note->empty() ? "" : "; ") + s.str() + " (accepted)";
    return "";
  }
  return s.str();
}

Eigen::VectorXd SimulatorKinematics::ColumnStep(const Eigen::VectorXd& c, double* scaled) const {
  Eigen::VectorXd dc(jac_columns_.size());
  double s2 = 0.0;
  for (size_t j = 0; j < jac_columns_.size(); ++j) {
    const int a = jac_columns_[j];
    dc[j] = c[a] - last_c_[a];
    s2 += std::pow(dc[j] / std::max(upper_[a] - lower_[a], 1e-300), 2);
  }
  *scaled = std::sqrt(s2);
  return dc;
}

bool SimulatorKinematics::PredictionIsSafe(const Eigen::MatrixX3d& from,
                                           const Eigen::MatrixX3d& predicted, double step) {
  // A linear extrapolation over a long step (a line search's first trial, the jump to another
  // sample) can fold elements over: the local-global iterations then converge from there to
  // another, folded equilibrium (cable_finger res 6: the tip 60 mm off) or take thousands of
  // iterations (14 s where the plain warm start took 0.2 s). Trust the linear model only within
  // predict_max_step of the state it belongs to, and never when it inverts an element that is
  // upright there.
  if (!(step <= options_.predict_max_step)) {
    ++rejected_predictions_;
    return false;
  }
  for (const Element& e : model_->mesh().elements)
    if (SignedVolume(e, predicted) <= 0.0 && SignedVolume(e, from) > 0.0) {
      ++rejected_predictions_;
      return false;
    }
  return true;
}

KinematicsEval SimulatorKinematics::Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c_in,
                                             bool with_jacobian) {
  const auto t0 = Clock::now();
  KinematicsEval ev;
  auto finish = [&]() -> KinematicsEval {
    ev.time_s = Seconds(t0, Clock::now());
    if (!ev.ok) {
      ev.J.resize(0, 0);
    }
    return ev;
  };
  ev.message = CheckKinematicsInput(*this, c_in);
  if (!ev.message.empty()) {
    // Name the actuator, not only its index.
    for (int a = 0; a < num_actuators() && c_in.size() == num_actuators(); ++a) {
      const double lo = lower_[a], hi = upper_[a], slack = 1e-12 * std::max(1.0, hi - lo);
      if (!std::isfinite(c_in[a]) || c_in[a] < lo - slack || c_in[a] > hi + slack) {
        ev.message += " (actuator '" + model_->scene().actuators[a].name + "')";
        break;
      }
    }
    return finish();
  }
  // Clamp the 1e-12 slack CheckKinematicsInput allows, so the solver sees an in-range value.
  const Eigen::VectorXd c = c_in.cwiseMax(lower_).cwiseMin(upper_);
  std::string note;

  // p(c): reuse, or warm start from the last converged state.
  const bool have_last = options_.warm_start && last_X_.rows() == model_->num_vertices();
  const Eigen::MatrixX3d* start = have_last ? &last_X_ : nullptr;
  // The start of the centre solve, kept for fd probes (solved as plain FK would be).
  Eigen::MatrixX3d centre_start;
  if (start) centre_start = *start;
  Eigen::MatrixX3d X;
  if (have_last && last_c_.size() == c.size() && last_c_ == c) {
    X = last_X_;
    centre_start = last_start_;  // where the reused state was solved from
    ev.inverted_elements = last_inverted_;
    ev.min_volume_ratio = last_min_volume_ratio_;
  } else {
    FkResult r;
    // First-order prediction from the previous state and its implicit Jacobian.
    Eigen::MatrixX3d predicted;
    if (have_last && options_.jacobian == JacobianMode::kImplicit && options_.predict_warm_start &&
        jac_c_.size() == c.size() && jac_c_ == last_c_ && jac_dXdc_.rows() == 3 * last_X_.rows()) {
      const int nv = static_cast<int>(last_X_.rows());
      double step = 0.0;
      const Eigen::VectorXd dc = ColumnStep(c, &step);
      const Eigen::VectorXd dx = jac_dXdc_ * dc;
      predicted =
          last_X_ + Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(
                        dx.data(), nv, 3);
      if (!predicted.allFinite() || !PredictionIsSafe(last_X_, predicted, step))
        predicted.resize(0, 3);
    }
    std::string err;
    bool from_rest = false;
    if (predicted.rows() > 0) {
      err = Solve(c, &predicted, &r, &note, "predicted", &ev.fk_solves, &from_rest);
      if (err.empty()) {
        if (from_rest)
          centre_start.resize(0, 3);  // fd probes start where the centre did
        else
          centre_start = predicted;
      }
    }
    // A failed prediction is retried from the plain warm start, unless a cold solve already failed.
    if (predicted.rows() == 0 || (!err.empty() && !from_rest)) {
      err = Solve(c, start, &r, &note, "warm", &ev.fk_solves, &from_rest);
      if (err.empty() && from_rest) centre_start.resize(0, 3);
    }
    if (!err.empty()) {
      ev.message = err;
      return finish();
    }
    X = r.positions;
    ev.inverted_elements = r.inverted_elements;
    ev.min_volume_ratio = r.min_volume_ratio;
    // Keep dX/dc first-order along the path: Broyden's secant update from the step just solved
    // (scaled by the ranges, as IK's broyden), so the next prediction is still close.
    if (have_last && options_.jacobian == JacobianMode::kImplicit && options_.secant_update &&
        jac_c_.size() == c.size() && jac_c_ == last_c_ && jac_dXdc_.rows() == 3 * X.rows()) {
      double step = 0.0;
      const Eigen::VectorXd dc = ColumnStep(c, &step);
      Eigen::VectorXd w(dc.size());  // dc / range^2
      for (Eigen::Index j = 0; j < dc.size(); ++j)
        w[j] = dc[j] /
               std::max(std::pow(upper_[jac_columns_[j]] - lower_[jac_columns_[j]], 2), 1e-300);
      bool others_fixed = true;  // actuators outside the columns (kinks) must not have moved
      for (int a = 0; a < num_actuators(); ++a)
        if (std::find(jac_columns_.begin(), jac_columns_.end(), a) == jac_columns_.end() &&
            c[a] != last_c_[a])
          others_fixed = false;
      const double den = step * step;  // = dc . w
      // A step below the differences' own scale (fd_step of the ranges) is mostly the forward
      // solves' tolerance: dividing that noise by |dc| would wreck dX/dc (a line search that
      // shrinks its steps to 1e-7 made the next prediction fold the finger over). Over such a
      // step dX/dc is carried to the new state unchanged (first-order the same); longer steps
      // update it.
      if (others_fixed && std::isfinite(den) && den > 0.0) {
        if (step >= options_.fd_step) {
          const Eigen::MatrixX3d dX = X - last_X_;
          Eigen::VectorXd y(3 * X.rows());
          for (Eigen::Index v = 0; v < X.rows(); ++v)
            for (int d = 0; d < 3; ++d) y[3 * v + d] = dX(v, d);
          y -= jac_dXdc_ * dc;
          jac_dXdc_ += y * (w.transpose() / den);
        }
        jac_c_ = c;
      }
    }
    last_X_ = X;
    last_c_ = c;
    last_start_ = centre_start;
    last_inverted_ = ev.inverted_elements;
    last_min_volume_ratio_ = ev.min_volume_ratio;
  }
  ev.p = Points(X);
  if (!with_jacobian) {
    ev.ok = true;
    ev.message = note;
    return finish();
  }

  const int na = num_actuators(), np = num_points();
  ev.J.setZero(3 * np, na);
  auto flatten = [&](const Eigen::MatrixX3d& P) {
    Eigen::VectorXd v(3 * np);
    for (int q = 0; q < np; ++q)
      for (int d = 0; d < 3; ++d) v[3 * q + d] = P(q, d);
    return v;
  };

  // Columns by differences (fd, fd-warm, or implicit's fallback at a kink).
  auto fd_column = [&](int a, bool warm_from_centre) -> std::string {
    const double h = fd_step(a);
    const Eigen::MatrixX3d* probe_start =
        warm_from_centre ? &X : (centre_start.rows() > 0 ? &centre_start : nullptr);
    auto probe = [&](double delta, Eigen::VectorXd* p) -> std::string {
      Eigen::VectorXd cp = c;
      cp[a] = std::min(upper_[a], std::max(lower_[a], c[a] + delta));
      FkResult r;
      const std::string err = Solve(cp, probe_start, &r, &note, "probe", &ev.fk_solves);
      if (!err.empty())
        return "probe of actuator '" + model_->scene().actuators[a].name + "': " + err;
      *p = flatten(Points(r.positions));
      return "";
    };
    Eigen::VectorXd p1, p2;
    std::string err;
    if (c[a] + h <= upper_[a] && c[a] - h >= lower_[a]) {
      if (!(err = probe(h, &p1)).empty() || !(err = probe(-h, &p2)).empty()) return err;
      ev.J.col(a) = (p1 - p2) / (2.0 * h);
    } else {
      // One-sided, second order, towards the inside of the box.
      const double s = (c[a] + h > upper_[a]) ? -1.0 : 1.0;
      if (!(err = probe(s * h, &p1)).empty() || !(err = probe(2.0 * s * h, &p2)).empty())
        return err;
      const Eigen::VectorXd p0 = flatten(ev.p);
      ev.J.col(a) = (-3.0 * p0 + 4.0 * p1 - p2) / (2.0 * s * h);
    }
    return "";
  };

  if (options_.jacobian == JacobianMode::kFd || options_.jacobian == JacobianMode::kFdWarm) {
    const bool warm = options_.jacobian == JacobianMode::kFdWarm;
    for (int a = 0; a < na; ++a) {
      const std::string err = fd_column(a, warm);
      if (!err.empty()) {
        ev.message = err;
        return finish();
      }
    }
    ev.ok = true;
    ev.message = note;
    return finish();
  }

  // Implicit.
  if (ContactHandlingActive(model_->scene(), fk_.collision)) {
    ev.message =
        "jacobian 'implicit' does not include collision springs, and collision response is "
        "active for scene '" +
        model_->scene().name + "'; use fd or fd-warm";
    return finish();
  }
  // A signed actuator at exactly 0 sits on a kink (both sides vented; p is not differentiable
  // there): its column is the central difference from the converged state (as fd-warm).
  std::vector<int> smooth, kinked;
  for (int a = 0; a < na; ++a) {
    const Actuator& act = model_->scene().actuators[a];
    (act.is_signed() && c[a] == 0.0 ? kinked : smooth).push_back(a);
  }
  if (!smooth.empty()) {
    const bool guess = options_.jacobian_initial_guess && jac_columns_ == smooth &&
                       jac_dXdc_.rows() == 3 * X.rows();
    EquilibriumJacobianOptions jo = options_.implicit;
    if (options_.implicit_tolerance_follows_fk)
      jo.tolerance = std::max(jo.tolerance, std::min(1e-2 * fk_.gradient_tolerance, 1e-4));
    last_implicit_ = ComputeEquilibriumJacobian(*model_, X, c, smooth, jo,
                                                guess ? &jac_dXdc_ : nullptr, workspace_.get());
    if (!last_implicit_.ok && !options_.implicit_fallback) {
      ev.message = last_implicit_.message;
      return finish();
    }
    if (!last_implicit_.ok) {
      // Fall back to fd-warm for these columns, and say so. dX/dc is not known at c, so no
      // prediction starts from it.
      jac_c_.resize(0);
      note += (note.empty() ? "" : "; ") + std::string("implicit Jacobian failed (") +
              last_implicit_.message + "); its columns are fd-warm central differences instead";
      for (int a : smooth) {
        const std::string err = fd_column(a, true);
        if (!err.empty()) {
          ev.message = err;
          return finish();
        }
      }
      smooth.clear();
    } else {
      jac_dXdc_ = last_implicit_.dXdc;
      jac_c_ = c;
      jac_columns_ = smooth;
    }
    for (size_t j = 0; j < smooth.size(); ++j)
      for (int q = 0; q < np; ++q)
        for (int t = offset_[q]; t < offset_[q + 1]; ++t)
          for (int d = 0; d < 3; ++d)
            ev.J(3 * q + d, smooth[j]) +=
                weight_[t] * last_implicit_.dXdc(3 * vertex_[t] + d, static_cast<Eigen::Index>(j));
  }
  for (int a : kinked) {
    const std::string err = fd_column(a, true);
    if (!err.empty()) {
      ev.message = err;
      return finish();
    }
    note += (note.empty() ? "" : "; ") + std::string("actuator '") +
            model_->scene().actuators[a].name +
            "' is a signed actuator at 0 (a kink): its column is a central difference";
  }
  ev.ok = true;
  ev.message = note;
  return finish();
}

}  // namespace softkin
