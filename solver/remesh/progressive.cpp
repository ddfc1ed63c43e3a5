/// \file progressive.cpp
/// Progressive remeshing, the driver of thesis Algorithm 2 (remesh.hpp): solve up a ladder of
/// chamber volume ratios, re-tessellating the chamber (RemeshChamber) whenever CheckRemesh asks
/// for it, and carry the state over to the new mesh.
#include "softkin/solver/remesh/remesh.hpp"

#include "softkin/solver/common/text_format.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace softkin {

namespace {

using Clock = std::chrono::steady_clock;

/// SolveProgressive treats a solution whose bounding-box diagonal exceeds this multiple of the
/// rest one as a runaway (diverged)...
constexpr double kRunawayExtent = 5.0;
/// ... or whose chamber volume ratio exceeds this multiple of the ratio asked for.
constexpr double kRunawayRatio = 2.0;

bool InRegions(int tag, const std::vector<int>& regions) {
  return std::find(regions.begin(), regions.end(), tag) != regions.end();
}

/// Throws std::invalid_argument if alpha_target, the snapshots or the explicit ladder are outside
/// the range of the chamber actuator `act`.
void CheckProgressiveTargets(const Actuator& act, double alpha_target,
                             const ProgressiveOptions& opt) {
  if (!(alpha_target > 1) || alpha_target > act.max || alpha_target < act.min)
    throw std::invalid_argument("SolveProgressive: alpha_target " + FormatNumber(alpha_target) +
                                " is outside (1, " + FormatNumber(act.max) +
                                "], the range of actuator '" + act.name + "'");
  for (double s : opt.snapshots)
    if (s > alpha_target)
      throw std::invalid_argument("SolveProgressive: snapshot " + FormatNumber(s) +
                                  " is beyond alpha_target " + FormatNumber(alpha_target) +
                                  "; expected snapshots in (1, alpha_target]");
  if (!opt.ladder.empty() && opt.ladder.back() > alpha_target)
    throw std::invalid_argument("SolveProgressive: ladder value " +
                                FormatNumber(opt.ladder.back()) + " is beyond alpha_target " +
                                FormatNumber(alpha_target) +
                                "; expected ladder values in (1, alpha_target]");
}

/// The ladder: k * step below the target (or the explicit values), the snapshot values, and the
/// target; ascending, values closer than 1e-12 merged.
std::vector<double> Ladder(double alpha_target, const ProgressiveOptions& opt) {
  const double step = opt.step > 0 ? opt.step : opt.criteria.alpha_max;
  std::vector<double> ladder = opt.ladder;
  if (ladder.empty())
    for (int k = 1; k * step < alpha_target - 1e-12; ++k)
      if (k * step > 1) ladder.push_back(k * step);
  for (double s : opt.snapshots)
    if (s < alpha_target) ladder.push_back(s);
  ladder.push_back(alpha_target);
  std::sort(ladder.begin(), ladder.end());
  ladder.erase(std::unique(ladder.begin(), ladder.end(),
                           [](double x, double y) { return std::abs(x - y) < 1e-12; }),
               ladder.end());
  return ladder;
}

/// Adds one solve's counts and times to the step and takes its status and collision state.
void AddSolve(const FkResult& r, ProgressiveStep* st) {
  st->solver_seconds += r.time_s;
  st->iterations += r.iterations;
  st->status = r.status;
  st->check_seconds += r.collision_stats.check_s;
  st->response_seconds += r.collision_stats.response_s;
  st->local_global_seconds += r.local_time_s + r.global_time_s;
  st->collision_active = r.collision_active;
  st->collision = r.collision;
  st->springs = r.springs;
}

/// A state that has grown far beyond any inflation is a runaway of the iteration, not a shape:
/// marks it diverged (so that the previous state is kept). The soft actuation of the
/// local-global solver reaches less than the ratio asked for, so a chamber beyond twice it has
/// run away too. V0: the original chamber volume; rest_extent: the rest bounding-box diagonal.
void FlagRunaway(const Mesh& mesh, const std::vector<int>& regions, double V0, double rest_extent,
                 double alpha, FkResult* r) {
  if (r->status == FkStatus::Diverged || r->status == FkStatus::InvalidInput) return;
  const double extent =
      (r->positions.colwise().maxCoeff() - r->positions.colwise().minCoeff()).norm();
  const double ratio = RegionVolume(mesh, r->positions, regions) / V0;
  if (!(extent <= kRunawayExtent * rest_extent) || !(ratio <= kRunawayRatio * alpha)) {
    r->message = "runaway: the chamber reached " + FormatNumber(ratio) +
                 " times its volume for alpha " + FormatNumber(alpha) + ", the bounding box " +
                 FormatNumber(extent / rest_extent) + " times the rest one (" +
                 FkStatusToString(r->status) + "); treated as diverged";
    r->status = FkStatus::Diverged;
  }
}

}  // namespace

bool ProgressiveOptions::IsValid(std::string* why) const {
  if (!criteria.IsValid(why)) return false;
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!(step >= 0) || !std::isfinite(step))
    return fail("step: expected >= 0 (0: alpha_max), got " + FormatNumber(step));
  if (max_remeshes_per_step < 1) return fail("max_remeshes_per_step: expected an integer >= 1");
  if (!remesh_options.IsValid(why)) return false;
  for (double s : snapshots)
    if (!(s > 1) || !std::isfinite(s))
      return fail("snapshots: expected volume ratios > 1, got " + FormatNumber(s));
  for (size_t i = 0; i < ladder.size(); ++i)
    if (!(ladder[i] > 1) || !std::isfinite(ladder[i]) || (i > 0 && !(ladder[i] > ladder[i - 1])))
      return fail("ladder: expected increasing volume ratios > 1, got " + FormatNumber(ladder[i]) +
                  " at position " + std::to_string(i));
  return true;
}

