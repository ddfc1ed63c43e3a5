/// \file bind_fk.cpp
/// Forward kinematics in Python: FkSolver (a solver chosen by name, with the scene JSON's solver
/// options as keyword arguments), its results with NumPy positions, and dX/dc by implicit
/// differentiation or central differences. The GIL is released while C++ solves, so Python
/// threads can run several solvers at once; one solver object runs one call at a time.
#include "arrays.hpp"
#include "bindings.hpp"
#include "softkin/solver/common/json_text.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/model.hpp"
#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/scene/solver_options_json.hpp"
#include "softkin/solver/sensitivity/equilibrium_jacobian.hpp"

#include <pybind11/stl.h>

#include <mutex>
#include <string>

namespace softkin {
namespace python {

namespace {

/// A forward solve's result and the scene it belongs to (for markers and the VTU writer).
struct PyFkResult {
  FkResult r;
  SceneHandle scene;
};

/// The probes of the central differences: fraction of each actuator's range (the same default
/// as SimulatorKinematicsOptions::fd_step, thesis Sec. 5.2.1).
constexpr double kFdStep = 1.0 / 160.0;

class PyFkSolver {
 public:
  PyFkSolver(SceneHandle scene, const std::string& options_json) : scene_(std::move(scene)) {
    const nlohmann::json j = ParseJsonText(options_json, "options");
    options_ = ReadSolverOptionsJson(j, "options", scene_->solver);
    py::gil_scoped_release release;
    model_ = std::make_shared<const Model>(*scene_);
    solver_ = MakeFkSolver(model_, options_);
  }

  PyFkResult Solve(const DoubleArray& c, const py::object& warm_start) {
    const Eigen::VectorXd cv = Actuation(c);
    Eigen::MatrixX3d warm;
    const bool has_warm = !warm_start.is_none();
    if (has_warm) warm = WarmStart(warm_start);
    PyFkResult out;
    {
      py::gil_scoped_release release;
      std::lock_guard<std::mutex> lock(mutex_);
      out = {solver_->Solve(cv, has_warm ? &warm : nullptr), scene_};
    }
    // Bad input (an actuation out of range, ...) is an error, as on the command line; a solve
    // that runs and fails returns its status.
    if (out.r.status == FkStatus::InvalidInput) throw std::invalid_argument(out.r.message);
    return out;
  }

  py::dict Jacobian(const DoubleArray& c, const std::string& mode, const py::object& warm_start) {
    if (mode != "implicit" && mode != "fd" && mode != "fd-warm")
      throw std::invalid_argument("mode: expected one of: implicit, fd, fd-warm; got \"" + mode +
                                  "\"");
    const Eigen::VectorXd cv = Actuation(c);
    Eigen::MatrixX3d warm;
    const bool has_warm = !warm_start.is_none();
    if (has_warm) warm = WarmStart(warm_start);
    const int nv = scene_->mesh.num_vertices(), na = scene_->num_actuators();
    Eigen::MatrixXd dXdc(3 * nv, na);
    PyFkResult centre;
    std::string error;
    {
      py::gil_scoped_release release;
      std::lock_guard<std::mutex> lock(mutex_);
      const Eigen::MatrixX3d* start = has_warm ? &warm : nullptr;
      centre = {solver_->Solve(cv, start), scene_};
      if (centre.r.status == FkStatus::InvalidInput) {
        error = centre.r.message;
      } else if (centre.r.status != FkStatus::Converged) {
        error = "the forward solve at c did not converge (" +
                std::string(FkStatusToString(centre.r.status)) + "): " + centre.r.message;
      } else if (mode == "implicit") {
        const EquilibriumJacobianResult jr =
            ComputeEquilibriumJacobian(*model_, centre.r.positions, cv);
        if (!jr.ok)
          error = "implicit Jacobian: " + jr.message;
        else
          dXdc = jr.dXdc;
      } else {
        const Eigen::MatrixX3d* probe_start = mode == "fd-warm" ? &centre.r.positions : start;
        error = Differences(cv, centre.r.positions, probe_start, &dXdc);
      }
    }
    if (centre.r.status == FkStatus::InvalidInput) throw std::invalid_argument(error);
    if (!error.empty()) throw std::runtime_error(error);
    // dX/dc as #V x 3 x #A (row 3 v + d of dXdc is coordinate d of vertex v).
    py::array_t<double> dX(
        {static_cast<py::ssize_t>(nv), static_cast<py::ssize_t>(3), static_cast<py::ssize_t>(na)});
    auto w = dX.mutable_unchecked<3>();
    for (int v = 0; v < nv; ++v)
      for (int d = 0; d < 3; ++d)
        for (int a = 0; a < na; ++a) w(v, d, a) = dXdc(3 * v + d, a);
    py::dict markers;
    for (const Marker& mk : scene_->markers) {
      Eigen::MatrixXd Jm = Eigen::MatrixXd::Zero(3, na);
      for (int v : mk.vertices) Jm += dXdc.middleRows(3 * v, 3);
      Jm /= static_cast<double>(std::max<std::size_t>(1, mk.vertices.size()));
      markers[py::str(mk.name)] = ToNumpy(Jm);
    }
    py::dict out;
    out["dX"] = dX;
    out["markers"] = markers;
    out["result"] = centre;
    out["mode"] = mode;
    return out;
  }

