#pragma once
/// \file
/// Learned kinematics (thesis Sec. 5.2-5.3): the trained networks of one robot, kept together in a
/// directory, and a Kinematics that drives IK with them.
///
///  - N_fk : c -> p, the tracked points (3P outputs, point-major x, y, z), mm;
///  - N_J  : c -> vec(J), the 3P x m Jacobian flattened row-major (output (3 q + d) m + a is
///           dp_{q,d}/dc_a, as in learn/dataset.hpp), mm per unit of actuation;
///  - N_s2r: p^s -> p^r, the sim-to-real layer (3P -> 3P, one hidden layer, Sec. 5.3.4);
///  - N_ik : p -> c, the direct-IK baseline (first tracked point only: 3 -> m), Table 5.1.
/// Only N_fk is required; the others may be absent (an Fnn with no layers).
///
/// Eq. 5.4: with the sim-to-real layer the kinematics of the hardware is p^r = N_s2r(N_fk(c)) and
/// its Jacobian is J^r = dN_s2r/dp^s (p^s) * J^s, where J^s is either N_J(c) (the learned
/// Jacobian, Eq. 5.3) or the input Jacobian of N_fk (its analytic derivative).
///
/// Directory format "softkin-nets v1": `nets.json` (format, version, points, lower, upper, rest,
/// which networks exist, and free-form "info": dataset, errors, training provenance) beside one
/// `softkin-fnn v1` file per network: fk.fnn, jac.fnn, s2r.fnn, ik.fnn.

#include "softkin/ik/kinematics.hpp"
#include "softkin/learn/fnn.hpp"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace softkin {

struct LearnedNets {
  Fnn fk, jac, s2r, ik;
  std::vector<std::string> points;                 ///< P tracked point names (N_fk's output order)
  Eigen::VectorXd lower, upper;                    ///< the actuation box (m each)
  Eigen::VectorXd rest;                            ///< rest actuation (m)
  nlohmann::json info = nlohmann::json::object();  ///< provenance and errors (free form)

  int num_actuators() const { return static_cast<int>(lower.size()); }
  int num_points() const { return static_cast<int>(points.size()); }
  bool has_fk() const { return fk.num_layers() > 0; }
  bool has_jac() const { return jac.num_layers() > 0; }
  bool has_s2r() const { return s2r.num_layers() > 0; }
  bool has_ik() const { return ik.num_layers() > 0; }
  /// "" when the networks fit together (shapes, bounds); else the first inconsistency.
  std::string Check() const;
  /// Writes dir/nets.json and one .fnn per present network (creates dir). Throws on I/O errors or
  /// when Check() fails.
  void Save(const std::string& dir) const;
  /// Reads a directory written by Save. Throws std::runtime_error naming the file and the key (or
  /// the network file's own error) for a missing, corrupt or inconsistent directory.
  static LearnedNets Load(const std::string& dir);
  /// The files Save writes and Load reads in `dir`: nets.json and the four networks' .fnn files.
  static std::vector<std::string> Files(const std::string& dir);
};

/// Where the learned kinematics takes J^s from.
enum class JacobianSource {
  kNetwork,       ///< "network": N_J(c) (Eq. 5.3); needs a jac network
  kFkDerivative,  ///< "fk-derivative": the analytic input Jacobian of N_fk
};
bool JacobianSourceFromString(const std::string& s, JacobianSource* out);
std::string JacobianSourceToString(JacobianSource s);

/// The Kinematics of a set of networks (Eq. 5.4). Evaluate is a few small dense products: no
/// forward solves (fk_solves = 0 per evaluation; total_fk_solves counts network evaluations).
class NetKinematics : public Kinematics {
 public:
  /// Throws std::invalid_argument when the networks are inconsistent, when the source is kNetwork
  /// without an N_J, or when use_s2r is set without an N_s2r.
  NetKinematics(LearnedNets nets, JacobianSource source = JacobianSource::kNetwork,
                bool use_s2r = false);
  std::string name() const override;
  int num_actuators() const override { return nets_.num_actuators(); }
  const std::vector<std::string>& point_names() const override { return nets_.points; }
  const Eigen::VectorXd& lower() const override { return nets_.lower; }
  const Eigen::VectorXd& upper() const override { return nets_.upper; }
  Eigen::VectorXd rest() const override { return nets_.rest; }
  KinematicsEval Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c, bool with_jacobian) override;
  long long total_fk_solves() const override { return evaluations_; }
  const LearnedNets& nets() const { return nets_; }

 private:
  LearnedNets nets_;
  JacobianSource source_;
  bool use_s2r_;
  long long evaluations_ = 0;
};

/// The direct-IK baseline: c = N_ik(p), clamped to the box. Throws without an ik network or
/// when p does not have the network's 3 inputs.
Eigen::VectorXd DirectIk(const LearnedNets& nets, const Eigen::Vector3d& p);

}  // namespace softkin
