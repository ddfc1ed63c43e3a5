/// \file scene_keys.cpp
/// The scene JSON's key table (scene_keys.hpp), the value checks and message texts that go with
/// it, and the schema printed from it (SceneSchema, scene_json.hpp).
#include "softkin/solver/scene/scene_keys.hpp"

#include "softkin/solver/scene/scene.hpp"
#include "softkin/solver/scene/scene_json.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <sstream>

namespace softkin {
namespace scene_json_detail {
namespace {

KeySpec Key(std::string path, Type type, Need need, std::string doc) {
  KeySpec k;
  k.path = std::move(path);
  k.type = type;
  k.need = need;
  k.doc = std::move(doc);
  return k;
}

const std::vector<std::string> kActuatorRoles = {"pneumatic", "cable", "dea"};

// Short names of the key types and needs, so that the table below reads as a table.
constexpr Type O = Type::Object, A = Type::ObjectArray, S = Type::String, N = Type::Number,
               I = Type::Integer, V = Type::Vec3;
constexpr Need R = Need::Required, Opt = Need::Optional, Sel = Need::Selector;

// ------------------------------------------------------------------------------------------------
// The key table: one function per section of the scene JSON, called in schema order by KeyTable()
// ------------------------------------------------------------------------------------------------

/// name, mesh.
void AddMeshKeys(std::vector<KeySpec>* t) {
  t->push_back(Key("name", S, Opt, "Scene name, used in messages and output names.")
                   .Def("")
                   .DefText("the JSON file's name without extension"));
  t->push_back(Key("mesh", O, R, "The volumetric mesh and how to read it."));
  t->push_back(Key("mesh.file", S, R,
                   "Mesh file, relative to the JSON's folder (TetGen: the .node or .ele file, or "
                   "the base name)."));
  t->push_back(Key("mesh.format", S, Opt,
                   "Reader; auto picks it from the extension (.tet, .node/.ele, .msh, .vtk, "
                   ".vtu).")
                   .Def("auto")
                   .Choices({"auto", "tet", "tetgen", "gmsh", "vtk", "vtu"}));
  t->push_back(Key("mesh.labels", S, Opt,
                   "tet only: file with one region tag per tet, in tet order, relative to the "
                   "JSON's folder (without it every tet is region 0).")
                   .Def("")
                   .DefText("none"));
  t->push_back(Key("mesh.tag_array", S, Opt,
                   "vtk and vtu only: integer cell-data array holding the region tags (none: the "
                   "first integer cell-data array).")
                   .Def("")
                   .DefText("none"));
  t->push_back(Key("mesh.scale", N, Opt,
                   "Multiplies every vertex coordinate (e.g. 1000 for a mesh in metres); all "
                   "coordinates below are in scaled units.")
                   .Def(1.0)
                   .Above(0.0));
}

/// regions[]: body materials and actuator regions.
void AddRegionKeys(std::vector<KeySpec>* t) {
  const Material mat;
  const Actuator act;
  t->push_back(Key("element_energy", S, Opt,
                   "How each element's energy term is weighted. shape: w Vol |N V^d - R N V^t|^2 "
                   "as Eq. 2.10 writes it, which for the same strain grows with the element's "
                   "size squared (small elements are softer); strain: the same divided by the "
                   "element's rest size |N V^t|^2 / 3, about w Vol |F - R|^2, the same for small "
                   "and large elements. Both give the same state on a mesh of equal elements.")
                   .Def("shape")
                   .Choices(ElementEnergyNames()));
  t->push_back(Key("regions", A, R,
                   "Role of each region tag; every tag that has elements needs exactly one "
                   "entry."));
  t->push_back(
      Key("regions[].tag", I, R, "Region tag in the mesh (label, physical group, attribute)."));
  t->push_back(Key("regions[].role", S, R,
                   "body: passive material; pneumatic, cable, dea: the region's elements drive an "
                   "actuator.")
                   .Choices({"body", "pneumatic", "cable", "dea"}));
  t->push_back(Key("regions[].material", S, Opt,
                   "Material name. With law mooney-rivlin, a named material (ecoflex-00-30, "
                   "dragon-skin-20; thesis Sec. 3.4) supplies c1 and c2; otherwise informational.")
                   .Def(mat.name)
                   .Roles({"body"}));
  t->push_back(Key("regions[].law", S, Opt,
                   "Body material law: blend (Ch. 2 shape blending, Eq. 2.5, constant r_omega) or "
                   "mooney-rivlin (hyperelastic target, Eq. 3.6-3.7: R_omega a function of strain "
                   "fitted to c1, c2, with r_omega its zero-strain value; docs/materials.md).")
                   .Def(ToString(mat.law))
                   .Choices(MaterialLawNames())
                   .Roles({"body"}));
  t->push_back(Key("regions[].c1", N, Opt,
                   "mooney-rivlin: c1, MPa (>= 0). Needed unless 'material' names a known "
                   "material.")
                   .Def(0.0)
                   .DefText("from material")
                   .AtLeast(0.0)
                   .Roles({"body"}));
  t->push_back(Key("regions[].c2", N, Opt,
                   "mooney-rivlin: c2, MPa (>= 0). Needed unless 'material' names a known "
                   "material.")
                   .Def(0.0)
                   .DefText("from material")
                   .AtLeast(0.0)
                   .Roles({"body"}));
  t->push_back(Key("regions[].r_omega", N, Opt,
                   "Shape-blending parameter R_omega (Eq. 2.5): 1 = rigid target "
                   "(as-rigid-as-possible), 0 = volume-preserving soft target.")
                   .Def(mat.r_omega)
                   .In(0.0, 1.0)
                   .Roles({"body"}));
  t->push_back(Key("regions[].weight", N, Opt, "Element weight w_i (Eq. 2.10) of body elements.")
                   .Def(mat.weight)
                   .Above(0.0)
                   .Roles({"body"}));
  t->push_back(Key("regions[].name", S, R,
                   "Actuator name; regions with the same name form one actuator. Actuators are "
                   "ordered by first appearance (the actuation vector's order).")
                   .Roles(kActuatorRoles));
  t->push_back(Key("regions[].min", N, Opt,
                   "Lower bound of the actuation value (pneumatic: volume ratio; cable: shortening "
                   "ratio; dea: area ratio; all > 0). Signed pneumatic: required, <= 0.")
                   .Def(act.min)
                   .DefText(Num(act.min) + " (signed: required)")
                   .Roles(kActuatorRoles));
  t->push_back(Key("regions[].max", N, Opt,
                   "Upper bound of the actuation value. Signed pneumatic: required, >= 0.")
                   .Def(act.max)
                   .DefText(Num(act.max) + " (signed: required)")
                   .Roles(kActuatorRoles));
  t->push_back(Key("regions[].rest", N, Opt,
                   "Actuation value at which the actuator is at rest (signed pneumatic: 0).")
                   .Def(act.rest)
                   .DefText(Num(act.rest) + " (signed: 0)")
                   .Roles(kActuatorRoles));
  t->push_back(Key("regions[].side", S, Opt,
                   "pneumatic: which chamber set of the actuator this region belongs to. An "
                   "actuator with a negative region is signed (Sec. 5.3.1): value v > 0 inflates "
                   "its positive regions to volume ratio 1 + gain v, v < 0 its negative ones to "
                   "1 + gain |v|; the other side is vented.")
                   .Def("positive")
                   .Choices({"positive", "negative"})
                   .Roles({"pneumatic"}));
  t->push_back(Key("regions[].gain", N, Opt,
                   "Signed pneumatic only: volume ratio per unit of |value| (e.g. per bar).")
                   .Def(act.gain)
                   .Above(0.0)
                   .Roles({"pneumatic"}));
  t->push_back(Key("regions[].weight", N, Opt,
                   "Element weight w_i (Eq. 2.10) of actuation elements (Sec. 2.5 uses 5).")
                   .Def(act.weight)
                   .Above(0.0)
                   .Roles(kActuatorRoles));
  t->push_back(Key("regions[].path", Type::Polyline, R,
                   "cable: the cable's path through the body, from its anchored end to where it "
                   "is pulled (mm). Elements take the direction of the nearest segment; the path "
                   "length outside the cable's elements is L_R of Eq. 2.6.")
                   .Roles({"cable"}));
}

/// The vertex selectors shared by fixed[] and motions[] (p: "fixed[]" or "motions[]"): exactly
/// one of region, box, plane, file per entry.
void AddSelectorKeys(const std::string& p, std::vector<KeySpec>* t) {
  t->push_back(Key(p + ".region", I, Sel, "Every vertex of the elements with this region tag."));
  t->push_back(
      Key(p + ".box", O, Sel, "Every vertex inside an axis-aligned box (bounds included)."));
  t->push_back(Key(p + ".box.min", V, R, "Lower corner [x, y, z]."));
  t->push_back(Key(p + ".box.max", V, R, "Upper corner [x, y, z]."));
  t->push_back(Key(p + ".plane", O, Sel, "Every vertex within `tolerance` of a plane."));
  t->push_back(Key(p + ".plane.point", V, R, "A point on the plane [x, y, z]."));
  t->push_back(Key(p + ".plane.normal", V, R, "Plane normal [x, y, z] (non-zero; normalised)."));
  t->push_back(Key(p + ".plane.tolerance", N, Opt, "Largest distance from the plane.")
                   .Def(1e-6)
                   .AtLeast(0.0));
  t->push_back(Key(p + ".file", S, Sel,
                   "Text file of vertex indices (whitespace-separated, '#' starts a comment), "
                   "relative to the JSON's folder."));
  t->push_back(
      Key(p + ".base", I, Opt, "Index base of `file`: 0 or 1.").Def(0).In(0, 1).With("file"));
}

/// fixed[] and motions[].
void AddFixedAndMotionKeys(std::vector<KeySpec>* t) {
  t->push_back(Key("fixed", A, R,
                   "Vertices held at their rest positions: the union of the entries' selections."));
  AddSelectorKeys("fixed[]", t);
  t->push_back(Key("fixed[].axes", S, Opt,
                   "Coordinates held: any of x, y, z once each (e.g. \"z\" for vertices that "
                   "slide on a plane z = const, or a symmetry plane's normal axis).")
                   .Def("xyz"));
  t->push_back(Key("motions", A, Opt,
                   "Motion actuators: a prescribed rigid motion of a vertex set, swept like an "
                   "actuation value (the tensile and twisting tests of Fig. 2.6). They follow the "
                   "region actuators in the actuation vector, in this order; rest 0. The moved "
                   "vertices are held at the moved positions; a vertex moved by several motions "
                   "gets them composed in order.")
                   .Def(json::array())
                   .DefText("[]"));
  t->push_back(Key("motions[].name", S, R, "Actuator name, unique among all actuators."));
  t->push_back(Key("motions[].type", S, R,
                   "displacement: translation (mm) along `axis`; twist: rotation (degrees, "
                   "right-hand rule) about the line through `centre` along `axis`.")
                   .Choices({"displacement", "twist"}));
  AddSelectorKeys("motions[]", t);
  t->push_back(Key("motions[].axis", V, R,
                   "Direction of the translation, or the rotation axis (non-zero; normalised)."));
  t->push_back(Key("motions[].centre", V, Opt, "A point on the rotation axis.")
                   .Def(json::array({0.0, 0.0, 0.0}))
                   .Roles({"twist"}));
  t->push_back(Key("motions[].min", N, R, "Lower bound of the value (mm or degrees), <= 0."));
  t->push_back(Key("motions[].max", N, R, "Upper bound of the value (mm or degrees), >= 0."));
}

/// markers[].
void AddMarkerKeys(std::vector<KeySpec>* t) {
  t->push_back(Key("markers", A, Opt,
                   "Named tracked points; each is the mean position of its selected vertices.")
                   .Def(json::array()));
  t->push_back(Key("markers[].name", S, R, "Marker name, unique (e.g. tip)."));
  t->push_back(Key("markers[].vertex", I, Sel, "One vertex, by 0-based index."));
  t->push_back(Key("markers[].nearest", V, Sel, "The vertex nearest to this point [x, y, z]."));
  t->push_back(Key("markers[].box", O, Sel,
                   "The mean of the vertices inside an axis-aligned box (bounds included)."));
  t->push_back(Key("markers[].box.min", V, R, "Lower corner [x, y, z]."));
  t->push_back(Key("markers[].box.max", V, R, "Upper corner [x, y, z]."));
}

/// obstacles[].
void AddObstacleKeys(std::vector<KeySpec>* t) {
  t->push_back(Key("obstacles", A, Opt,
                   "Static obstacles the robot must stay out of (Eq. 3.4): closed surfaces; the "
                   "local-global solvers respond to them with springs (solver.collision).")
                   .Def(json::array())
                   .DefText("[]"));
  t->push_back(Key("obstacles[].type", S, R,
                   "box: axis-aligned box; cylinder: closed cylinder; file: a closed, consistently "
                   "oriented OBJ or STL surface.")
                   .Choices({"box", "cylinder", "file"}));
  t->push_back(Key("obstacles[].min", V, R, "Lower corner [x, y, z] (mm).").Roles({"box"}));
  t->push_back(Key("obstacles[].max", V, R, "Upper corner [x, y, z] (mm), above min on every axis.")
                   .Roles({"box"}));
  t->push_back(Key("obstacles[].base", V, R, "Centre of the cylinder's base disc [x, y, z] (mm).")
                   .Roles({"cylinder"}));
  t->push_back(Key("obstacles[].axis", V, R, "Cylinder axis from the base (non-zero; normalised).")
                   .Roles({"cylinder"}));
  t->push_back(
      Key("obstacles[].radius", N, R, "Cylinder radius (mm).").Above(0.0).Roles({"cylinder"}));
  t->push_back(Key("obstacles[].height", N, R, "Cylinder length along the axis (mm).")
                   .Above(0.0)
                   .Roles({"cylinder"}));
  t->push_back(Key("obstacles[].segments", I, Opt,
                   "Number of sides of the cylinder's polygon (4 triangles each).")
                   .Def(48)
                   .In(3, 100000)
                   .Roles({"cylinder"}));
  t->push_back(
      Key("obstacles[].file", S, R, "Surface file (.obj or .stl), relative to the JSON's folder.")
          .Roles({"file"}));
}

std::string RangeText(const KeySpec& k) {
  const bool has_lo = std::isfinite(k.lo), has_hi = std::isfinite(k.hi);
  if (has_lo && has_hi)
    return std::string(" in ") + (k.lo_open ? "(" : "[") + Num(k.lo) + ", " + Num(k.hi) + "]";
  if (has_lo) return (k.lo_open ? " > " : " >= ") + Num(k.lo);
  if (has_hi) return " <= " + Num(k.hi);
  return "";
}

bool InRange(const KeySpec& k, double x) {
  if (std::isfinite(k.lo) && (k.lo_open ? !(x > k.lo) : !(x >= k.lo))) return false;
  if (std::isfinite(k.hi) && !(x <= k.hi)) return false;
  return true;
}

}  // namespace

const std::vector<KeySpec>& KeyTable() {
  static const std::vector<KeySpec> table = [] {
    std::vector<KeySpec> t;
    AddMeshKeys(&t);
    AddRegionKeys(&t);
    AddFixedAndMotionKeys(&t);
    AddMarkerKeys(&t);
    AddObstacleKeys(&t);
    const std::vector<KeySpec> solver = SolverKeySpecs();  // from the FK option table
    t.insert(t.end(), solver.begin(), solver.end());
    return t;
  }();
  return table;
}

std::string ParentOf(const std::string& path) {
  const auto dot = path.rfind('.');
  return dot == std::string::npos ? std::string() : path.substr(0, dot);
}
std::string LeafOf(const std::string& path) {
  const auto dot = path.rfind('.');
  return dot == std::string::npos ? path : path.substr(dot + 1);
}
std::string Join(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}

// ------------------------------------------------------------------------------------------------
// Formatting
// ------------------------------------------------------------------------------------------------

std::string Num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

std::string VecText(const Eigen::Vector3d& v) {
  return "[" + Num(v.x()) + ", " + Num(v.y()) + ", " + Num(v.z()) + "]";
}

std::string ListText(const std::vector<std::string>& v) {
  std::string s;
  for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + v[i];
  return s;
}

std::string IntListText(const std::vector<int>& v) {
  std::string s;
  for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + std::to_string(v[i]);
  return s.empty() ? "none" : s;
}

std::string TypeText(const KeySpec& k, bool with_article) {
  auto art = [&](const char* a, const char* s) { return std::string(with_article ? a : "") + s; };
  switch (k.type) {
    case Type::Object:
      return art("an ", "object");
    case Type::ObjectArray:
      return art("an ", "array of objects");
    case Type::String:
      if (!k.choices.empty()) return "one of: " + ListText(k.choices);
      return art("a ", "string");
    case Type::Number:
      return art("a ", "number") + RangeText(k);
    case Type::Integer:
      return art("an ", "integer") + RangeText(k);
    case Type::Vec3:
      return art("an ", "array of 3 numbers [x, y, z]");
    case Type::Polyline:
      return art("an ", "array of >= 2 points [[x, y, z], ...]");
    case Type::Bool:
      return art("a ", "boolean (true or false)");
  }
  return "?";
}

std::string Got(const json& v) {
  std::string s = v.dump();
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}

int EditDistance(const std::string& a, const std::string& b) {
  std::vector<int> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = static_cast<int>(j);
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = static_cast<int>(i);
    for (size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1])});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

