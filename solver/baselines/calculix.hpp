#pragma once
/// \file calculix.hpp
/// A finite-element baseline through CalculiX (`ccx`, Debian package calculix-ccx), standing in
/// for the Abaqus runs of the thesis (Table 2.2, Fig. 2.11: "FEM 1" linear elastic, "FEM 2"
/// nonlinear material, both with geometric nonlinearity).
///
/// The scene becomes an Abaqus-style .inp deck that ccx reads:
///  - every tet becomes a C3D4 element, every region an element set R<tag>;
///  - fixed vertices: *BOUNDARY on all three dofs; vertices held on some axes: on those dofs;
///  - body regions: a material of Young's modulus E = w * E0 (the region's element weight w of
///    Eq. 2.10 taken as its relative stiffness) and Poisson ratio nu;
///  - pneumatic chambers: the cavity's elements get an isotropic eigenstrain, a thermal expansion
///    with coefficient a = cbrt(alpha) - 1 under a temperature rise from 0 to 1, so that a free
///    chamber element reaches volume ratio (1 + a)^3 = alpha, and stiffness E = w_act * E0.
///    This is the FEM counterpart of a pneumatic actuation element: its stress-free shape is the
///    rest shape scaled by cbrt(alpha), exactly the target of Eq. 2.8, and the surrounding body
///    resists it with its own stiffness, as the element weights do in Eq. 2.10. (Pressure on the
///    cavity walls would need a pressure-volume calibration per alpha; the eigenstrain needs
///    none.) The inactive side of a signed actuator gets no expansion and a near-zero stiffness
///    (1e-3 E0), an open cavity.
///  - "linear": *ELASTIC (FEM 1); "nonlinear": *HYPERELASTIC, NEO HOOKE with C10 = E / (4 (1 + nu))
///    and D1 = 6 (1 - 2 nu) / E, the small-strain equivalent of (E, nu) (FEM 2). Both use NLGEOM
///    and a fixed number of increments; displacements are printed for every increment.
/// Not exported (std::invalid_argument with the reason): prism elements, cable and DEA actuators,
/// motion actuators.
#include "softkin/solver/baselines/ccx_run.hpp"
#include "softkin/solver/fk/fk_solver.hpp"

#include <ostream>
#include <string>
#include <vector>

namespace softkin {

struct CalculixOptions {
  std::string law = "linear";  ///< "linear" (FEM 1) or "neo-hooke" (FEM 2)
  double young = 1.0;          ///< E0, MPa (the solution does not depend on its scale)
  double poisson = 0.3;        ///< nu
  int increments = 10;         ///< equal load increments (the temperature ramp)
  double time_limit_s = 0;     ///< wall-clock limit of the ccx run (0: none)
  bool keep_files = false;     ///< keep the work folder (otherwise removed after parsing)
};

/// A number as written in .inp decks (%.12g).
std::string InpNumber(double v);

/// Writes 0-based ids 1-based, at most 8 per line (the .inp line-length convention).
void WriteInpIds(std::ostream& o, const std::vector<int>& ids);

/// Writes a *MATERIAL card `name` for `law` ("linear": *ELASTIC E, nu; otherwise a hyperelastic
/// law with small-strain modulus E and Poisson ratio nu: NEO HOOKE with C10 = E / (4 (1 + nu)),
/// or, for a Mooney-Rivlin region `mr`, MOONEY-RIVLIN with its c1 : c2 ratio; D1 = 6 (1 - 2 nu) /
/// E).
void WriteCalculixMaterial(std::ostream& o, const std::string& name, const std::string& law,
                           double E, double nu, const Material* mr);

/// Writes the .inp deck for actuation c to `path`. Throws std::invalid_argument if the scene uses
/// something the export does not support, std::runtime_error if the file cannot be written.
void WriteCalculixInput(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& c,
                        const CalculixOptions& options, const std::string& path);

/// Displacement blocks of a ccx .dat file ("displacements (vx,vy,vz) for set NALL and time T"):
/// one (T, #V x 3 displacement) pair per increment, in file order. Node numbers are 1-based. Every
/// node must be in every block, or, if `printed` is given, the nodes v with printed[v] (the
/// others are NaN). Throws std::runtime_error naming the file and line on malformed content.
std::vector<std::pair<double, Eigen::MatrixX3d>> ReadCalculixDisplacements(
    const std::string& dat_path, int num_vertices, const std::vector<bool>* printed = nullptr);

/// The chamber volume ratio a free chamber element has at load fraction `load` (0..1) of a run to
/// ratio `alpha`: the expansion coefficient cbrt(alpha) - 1 ramps linearly with the load, so the
/// ratio is (1 + (cbrt(alpha) - 1) load)^3, not linear in the load.
double CalculixRatioAtLoad(double alpha, double load);

/// One converged CalculiX increment: its load fraction (the time of the temperature ramp, 0..1),
/// the wall-clock time since Solve() started when ccx reported it, and the positions.
struct CalculixIncrement {
  double load = 0;
  double wall_s = 0;
  Eigen::MatrixX3d positions;
};

/// FK by CalculiX: writes the deck into a fresh temporary folder, runs ccx as a child process
/// (argument list, no shell), parses the displacements and returns the final positions. Warm
/// starts are ignored (FEM loads from the rest state in increments). status: converged if ccx
/// reached time 1; diverged (with ccx's last message) otherwise; invalid_input if ccx is missing
/// or the scene cannot be exported. iterations = increments completed. energy: Eq. 2.10 at the
/// result, for comparison. Increments: FkOptions::continuation_steps if > 1, else
/// CalculixOptions::increments; ccx may cut an increment back, and every converged one is kept
/// with the wall-clock time at which it was reported (increments()), so one run gives the time
/// to every intermediate shape, as a FEM user would read it off the job's status file.
class CalculixSolver : public FkSolver {
 public:
  CalculixSolver(std::shared_ptr<const Model> model, const FkOptions& fk, CalculixOptions options);
  std::string name() const override { return name_; }

 protected:
  FkResult SolveImpl(const Eigen::Ref<const Eigen::VectorXd>& c,
                     const Eigen::MatrixX3d* warm_start) override;

 public:
  /// The converged increments of the last Solve, in load order.
  const std::vector<CalculixIncrement>& increments() const { return history_; }

 private:
  std::string name_;
  CalculixOptions options_;
  std::vector<CalculixIncrement> history_;
};

}  // namespace softkin
