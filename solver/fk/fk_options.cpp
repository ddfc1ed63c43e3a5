#include "softkin/solver/fk/fk_options.hpp"

#include "softkin/solver/common/enum_names.hpp"

#include <nlohmann/json.hpp>

#include <cmath>

namespace softkin {

namespace {

constexpr EnumName<FkSolverType> kSolverNames[] = {
    {FkSolverType::kLg, "lg"},
    {FkSolverType::kLgAa, "lg-aa"},
    {FkSolverType::kNewton, "newton"},
    {FkSolverType::kAuto, "auto"},
    {FkSolverType::kCeres, "ceres"},
    {FkSolverType::kIpoptLbfgs, "ipopt-lbfgs"},
    {FkSolverType::kIpoptNewton, "ipopt-newton"},
    {FkSolverType::kIpoptHard, "ipopt-hard"},
    {FkSolverType::kCalculixLinear, "calculix-linear"},
    {FkSolverType::kCalculixNonlinear, "calculix-nonlinear"},
};
constexpr EnumName<AndersonSafeguard> kSafeguardNames[] = {
    {AndersonSafeguard::kHybrid, "hybrid"},
    {AndersonSafeguard::kEnergy, "energy"},
    {AndersonSafeguard::kNone, "none"},
};
constexpr EnumName<SpringUpdate> kUpdateNames[] = {
    {SpringUpdate::kUpdown, "updown"},
    {SpringUpdate::kRefactor, "refactor"},
};
constexpr EnumName<SelfTarget> kSelfTargetNames[] = {
    {SelfTarget::kAuto, "auto"},
    {SelfTarget::kWalk, "walk"},
};
constexpr EnumName<SelfSpring> kSelfSpringNames[] = {
    {SelfSpring::kTarget, "target"},
    {SelfSpring::kPair, "pair"},
};
constexpr EnumName<ObstacleSpring> kObstacleSpringNames[] = {
    {ObstacleSpring::kPlane, "plane"},
    {ObstacleSpring::kPoint, "point"},
};

}  // namespace

std::string ToString(FkSolverType t) { return EnumToString(kSolverNames, t); }
FkSolverType FkSolverTypeFromString(const std::string& s) {
  return EnumFromString(kSolverNames, s, "FK solver");
}
std::vector<std::string> FkSolverTypeNames() { return EnumNames(kSolverNames); }
void to_json(nlohmann::json& j, FkSolverType v) { j = ToString(v); }
void from_json(const nlohmann::json& j, FkSolverType& v) {
  v = FkSolverTypeFromString(j.get<std::string>());
}

std::string ToString(AndersonSafeguard g) { return EnumToString(kSafeguardNames, g); }
AndersonSafeguard AndersonSafeguardFromString(const std::string& s) {
  return EnumFromString(kSafeguardNames, s, "Anderson safeguard");
}
std::vector<std::string> AndersonSafeguardNames() { return EnumNames(kSafeguardNames); }
void to_json(nlohmann::json& j, AndersonSafeguard v) { j = ToString(v); }
void from_json(const nlohmann::json& j, AndersonSafeguard& v) {
  v = AndersonSafeguardFromString(j.get<std::string>());
}

std::string ToString(SpringUpdate u) { return EnumToString(kUpdateNames, u); }
SpringUpdate SpringUpdateFromString(const std::string& s) {
  return EnumFromString(kUpdateNames, s, "spring update");
}
std::vector<std::string> SpringUpdateNames() { return EnumNames(kUpdateNames); }
void to_json(nlohmann::json& j, SpringUpdate v) { j = ToString(v); }
void from_json(const nlohmann::json& j, SpringUpdate& v) {
  v = SpringUpdateFromString(j.get<std::string>());
}

std::string ToString(SelfTarget t) { return EnumToString(kSelfTargetNames, t); }
SelfTarget SelfTargetFromString(const std::string& s) {
  return EnumFromString(kSelfTargetNames, s, "self-collision target");
}
std::vector<std::string> SelfTargetNames() { return EnumNames(kSelfTargetNames); }
void to_json(nlohmann::json& j, SelfTarget v) { j = ToString(v); }
void from_json(const nlohmann::json& j, SelfTarget& v) {
  v = SelfTargetFromString(j.get<std::string>());
}

std::string ToString(SelfSpring s) { return EnumToString(kSelfSpringNames, s); }
SelfSpring SelfSpringFromString(const std::string& s) {
  return EnumFromString(kSelfSpringNames, s, "self-collision spring");
}
std::vector<std::string> SelfSpringNames() { return EnumNames(kSelfSpringNames); }
void to_json(nlohmann::json& j, SelfSpring v) { j = ToString(v); }
void from_json(const nlohmann::json& j, SelfSpring& v) {
  v = SelfSpringFromString(j.get<std::string>());
}

std::string ToString(ObstacleSpring s) { return EnumToString(kObstacleSpringNames, s); }
ObstacleSpring ObstacleSpringFromString(const std::string& s) {
  return EnumFromString(kObstacleSpringNames, s, "obstacle spring");
}
std::vector<std::string> ObstacleSpringNames() { return EnumNames(kObstacleSpringNames); }
void to_json(nlohmann::json& j, ObstacleSpring v) { j = ToString(v); }
void from_json(const nlohmann::json& j, ObstacleSpring& v) {
  v = ObstacleSpringFromString(j.get<std::string>());
}

bool CollisionOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!(epsilon >= 0.0) || !std::isfinite(epsilon))
    return bad("collision.epsilon: expected a number >= 0 (mm)");
  if (!(stiffness > 0.0) || !std::isfinite(stiffness))
    return bad("collision.stiffness: expected a number > 0");
  if (check_interval < 1) return bad("collision.check_interval: expected an integer >= 1");
  return true;
}

bool FkOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (max_iterations < 1) return bad("max_iterations: expected an integer >= 1");
  if (!(tolerance > 0.0) || !std::isfinite(tolerance))
    return bad("tolerance: expected a number > 0");
  if (!(gradient_tolerance > 0.0) || !std::isfinite(gradient_tolerance))
    return bad("gradient_tolerance: expected a number > 0");
  if (anderson_window < 1 || anderson_window > 50)
    return bad("anderson_window: expected an integer in [1, 50]");
  if (continuation_steps < 1) return bad("continuation_steps: expected an integer >= 1");
  if (threads < 0 || threads > kMaxThreads)
    return bad("threads: expected an integer in [0, " + std::to_string(kMaxThreads) + "]");
  if (!(time_limit_s >= 0.0) || !std::isfinite(time_limit_s))
    return bad("time_limit_s: expected a number >= 0 (0: no limit)");
  if (!(progress_interval_s > 0.0) || !std::isfinite(progress_interval_s))
    return bad("progress_interval_s: expected a number > 0");
  if (!collision.IsValid(why)) return false;
  return true;
}

}  // namespace softkin
