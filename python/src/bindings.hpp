#pragma once
/// \file bindings.hpp
/// The parts of the Python module softkin._softkin (python/src/module.cpp), one per area:
/// scenes (bind_scene.cpp), forward kinematics and its Jacobian (bind_fk.cpp), kinematics for IK
/// (bind_kinematics.cpp), IK (bind_ik.cpp), the command line (bind_cli.cpp). Shared here: the Scene
/// handle the Python objects keep alive.
#include "softkin/ik/kinematics.hpp"
#include "softkin/solver/scene/scene.hpp"

#include <Eigen/Core>
#include <pybind11/pybind11.h>

#include <memory>
#include <mutex>

namespace softkin {
namespace python {

/// A scene as Python holds it: immutable once built, shared by the solvers made from it.
using SceneHandle = std::shared_ptr<const Scene>;

void BindScene(pybind11::module_& m);
void BindFk(pybind11::module_& m);
void BindKinematics(pybind11::module_& m);
void BindIk(pybind11::module_& m);
void BindCli(pybind11::module_& m);

/// Marker name -> mean position (3,) at positions X (#V x 3), as FkResult.markers and
/// Scene.marker_positions give them (bind_scene.cpp).
pybind11::dict MarkerDict(const Scene& scene, const Eigen::Ref<const Eigen::MatrixX3d>& X);

/// The lock of one Kinematics object: its calls run with the GIL released, one at a time.
std::mutex& KinematicsMutex(const Kinematics* k);

}  // namespace python
}  // namespace softkin
