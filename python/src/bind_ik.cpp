/// \file bind_ik.cpp
/// IK in Python: one target (ik/ik_solver.hpp, point tracking Eq. 4.4) and a path of waypoints
/// (Algorithm 4, ik/trajectory.hpp) on any softkin.Kinematics, with the methods by name.
#include "arrays.hpp"
#include "bindings.hpp"
#include "softkin/ik/ik_solver.hpp"
#include "softkin/ik/objectives.hpp"
#include "softkin/ik/trajectory.hpp"

#include <pybind11/stl.h>

#include <cmath>
#include <string>

namespace softkin {
namespace python {

namespace {

/// `inner` restricted to a narrower box [lower, upper] (softkin.ik's bounds=): IK stays inside it.
class BoxedKinematics : public Kinematics {
 public:
  BoxedKinematics(Kinematics& inner, const py::object& bounds) : inner_(inner) {
    lower_ = inner.lower();
    upper_ = inner.upper();
    if (bounds.is_none()) return;
    const DoubleArray b = bounds.cast<DoubleArray>();
    CheckMatrix(b, "bounds", 2, "(" + std::to_string(inner.num_actuators()) + ", 2)");
    if (b.shape(0) != inner.num_actuators())
      throw std::invalid_argument("bounds: expected one (min, max) row per actuator, " +
                                  std::to_string(inner.num_actuators()) + " rows; got " +
                                  std::to_string(b.shape(0)));
    auto v = b.unchecked<2>();
    for (int a = 0; a < inner.num_actuators(); ++a) {
      if (!(v(a, 0) < v(a, 1)) || v(a, 0) < inner.lower()(a) || v(a, 1) > inner.upper()(a))
        throw std::invalid_argument(
            "bounds[" + std::to_string(a) + "]: expected min < max within the actuator's range [" +
            std::to_string(inner.lower()(a)) + ", " + std::to_string(inner.upper()(a)) +
            "], got [" + std::to_string(v(a, 0)) + ", " + std::to_string(v(a, 1)) + "]");
      lower_(a) = v(a, 0);
      upper_(a) = v(a, 1);
    }
  }
  std::string name() const override { return inner_.name(); }
  int num_actuators() const override { return inner_.num_actuators(); }
  const std::vector<std::string>& point_names() const override { return inner_.point_names(); }
  const Eigen::VectorXd& lower() const override { return lower_; }
  const Eigen::VectorXd& upper() const override { return upper_; }
  Eigen::VectorXd rest() const override { return inner_.rest().cwiseMax(lower_).cwiseMin(upper_); }
  KinematicsEval Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c, bool with_jacobian) override {
    return inner_.Evaluate(c, with_jacobian);
  }
  long long total_fk_solves() const override { return inner_.total_fk_solves(); }