// ------------------------------------------------------------------------------------------------
// Value checks
// ------------------------------------------------------------------------------------------------

bool IsInt(const json& v) {
  if (v.is_number_unsigned())
    return v.get<std::uint64_t>() <= static_cast<std::uint64_t>(std::numeric_limits<int>::max());
  if (v.is_number_integer()) {
    const auto i = v.get<std::int64_t>();
    return i >= std::numeric_limits<int>::min() && i <= std::numeric_limits<int>::max();
  }
  if (v.is_number_float()) {
    const double d = v.get<double>();
    return std::isfinite(d) && d == std::floor(d) && std::abs(d) <= std::numeric_limits<int>::max();
  }
  return false;
}
int AsInt(const json& v) {
  return v.is_number_integer() ? static_cast<int>(v.get<std::int64_t>())
                               : static_cast<int>(v.get<double>());
}

bool ValueOk(const KeySpec& k, const json& v) {
  switch (k.type) {
    case Type::Object:
      return v.is_object();
    case Type::ObjectArray:
      return v.is_array();
    case Type::String:
      if (!v.is_string()) return false;
      return k.choices.empty() ||
             std::find(k.choices.begin(), k.choices.end(), v.get<std::string>()) != k.choices.end();
    case Type::Number:
      return v.is_number() && std::isfinite(v.get<double>()) && InRange(k, v.get<double>());
    case Type::Integer:
      return IsInt(v) && InRange(k, AsInt(v));
    case Type::Vec3:
      if (!v.is_array() || v.size() != 3) return false;
      for (const auto& e : v)
        if (!e.is_number() || !std::isfinite(e.get<double>())) return false;
      return true;
    case Type::Polyline:
      if (!v.is_array() || v.size() < 2) return false;
      for (const auto& p : v) {
        if (!p.is_array() || p.size() != 3) return false;
        for (const auto& e : p)
          if (!e.is_number() || !std::isfinite(e.get<double>())) return false;
      }
      return true;
    case Type::Bool:
      return v.is_boolean();
  }
  return false;
}

