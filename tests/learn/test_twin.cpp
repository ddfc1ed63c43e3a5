// The "hardware" twins: labelled as twins, positions only, and differing from the nominal robot
// exactly by the documented offset and noise where the physics agrees (at rest), by more where
// the perturbed material and geometry act (when actuated).
#include "softkin/learn/twin.hpp"

#include "softkin/ik/simulator_kinematics.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

namespace softkin {
namespace {

constexpr int kRes = 3;  // the coarsest three_chamber: a test stays well under a second

TwinOptions Opts(bool noise, bool offset) {
  TwinOptions o;
  o.res = kRes;
  o.points = {"tip"};
  o.noise = noise;
  o.offset = offset;
  o.gradient_tolerance = 1e-4;  // micrometres of tip motion; a third of the iterations
  return o;
}

/// The nominal three_chamber's tip, solved with the twins' test tolerance.
std::unique_ptr<SimulatorKinematics> Nominal() {
  const Scene s = MakeRobot("three_chamber", kRes);
  FkOptions fk = s.solver;
  fk.gradient_tolerance = 1e-4;
  SimulatorKinematicsOptions ko;
  ko.points = {"tip"};
  return std::make_unique<SimulatorKinematics>(s, ko, &fk);
}

TEST(Twin, NamesSayTwinAndUnknownNamesAreListed) {
  EXPECT_EQ(TwinNames().size(), 3u);
  for (const auto& n : TwinNames()) {
    const TwinSpec s = GetTwinSpec(n);
    EXPECT_EQ(s.name, n);
    EXPECT_FALSE(s.doc.empty());
    EXPECT_GT(s.marker_offset.norm(), 0.0);
    EXPECT_DOUBLE_EQ(s.noise_sigma_mm, 0.05);
    EXPECT_EQ(MakeTwinScene(s, s.robot == "three_chamber" ? kRes : 6).name, "twin:" + n);
  }
  try {
    GetTwinSpec("three_chamber/robot3");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("three_chamber/robot1"), std::string::npos);
  }
  TwinKinematics t(GetTwinSpec("three_chamber/robot1"), Opts(true, true));
  EXPECT_EQ(t.name(), "twin:three_chamber/robot1");
}

TEST(Twin, GivesNoJacobian) {
  TwinKinematics t(GetTwinSpec("three_chamber/robot2"), Opts(true, true));
  const KinematicsEval e = t.Evaluate(t.rest(), true);
  EXPECT_FALSE(e.ok);
  EXPECT_NE(e.message.find("no Jacobian"), std::string::npos) << e.message;
  EXPECT_EQ(t.total_fk_solves(), 0);
}

TEST(Twin, PerturbationsReachTheScene) {
  // chamber_radius: the default reproduces the nominal tagging; a larger radius tags more tets.
  const Scene nominal = MakeRobot("three_chamber", kRes);
  const Scene same = MakeRobot("three_chamber", kRes, {{"chamber_radius", 7.0}});
  auto regions = [](const Scene& s) {
    std::vector<int> r;
    for (const auto& e : s.mesh.elements) r.push_back(e.region);
    return r;
  };
  EXPECT_EQ(regions(nominal), regions(same));
  auto chamber_tets = [](const Scene& s) {
    long long n = 0;
    for (const auto& e : s.mesh.elements) n += (e.region >= 1 && e.region <= 3);
    return n;
  };
  const TwinSpec r1 = GetTwinSpec("three_chamber/robot1"), r2 = GetTwinSpec("three_chamber/robot2");
  const Scene s1 = MakeTwinScene(r1, kRes), s2 = MakeTwinScene(r2, kRes);
  EXPECT_GT(chamber_tets(s1), chamber_tets(nominal));
  EXPECT_LT(chamber_tets(s2), chamber_tets(nominal));
  EXPECT_DOUBLE_EQ(s1.body.at(0).r_omega, r1.body_r_omega);
  EXPECT_DOUBLE_EQ(s2.actuators[0].weight, nominal.actuators[0].weight * r2.actuator_weight_scale);
  const TwinSpec f = GetTwinSpec("finger_manipulator/robot1");
  const Scene sf = MakeTwinScene(f, 6);
  EXPECT_DOUBLE_EQ(sf.actuators[0].gain, f.params.at("gain"));
  EXPECT_THROW(MakeRobot("three_chamber", kRes, {{"chamber_radius", 12.0}}), std::invalid_argument);
}

TEST(Twin, AtRestTheTwinIsTheNominalPlusOffsetPlusNoise) {
  // At the rest actuation every twin's body is undeformed, whatever its material, so the
  // measurement is the nominal tip plus exactly the marker offset and the noise.
  const TwinSpec spec = GetTwinSpec("three_chamber/robot2");
  TwinKinematics twin(spec, Opts(true, true));
  const Eigen::VectorXd c = twin.rest();
  const KinematicsEval en = Nominal()->Evaluate(c, false), et = twin.Evaluate(c, false);
  ASSERT_TRUE(en.ok && et.ok) << en.message << et.message;
  for (int d = 0; d < 3; ++d)
    EXPECT_NEAR(et.p(0, d) - en.p(0, d), spec.marker_offset[d] + twin.Noise(c, 0, d), 1e-6) << d;
}

TEST(Twin, OffsetAndNoiseAreExactlyTheDocumentedTerms) {
  const TwinSpec spec = GetTwinSpec("three_chamber/robot1");
  TwinKinematics clean(spec, Opts(false, false)), measured(spec, Opts(true, true));
  const Eigen::Vector3d c(1.6, 1.0, 1.3);
  const KinematicsEval a = clean.Evaluate(c, false), b = measured.Evaluate(c, false);
  ASSERT_TRUE(a.ok && b.ok) << a.message << b.message;
  for (int d = 0; d < 3; ++d)
    EXPECT_NEAR(b.p(0, d) - a.p(0, d), spec.marker_offset[d] + measured.Noise(c, 0, d), 1e-9);
  // The same actuation gives the same measurement (a frozen noise field).
  measured.Reset();
  const KinematicsEval b2 = measured.Evaluate(c, false);
  EXPECT_EQ(b.p, b2.p);
  EXPECT_EQ(clean.Noise(c, 0, 0), 0.0);
}

TEST(Twin, NoiseIsGaussianWithTheDocumentedSigma) {
  const TwinSpec spec = GetTwinSpec("finger_manipulator/robot1");
  TwinOptions o;
  o.res = 6;
  TwinKinematics t(spec, o);
  const int n = 20000;
  double sum = 0, sum2 = 0, sum4 = 0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d c(-3.0 + 6.0 * i / n, 0.5, -1.0);
    const double z = t.Noise(c, i % 3, (i / 3) % 3);
    sum += z;
    sum2 += z * z;
    sum4 += z * z * z * z;
  }
  const double sigma = spec.noise_sigma_mm, mean = sum / n, var = sum2 / n;
  EXPECT_LT(std::abs(mean), 4.0 * sigma / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(var), sigma, 0.03 * sigma);
  // Gaussian kurtosis 3 (a uniform would give 1.8).
  EXPECT_NEAR(sum4 / n / (var * var), 3.0, 0.15);
}

TEST(Twin, ActuatedTwinDiffersFromTheNominalBeyondTheOffset) {
  const Eigen::Vector3d c(2.0, 1.0, 1.0);
  const KinematicsEval en = Nominal()->Evaluate(c, false);
  ASSERT_TRUE(en.ok) << en.message;
  for (const std::string name : {"three_chamber/robot1", "three_chamber/robot2"}) {
    TwinKinematics clean(GetTwinSpec(name), Opts(false, false));
    const KinematicsEval et = clean.Evaluate(c, false);
    ASSERT_TRUE(et.ok) << et.message;
    EXPECT_GT((et.p - en.p).norm(), 0.5) << name;  // the material and geometry act
  }
}

}  // namespace
}  // namespace softkin
