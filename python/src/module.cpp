/// \file module.cpp
/// softkin._softkin: the compiled half of the Python package softkin (python/softkin/ is the
/// other, with keyword-argument wrappers and the docs). std::invalid_argument (bad input, with
/// the CLI's file:line or key path) arrives in Python as ValueError, std::runtime_error as
/// RuntimeError.
#include "bindings.hpp"

PYBIND11_MODULE(_softkin, m) {
  m.doc() = "SoftKin's compiled core: scenes, forward kinematics, Jacobians and kinematics.";
  softkin::python::BindScene(m);
  softkin::python::BindFk(m);
  softkin::python::BindKinematics(m);
  softkin::python::BindIk(m);
  softkin::python::BindCli(m);
}
