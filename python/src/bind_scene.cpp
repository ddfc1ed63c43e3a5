/// \file bind_scene.cpp
/// Scenes in Python: the embedded robots, scene JSON files and scenes built from arrays, with the
/// mesh, actuators, markers and held vertices as NumPy arrays.
#include "arrays.hpp"
#include "bindings.hpp"
#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/scene/scene_json.hpp"
#include "softkin/solver/scene/solver_options_json.hpp"

#include <pybind11/stl.h>

#include <iostream>
#include <map>
#include <string>

namespace softkin {
namespace python {

namespace {

py::array_t<long long> ElementArray(const Mesh& mesh) {
  int k = 4;
  for (const Element& e : mesh.elements) k = std::max(k, e.k());
  py::array_t<long long> out(
      {static_cast<py::ssize_t>(mesh.num_elements()), static_cast<py::ssize_t>(k)});
  auto w = out.mutable_unchecked<2>();
  for (int i = 0; i < mesh.num_elements(); ++i)
    for (int j = 0; j < k; ++j) w(i, j) = j < mesh.elements[i].k() ? mesh.elements[i].v[j] : -1;
  return out;
}

/// One field (min or max) of every actuator, #A.
py::array_t<double> ActuatorBound(const Scene& s, double Actuator::*field) {
  Eigen::VectorXd v(s.num_actuators());
  for (int a = 0; a < s.num_actuators(); ++a) v(a) = s.actuators[a].*field;
  return ToNumpyVector(v);
}

py::dict ActuatorDict(const Actuator& a) {
  py::dict d;
  d["name"] = a.name;
  d["type"] = ActuatorTypeToString(a.type);
  d["min"] = a.min;
  d["max"] = a.max;
  d["rest"] = a.rest;
  d["weight"] = a.weight;
  d["regions"] = a.regions;
  return d;
}

Mesh MeshFromArrays(const DoubleArray& vertices, const IntArray& elements, const IntArray& tags) {
  Mesh mesh;
  mesh.vertices = ToPoints(vertices, "vertices");
  if (elements.ndim() != 2 || (elements.shape(1) != 4 && elements.shape(1) != 6))
    throw std::invalid_argument(
        "elements: expected an array of shape (#E, 4) for tets or (#E, 6) for prisms, got shape " +
        ShapeText(elements));
  if (tags.ndim() != 1 || tags.shape(0) != elements.shape(0))
    throw std::invalid_argument("tags: expected one region tag per element, shape (" +
                                std::to_string(elements.shape(0)) + ",), got shape " +
                                ShapeText(tags));
  const int k = static_cast<int>(elements.shape(1));
  auto ev = elements.unchecked<2>();
  auto tv = tags.unchecked<1>();
  const long long nv = mesh.num_vertices();
  mesh.elements.resize(static_cast<std::size_t>(elements.shape(0)));
  for (py::ssize_t i = 0; i < elements.shape(0); ++i) {
    Element& e = mesh.elements[static_cast<std::size_t>(i)];
    e.type = k == 4 ? ElementType::Tet : ElementType::Prism;
    for (int j = 0; j < k; ++j) {
      const long long v = ev(i, j);
      if (v < 0 || v >= nv)
        throw std::invalid_argument("elements[" + std::to_string(i) + "]: vertex index " +
                                    std::to_string(v) + " out of range; expected 0-based rows of " +
                                    "vertices, in [0, " + std::to_string(nv - 1) + "]");
      e.v[j] = static_cast<int>(v);
    }
    e.region = static_cast<int>(tv(i));
  }
  return mesh;
}

std::shared_ptr<Scene> SceneFromArrays(const DoubleArray& vertices, const IntArray& elements,
                                       const IntArray& tags, const std::string& spec_json,
                                       const std::string& source) {
  Mesh mesh = MeshFromArrays(vertices, elements, tags);
  MeshReport report;
  try {
    report = ValidateAndOrient(mesh, source);
  } catch (const std::runtime_error& e) {  // the arrays are the input: bad input, ValueError
    throw std::invalid_argument(e.what());
  }
  PrintMeshReport(report, std::cerr);
  return std::make_shared<Scene>(ParseSceneJsonWithMesh(spec_json, source, mesh, report));
}

py::list Robots() {
  py::list out;
  for (const RobotInfo& r : ListRobots()) {
    py::dict d;
    d["name"] = r.name;
    d["description"] = r.description;
    d["default_resolution"] = r.default_resolution;
    d["resolution_doc"] = r.resolution_doc;
    py::list params;
    for (const RobotParam& p : r.params) {
      py::dict q;
      q["name"] = p.name;
      q["default"] = p.def;
      q["min"] = p.lo;
      q["max"] = p.hi;
      q["doc"] = p.doc;
      params.append(q);
    }
    d["params"] = params;
    out.append(d);
  }
  return out;
}

}  // namespace

py::dict MarkerDict(const Scene& scene, const Eigen::Ref<const Eigen::MatrixX3d>& X) {
  const Eigen::MatrixX3d M = scene.marker_positions(X);
  py::dict d;
  for (int i = 0; i < static_cast<int>(scene.markers.size()); ++i)
    d[py::str(scene.markers[i].name)] = ToNumpyVector(M.row(i).transpose());
  return d;
}

void BindScene(py::module_& m) {
  py::class_<Scene, std::shared_ptr<Scene>>(m, "Scene",
                                            "A robot: rest mesh (mm), materials, actuators, held "
                                            "vertices, markers and default solver options.")
      .def_property_readonly("name", [](const Scene& s) { return s.name; })
      .def_property_readonly(
          "vertices", [](const Scene& s) { return ToNumpy(s.mesh.vertices); },
          "Rest positions, #V x 3, mm (a copy).")
      .def_property_readonly(
          "elements", [](const Scene& s) { return ElementArray(s.mesh); },
          "Vertex indices per element, #E x 4 (tets) or #E x 6 (prisms; -1 "
          "pads the tets of a mixed mesh).")
      .def_property_readonly(
          "tags",
          [](const Scene& s) {
            std::vector<int> t;
            for (const Element& e : s.mesh.elements) t.push_back(e.region);
            return ToIndexArray(t);
          },
          "Region tag per element, #E.")
      .def_property_readonly("num_vertices", [](const Scene& s) { return s.mesh.num_vertices(); })
      .def_property_readonly("num_elements", [](const Scene& s) { return s.mesh.num_elements(); })
      .def_property_readonly("num_actuators", &Scene::num_actuators)
      .def_property_readonly(
          "actuators",
          [](const Scene& s) {
            py::list l;
            for (const Actuator& a : s.actuators) l.append(ActuatorDict(a));
            return l;
          },
          "One dict per actuator, in actuation-vector order: name, type, min, max, rest, weight, "
          "regions.")
      .def_property_readonly(
          "lower", [](const Scene& s) { return ActuatorBound(s, &Actuator::min); },
          "Lower bounds of the actuation, #A.")
      .def_property_readonly(
          "upper", [](const Scene& s) { return ActuatorBound(s, &Actuator::max); },
          "Upper bounds of the actuation, #A.")
      .def_property_readonly(
          "rest", [](const Scene& s) { return ToNumpyVector(s.rest_actuation()); },
          "The rest actuation, #A.")
      .def_property_readonly(
          "markers",
          [](const Scene& s) {
            py::dict d;
            for (const Marker& mk : s.markers) d[py::str(mk.name)] = ToIndexArray(mk.vertices);
            return d;
          },
          "Marker name -> its vertex indices (a marker tracks their mean).")
      .def_property_readonly(
          "fixed", [](const Scene& s) { return ToIndexArray(s.fixed); },
          "Vertices held at rest (every coordinate).")
      .def_property_readonly("_solver_options_json",
                             [](const Scene& s) { return SolverOptionsToJson(s.solver).dump(); })
      .def(
          "marker_positions",
          [](const Scene& s, const DoubleArray& X) {
            const Eigen::MatrixX3d P = ToPoints(X, "positions");
            if (P.rows() != s.mesh.num_vertices())
              throw std::invalid_argument(
                  "positions: expected " + std::to_string(s.mesh.num_vertices()) +
                  " rows (one per vertex), got " + std::to_string(P.rows()));
            return MarkerDict(s, P);
          },
          py::arg("positions"), "Marker name -> mean position (3,) at positions #V x 3.")
      .def("__repr__", [](const Scene& s) {
        return "<softkin.Scene '" + s.name + "': " + std::to_string(s.mesh.num_vertices()) +
               " vertices, " + std::to_string(s.mesh.num_elements()) + " elements, " +
               std::to_string(s.num_actuators()) + " actuators>";
      });

  m.def("_robots", &Robots);
  m.def(
      "_robot",
      [](const std::string& name, int res, const std::map<std::string, double>& params) {
        return std::make_shared<Scene>(MakeRobot(name, res, params));
      },
      py::arg("name"), py::arg("res"), py::arg("params"));
  m.def(
      "_load_scene",
      [](const std::string& path) { return std::make_shared<Scene>(LoadSceneJson(path)); },
      py::arg("path"));
  m.def("_scene_from_arrays", &SceneFromArrays, py::arg("vertices"), py::arg("elements"),
        py::arg("tags"), py::arg("spec_json"), py::arg("source"));
}

}  // namespace python
}  // namespace softkin
