/// \file bind_kinematics.cpp
/// Kinematics for IK in Python (ik/kinematics.hpp): one base class, softkin.Kinematics, with
/// p(c) (#P x 3) and J(c) (3 #P x #A) as NumPy arrays, for the simulator, the PCC model, learned
/// networks and kinematics written in Python (a subclass that implements compute()). The C++ IK
/// solvers (bind_ik.cpp) take any of them.
#include "arrays.hpp"
#include "bindings.hpp"
#include "softkin/ik/pcc_kinematics.hpp"
#include "softkin/ik/simulator_kinematics.hpp"
#include "softkin/learn/net_kinematics.hpp"
#include "softkin/solver/common/json_text.hpp"
#include "softkin/solver/scene/solver_options_json.hpp"

#include <pybind11/stl.h>

#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace softkin {
namespace python {

std::mutex& KinematicsMutex(const Kinematics* k) {
  static std::mutex registry_mutex;
  static std::map<const Kinematics*, std::unique_ptr<std::mutex>> registry;
  std::lock_guard<std::mutex> lock(registry_mutex);
  auto& m = registry[k];
  if (!m) m = std::make_unique<std::mutex>();
  return *m;
}

namespace {

/// Kinematics written in Python: the points, bounds and rest are given once to the constructor;
/// each evaluation calls the subclass's compute(c, with_jacobian), which returns p (#P x 3) or
/// (p, J) with J 3 #P x #A. An exception or a wrong shape there makes the evaluation fail (ok =
/// false, with the reason), as a failed forward solve does.
class PyKinematics : public Kinematics {
 public:
  PyKinematics(std::vector<std::string> points, const DoubleArray& lower, const DoubleArray& upper,
               const py::object& rest, std::string name)
      : names_(std::move(points)), name_(std::move(name)) {
    lower_ = ToVector(lower, -1, "lower");
    upper_ = ToVector(upper, lower_.size(), "upper (one bound per actuator, as lower)");
    rest_ = rest.is_none() ? lower_
                           : ToVector(rest.cast<DoubleArray>(), lower_.size(), "rest (as lower)");
    if (names_.empty()) throw std::invalid_argument("points: expected at least one point name");
    if (lower_.size() == 0) throw std::invalid_argument("lower: expected at least one actuator");
    for (Eigen::Index a = 0; a < lower_.size(); ++a)
      if (!(lower_(a) < upper_(a)) || !std::isfinite(lower_(a)) || !std::isfinite(upper_(a)))
        throw std::invalid_argument(
            "lower, upper: expected finite bounds with lower < upper, got [" +
            std::to_string(lower_(a)) + ", " + std::to_string(upper_(a)) + "] for actuator " +
            std::to_string(a));
  }
  std::string name() const override { return name_; }
  int num_actuators() const override { return static_cast<int>(lower_.size()); }
  const std::vector<std::string>& point_names() const override { return names_; }
  const Eigen::VectorXd& lower() const override { return lower_; }
  const Eigen::VectorXd& upper() const override { return upper_; }
  Eigen::VectorXd rest() const override { return rest_; }
  long long total_fk_solves() const override { return evaluations_; }

  KinematicsEval Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c, bool with_jacobian) override {
    KinematicsEval e;
    e.message = CheckKinematicsInput(*this, c);
    if (!e.message.empty()) return e;
    py::gil_scoped_acquire gil;
    ++evaluations_;
    e.fk_solves = 1;
    try {
      py::function f = py::get_override(static_cast<const Kinematics*>(this), "compute");
      if (!f) throw std::invalid_argument("the subclass has no compute(c, with_jacobian) method");
      py::object r = f(ToNumpyVector(c), with_jacobian);
      py::object p = r, J = py::none();
      if (py::isinstance<py::tuple>(r)) {
        const py::tuple t = r.cast<py::tuple>();
        if (t.size() < 1 || t.size() > 2)
          throw std::invalid_argument("expected p or (p, J), got a tuple of " +
                                      std::to_string(t.size()));
        p = t[0];
        if (t.size() == 2) J = t[1];
      }
      e.p = ToPoints(p.cast<DoubleArray>(), "p");
      if (e.p.rows() != num_points())
        throw std::invalid_argument("p: expected " + std::to_string(num_points()) +
                                    " rows (one per point), got " + std::to_string(e.p.rows()));
      if (!e.p.allFinite()) throw std::invalid_argument("p has NaN or infinite entries");
      if (with_jacobian) {
        if (J.is_none()) throw std::invalid_argument("with_jacobian: expected (p, J), got p only");
        const DoubleArray Ja = J.cast<DoubleArray>();
        CheckMatrix(
            Ja, "J", num_actuators(),
            "(" + std::to_string(3 * num_points()) + ", " + std::to_string(num_actuators()) + ")");
        if (Ja.shape(0) != 3 * num_points())
          throw std::invalid_argument("J: expected " + std::to_string(3 * num_points()) +
                                      " rows (3 per point), got " + std::to_string(Ja.shape(0)));
        e.J.resize(Ja.shape(0), Ja.shape(1));
        auto v = Ja.unchecked<2>();
        for (py::ssize_t i = 0; i < Ja.shape(0); ++i)
          for (py::ssize_t j = 0; j < Ja.shape(1); ++j) e.J(i, j) = v(i, j);
        if (!e.J.allFinite()) throw std::invalid_argument("J has NaN or infinite entries");
      }
      e.ok = true;
    } catch (py::error_already_set& ex) {
      e = KinematicsEval();
      e.message = name_ + ".compute(): " + ex.what();
    } catch (const std::exception& ex) {
      e = KinematicsEval();
      e.message = name_ + ".compute(): " + ex.what();
    }
    return e;
  }

