#include "softkin/solver/fk/contact_term.hpp"

#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/scene/scene.hpp"

#include <algorithm>
#include <exception>

namespace softkin {

bool ContactHandlingActive(const Scene& scene, const CollisionOptions& o) {
  return o.self || (o.obstacles && !scene.obstacles.empty());
}

bool EnsureContactTerm(const ContactTermFactory& factory, const Model& model,
                       const CollisionOptions& options, std::unique_ptr<ContactTerm>* term,
                       std::string* why) {
  if (*term) return true;
  if (!factory) {
    *why = "scene '" + model.scene().name +
           "' has collision handling on, and this solver was built without a contact term (build "
           "it with MakeFkSolver, solver/factory/fk_factory.hpp, or turn solver.collision off)";
    return false;
  }
  try {
    *term = factory(model, options);
  } catch (const std::exception& e) {
    *why = e.what();
    return false;
  }
  return true;
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
