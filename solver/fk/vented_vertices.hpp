#pragma once
/// \file vented_vertices.hpp
/// Where the inner vertices of a vented chamber side go.
///
/// The inactive side of a signed pneumatic actuator is vented (targets.hpp, kVented): its
/// elements follow the deformation and add no energy. A vertex whose every element is vented
/// (inside a cavity two or more cells across, e.g. `finger_manipulator` from res 8) then feels no
/// force, so every position of it is an equilibrium, and a solver leaves it wherever its iterates
/// happened to put it: lg-aa drags it along with the walls, newton leaves it near its start
/// (`finger_manipulator` res 8 at s1 = 0.5, measured on its earlier 5-layer mesh: 40 such vertices,
/// up to 54 mm apart between the two solvers, and 328 folded chamber elements in newton's answer).
/// The answer's other vertices, its energy, its residual and its volumes do not depend on them.
///
/// PlaceVentedVertices gives them one well-defined position, where the cavity keeps its rest
/// shape best: it minimises the vented elements' energy of Eq. 2.10 with rigid targets,
/// sum_e w_e Vol_e |D_e - P_e R_e^T|^2 (D_e, P_e: the centred current and rest rows, R_e the best
/// rotation), over these vertices only, the others fixed (as-rigid-as-possible local-global
/// iterations from the rest positions moved by the harmonic extension of the other vertices'
/// displacements). So a cavity whose walls are at rest is at rest, one whose walls move rigidly
/// moves with them, and a bent cavity bends without folding, whatever the solver and its
/// iterates.
#include "softkin/solver/fk/model.hpp"

#include <Eigen/Core>

#include <vector>

namespace softkin {

/// The vertices that only vented actuation elements hold at actuation c, with all three
/// coordinates free (sorted). Empty for a robot without signed actuators.
std::vector<int> VentedVertices(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& c);

/// Moves the VentedVertices(model, c) of X (#V x 3) to the harmonic extension of the others (see
/// above). Leaves X unchanged if there are none, if X is not finite, or if the extension's system
/// cannot be factored (a vented region that touches no other vertex).
void PlaceVentedVertices(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& c,
                         Eigen::MatrixX3d* X);

}  // namespace softkin
