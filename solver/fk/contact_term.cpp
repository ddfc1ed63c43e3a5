#include "softkin/solver/fk/contact_term.hpp"

#include "softkin/solver/scene/scene.hpp"

#include <algorithm>

namespace softkin {

bool ContactHandlingActive(const Scene& scene, const CollisionOptions& o) {
  return o.self || (o.obstacles && !scene.obstacles.empty());
}

void CollisionStats::Add(const CollisionStats& o) {
  checks += o.checks;
  springs_added += o.springs_added;
  springs_released += o.springs_released;
  max_springs = std::max(max_springs, o.max_springs);
  unresolved += o.unresolved;
  stiffenings += o.stiffenings;
  check_s += o.check_s;
  response_s += o.response_s;
}

}  // namespace softkin
