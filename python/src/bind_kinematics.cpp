/// \file bind_kinematics.cpp
/// Kinematics for IK in Python: the simulator as p(c) (tracked points, #P x 3) and J(c)
/// (3 #P x #A), with the Jacobian modes of ik/simulator_kinematics.hpp.
#include "arrays.hpp"
#include "bindings.hpp"
#include "softkin/ik/simulator_kinematics.hpp"
#include "softkin/solver/common/json_text.hpp"
#include "softkin/solver/scene/solver_options_json.hpp"

#include <pybind11/stl.h>

#include <mutex>
#include <string>
#include <vector>

namespace softkin {
namespace python {

namespace {

class PySimulatorKinematics {
 public:
  PySimulatorKinematics(const SceneHandle& scene, const std::string& jacobian,
                        const std::vector<std::string>& points, double fd_step,
                        const std::string& options_json) {
    SimulatorKinematicsOptions o;
    if (!JacobianModeFromString(jacobian, &o.jacobian))
      throw std::invalid_argument("jacobian: expected one of: " + JacobianModeNames() + "; got \"" +
                                  jacobian + "\"");
    o.points = points;
    o.fd_step = fd_step;
    const FkOptions fk =
        ReadSolverOptionsJson(ParseJsonText(options_json, "options"), "options", scene->solver);
    py::gil_scoped_release release;
    kin_ = std::make_unique<SimulatorKinematics>(*scene, o, &fk);
  }

  py::dict Evaluate(const DoubleArray& c, bool with_jacobian) {
    const Eigen::VectorXd cv = ToVector(c, kin_->num_actuators(), "c (one value per actuator)");
    KinematicsEval e;
    {
      py::gil_scoped_release release;
      std::lock_guard<std::mutex> lock(mutex_);
      e = kin_->Evaluate(cv, with_jacobian);
    }
    if (!e.ok) throw std::runtime_error(e.message);
    py::dict d;
    d["p"] = ToNumpy(e.p);
    if (with_jacobian) d["J"] = ToNumpy(e.J);
    d["inverted_elements"] = e.inverted_elements;
    d["min_volume_ratio"] = e.min_volume_ratio;
    d["fk_solves"] = e.fk_solves;
    d["time_s"] = e.time_s;
    d["message"] = e.message;
    return d;
  }

  SimulatorKinematics& kin() { return *kin_; }

 private:
  std::unique_ptr<SimulatorKinematics> kin_;
  std::mutex mutex_;
};

}  // namespace

void BindKinematics(py::module_& m) {
  py::class_<PySimulatorKinematics>(m, "_SimulatorKinematics")
      .def(py::init<const SceneHandle&, const std::string&, const std::vector<std::string>&, double,
                    const std::string&>(),
           py::arg("scene"), py::arg("jacobian"), py::arg("points"), py::arg("fd_step"),
           py::arg("options_json"))
      .def("evaluate", &PySimulatorKinematics::Evaluate, py::arg("c"), py::arg("with_jacobian"))
      .def("reset", [](PySimulatorKinematics& k) { k.kin().Reset(); })
      .def_property_readonly("name", [](PySimulatorKinematics& k) { return k.kin().name(); })
      .def_property_readonly("point_names",
                             [](PySimulatorKinematics& k) { return k.kin().point_names(); })
      .def_property_readonly("num_actuators",
                             [](PySimulatorKinematics& k) { return k.kin().num_actuators(); })
      .def_property_readonly(
          "lower", [](PySimulatorKinematics& k) { return ToNumpyVector(k.kin().lower()); })
      .def_property_readonly(
          "upper", [](PySimulatorKinematics& k) { return ToNumpyVector(k.kin().upper()); })
      .def_property_readonly("total_fk_solves",
                             [](PySimulatorKinematics& k) { return k.kin().total_fk_solves(); });
}

}  // namespace python
}  // namespace softkin
