/// \file solver_options_json.cpp
/// The FK option table (solver_options_json.hpp): every option of FkOptions once, with its schema
/// entry and accessors; the reader, the writer and the schema entries generated from it.
#include "softkin/solver/scene/solver_options_json.hpp"

#include "softkin/solver/scene/scene_keys.hpp"

#include <algorithm>
#include <functional>
#include <stdexcept>
#include <type_traits>

namespace softkin {

namespace {

using json = nlohmann::json;
using scene_json_detail::KeySpec;
using scene_json_detail::Need;
using scene_json_detail::Type;

/// The allowed names of an enum option (overloaded on the enum, for Option below).
std::vector<std::string> NamesOf(FkSolverType) { return FkSolverTypeNames(); }
std::vector<std::string> NamesOf(AndersonSafeguard) { return AndersonSafeguardNames(); }
std::vector<std::string> NamesOf(SpringUpdate) { return SpringUpdateNames(); }
std::vector<std::string> NamesOf(SelfTarget) { return SelfTargetNames(); }
std::vector<std::string> NamesOf(SelfSpring) { return SelfSpringNames(); }
std::vector<std::string> NamesOf(ObstacleSpring) { return ObstacleSpringNames(); }

/// The option a member pointer names, on FkOptions or on its CollisionOptions.
template <class T>
T& Member(FkOptions& o, T FkOptions::*m) {
  return o.*m;
}
template <class T>
T& Member(FkOptions& o, T CollisionOptions::*m) {
  return o.collision.*m;
}
template <class T>
const T& Member(const FkOptions& o, T FkOptions::*m) {
  return o.*m;
}
template <class T>
const T& Member(const FkOptions& o, T CollisionOptions::*m) {
  return o.collision.*m;
}

/// One option: its schema entry (path solver.<key>; the default is a default-constructed
/// FkOptions' value) and how to read and write it.
struct Row {
  KeySpec spec;
  std::function<json(const FkOptions&)> get;
  std::function<void(const json&, FkOptions*)> set;