 private:
  std::vector<std::string> names_;
  std::string name_;
  Eigen::VectorXd lower_, upper_, rest_;
  long long evaluations_ = 0;
};

py::dict EvaluateToDict(Kinematics& k, const DoubleArray& c, bool with_jacobian) {
  const Eigen::VectorXd cv = ToVector(c, k.num_actuators(), "c (one value per actuator)");
  const std::string bad = CheckKinematicsInput(k, cv);  // bad input: ValueError
  if (!bad.empty()) throw std::invalid_argument(bad);
  KinematicsEval e;
  {
    py::gil_scoped_release release;
    std::lock_guard<std::mutex> lock(KinematicsMutex(&k));
    e = k.Evaluate(cv, with_jacobian);
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

std::shared_ptr<SimulatorKinematics> MakeSimulator(const SceneHandle& scene,
                                                   const std::string& jacobian,
                                                   const std::vector<std::string>& points,
                                                   double fd_step,
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
  return std::make_shared<SimulatorKinematics>(*scene, o, &fk);
}

}  // namespace

void BindKinematics(py::module_& m) {
  py::class_<Kinematics, PyKinematics, std::shared_ptr<Kinematics>>(
      m, "Kinematics",
      "Tracked points p(c) (#P x 3, mm) and their Jacobian J(c) (3 #P x #A) of an actuation c "
      "within [lower, upper]. Subclass it in Python: call Kinematics.__init__(self, points, lower, "
      "upper, rest=None, name='python') and implement compute(self, c, with_jacobian) returning p "
      "or (p, J).")
      .def(py::init<std::vector<std::string>, const DoubleArray&, const DoubleArray&, py::object,
                    std::string>(),
           py::arg("points"), py::arg("lower"), py::arg("upper"), py::arg("rest") = py::none(),
           py::arg("name") = "python")
      .def("evaluate", &EvaluateToDict, py::arg("c"), py::arg("with_jacobian") = true,
           "A dict with p, J (when with_jacobian), inverted_elements, min_volume_ratio, "
           "fk_solves, time_s and message. RuntimeError when c cannot be evaluated.")
      .def(
          "p",
          [](Kinematics& k, const DoubleArray& c) {
            const py::dict d = EvaluateToDict(k, c, false);
            return py::object(d["p"]);
          },
          py::arg("c"), "Tracked points at c, #P x 3, mm.")
      .def(
          "J",
          [](Kinematics& k, const DoubleArray& c) {
            const py::dict d = EvaluateToDict(k, c, true);
            return py::object(d["J"]);
          },
          py::arg("c"), "dp/dc at c, 3 #P x #A (row 3 i + d: coordinate d of point i).")
      .def_property_readonly("name", &Kinematics::name)
      .def_property_readonly("num_actuators", &Kinematics::num_actuators)
      .def_property_readonly("point_names", &Kinematics::point_names)
      .def_property_readonly("lower", [](Kinematics& k) { return ToNumpyVector(k.lower()); })
      .def_property_readonly("upper", [](Kinematics& k) { return ToNumpyVector(k.upper()); })
      .def_property_readonly("rest", [](Kinematics& k) { return ToNumpyVector(k.rest()); })
      .def_property_readonly("total_fk_solves", &Kinematics::total_fk_solves);

  py::class_<SimulatorKinematics, Kinematics, std::shared_ptr<SimulatorKinematics>>(
      m, "_SimulatorKinematics")
      .def(py::init(&MakeSimulator), py::arg("scene"), py::arg("jacobian"), py::arg("points"),
           py::arg("fd_step"), py::arg("options_json"))
      .def("reset", [](SimulatorKinematics& k) {
        std::lock_guard<std::mutex> lock(KinematicsMutex(&k));
        k.Reset();
      });

  py::class_<PccKinematics, Kinematics, std::shared_ptr<PccKinematics>>(
      m, "PccKinematics",
      "The analytical piecewise-constant-curvature model of a three-cable continuum robot "
      "(ik/pcc_kinematics.hpp): points tip and backbone[0..K-1], mm; c is the three cable pulls, "
      "mm.")
      .def(py::init([](double length, double cable_offset, double max_pull, int backbone_points,
                       bool axial) {
             PccParams p;
             p.length = length;
             p.cable_offset = cable_offset;
             p.max_pull = max_pull;
             p.backbone_points = backbone_points;
             p.axial = axial;
             return std::make_shared<PccKinematics>(p);
           }),
           py::arg("length") = PccParams().length,
           py::arg("cable_offset") = PccParams().cable_offset,
           py::arg("max_pull") = PccParams().max_pull,
           py::arg("backbone_points") = PccParams().backbone_points,
           py::arg("axial") = PccParams().axial);

  py::class_<NetKinematics, Kinematics, std::shared_ptr<NetKinematics>>(m, "_NetKinematics");
  m.def(
      "_load_nets",
      [](const std::string& dir, const std::string& jacobian, bool use_s2r) {
        JacobianSource src;
        if (!JacobianSourceFromString(jacobian, &src))
          throw std::invalid_argument("jacobian: expected one of: network, fk-derivative; got \"" +
                                      jacobian + "\"");
        return std::make_shared<NetKinematics>(LearnedNets::Load(dir), src, use_s2r);
      },
      py::arg("dir"), py::arg("jacobian"), py::arg("use_s2r"));
}

}  // namespace python
}  // namespace softkin
