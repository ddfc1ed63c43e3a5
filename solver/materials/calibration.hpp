#pragma once
/// \file calibration.hpp
/// Calibration of the shape parameter R_omega (thesis Sec. 2.4.2, Eq. 2.9, Table 2.1, Fig. 2.6),
/// run in simulation on the embedded `bimaterial_bar`: material A from the fixed end x = 0 to the
/// interface x = L1, material B from there to the free end x = L.
///
/// Elongation test: the free end is displaced by dL along the bar; the interface moves by dL1.
/// Eq. 2.9 gives the elasticity ratio
///     R_m = L1 (dL - dL1) / ((L - L1) dL1).
/// With eps_A = dL1 / L1 and eps_B = (dL - dL1) / (L - L1) this expression is eps_B / eps_A, the
/// stiffness ratio E_A / E_B of two linear materials in series (the thesis's text calls it
/// eps_A / eps_B, but its expression and Table 2.1, where R_m > 1 goes with R_omega^A/R_omega^B
/// > 1, both mean the stiffness ratio). R_m > 1: A is the stiffer material.
///
/// Calibration: the stiffer material keeps R_omega = 1, and the softer one's R_omega is found by
/// bisection (on its logarithm) so that the simulated R_m matches the measured one. The result is
/// the ratio R_omega^A / R_omega^B. Element weights stay 1: R_omega alone models the material.
///
/// Twisting test (Fig. 2.6d): the free end is turned about the bar's axis; the rotation of the
/// interface cross-section is material A's twist, the rest is B's. For linear materials of equal
/// length the ratio of the twists, B over A, is the shear-modulus ratio G_A / G_B, the same as R_m,
/// which makes the twist a check of a calibration made by elongation.
#include "softkin/solver/fk/fk_solver.hpp"

#include <string>
#include <vector>

namespace softkin {

/// The test specimen and its load. Defaults: bimaterial_bar's own resolution, interface at mid
/// length, 10% elongation, a quarter turn.
struct BarTestOptions {
  int res = 0;              ///< bimaterial_bar resolution (cells across 12 mm; 0 = default)
  double interface = 0.5;   ///< interface position as a fraction of the length (snapped)
  double stretch_mm = 8.0;  ///< dL: imposed end displacement, mm, in (0, 40]
  double twist_deg = 90.0;  ///< imposed end rotation of the twisting test, degrees
  int twist_steps = 3;      ///< continuation steps of the twisting test
  FkOptions solver;         ///< FK options (lg-aa by default)
  /// Throws std::invalid_argument naming the field if a value is out of range.
  void Validate() const;
};

/// Eq. 2.9. Throws std::invalid_argument unless 0 < L1 < L and 0 < dL1 < dL.
double ElasticityRatio(double L, double L1, double dL, double dL1);

struct ElongationResult {
  double rm = 0;      ///< Eq. 2.9
  double l_mm = 0;    ///< L: bar length
  double l1_mm = 0;   ///< L1: interface position at rest (after snapping to the mesh)
  double dl_mm = 0;   ///< dL: end displacement
  double dl1_mm = 0;  ///< dL1: mean displacement of the interface cross-section along the bar
  FkResult fk;        ///< the FK solve (status, iterations, time)
};

/// One elongation test with the given R_omega of A and B. Throws std::runtime_error if the FK
/// solve does not converge or the interface does not move between the ends.
ElongationResult RunElongationTest(double r_omega_a, double r_omega_b, const BarTestOptions& opt);

struct TwistResult {
  double twist_deg = 0;        ///< imposed end rotation
  double l_mm = 0, l1_mm = 0;  ///< bar length and interface position at rest (as in elongation)
  double angle_a_deg = 0;      ///< rotation of the interface section (material A's twist)
  double angle_b_deg = 0;      ///< twist_deg - angle_a_deg (material B's twist)
  double a_mid_deg = 0;        ///< rotation of the section midway through A
  double b_mid_deg = 0;        ///< rotation of the section midway through B
  FkResult fk;
};

/// One twisting test. Throws std::runtime_error if the FK solve does not converge.
TwistResult RunTwistTest(double r_omega_a, double r_omega_b, const BarTestOptions& opt);

struct CalibrationResult {
  double target_rm = 0;
  double achieved_rm = 0;  ///< R_m simulated with the returned parameters
  double r_omega_a = 1, r_omega_b = 1;
  double ratio = 1;     ///< r_omega_a / r_omega_b
  int evaluations = 0;  ///< elongation tests run
  /// Every test run: (R_omega of the softer material, simulated R_m), in order.
  std::vector<std::pair<double, double>> history;
};

/// Finds R_omega^A / R_omega^B such that the simulated R_m equals `target_rm` within
/// `rel_tol` (relative), by bisection on log R_omega of the softer material in [r_min, 1].
/// Throws std::invalid_argument if target_rm is not a finite number > 0, or if it lies outside the
/// range the specimen can reach (the message gives that range), std::runtime_error if a solve
/// fails.
CalibrationResult CalibrateROmega(double target_rm, const BarTestOptions& opt,
                                  double rel_tol = 1e-3, double r_min = 1e-3);

/// One point of a simulated uniaxial tension test.
struct UniaxialPoint {
  double end_stretch = 1;      ///< imposed: (L + dL) / L
  double mid_stretch = 1;      ///< measured axial stretch of the middle third of the bar
  double lateral_stretch = 1;  ///< measured width ratio at mid-length
  double force = 0;            ///< reaction of the energy on the moved end, along the bar
  double stress = 0;           ///< force / rest cross-section (model units per mm^2)
  int iterations = 0;
};

/// Uniaxial tension of a 60 x 10 x 10 mm bar of one body material (cells of 10 / res mm): the
/// x = 0 face fixed, the x = 60 face moved along +x to each end stretch in turn (warm-started),
/// the middle third measured away from the clamped ends. The force is the frozen-target gradient
/// of Eq. 2.10 summed over the moved face: the load a testing machine would read, in the energy's
/// units. Used to check the hyperelastic law against its Mooney-Rivlin curve (hyperelastic.hpp).
/// Throws std::invalid_argument for stretches not in (1, 2] or not increasing, std::runtime_error
/// if a solve fails.
std::vector<UniaxialPoint> SimulateUniaxialTension(const Material& material,
                                                   const std::vector<double>& end_stretches,
                                                   int res = 3,
                                                   const FkOptions& solver = FkOptions());

}  // namespace softkin