std::string ProgressiveResult::BriefReport() const {
  std::ostringstream os;
  os << FkStatusToString(status) << ": " << steps.size() << " steps, " << remeshes
     << " remeshes, chamber volume ratio " << chamber_volume_ratio << ", " << scene.mesh.num_tets()
     << " tets; mesh " << mesh_seconds << " s, solver " << solver_seconds << " s";
  if (remesh_failures > 0)
    os << "; " << remesh_failures << " remesh(es) failed, first at " << first_remesh_failure;
  if (!completed) os << "; stopped early";
  if (!message.empty()) os << " (" << message << ")";
  return os.str();
}

ProgressiveResult SolveProgressive(const Scene& scene, double alpha_target,
                                   const ProgressiveOptions& opt) {
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument("progressive remeshing option " + why);
  scene.validate();
  const int a = ChamberActuator(scene);
  const Actuator& act = scene.actuators[a];
  CheckProgressiveTargets(act, alpha_target, opt);
  const std::vector<int> regions = act.regions;
  const std::vector<double> ladder = Ladder(alpha_target, opt);

  ProgressiveResult res;
  res.scene = scene;
  Eigen::MatrixX3d X = scene.mesh.vertices, Xref = X;
  const double rest_extent = scene.mesh.size();
  const double V0 = RegionVolume(scene.mesh, scene.rest_positions_of(regions[0]), regions);
  auto build = [&](const Scene& s) {
    auto model = std::make_shared<const Model>(s);
    return MakeFkSolver(model, s.solver);
  };
  auto tb = Clock::now();
  std::unique_ptr<FkSolver> solver = build(res.scene);
  double build_s = SecondsSince(tb);

  // The actuator value that asks for chamber volume alpha * V0 from the current chamber, whose
  // rest volume a whole re-tessellation may change slightly.
  // After a remesh the actuator's range is widened by the same factor (before the model is built).
  auto value_for = [&](double alpha) {
    return alpha * V0 /
           RegionVolume(res.scene.mesh, res.scene.rest_positions_of(regions[0]), regions);
  };
  auto widen = [&]() {
    res.scene.actuators[a].max = std::max(act.max, value_for(act.max));
    res.scene.actuators[a].min = std::min(act.min, value_for(act.min));
  };

  for (size_t k = 0; k < ladder.size(); ++k) {
    ProgressiveStep st;
    st.k = static_cast<int>(k) + 1;
    st.alpha = ladder[k];
    st.solver_seconds = build_s;
    build_s = 0;
    bool stop = false;
    for (int round = 0;; ++round) {
      Eigen::VectorXd c = res.scene.rest_actuation();
      c[a] = value_for(st.alpha);
      FkResult r = solver->Solve(c, &X);
      AddSolve(r, &st);
      FlagRunaway(res.scene.mesh, regions, V0, rest_extent, st.alpha, &r);
      st.status = r.status;
      if (r.status == FkStatus::Diverged || r.status == FkStatus::InvalidInput) {
        res.status = r.status;
        res.completed = false;
        res.message = "alpha " + FormatNumber(st.alpha) + ": " + r.message;
        stop = true;
        break;
      }
      X = r.positions;
      const RemeshCheck check = CheckRemesh(res.scene.mesh, Xref, X, regions, opt.criteria);
      if (round == 0) {
        st.max_volume_ratio = check.max_volume_ratio;
        st.max_distortion = check.max_distortion;
      }
      if (!opt.remesh || !check.needed || round >= opt.max_remeshes_per_step) break;
      ChamberRemesh rm;
      const auto tr = Clock::now();
      try {
        rm = RemeshChamber(res.scene, X, opt.remesh_options);
      } catch (const std::runtime_error& e) {
        // Keep the state on the current mesh and go on up the ladder; the next check will try
        // again. The failed attempt's time is mesh generation time too.
        st.mesh_seconds += SecondsSince(tr);
        ++st.remesh_failures;
        ++res.remesh_failures;
        if (res.first_remesh_failure.empty())
          res.first_remesh_failure = "alpha " + FormatNumber(st.alpha) + ": " + e.what();
        break;
      }
      st.mesh_seconds += rm.seconds;
      ++st.remeshes;
      ++res.remeshes;
      st.methods += (st.methods.empty() ? "" : "+") + std::string(RemeshMethodToString(rm.method));
      res.scene = std::move(rm.scene);
      X = std::move(rm.positions);
      Xref = X;
      widen();
      tb = Clock::now();
      solver = build(res.scene);
      st.solver_seconds += SecondsSince(tb);
    }
    if (st.status != FkStatus::Converged && res.status == FkStatus::Converged) {
      res.status = st.status;
      if (res.message.empty())
        res.message = "alpha " + FormatNumber(st.alpha) + ": " + FkStatusToString(st.status);
    }
    st.tets = res.scene.mesh.num_tets();
    st.chamber_tets = 0;
    for (const auto& e : res.scene.mesh.elements)
      if (InRegions(e.region, regions)) ++st.chamber_tets;
    st.chamber_volume_ratio = RegionVolume(res.scene.mesh, X, regions) / V0;
    res.mesh_seconds += st.mesh_seconds;
    res.solver_seconds += st.solver_seconds;
    res.steps.push_back(st);
    if (opt.on_step) opt.on_step(st, res.scene, X);
    for (double s : opt.snapshots)
      if (std::abs(s - st.alpha) < 1e-12)
        res.snapshots.push_back({st.alpha, res.scene, X, st.chamber_volume_ratio});
    if (stop) break;
  }
  res.positions = X;
  res.chamber_volume_ratio = RegionVolume(res.scene.mesh, X, regions) / V0;
  return res;
}

}  // namespace softkin
