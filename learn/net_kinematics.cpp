#include "softkin/learn/net_kinematics.hpp"

#include "softkin/solver/common/output_file.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace softkin {

namespace fs = std::filesystem;

namespace {

constexpr const char* kFormat = "softkin-nets";
constexpr int kVersion = 1;
const char* const kNetNames[4] = {"fk", "jac", "s2r", "ik"};

Fnn* NetByName(LearnedNets& n, int i) {
  Fnn* all[4] = {&n.fk, &n.jac, &n.s2r, &n.ik};
  return all[i];
}
const Fnn* NetByName(const LearnedNets& n, int i) {
  const Fnn* all[4] = {&n.fk, &n.jac, &n.s2r, &n.ik};
  return all[i];
}

nlohmann::json ToJson(const Eigen::VectorXd& v) {
  nlohmann::json a = nlohmann::json::array();
  for (int i = 0; i < v.size(); ++i) a.push_back(v[i]);
  return a;
}

}  // namespace

std::string LearnedNets::Check() const {
  std::ostringstream s;
  const int m = num_actuators(), P = num_points();
  if (m < 1) return "no actuators (empty lower bound)";
  if (upper.size() != m || rest.size() != m) return "lower, upper and rest have different sizes";
  for (int a = 0; a < m; ++a) {
    if (!std::isfinite(lower[a]) || !std::isfinite(upper[a]) || !(lower[a] < upper[a]))
      return "actuator " + std::to_string(a) + ": expected finite bounds with lower < upper";
    if (!(rest[a] >= lower[a] && rest[a] <= upper[a]))
      return "actuator " + std::to_string(a) + ": rest lies outside [lower, upper]";
  }
  if (P < 1) return "no tracked points";
  if (!has_fk()) return "the fk network is missing";
  if (fk.num_inputs() != m || fk.num_outputs() != 3 * P)
    s << "fk network maps " << fk.num_inputs() << " -> " << fk.num_outputs() << ", expected " << m
      << " actuators -> " << 3 * P << " coordinates";
  else if (has_jac() && (jac.num_inputs() != m || jac.num_outputs() != 3 * P * m))
    s << "jac network maps " << jac.num_inputs() << " -> " << jac.num_outputs() << ", expected "
      << m << " -> " << 3 * P * m << " (the flattened 3P x m Jacobian)";
  else if (has_s2r() && (s2r.num_inputs() != 3 * P || s2r.num_outputs() != 3 * P))
    s << "s2r network maps " << s2r.num_inputs() << " -> " << s2r.num_outputs() << ", expected "
      << 3 * P << " -> " << 3 * P;
  else if (has_ik() && (ik.num_inputs() != 3 || ik.num_outputs() != m))
    s << "ik network maps " << ik.num_inputs() << " -> " << ik.num_outputs() << ", expected 3 -> "
      << m;
  return s.str();
}

void LearnedNets::Save(const std::string& dir) const {
  const std::string why = Check();
  if (!why.empty()) throw std::invalid_argument("LearnedNets::Save(" + dir + "): " + why);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create directory " + dir + ": " + ec.message());
  nlohmann::json j;
  j["format"] = kFormat;
  j["version"] = kVersion;
  j["points"] = points;
  j["lower"] = ToJson(lower);
  j["upper"] = ToJson(upper);
  j["rest"] = ToJson(rest);
  const std::vector<std::string> paths = Files(dir);  // nets.json, then one per network
  nlohmann::json files = nlohmann::json::object();
  for (int i = 0; i < 4; ++i) {
    const Fnn* f = NetByName(*this, i);
    const fs::path file = paths[1 + i];
    if (f->num_layers() > 0) {
      f->Save(file.string());
      files[kNetNames[i]] = file.filename().string();
    } else {
      fs::remove(file, ec);  // a stale network from an earlier Save must not be picked up
    }
  }
  j["networks"] = files;
  j["info"] = info;
  WriteTextFile(paths[0], j.dump(2) + "\n");
}

std::vector<std::string> LearnedNets::Files(const std::string& dir) {
  std::vector<std::string> out = {(fs::path(dir) / "nets.json").string()};
  for (const char* name : kNetNames)
    out.push_back((fs::path(dir) / (name + std::string(".fnn"))).string());
  return out;
}