  std::string key() const { return spec.path.substr(7); }  // without "solver."
  Row& AtLeast(double v) {
    spec.AtLeast(v);
    return *this;
  }
  Row& Above(double v) {
    spec.Above(v);
    return *this;
  }
  Row& AtMost(double v) {
    spec.AtMost(v);
    return *this;
  }
  Row& In(double a, double b) {
    spec.In(a, b);
    return *this;
  }
};

/// The option `key` (collision options as "collision.<key>") held by member m (of FkOptions or of
/// CollisionOptions): its schema type follows the member's type (an enum: a string, one of its
/// names), its default comes from FkOptions().
template <class S, class T>
Row Option(const std::string& key, T S::*m, std::string doc) {
  Row r;
  r.spec.path = "solver." + key;
  r.spec.need = Need::Optional;
  r.spec.doc = std::move(doc);
  if constexpr (std::is_same_v<T, bool>) {
    r.spec.type = Type::Bool;
  } else if constexpr (std::is_same_v<T, int>) {
    r.spec.type = Type::Integer;
  } else if constexpr (std::is_same_v<T, double>) {
    r.spec.type = Type::Number;
  } else {
    static_assert(std::is_enum_v<T>, "an option is a bool, int, double or named enum");
    r.spec.type = Type::String;
    r.spec.choices = NamesOf(T{});
  }
  // Enums go through their to_json / from_json: their names (fk_options.hpp).
  r.get = [m](const FkOptions& o) { return json(Member(o, m)); };
  r.set = [m](const json& v, FkOptions* o) {
    if constexpr (std::is_same_v<T, int>)
      Member(*o, m) = scene_json_detail::AsInt(v);  // an integral float counts, as in the scene
    else
      Member(*o, m) = v.get<T>();
  };
  r.spec.Def(r.get(FkOptions()));
  return r;
}

/// Every option, in schema order: the FkOptions, then its CollisionOptions.
const std::vector<Row>& Rows() {
  using F = FkOptions;
  using C = CollisionOptions;
  static const std::vector<Row> rows = {
      Option("solver", &F::solver,
             "lg: plain local-global (Algorithm 1); lg-aa: Anderson-accelerated local-global; "
             "newton: Newton-Krylov on the same equilibrium, with load stepping; auto: lg-aa, "
             "or newton from the same start if lg-aa is far from the tolerance after 500 "
             "iterations (docs/newton.md); ceres, "
             "ipopt-lbfgs, ipopt-newton: the same energy minimised by Ceres or Ipopt; "
             "ipopt-hard: body energy with hard actuation constraints; calculix-linear, "
             "calculix-nonlinear: FEM baselines by CalculiX (docs/solvers.md)."),
      Option("max_iterations", &F::max_iterations, "Iteration limit (per continuation step).")
          .AtLeast(1),
      Option("tolerance", &F::tolerance,
             "Converged when every vertex moves less than tolerance x model size in one "
             "iteration (and the gradient test of gradient_tolerance holds).")
          .Above(0.0)
          .AtMost(0.01),
      Option("gradient_tolerance", &F::gradient_tolerance,
             "Converged when the energy gradient norm is below this fraction of its first value "
             "(and the move test of tolerance holds).")
          .Above(0.0)
          .AtMost(0.1),
      Option("anderson_window", &F::anderson_window,
             "History length of Anderson acceleration (lg-aa).")
          .In(1, 50),
      Option("anderson_safeguard", &F::anderson_safeguard,
             "Keep an Anderson step if it lowers the energy or the fixed-point residual "
             "(hybrid), only if it does not raise the energy (energy), or always (none)."),
      Option("continuation_steps", &F::continuation_steps,
             "Apply the actuation in this many equal steps, warm-starting each.")
          .AtLeast(1),
      Option("threads", &F::threads, "OpenMP threads for the local step (0: library default).")
          .In(0, kMaxThreads),
      Option("time_limit_s", &F::time_limit_s,
             "Wall-clock limit of one solve in seconds (0: none); when it runs out the solve "
             "ends with status time_limit and its last checked state.")
          .AtLeast(0.0),
      Option("collision.self", &C::self,
             "Respond to self-collision: boundary vertices inside tets not incident to them (tet "
             "meshes only)."),
      Option("collision.obstacles", &C::obstacles, "Respond to the scene's obstacles."),
      Option("collision.epsilon", &C::epsilon,
             "Offset of the contact boundary (mm): springs pull vertices this far beyond it and "
             "release them once they are this far beyond their target (Eq. 3.8).")
          .AtLeast(0.0),
      Option("collision.stiffness", &C::stiffness,
             "Spring stiffness k (Eq. 3.5) relative to the median diagonal entry of the global "
             "matrix over the boundary vertices.")
          .Above(0.0),
      Option("collision.check_interval", &C::check_interval,
             "Run collision detection every this many iterations (and before stopping).")
          .AtLeast(1),
      Option("collision.update", &C::update,
             "How the factor follows the spring set: CHOLMOD update/downdate, or a numeric "
             "refactorisation."),
      Option("collision.self_target", &C::self_target,
             "Where a self-collided vertex is sent: 'walk' along -n(v) through the collided "
             "region (the thesis's rule) for every contact, or 'auto': the same within one body, "
             "the closest facing point of the other body's surface between separate bodies."),
      Option("collision.self_spring", &C::self_spring,
             "What a self-collision spring pulls its vertex to: 'pair', the exit point as a point "
             "of the exit face, which moves with the face and loads both sides of the contact "
             "equally and oppositely; or a fixed 'target' half way to the exit point (Eq. 3.5 as "
             "the thesis writes it; unbalanced and sticky)."),
      Option("collision.obstacle_spring", &C::obstacle_spring,
             "What an obstacle spring resists: 'plane', only the normal part of the offset to "
             "the closest point plus eps, against the obstacle's tangent plane (frictionless), "
             "or 'point', the whole offset (Eq. 3.5 as written; it holds the vertex "
             "tangentially between checks, so sliding contacts creep)."),
  };
  return rows;
}

/// The known keys below `prefix` ("" or "collision."), for messages.
std::string KnownKeys(const std::string& prefix) {
  std::vector<std::string> keys;
  for (const Row& r : Rows()) {
    const std::string key = r.key();
    if (key.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string rest = key.substr(prefix.size());
    const std::string head = rest.substr(0, rest.find('.'));
    if (std::find(keys.begin(), keys.end(), head) == keys.end()) keys.push_back(head);
  }
  return scene_json_detail::ListText(keys);
}

void ReadObject(const json& j, const std::string& where, const std::string& prefix, FkOptions* o) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string key = prefix + it.key();
    const json& v = it.value();
    if (prefix.empty() && it.key() == "collision") {
      if (!v.is_object())
        throw std::invalid_argument(where +
                                    ".collision: expected an object of collision "
                                    "options, got " +
                                    scene_json_detail::Got(v));
      ReadObject(v, where, "collision.", o);
      continue;
    }
    const auto row =
        std::find_if(Rows().begin(), Rows().end(), [&](const Row& r) { return r.key() == key; });
    if (row == Rows().end())
      throw std::invalid_argument(where + "." + key + ": unknown key (expected one of " +
                                  KnownKeys(prefix) + ")");
    if (!scene_json_detail::ValueOk(row->spec, v))
      throw std::invalid_argument(where + "." + key + ": expected " +
                                  scene_json_detail::TypeText(row->spec, true) + ", got " +
                                  scene_json_detail::Got(v));
    row->set(v, o);
  }
}

}  // namespace

