#include "softkin/experiments/matched_volume.hpp"

#include <algorithm>
#include <cmath>

namespace softkin {

MatchedVolume SolveAtVolume(FkSolver* solver, const Scene& scene, const std::vector<double>& target,
                            const std::vector<bool>& loaded, const Eigen::MatrixX3d* warm) {
  MatchedVolume m;
  const int na = scene.num_actuators();
  Eigen::VectorXd c = scene.rest_actuation(), c_prev = c, r_prev = Eigen::VectorXd::Ones(na);
  for (int a = 0; a < na; ++a)
    if (loaded[a]) c[a] = std::clamp(target[a], scene.actuators[a].min, scene.actuators[a].max);
  Eigen::MatrixX3d start = warm ? *warm : scene.mesh.vertices;
  for (int it = 0; it < 12; ++it) {
    m.r = solver->Solve(c, &start);
    m.c = c;
    if (m.r.status != FkStatus::Converged) return m;
    start = m.r.positions;
    double worst = 0;
    Eigen::VectorXd next = c;
    for (int a = 0; a < na; ++a) {
      if (!loaded[a]) continue;
      const double r = m.r.volume_ratios[a];
      worst = std::max(worst, std::abs(r - target[a]) / target[a]);
      // The secant slope dc/dratio, bounded so that one noisy pair cannot throw c far away.
      const double slope =
          std::abs(r - r_prev[a]) > 1e-12 ? (c[a] - c_prev[a]) / (r - r_prev[a]) : 1.0;
      next[a] = std::clamp(c[a] + std::clamp(slope, 0.2, 20.0) * (target[a] - r),
                           scene.actuators[a].min, scene.actuators[a].max);
      r_prev[a] = r;
    }
    if (worst < 1e-3) {
      m.matched = true;
      return m;
    }
    c_prev = c;
    if ((next - c).cwiseAbs().maxCoeff() < 1e-12) return m;  // held at the range's end
    c = next;
  }
  return m;
}

}  // namespace softkin
