#include "softkin/solver/fk/fk_solver.hpp"

#include "softkin/solver/fk/energy.hpp"
#include "softkin/solver/fk/vented_vertices.hpp"
#include "softkin/solver/mesh/element_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace softkin {

const char* FkStatusToString(FkStatus s) {
  switch (s) {
    case FkStatus::Converged:
      return "converged";
    case FkStatus::IterationCap:
      return "iteration_cap";
    case FkStatus::Diverged:
      return "diverged";
    case FkStatus::InvalidInput:
      return "invalid_input";
    case FkStatus::TimeLimit:
      return "time_limit";
    case FkStatus::Inverted:
      return "inverted";
  }
  return "unknown";
}

bool FkStatusFromString(const std::string& s, FkStatus* out) {
  for (FkStatus v : {FkStatus::Converged, FkStatus::IterationCap, FkStatus::Diverged,
                     FkStatus::InvalidInput, FkStatus::TimeLimit, FkStatus::Inverted})
    if (s == FkStatusToString(v)) {
      *out = v;
      return true;
    }
  return false;
}

std::string FkResult::BriefReport() const {
  char buf[256];
  // A diverged solve has no energy or residual to speak of: "n/a", never "nan".
  auto num = [](double v, const char* fmt) {
    char t[32];
    std::snprintf(t, sizeof(t), fmt, v);
    return std::isfinite(v) ? std::string(t) : std::string("n/a");
  };
  std::snprintf(buf, sizeof(buf), "%s: %s, %d iterations, energy %s, residual ratio %s, %.3f s",
                solver.c_str(), FkStatusToString(status), iterations, num(energy, "%.6g").c_str(),
                num(gradient_ratio, "%.3g").c_str(), time_s);
  std::string s = buf;
  if (!message.empty()) s += " (" + message + ")";
  if (inverted_elements > 0) {
    std::snprintf(buf, sizeof(buf),
                  "; WARNING: %d inverted body element(s), smallest volume ratio %.3g",
                  inverted_elements, min_volume_ratio);
    s += buf;
  }
  if (collision_active) {
    std::snprintf(buf, sizeof(buf),
                  "; collisions: %d springs left, %s (max penetration %.3g mm), check %.3f s, "
                  "response %.3f s",
                  springs, collision.collision_free() ? "collision-free" : "contacts left",
                  collision.max_penetration, collision_stats.check_s, collision_stats.response_s);
    s += buf;
    if (collision.inverted_elements > 0) {
      std::snprintf(buf, sizeof(buf), "; %d inverted elements (%d of the self contacts in them)",
                    collision.inverted_elements, collision.tangled_contacts);
      s += buf;
    }
  }
  return s;
}

FkResult FkSolver::Solve(const Eigen::Ref<const Eigen::VectorXd>& c,
                         const Eigen::MatrixX3d* warm_start) {
  FkResult r = SolveImpl(c, warm_start);
  // The inner vertices of vented chamber sides feel no force: every solver's answer puts them at
  // the same place, inside their cavity (vented_vertices.hpp).
  if (r.status != FkStatus::InvalidInput) PlaceVentedVertices(*model_, c, &r.positions);
  ReportInvertedElements(*model_, &r);
  if (r.status == FkStatus::Converged && r.inverted_elements > 0) {
    char buf[160];
    std::snprintf(buf, sizeof(buf),
                  "met the tolerance, but %d body element(s) are inverted (smallest volume ratio "
                  "%.3g): not a state a material takes",
                  r.inverted_elements, r.min_volume_ratio);
    r.status = FkStatus::Inverted;
    r.message = r.message.empty() ? buf : r.message + "; " + buf;
  }
  return r;
}

InvertedCount CountInverted(const Model& model, const Eigen::MatrixX3d& X) {
  InvertedCount n;
  double worst = std::numeric_limits<double>::infinity();
  ElemRows P = ElemRows::Zero();
  for (const ModelElement& e : model.elements()) {
    for (int j = 0; j < e.k; ++j) P.row(j) = X.row(e.v[j]);
    const double ratio = RowsVolume(P, e.k) / e.rest_volume;
    if (e.role == ElementRole::Body) {
      worst = std::min(worst, ratio);
      n.body += ratio <= 0.0;
    } else {
      n.actuation += ratio <= 0.0;
    }
  }
  if (std::isfinite(worst)) n.min_body_ratio = worst;
  return n;
}

void ReportInvertedElements(const Model& model, FkResult* r) {
  const Eigen::MatrixX3d& X = r->positions;
  if (X.rows() != model.num_vertices() || !X.allFinite()) return;
  const InvertedCount n = CountInverted(model, X);
  r->inverted_elements = n.body;
  r->inverted_actuation_elements = n.actuation;
  r->min_volume_ratio = n.min_body_ratio;
}

std::string SolveInputError(const Model& m, const Eigen::Ref<const Eigen::VectorXd>& c,
                            const Eigen::MatrixX3d* warm_start) {
  try {
    CheckActuation(m, c);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  if (warm_start) {
    if (warm_start->rows() != m.num_vertices())
      return "warm start: expected " + std::to_string(m.num_vertices()) + " x 3 positions, got " +
             std::to_string(warm_start->rows()) + " rows";
    if (!warm_start->allFinite()) return "warm start: positions must be finite";
  }
  return "";
}

bool FkSolver::StartResult(const Eigen::Ref<const Eigen::VectorXd>& c,
                           const Eigen::MatrixX3d* warm_start, FkResult* r) const {
  r->solver = name();
  r->actuation = c;
  r->positions = model_->rest_positions();
  r->message = SolveInputError(*model_, c, warm_start);
  if (!r->message.empty()) {
    r->status = FkStatus::InvalidInput;
    return false;
  }
  if (warm_start) r->positions = *warm_start;
  return true;
}

}  // namespace softkin