namespace scene_json_detail {

std::vector<KeySpec> SolverKeySpecs() {
  auto object = [](std::string path, std::string doc) {
    KeySpec k;
    k.path = std::move(path);
    k.type = Type::Object;
    k.need = Need::Optional;
    k.doc = std::move(doc);
    k.Def(json::object());
    return k;
  };
  std::vector<KeySpec> t = {
      object("solver", "Default forward-kinematics solver options of this scene.")};
  bool collision = false;  // the solver.collision object comes before its first option
  for (const Row& r : Rows()) {
    if (!collision && r.key().rfind("collision.", 0) == 0) {
      t.push_back(object("solver.collision",
                         "Collision response by springs (Sec. 3.2.3, Eq. 3.5, 3.8, 3.9; lg and "
                         "lg-aa)."));
      collision = true;
    }
    t.push_back(r.spec);
  }
  return t;
}

}  // namespace scene_json_detail

FkOptions ReadSolverOptionsJson(const json& j, const std::string& where, const FkOptions& base) {
  if (!j.is_object())
    throw std::invalid_argument(where + ": expected an object of solver options, got " +
                                scene_json_detail::Got(j));
  FkOptions o = base;
  ReadObject(j, where, "", &o);
  std::string why;
  if (!o.IsValid(&why)) throw std::invalid_argument(where + "." + why);
  return o;
}

json SolverOptionsToJson(const FkOptions& o) {
  json j = json::object();
  for (const Row& r : Rows()) {
    const std::string key = r.key();
    if (key.rfind("collision.", 0) == 0)
      j["collision"][key.substr(10)] = r.get(o);
    else
      j[key] = r.get(o);
  }
  return j;
}

std::vector<SolverOptionDoc> SolverOptionDocs() {
  std::vector<SolverOptionDoc> docs;
  for (const Row& r : Rows())
    docs.push_back({r.key(), scene_json_detail::TypeText(r.spec, true), r.spec.doc, r.spec.def});
  return docs;
}

std::vector<std::string> SolverOptionKeys() {
  std::vector<std::string> keys;
  for (const Row& r : Rows()) keys.push_back(r.key());
  return keys;
}

}  // namespace softkin
