#include "softkin/solver/fk/contact_term.hpp"

#include "softkin/solver/scene/scene.hpp"

namespace softkin {

bool ContactHandlingActive(const Scene& scene, const CollisionOptions& o) {
  return o.self || (o.obstacles && !scene.obstacles.empty());
}

}  // namespace softkin