 private:
  Kinematics& inner_;
  Eigen::VectorXd lower_, upper_;
};

/// IK options from the keyword arguments the Python layer passes (its defaults are IkOptions').
IkOptions ReadIkOptions(const std::string& method, const std::string& gradient, double lambda_mm,
                        int max_iterations, int max_evaluations, double max_time_s) {
  IkOptions o;
  if (!StringToIkMethod(method, &o.method))
    throw std::invalid_argument("method: expected one of: " + IkMethodNames() + "; got \"" +
                                method + "\"");
  if (!StringToIkGradient(gradient, &o.gradient))
    throw std::invalid_argument("gradient: expected one of: jacobian, central-difference; got \"" +
                                gradient + "\"");
  if (!(lambda_mm >= 0) || !std::isfinite(lambda_mm))
    throw std::invalid_argument("lambda_mm: expected a distance >= 0 mm");
  o.lambda = lambda_mm * lambda_mm;
  o.max_iterations = max_iterations;
  o.max_evaluations = max_evaluations;
  o.max_time_s = max_time_s;
  std::string why;
  if (!o.IsValid(&why)) throw std::invalid_argument(why);
  return o;
}

std::string DefaultPoint(const Kinematics& k, const std::string& point) {
  if (!point.empty()) return point;
  for (const std::string& n : k.point_names())
    if (n == "tip") return n;
  return k.point_names().front();
}

py::dict Solve(Kinematics& inner, const DoubleArray& target, const std::string& point,
               const py::object& c0, const py::object& bounds, const IkOptions& o) {
  BoxedKinematics kin(inner, bounds);
  const Eigen::Vector3d t = ToVector(target, 3, "target (x, y, z in mm)");
  const std::string pt = DefaultPoint(kin, point);
  const PointTrackingObjective objective(kin.point_names(), pt, t);
  const Eigen::VectorXd start =
      c0.is_none() ? kin.rest()
                   : ToVector(c0.cast<DoubleArray>(), kin.num_actuators(), "c0 (one per actuator)");
  IkResult r;
  {
    py::gil_scoped_release release;
    std::lock_guard<std::mutex> lock(KinematicsMutex(&inner));
    r = SolveIk(kin, objective, start, o);
  }
  py::dict d;
  d["c"] = ToNumpyVector(r.c);
  d["p"] = ToNumpy(r.p);
  d["point"] = pt;
  d["objective"] = r.objective;
  d["error_mm"] = r.p.rows() ? std::sqrt(r.objective) : -1.0;
  d["converged"] = r.summary.converged();
  d["termination"] = IkTerminationToString(r.summary.termination);
  d["message"] = r.summary.message;
  d["iterations"] = r.summary.iterations;
  d["evaluations"] = r.summary.evaluations;
  d["fk_solves"] = r.summary.fk_solves;
  d["time_s"] = r.summary.time_s;
  d["history"] = ToNumpyVector(Eigen::Map<const Eigen::VectorXd>(
      r.summary.history.data(), static_cast<Eigen::Index>(r.summary.history.size())));
  d["inverted_elements"] = r.inverted_elements;
  return d;
}

py::dict Follow(Kinematics& inner, const DoubleArray& waypoints, const std::string& point,
                const py::object& c0, const py::object& bounds, int samples_per_axis,
                const IkOptions& o) {
  BoxedKinematics kin(inner, bounds);
  const Eigen::MatrixX3d W = ToPoints(waypoints, "waypoints");
  TrajectoryOptions t;
  t.point = DefaultPoint(kin, point);
  t.ik = o;
  t.sampling.samples_per_axis = samples_per_axis;
  if (!c0.is_none())
    t.warm_start = ToVector(c0.cast<DoubleArray>(), kin.num_actuators(), "c0 (one per actuator)");
  TrajectoryResult r;
  {
    py::gil_scoped_release release;
    std::lock_guard<std::mutex> lock(KinematicsMutex(&inner));
    r = FollowTrajectory(kin, W, t);
  }
  const int n = static_cast<int>(r.waypoints.size());
  Eigen::MatrixXd C(n, kin.num_actuators());
  Eigen::MatrixX3d reached(n, 3);
  Eigen::VectorXd err(n);
  std::vector<int> conv(n), inverted(n), iterations(n);
  std::vector<std::string> termination(n);
  for (int i = 0; i < n; ++i) {
    const WaypointResult& w = r.waypoints[i];
    C.row(i) = w.c.transpose();
    reached.row(i) = w.reached.transpose();
    err(i) = w.error_mm;
    conv[i] = w.converged;
    inverted[i] = w.inverted_elements;
    iterations[i] = w.iterations;
    termination[i] = IkTerminationToString(w.termination);
  }
  py::dict d;
  d["c"] = ToNumpy(C);
  d["reached"] = ToNumpy(reached);
  d["error_mm"] = ToNumpyVector(err);
  d["converged"] = py::array_t<bool>(py::cast(std::vector<bool>(conv.begin(), conv.end())));
  d["inverted_elements"] = ToIndexArray(inverted);
  d["iterations"] = ToIndexArray(iterations);
  d["termination"] = termination;
  d["point"] = t.point;
  d["num_converged"] = r.converged;
  d["mean_error_mm"] = r.mean_error_mm;
  d["max_error_mm"] = r.max_error_mm;
  d["max_jump_fraction"] = r.max_jump_fraction;
  d["time_s"] = r.total_time_s;
  return d;
}

}  // namespace

void BindIk(py::module_& m) {
  auto ik = m.def_submodule("_ik");
  ik.def(
      "solve",
      [](Kinematics& kin, const DoubleArray& target, const std::string& point, const py::object& c0,
         const py::object& bounds, const std::string& method, const std::string& gradient,
         double lambda_mm, int max_iterations, int max_evaluations, double max_time_s) {
        return Solve(kin, target, point, c0, bounds,
                     ReadIkOptions(method, gradient, lambda_mm, max_iterations, max_evaluations,
                                   max_time_s));
      },
      py::arg("kin"), py::arg("target"), py::arg("point"), py::arg("c0"), py::arg("bounds"),
      py::arg("method"), py::arg("gradient"), py::arg("lambda_mm"), py::arg("max_iterations"),
      py::arg("max_evaluations"), py::arg("max_time_s"));
  ik.def(
      "follow",
      [](Kinematics& kin, const DoubleArray& waypoints, const std::string& point,
         const py::object& c0, const py::object& bounds, int samples_per_axis,
         const std::string& method, const std::string& gradient, double lambda_mm,
         int max_iterations, int max_evaluations, double max_time_s) {
        return Follow(kin, waypoints, point, c0, bounds, samples_per_axis,
                      ReadIkOptions(method, gradient, lambda_mm, max_iterations, max_evaluations,
                                    max_time_s));
      },
      py::arg("kin"), py::arg("waypoints"), py::arg("point"), py::arg("c0"), py::arg("bounds"),
      py::arg("samples_per_axis"), py::arg("method"), py::arg("gradient"), py::arg("lambda_mm"),
      py::arg("max_iterations"), py::arg("max_evaluations"), py::arg("max_time_s"));
  ik.def("methods", [] { return IkMethodNames(); });
}

}  // namespace python
}  // namespace softkin
