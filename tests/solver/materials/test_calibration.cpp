// R_omega calibration (solver/materials/calibration.hpp): Eq. 2.9, the elongation and twisting
// tests on bimaterial_bar, monotonicity of R_m in R_omega, and the bisection recovering known
// parameters.
#include "softkin/solver/materials/calibration.hpp"

#include <gtest/gtest.h>

#include <sstream>

#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace softkin {
namespace {

BarTestOptions Coarse() {
  BarTestOptions o;
  o.res = 2;  // 6 mm cells across, 6.7 mm along: 288 tets, a fraction of a second per test
  return o;
}

TEST(Calibration, Eq29) {
  // Equal strains (dL1 / L1 = dL / L): R_m = 1.
  EXPECT_DOUBLE_EQ(ElasticityRatio(80, 40, 8, 4), 1.0);
  // A stiffer: the interface moves less. L1 = 40, dL1 = 1 of dL = 8: eps_A = 1/40, eps_B = 7/40.
  EXPECT_DOUBLE_EQ(ElasticityRatio(80, 40, 8, 1), 7.0);
  // Unequal lengths: L1 = 20, L = 80, dL1 = 1, dL = 4: eps_A = 1/20, eps_B = 3/60.
  EXPECT_DOUBLE_EQ(ElasticityRatio(80, 20, 4, 1), 1.0);
  for (auto bad :
       {std::array<double, 4>{80, 0, 8, 1}, {80, 80, 8, 1}, {80, 40, 8, 0}, {80, 40, 8, 8}})
    EXPECT_THROW(ElasticityRatio(bad[0], bad[1], bad[2], bad[3]), std::invalid_argument);
}

TEST(Calibration, EqualMaterialsGiveUnitRatioAndTwistSymmetrically) {
  const BarTestOptions o = Coarse();
  const ElongationResult e = RunElongationTest(1.0, 1.0, o);
  std::printf("  equal materials: L = %.2f, L1 = %.2f, dL1 = %.4f of %.1f mm, R_m = %.5f\n", e.l_mm,
              e.l1_mm, e.dl1_mm, e.dl_mm, e.rm);
  // The bar keeps its design dimensions at any res (grid lines on its ends and interface), and
  // its mesh is mirror-symmetric about the interface, so equal halves strain equally.
  EXPECT_DOUBLE_EQ(e.l_mm, 80.0);
  EXPECT_DOUBLE_EQ(e.l1_mm, 40.0);
  EXPECT_NEAR(e.rm, 1.0, 1e-4);
  const TwistResult t = RunTwistTest(1.0, 1.0, o);
  std::printf("  twist %.0f: A %.3f, B %.3f, a_mid %.3f, b_mid %.3f deg\n", t.twist_deg,
              t.angle_a_deg, t.angle_b_deg, t.a_mid_deg, t.b_mid_deg);
  // Equal materials twist in proportion to their lengths: half each.
  EXPECT_NEAR(t.angle_a_deg, 0.5 * t.twist_deg, 0.05);
  EXPECT_NEAR(t.angle_b_deg, 0.5 * t.twist_deg, 0.05);
  EXPECT_GT(t.a_mid_deg, 0.0);
  EXPECT_LT(t.a_mid_deg, t.angle_a_deg);
  EXPECT_GT(t.b_mid_deg, t.angle_a_deg);
  EXPECT_LT(t.b_mid_deg, t.twist_deg);
}

TEST(Calibration, RmGrowsAsTheFreeEndMaterialSoftens) {
  const BarTestOptions o = Coarse();
  double prev = 0;
  for (double rb : {1.0, 0.5, 0.2, 0.1, 0.05}) {
    const double rm = RunElongationTest(1.0, rb, o).rm;
    std::printf("  R_omega^B = %.2f: R_m = %.4f\n", rb, rm);
    EXPECT_GT(rm, prev + 1e-3) << "R_omega^B = " << rb;
    prev = rm;
  }
  // And the other way round: softening A (fixed end) lowers R_m below 1.
  EXPECT_LT(RunElongationTest(0.2, 1.0, o).rm, 0.8);
  // A softer B also twists more.
  const TwistResult t = RunTwistTest(1.0, 0.2, o);
  EXPECT_GT(t.angle_b_deg, 1.5 * t.angle_a_deg);
}

TEST(Calibration, BisectionRecoversKnownParameters) {
  const BarTestOptions o = Coarse();
  // A stiffer (R_m > 1): B's R_omega is found.
  const double rm = RunElongationTest(1.0, 0.25, o).rm;
  const CalibrationResult c = CalibrateROmega(rm, o, 1e-4);
  std::printf("  target R_m %.5f: ratio %.4f (expected 4), R_m %.5f, %d tests\n", rm, c.ratio,
              c.achieved_rm, c.evaluations);
  EXPECT_NEAR(c.r_omega_a, 1.0, 0.0);
  EXPECT_NEAR(c.r_omega_b, 0.25, 0.25 * 0.01);
  EXPECT_NEAR(c.achieved_rm, rm, 1e-4 * rm);
  EXPECT_EQ(c.evaluations, static_cast<int>(c.history.size()));
  // B stiffer (R_m < 1): A's R_omega is found.
  const double rm2 = RunElongationTest(0.4, 1.0, o).rm;
  ASSERT_LT(rm2, 1.0);
  const CalibrationResult c2 = CalibrateROmega(rm2, o, 1e-4);
  EXPECT_NEAR(c2.r_omega_b, 1.0, 0.0);
  EXPECT_NEAR(c2.r_omega_a, 0.4, 0.4 * 0.01);
  EXPECT_NEAR(c2.ratio, 0.4, 0.4 * 0.01);
}

TEST(Calibration, BadTargetsAndOptionsAreRejectedWithTheRange) {
  BarTestOptions o = Coarse();
  for (double bad : {0.0, -2.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    try {
      CalibrateROmega(bad, o);
      ADD_FAILURE() << "accepted R_m = " << bad;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("rm"), std::string::npos) << e.what();
    }
  }
  // Beyond what R_omega in [0.5, 1] can reach on this bar: the message gives the reachable range.
  try {
    CalibrateROmega(50.0, o, 1e-3, 0.5);
    ADD_FAILURE() << "accepted an unreachable R_m";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("outside the range"), std::string::npos) << e.what();
  }
  // Two bracketing steps (R_omega 0.25, then the bound 0.2): the range still starts at the
  // equal-material ratio (it used to print the ratio at R_omega = 0.25 as "equal R_omega").
  {
    std::ostringstream equal;
    equal << "from " << RunElongationTest(1.0, 1.0, o).rm << " (equal R_omega)";
    try {
      CalibrateROmega(1000.0, o, 1e-3, 0.2);
      ADD_FAILURE() << "accepted an unreachable R_m";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(equal.str()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("R_omega in [0.2, 1]"), std::string::npos) << e.what();
    }
  }
  o.stretch_mm = 0;
  try {
    RunElongationTest(1.0, 1.0, o);
    ADD_FAILURE() << "accepted stretch 0";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("stretch_mm"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace softkin