LearnedNets LearnedNets::Load(const std::string& dir) {
  const std::string path = (fs::path(dir) / "nets.json").string();
  std::ifstream in(path);
  if (!in)
    throw std::runtime_error(path + ": cannot open (is " + dir +
                             " a network directory written by `softkin train`?)");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path + ": not valid JSON: " + e.what());
  }
  auto fail = [&path](const std::string& key, const std::string& what) -> std::runtime_error {
    return std::runtime_error(path + ": key '" + key + "': " + what);
  };
  if (!j.is_object()) throw fail("(root)", "expected a JSON object");
  if (!j.contains("format") || j["format"] != kFormat)
    throw fail("format", std::string("expected \"") + kFormat + "\"");
  if (!j.contains("version") || !j["version"].is_number_integer() || j["version"] != kVersion)
    throw fail("version", "expected " + std::to_string(kVersion));
  auto vec = [&](const char* key) {
    if (!j.contains(key) || !j[key].is_array()) throw fail(key, "expected an array of numbers");
    Eigen::VectorXd v(j[key].size());
    for (size_t i = 0; i < j[key].size(); ++i) {
      if (!j[key][i].is_number())
        throw fail(key, "entry " + std::to_string(i) + " is not a number");
      v[static_cast<int>(i)] = j[key][i].get<double>();
    }
    return v;
  };
  LearnedNets n;
  n.lower = vec("lower");
  n.upper = vec("upper");
  n.rest = vec("rest");
  if (!j.contains("points") || !j["points"].is_array() || j["points"].empty())
    throw fail("points", "expected a non-empty array of point names");
  for (const auto& p : j["points"]) {
    if (!p.is_string()) throw fail("points", "expected strings");
    n.points.push_back(p.get<std::string>());
  }
  if (!j.contains("networks") || !j["networks"].is_object())
    throw fail("networks", "expected an object {\"fk\": \"fk.fnn\", ...}");
  for (auto it = j["networks"].begin(); it != j["networks"].end(); ++it) {
    int which = -1;
    for (int i = 0; i < 4; ++i)
      if (it.key() == kNetNames[i]) which = i;
    if (which < 0)
      throw fail("networks." + it.key(), "unknown network (expected fk, jac, s2r or ik)");
    if (!it.value().is_string()) throw fail("networks." + it.key(), "expected a file name");
    const fs::path file = fs::path(dir) / it.value().get<std::string>();
    *NetByName(n, which) = Fnn::Load(file.string());  // throws naming the file and line
  }
  if (j.contains("info")) n.info = j["info"];
  const std::string why = n.Check();
  if (!why.empty()) throw std::runtime_error(path + ": inconsistent networks: " + why);
  return n;
}

bool JacobianSourceFromString(const std::string& s, JacobianSource* out) {
  if (s == "network")
    *out = JacobianSource::kNetwork;
  else if (s == "fk-derivative")
    *out = JacobianSource::kFkDerivative;
  else
    return false;
  return true;
}

std::string JacobianSourceToString(JacobianSource s) {
  return s == JacobianSource::kNetwork ? "network" : "fk-derivative";
}

NetKinematics::NetKinematics(LearnedNets nets, JacobianSource source, bool use_s2r)
    : nets_(std::move(nets)), source_(source), use_s2r_(use_s2r) {
  const std::string why = nets_.Check();
  if (!why.empty()) throw std::invalid_argument("NetKinematics: " + why);
  if (source_ == JacobianSource::kNetwork && !nets_.has_jac())
    throw std::invalid_argument(
        "NetKinematics: the Jacobian source 'network' needs a jac network (train it with "
        "--what fk,jac, or use the source fk-derivative)");
  if (use_s2r_ && !nets_.has_s2r())
    throw std::invalid_argument("NetKinematics: sim-to-real requested but there is no s2r network");
}

std::string NetKinematics::name() const {
  return std::string("learned(") + JacobianSourceToString(source_) + (use_s2r_ ? ",s2r" : "") + ")";
}

KinematicsEval NetKinematics::Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c,
                                       bool with_jacobian) {
  const auto t0 = std::chrono::steady_clock::now();
  KinematicsEval e;
  e.message = CheckKinematicsInput(*this, c);
  if (!e.message.empty()) return e;
  ++evaluations_;
  const int m = num_actuators(), P = num_points();
  Eigen::VectorXd ps(3 * P);
  Eigen::MatrixXd Js;
  if (with_jacobian && source_ == JacobianSource::kFkDerivative) {
    Js = nets_.fk.InputJacobian(c);
    ps = nets_.fk.Forward(c);
  } else {
    ps = nets_.fk.Forward(c);
    if (with_jacobian) {
      const Eigen::VectorXd flat = nets_.jac.Forward(c);
      Js.resize(3 * P, m);
      for (int r = 0; r < 3 * P; ++r)
        for (int a = 0; a < m; ++a) Js(r, a) = flat[r * m + a];
    }
  }
  Eigen::VectorXd p = ps;
  if (use_s2r_) {
    p = nets_.s2r.Forward(ps);
    if (with_jacobian) Js = nets_.s2r.InputJacobian(ps) * Js;  // Eq. 5.4
  }
  if (!p.allFinite() || (with_jacobian && !Js.allFinite())) {
    e.message = "the networks returned a non-finite value";
    return e;
  }
  e.p.resize(P, 3);
  for (int q = 0; q < P; ++q) e.p.row(q) = p.segment<3>(3 * q).transpose();
  if (with_jacobian) e.J = std::move(Js);
  e.ok = true;
  e.time_s = SecondsSince(t0);
  return e;
}

Eigen::VectorXd DirectIk(const LearnedNets& nets, const Eigen::Vector3d& p) {
  if (!nets.has_ik())
    throw std::invalid_argument("direct IK needs an ik network (train it with --what ik)");
  Eigen::VectorXd c = nets.ik.Forward(p);
  for (int a = 0; a < c.size(); ++a) {
    if (!std::isfinite(c[a])) c[a] = nets.rest[a];
    c[a] = std::clamp(c[a], nets.lower[a], nets.upper[a]);
  }
  return c;
}

}  // namespace softkin