  const SceneHandle& scene() const { return scene_; }
  std::string name() const { return solver_->name(); }
  std::string options_json() const { return SolverOptionsToJson(options_).dump(); }

 private:
  Eigen::VectorXd Actuation(const DoubleArray& c) const {
    return ToVector(c, scene_->num_actuators(), "c (one value per actuator)");
  }

  Eigen::MatrixX3d WarmStart(const py::object& o) const {
    const Eigen::MatrixX3d X = ToPoints(o.cast<DoubleArray>(), "warm_start");
    if (X.rows() != scene_->mesh.num_vertices())
      throw std::invalid_argument("warm_start: expected " +
                                  std::to_string(scene_->mesh.num_vertices()) +
                                  " rows (one per vertex), got " + std::to_string(X.rows()));
    if (!X.allFinite()) throw std::invalid_argument("warm_start: has NaN or infinite entries");
    return X;
  }

  /// Central differences of the positions, one-sided (second order) at a bound so that probes
  /// stay within [min, max]; "" or the failed probe.
  std::string Differences(const Eigen::VectorXd& c, const Eigen::MatrixX3d& X0,
                          const Eigen::MatrixX3d* start, Eigen::MatrixXd* dXdc) {
    auto flat = [](const Eigen::MatrixX3d& X) {
      Eigen::MatrixXd t = X.transpose();
      return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(t.data(), t.size()));
    };
    for (int a = 0; a < scene_->num_actuators(); ++a) {
      const Actuator& act = scene_->actuators[a];
      const double h = kFdStep * (act.max - act.min);
      auto probe = [&](double offset, Eigen::VectorXd* out) -> std::string {
        Eigen::VectorXd cp = c;
        cp(a) += offset;
        const FkResult r = solver_->Solve(cp, start);
        if (r.status != FkStatus::Converged)
          return "fd probe of actuator '" + act.name + "' did not converge (" +
                 FkStatusToString(r.status) + "): " + r.message;
        *out = flat(r.positions);
        return "";
      };
      Eigen::VectorXd p1, p2;
      std::string e;
      if (c(a) + h <= act.max && c(a) - h >= act.min) {
        if (!(e = probe(h, &p1)).empty() || !(e = probe(-h, &p2)).empty()) return e;
        dXdc->col(a) = (p1 - p2) / (2 * h);
      } else {
        const double s = c(a) + h > act.max ? -1.0 : 1.0;  // step inwards
        if (!(e = probe(s * h, &p1)).empty() || !(e = probe(2 * s * h, &p2)).empty()) return e;
        dXdc->col(a) = (-3 * flat(X0) + 4 * p1 - p2) / (2 * s * h);
      }
    }
    return "";
  }

