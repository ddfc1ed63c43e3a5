#pragma once
/// \file calculix_pressure.hpp
/// A pressure-driven hyperelastic FEM of a pneumatic robot in CalculiX, modelled the way Abaqus
/// users model these robots (the thesis's FEM 1 / FEM 2 of Fig. 2.11 and Table 2.2), as an
/// independent reference for SoftKin's geometric model:
///  - the chambers are hollow: the FEM mesh is the scene's body elements only, without the
///    chamber (pneumatic actuation) elements; vertices used only by chamber elements are dropped;
///  - the cavity walls (the faces a chamber element shares with a body element) carry a uniform
///    pressure (*DLOAD, label P1..P4 of the body element's face), ramped linearly from 0 with
///    automatic incrementation and cut-back under NLGEOM, where CalculiX applies it to the
///    deformed faces (a follower load);
///  - elements are C3D10 (quadratic tets: one node at each edge midpoint) or C3D4; linear tets
///    lock in bending;
///  - body region r has Young's modulus w_r E0 (its element weight of Eq. 2.10 as relative
///    stiffness), with law "linear" (FEM 1: *ELASTIC) or "neo-hooke" (FEM 2: NEO HOOKE, or
///    MOONEY-RIVLIN for a region with that law), Poisson ratio nu for all.
/// Each converged increment gives the pressure, the positions and each chamber's deformed cavity
/// volume, computed from the cavity's boundary faces (with their edge-midpoint nodes for C3D10),
/// so that SoftKin can be compared with it at the same chamber volume.
///
/// Supported scenes: tet meshes whose actuators are all pneumatic, each chamber closed by body
/// elements (a chamber face on the outer surface or against another chamber is an error naming
/// the chamber). Signed actuators: pressure p > 0 loads the positive side's chambers, p < 0 the
/// negative side's with |p|.
#include "softkin/solver/fk/model.hpp"

#include <Eigen/Dense>

#include <array>
#include <string>
#include <vector>

namespace softkin {

struct PressureFemOptions {
  std::string law = "neo-hooke";  ///< "linear" (FEM 1) or "neo-hooke" (FEM 2)
  std::string element = "C3D10";  ///< "C3D10" (quadratic tets) or "C3D4"
  double young = 1.0;             ///< E0, MPa; body region r gets w_r E0
  double poisson = 0.45;          ///< nu, all regions
  /// Largest load increment as a fraction of the ramp (also the first increment's size); ccx cuts
  /// it back on non-convergence down to min_increment.
  double max_increment = 0.02;
  double min_increment = 1e-5;
  int max_increments = 2000;  ///< ccx's INC limit
  double time_limit_s = 0;    ///< wall-clock limit of the ccx run (0: none)
  bool keep_files = false;    ///< keep the work folder
};

/// One cavity wall face: a face of body element `element` (FEM element index) with CalculiX face
/// number `face` (1..4), its corner nodes ordered so that the normal points out of the cavity, and
/// its edge-midpoint nodes (C3D10: of edges 01, 12, 20; -1 for C3D4).
struct CavityFace {
  int element = -1;
  int face = 0;
  std::array<int, 3> corners{};
  std::array<int, 3> mids{-1, -1, -1};
};

/// The hollow FEM mesh of a scene.
struct PressureFemMesh {
  std::string element_type;      ///< "C3D4" or "C3D10"
  Eigen::MatrixX3d rest;         ///< FEM node rest positions (mm)
  std::vector<int> node_vertex;  ///< FEM node -> scene vertex (-1: edge-midpoint node)
  std::vector<int> vertex_node;  ///< scene vertex -> FEM node (-1: only in chambers)
  std::vector<std::vector<int>> connectivity;  ///< FEM element -> 4 or 10 FEM nodes (0-based)
  std::vector<int> element_scene;              ///< FEM element -> scene element
  std::vector<int> element_region;
  /// Per actuation group of the Model: its cavity's wall faces and rest volume (mm^3).
  std::vector<std::vector<CavityFace>> cavities;
  std::vector<double> cavity_rest_volume;
};

/// Builds the hollow mesh. Throws std::invalid_argument naming the element, chamber or actuator
/// for what it cannot represent (prisms, non-pneumatic or motion actuators, per-region rest
/// shapes, open chambers, chambers that touch each other).
PressureFemMesh BuildPressureFemMesh(const Model& model, const std::string& element_type);

/// Volume enclosed by cavity `faces` for FEM node positions X (the divergence theorem over the
/// faces; a C3D10 face is split at its edge midpoints into four triangles).
double CavityVolume(const std::vector<CavityFace>& faces,
                    const Eigen::Ref<const Eigen::MatrixX3d>& X);

/// Pressure on each actuation group's cavity at the end of the ramp for per-actuator pressures p.
std::vector<double> GroupPressures(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& p);

/// Writes the CalculiX deck for per-actuator end pressures p (MPa) to `path`. Throws
/// std::invalid_argument for bad options, std::runtime_error if the file cannot be written.
void WritePressureFemInput(const Model& model, const PressureFemMesh& fem,
                           const Eigen::Ref<const Eigen::VectorXd>& p,
                           const PressureFemOptions& options, const std::string& path);

/// One converged increment.
struct PressureFemIncrement {
  double load = 0;                   ///< fraction of the ramp (0..1)
  Eigen::VectorXd pressure;          ///< per actuator, MPa
  double wall_s = 0;                 ///< wall-clock time since the run started when ccx reported it
  Eigen::MatrixX3d positions;        ///< scene vertices (#V x 3); NaN for those not in the FEM mesh
  std::vector<double> cavity_ratio;  ///< per actuator: loaded cavity volume / its rest volume
};

struct PressureFemRun {
  bool ok = false;           ///< ccx ran and its output was read (even if it stopped early)
  bool reached_end = false;  ///< the whole ramp converged
  std::string message;       ///< why it stopped early, or why it could not run
  double time_s = 0;
  int nodes = 0, elements = 0;
  std::vector<PressureFemIncrement> increments;  ///< in load order
};

/// Runs the pressure ramp to per-actuator pressures p in ccx. Never throws for a missing ccx, a
/// scene it cannot represent or a failed run: ok = false with the message.
PressureFemRun RunPressureFem(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& p,
                              const PressureFemOptions& options);

}  // namespace softkin