Eigen::Vector3d AsVec(const json& v) {
  return Eigen::Vector3d(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
}

}  // namespace scene_json_detail

std::string SceneSchema() {
  using scene_json_detail::KeyTable;
  using scene_json_detail::ListText;
  using scene_json_detail::Need;
  using scene_json_detail::TypeText;
  std::ostringstream o;
  o << "SoftKin scene JSON\n"
       "==================\n"
       "Key paths: a.b is key b of object a; a[] is each element of array a.\n"
       "Relative file paths are relative to the scene JSON's folder. Coordinates are in mesh "
       "units\n"
       "after mesh.scale. Unknown keys, duplicate keys and wrong types are errors. Keys marked\n"
       "'selector' form a group: each object needs exactly one key of its group.\n"
       "Each key: key path, type, default (or required / selector) [condition]; then its doc "
       "line.\n"
       "\n"
       "Keys:\n";
  for (const auto& k : KeyTable()) {
    std::string def;
    switch (k.need) {
      case Need::Required:
        def = "required";
        break;
      case Need::Selector:
        def = "selector";
        break;
      case Need::Optional:
        def = "default " + (k.def_text.empty() ? k.def.dump() : k.def_text);
        break;
    }
    if (!k.roles.empty())
      def += std::string(k.path.rfind("motions", 0) == 0 || k.path.rfind("obstacles", 0) == 0
                             ? " [type "
                             : " [role ") +
             ListText(k.roles) + "]";
    if (!k.with.empty()) def += " [only with " + k.with + "]";
    std::string line = k.path;
    line.resize(std::max<size_t>(line.size() + 2, 28), ' ');
    line += TypeText(k, false);
    line.resize(std::max<size_t>(line.size() + 2, 66), ' ');
    line += def;
    o << line << "\n    " << k.doc << "\n";
  }
  return o.str();
}

}  // namespace softkin