  SceneHandle scene_;
  FkOptions options_;
  std::shared_ptr<const Model> model_;
  std::unique_ptr<FkSolver> solver_;
  std::mutex mutex_;
};

}  // namespace

void BindFk(py::module_& m) {
  py::class_<PyFkResult>(m, "FkResult", "The outcome of one forward solve.")
      .def_property_readonly(
          "positions", [](const PyFkResult& p) { return ToNumpy(p.r.positions); },
          "Deformed vertex positions, #V x 3, mm (never NaN: the last finite iterate).")
      .def_property_readonly(
          "markers", [](const PyFkResult& p) { return MarkerDict(*p.scene, p.r.positions); },
          "Marker name -> position (3,), mm.")
      .def_property_readonly(
          "status", [](const PyFkResult& p) { return std::string(FkStatusToString(p.r.status)); },
          "converged, iteration_cap, diverged, invalid_input, time_limit or inverted (met the "
          "tolerance at a state with inverted body elements).")
      .def_property_readonly("converged",
                             [](const PyFkResult& p) { return p.r.status == FkStatus::Converged; })
      .def_property_readonly("message", [](const PyFkResult& p) { return p.r.message; })
      .def_property_readonly("solver", [](const PyFkResult& p) { return p.r.solver; })
      .def_property_readonly("actuation",
                             [](const PyFkResult& p) { return ToNumpyVector(p.r.actuation); })
      .def_property_readonly("iterations", [](const PyFkResult& p) { return p.r.iterations; })
      .def_property_readonly("energy", [](const PyFkResult& p) { return p.r.energy; })
      .def_property_readonly("gradient_ratio",
                             [](const PyFkResult& p) { return p.r.gradient_ratio; })
      .def_property_readonly("time_s", [](const PyFkResult& p) { return p.r.time_s; })
      .def_property_readonly(
          "local_time_s", [](const PyFkResult& p) { return p.r.local_time_s; },
          "Time in the local steps (local-global solvers), s.")
      .def_property_readonly(
          "global_time_s", [](const PyFkResult& p) { return p.r.global_time_s; },
          "Time in the global steps (local-global solvers), s.")
      .def_property_readonly(
          "volume_ratios",
          [](const PyFkResult& p) {
            return ToNumpyVector(Eigen::Map<const Eigen::VectorXd>(
                p.r.volume_ratios.data(), static_cast<Eigen::Index>(p.r.volume_ratios.size())));
          },
          "Achieved volume (pneumatic), length (cable) or area (DEA) ratio per actuator.")
      .def_property_readonly("inverted_elements",
                             [](const PyFkResult& p) { return p.r.inverted_elements; })
      .def_property_readonly("min_volume_ratio",
                             [](const PyFkResult& p) { return p.r.min_volume_ratio; })
      .def(
          "write_vtu",
          [](const PyFkResult& p, const std::string& path) {
            const VtuSolveInfo info{p.r.status == FkStatus::Converged, p.r.iterations,
                                    p.r.gradient_ratio, p.r.inverted_elements};
            py::gil_scoped_release release;
            WriteVtu(path, p.scene->mesh, p.r.positions, {}, nullptr, &info);
          },
          py::arg("path"),
          "Writes the deformed mesh for ParaView (.vtu, written atomically), with the status as "
          "field data.")
      .def("__repr__",
           [](const PyFkResult& p) { return "<softkin.FkResult " + p.r.BriefReport() + ">"; });

  py::class_<PyFkSolver>(m, "_FkSolver")
      .def(py::init<SceneHandle, const std::string&>(), py::arg("scene"), py::arg("options_json"))
      .def("solve", &PyFkSolver::Solve, py::arg("c"), py::arg("warm_start") = py::none())
      .def("jacobian", &PyFkSolver::Jacobian, py::arg("c"), py::arg("mode") = "implicit",
           py::arg("warm_start") = py::none())
      .def_property_readonly("scene", &PyFkSolver::scene)
      .def_property_readonly("name", &PyFkSolver::name)
      .def_property_readonly("_options_json", &PyFkSolver::options_json);
}

}  // namespace python
}  // namespace softkin
