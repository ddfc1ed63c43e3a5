/// \file scene_json.cpp
/// Scene JSON reader. One key table (KeyTable()) drives both the validator and SceneSchema(): every
/// key path, its type, range or allowed values, default, role condition and doc line live there,
/// and the parser takes its defaults from it, so the documentation cannot drift from the code.
#include "softkin/solver/scene/scene_json.hpp"

#include "softkin/solver/materials/hyperelastic.hpp"

#include "softkin/solver/mesh/io/mesh_io.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

namespace softkin {
namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;

constexpr double kInf = std::numeric_limits<double>::infinity();

// ------------------------------------------------------------------------------------------------
// The key table
// ------------------------------------------------------------------------------------------------

enum class Type { Object, ObjectArray, String, Number, Integer, Vec3, Polyline, Bool };
/// Required: must be present. Optional: has a default. Selector: each object of that kind needs
/// exactly one key of its selector group (e.g. fixed[]: region | box | plane | file).
enum class Need { Required, Optional, Selector };

struct KeySpec {
  std::string path;  ///< "a.b" = key b of object a; "a[]" = each element of array a
  Type type = Type::String;
  Need need = Need::Optional;
  json def;                        ///< default value of an Optional key
  std::string def_text;            ///< shown in the schema instead of def.dump() when non-empty
  std::vector<std::string> roles;  ///< regions[] keys: roles allowing the key (empty: every role)
  std::string with;                ///< sibling key this key needs (empty: none)
  double lo = -kInf, hi = kInf;    ///< numeric range
  bool lo_open = false;            ///< lo excluded
  std::vector<std::string> choices;  ///< allowed string values (empty: any)
  std::string doc;

  KeySpec& Def(json v) { def = std::move(v); return *this; }
  KeySpec& DefText(std::string t) { def_text = std::move(t); return *this; }
  KeySpec& Roles(std::vector<std::string> r) { roles = std::move(r); return *this; }
  KeySpec& With(std::string w) { with = std::move(w); return *this; }
  KeySpec& AtLeast(double v) { lo = v; lo_open = false; return *this; }
  KeySpec& Above(double v) { lo = v; lo_open = true; return *this; }
  KeySpec& In(double a, double b) { lo = a; hi = b; lo_open = false; return *this; }
  KeySpec& Choices(std::vector<std::string> c) { choices = std::move(c); return *this; }

  bool allows_role(const std::string& role) const {
    return roles.empty() || std::find(roles.begin(), roles.end(), role) != roles.end();
  }
};

KeySpec Key(std::string path, Type type, Need need, std::string doc) {
  KeySpec k;
  k.path = std::move(path);
  k.type = type;
  k.need = need;
  k.doc = std::move(doc);
  return k;
}

const std::vector<std::string> kActuatorRoles = {"pneumatic", "cable", "dea"};

std::string Num(double v);

const std::vector<KeySpec>& KeyTable() {
  static const std::vector<KeySpec> table = [] {
    const Material mat;
    const Actuator act;
    const FkOptions fk;
    const Type O = Type::Object, A = Type::ObjectArray, S = Type::String, N = Type::Number,
               I = Type::Integer, V = Type::Vec3;
    const Need R = Need::Required, Opt = Need::Optional, Sel = Need::Selector;
    std::vector<KeySpec> t;
    t.push_back(Key("name", S, Opt, "Scene name, used in messages and output names.")
                    .Def("").DefText("the JSON file's name without extension"));
    t.push_back(Key("mesh", O, R, "The volumetric mesh and how to read it."));
    t.push_back(Key("mesh.file", S, R,
                    "Mesh file, relative to the JSON's folder (TetGen: the .node or .ele file, or "
                    "the base name)."));
    t.push_back(Key("mesh.format", S, Opt,
                    "Reader; auto picks it from the extension (.tet, .node/.ele, .msh, .vtk).")
                    .Def("auto").Choices({"auto", "tet", "tetgen", "gmsh", "vtk"}));
    t.push_back(Key("mesh.labels", S, Opt,
                    "tet only: file with one region tag per tet, in tet order, relative to the "
                    "JSON's folder (without it every tet is region 0).")
                    .Def("").DefText("none"));
    t.push_back(Key("mesh.tag_array", S, Opt,
                    "vtk only: integer cell-data array holding the region tags (none: the first "
                    "integer cell-data array).")
                    .Def("").DefText("none"));
    t.push_back(Key("mesh.scale", N, Opt,
                    "Multiplies every vertex coordinate (e.g. 1000 for a mesh in metres); all "
                    "coordinates below are in scaled units.")
                    .Def(1.0).Above(0.0));
    t.push_back(Key("regions", A, R,
                    "Role of each region tag; every tag that has elements needs exactly one entry."));
    t.push_back(Key("regions[].tag", I, R, "Region tag in the mesh (label, physical group, attribute)."));
    t.push_back(Key("regions[].role", S, R,
                    "body: passive material; pneumatic, cable, dea: the region's elements drive an "
                    "actuator.")
                    .Choices({"body", "pneumatic", "cable", "dea"}));
    t.push_back(Key("regions[].material", S, Opt,
                    "Material name. With law mooney-rivlin, a named material (ecoflex-00-30, "
                    "dragon-skin-20; thesis Sec. 3.4) supplies c1 and c2; otherwise informational.")
                    .Def(mat.name).Roles({"body"}));
    t.push_back(Key("regions[].law", S, Opt,
                    "Body material law: blend (Ch. 2 shape blending, Eq. 2.5, constant r_omega) or "
                    "mooney-rivlin (hyperelastic target, Eq. 3.6-3.7: R_omega a function of strain "
                    "fitted to c1, c2, with r_omega its zero-strain value; docs/materials.md).")
                    .Def(mat.law).Choices({"blend", "mooney-rivlin"}).Roles({"body"}));
    t.push_back(Key("regions[].c1", N, Opt,
                    "mooney-rivlin: c1, MPa (>= 0). Needed unless 'material' names a known material.")
                    .Def(0.0).DefText("from material").AtLeast(0.0).Roles({"body"}));
    t.push_back(Key("regions[].c2", N, Opt,
                    "mooney-rivlin: c2, MPa (>= 0). Needed unless 'material' names a known material.")
                    .Def(0.0).DefText("from material").AtLeast(0.0).Roles({"body"}));
    t.push_back(Key("regions[].r_omega", N, Opt,
                    "Shape-blending parameter R_omega (Eq. 2.5): 1 = rigid target "
                    "(as-rigid-as-possible), 0 = volume-preserving soft target.")
                    .Def(mat.r_omega).In(0.0, 1.0).Roles({"body"}));
    t.push_back(Key("regions[].weight", N, Opt, "Element weight w_i (Eq. 2.10) of body elements.")
                    .Def(mat.weight).Above(0.0).Roles({"body"}));
    t.push_back(Key("regions[].name", S, R,
                    "Actuator name; regions with the same name form one actuator. Actuators are "
                    "ordered by first appearance (the actuation vector's order).")
                    .Roles(kActuatorRoles));
    t.push_back(Key("regions[].min", N, Opt,
                    "Lower bound of the actuation value (pneumatic: volume ratio; cable: shortening "
                    "ratio; dea: area ratio; all > 0). Signed pneumatic: required, <= 0.")
                    .Def(act.min).DefText(Num(act.min) + " (signed: required)").Roles(kActuatorRoles));
    t.push_back(Key("regions[].max", N, Opt,
                    "Upper bound of the actuation value. Signed pneumatic: required, >= 0.")
                    .Def(act.max).DefText(Num(act.max) + " (signed: required)").Roles(kActuatorRoles));
    t.push_back(Key("regions[].rest", N, Opt,
                    "Actuation value at which the actuator is at rest (signed pneumatic: 0).")
                    .Def(act.rest).DefText(Num(act.rest) + " (signed: 0)").Roles(kActuatorRoles));
    t.push_back(Key("regions[].side", S, Opt,
                    "pneumatic: which chamber set of the actuator this region belongs to. An "
                    "actuator with a negative region is signed (Sec. 5.3.1): value v > 0 inflates "
                    "its positive regions to volume ratio 1 + gain v, v < 0 its negative ones to "
                    "1 + gain |v|; the other side is vented.")
                    .Def("positive").Choices({"positive", "negative"}).Roles({"pneumatic"}));
    t.push_back(Key("regions[].gain", N, Opt,
                    "Signed pneumatic only: volume ratio per unit of |value| (e.g. per bar).")
                    .Def(act.gain).Above(0.0).Roles({"pneumatic"}));
    t.push_back(Key("regions[].weight", N, Opt,
                    "Element weight w_i (Eq. 2.10) of actuation elements (Sec. 2.5 uses 5).")
                    .Def(act.weight).Above(0.0).Roles(kActuatorRoles));
    t.push_back(Key("regions[].path", Type::Polyline, R,
                    "cable: the cable's path through the body, from its anchored end to where it "
                    "is pulled (mm). Elements take the direction of the nearest segment; the path "
                    "length outside the cable's elements is L_R of Eq. 2.6.")
                    .Roles({"cable"}));
    t.push_back(Key("fixed", A, R,
                    "Vertices held at their rest positions: the union of the entries' selections."));
    // The vertex selectors shared by fixed[] and motions[]: exactly one of region, box, plane,
    // file per entry.
    auto selectors = [&](const std::string& p) {
      t.push_back(Key(p + ".region", I, Sel, "Every vertex of the elements with this region tag."));
      t.push_back(Key(p + ".box", O, Sel, "Every vertex inside an axis-aligned box (bounds included)."));
      t.push_back(Key(p + ".box.min", V, R, "Lower corner [x, y, z]."));
      t.push_back(Key(p + ".box.max", V, R, "Upper corner [x, y, z]."));
      t.push_back(Key(p + ".plane", O, Sel, "Every vertex within `tolerance` of a plane."));
      t.push_back(Key(p + ".plane.point", V, R, "A point on the plane [x, y, z]."));
      t.push_back(Key(p + ".plane.normal", V, R, "Plane normal [x, y, z] (non-zero; normalised)."));
      t.push_back(Key(p + ".plane.tolerance", N, Opt, "Largest distance from the plane.")
                      .Def(1e-6).AtLeast(0.0));
      t.push_back(Key(p + ".file", S, Sel,
                      "Text file of vertex indices (whitespace-separated, '#' starts a comment), "
                      "relative to the JSON's folder."));
      t.push_back(Key(p + ".base", I, Opt, "Index base of `file`: 0 or 1.").Def(0).In(0, 1).With("file"));
    };
    selectors("fixed[]");
    t.push_back(Key("fixed[].axes", S, Opt,
                    "Coordinates held: any of x, y, z once each (e.g. \"z\" for vertices that "
                    "slide on a plane z = const, or a symmetry plane's normal axis).")
                    .Def("xyz"));
    t.push_back(Key("motions", A, Opt,
                    "Motion actuators: a prescribed rigid motion of a vertex set, swept like an "
                    "actuation value (the tensile and twisting tests of Fig. 2.6). They follow the "
                    "region actuators in the actuation vector, in this order; rest 0. The moved "
                    "vertices are held at the moved positions; a vertex moved by several motions "
                    "gets them composed in order.")
                    .Def(json::array()).DefText("[]"));
    t.push_back(Key("motions[].name", S, R, "Actuator name, unique among all actuators."));
    t.push_back(Key("motions[].type", S, R,
                    "displacement: translation (mm) along `axis`; twist: rotation (degrees, "
                    "right-hand rule) about the line through `centre` along `axis`.")
                    .Choices({"displacement", "twist"}));
    selectors("motions[]");
    t.push_back(Key("motions[].axis", V, R,
                    "Direction of the translation, or the rotation axis (non-zero; normalised)."));
    t.push_back(Key("motions[].centre", V, Opt, "A point on the rotation axis.")
                    .Def(json::array({0.0, 0.0, 0.0})).Roles({"twist"}));
    t.push_back(Key("motions[].min", N, R, "Lower bound of the value (mm or degrees), <= 0."));
    t.push_back(Key("motions[].max", N, R, "Upper bound of the value (mm or degrees), >= 0."));
    t.push_back(Key("markers", A, Opt,
                    "Named tracked points; each is the mean position of its selected vertices.")
                    .Def(json::array()));
    t.push_back(Key("markers[].name", S, R, "Marker name, unique (e.g. tip)."));
    t.push_back(Key("markers[].vertex", I, Sel, "One vertex, by 0-based index."));
    t.push_back(Key("markers[].nearest", V, Sel, "The vertex nearest to this point [x, y, z]."));
    t.push_back(Key("markers[].box", O, Sel,
                  "The mean of the vertices inside an axis-aligned box (bounds included)."));
    t.push_back(Key("markers[].box.min", V, R, "Lower corner [x, y, z]."));
    t.push_back(Key("markers[].box.max", V, R, "Upper corner [x, y, z]."));
    t.push_back(Key("obstacles", A, Opt,
                    "Static obstacles the robot must stay out of (Eq. 3.4): closed surfaces; the "
                    "local-global solvers respond to them with springs (solver.collision).")
                    .Def(json::array()).DefText("[]"));
    t.push_back(Key("obstacles[].type", S, R,
                    "box: axis-aligned box; cylinder: closed cylinder; file: a closed, consistently "
                    "oriented OBJ or STL surface.")
                    .Choices({"box", "cylinder", "file"}));
    t.push_back(Key("obstacles[].min", V, R, "Lower corner [x, y, z] (mm).").Roles({"box"}));
    t.push_back(Key("obstacles[].max", V, R, "Upper corner [x, y, z] (mm), above min on every axis.")
                    .Roles({"box"}));
    t.push_back(Key("obstacles[].base", V, R, "Centre of the cylinder's base disc [x, y, z] (mm).")
                    .Roles({"cylinder"}));
    t.push_back(Key("obstacles[].axis", V, R, "Cylinder axis from the base (non-zero; normalised).")
                    .Roles({"cylinder"}));
    t.push_back(Key("obstacles[].radius", N, R, "Cylinder radius (mm).").Above(0.0).Roles({"cylinder"}));
    t.push_back(Key("obstacles[].height", N, R, "Cylinder length along the axis (mm).")
                    .Above(0.0).Roles({"cylinder"}));
    t.push_back(Key("obstacles[].segments", I, Opt, "Number of sides of the cylinder's polygon.")
                    .Def(48).AtLeast(3).Roles({"cylinder"}));
    t.push_back(Key("obstacles[].file", S, R,
                    "Surface file (.obj or .stl), relative to the JSON's folder.")
                    .Roles({"file"}));
    t.push_back(Key("solver", O, Opt, "Default forward-kinematics solver options of this scene.")
                    .Def(json::object()));
    t.push_back(Key("solver.solver", S, Opt,
                    "lg: plain local-global (Algorithm 1); lg-aa: Anderson-accelerated local-global; "
                    "ceres, ipopt-lbfgs, ipopt-newton: the same energy minimised by Ceres or Ipopt; "
                    "ipopt-hard: body energy with hard actuation constraints; calculix-linear, "
                    "calculix-nonlinear: FEM baselines by CalculiX (docs/solvers.md).")
                    .Def(fk.solver)
                    .Choices({"lg", "lg-aa", "ceres", "ipopt-lbfgs", "ipopt-newton", "ipopt-hard",
                              "calculix-linear", "calculix-nonlinear"}));
    t.push_back(Key("solver.max_iterations", I, Opt, "Iteration limit (per continuation step).")
                    .Def(fk.max_iterations).AtLeast(1));
    t.push_back(Key("solver.tolerance", N, Opt,
                    "Converged when every vertex moves less than tolerance x model size in one "
                    "iteration ...")
                    .Def(fk.tolerance).Above(0.0));
    t.push_back(Key("solver.gradient_tolerance", N, Opt,
                    "... and the energy gradient norm is below this fraction of its first value.")
                    .Def(fk.gradient_tolerance).Above(0.0));
    t.push_back(Key("solver.anderson_window", I, Opt, "History length of Anderson acceleration (lg-aa).")
                    .Def(fk.anderson_window).In(1, 50));
    t.push_back(Key("solver.anderson_safeguard", S, Opt,
                    "Keep an Anderson step if it lowers the energy or the fixed-point residual "
                    "(hybrid), only if it does not raise the energy (energy), or always (none).")
                    .Def(fk.anderson_safeguard).Choices({"hybrid", "energy", "none"}));
    t.push_back(Key("solver.continuation_steps", I, Opt,
                    "Apply the actuation in this many equal steps, warm-starting each.")
                    .Def(fk.continuation_steps).AtLeast(1));
    t.push_back(Key("solver.threads", I, Opt, "OpenMP threads for the local step (0: library default).")
                    .Def(fk.threads).AtLeast(0));
    const CollisionOptions co;
    t.push_back(Key("solver.collision", O, Opt,
                    "Collision response by springs (Sec. 3.2.3, Eq. 3.5, 3.8, 3.9; lg and lg-aa).")
                    .Def(json::object()));
    t.push_back(Key("solver.collision.self", Type::Bool, Opt,
                    "Respond to self-collision: boundary vertices inside tets not incident to them "
                    "(tet meshes only).")
                    .Def(co.self));
    t.push_back(Key("solver.collision.obstacles", Type::Bool, Opt,
                    "Respond to the scene's obstacles.")
                    .Def(co.obstacles));
    t.push_back(Key("solver.collision.epsilon", N, Opt,
                    "Offset of the contact boundary (mm): springs pull vertices this far beyond it "
                    "and release them once they are this far beyond their target (Eq. 3.8).")
                    .Def(co.epsilon).AtLeast(0.0));
    t.push_back(Key("solver.collision.stiffness", N, Opt,
                    "Spring stiffness k (Eq. 3.5) relative to the median diagonal entry of the "
                    "global matrix over the boundary vertices.")
                    .Def(co.stiffness).Above(0.0));
    t.push_back(Key("solver.collision.check_interval", I, Opt,
                    "Run collision detection every this many iterations (and before stopping).")
                    .Def(co.check_interval).AtLeast(1));
    t.push_back(Key("solver.collision.update", S, Opt,
                    "How the factor follows the spring set: CHOLMOD update/downdate, or a numeric "
                    "refactorisation.")
                    .Def(co.update).Choices({"updown", "refactor"}));
    t.push_back(Key("solver.collision.self_target", S, Opt,
                    "Where a self-collided vertex is sent: 'walk' along -n(v) through the collided "
                    "region (the thesis's rule) for every contact, or 'auto': the same within one "
                    "body, the closest facing point of the other body's surface between separate "
                    "bodies.")
                    .Def(co.self_target).Choices({"auto", "walk"}));
    t.push_back(Key("solver.collision.self_spring", S, Opt,
                    "What a self-collision spring pulls its vertex to: a fixed 'target' half way "
                    "to the exit point (Eq. 3.5), or 'pair': the exit point as a point of the "
                    "exit face, which moves with the face and loads both sides equally.")
                    .Def(co.self_spring).Choices({"target", "pair"}));
    t.push_back(Key("solver.collision.obstacle_spring", S, Opt,
                    "What an obstacle spring resists: 'plane', only the normal part of the offset "
                    "to the closest point plus eps, against the obstacle's tangent plane "
                    "(frictionless), or 'point', the whole offset (Eq. 3.5 as written; it holds "
                    "the vertex tangentially between checks, so sliding contacts creep).")
                    .Def(co.obstacle_spring).Choices({"plane", "point"}));
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

std::string RangeText(const KeySpec& k) {
  const bool has_lo = std::isfinite(k.lo), has_hi = std::isfinite(k.hi);
  if (has_lo && has_hi)
    return std::string(" in ") + (k.lo_open ? "(" : "[") + Num(k.lo) + ", " + Num(k.hi) + "]";
  if (has_lo) return (k.lo_open ? " > " : " >= ") + Num(k.lo);
  if (has_hi) return " <= " + Num(k.hi);
  return "";
}

/// The type, e.g. "number in [0, 1]"; with_article: "a number in [0, 1]" (for "expected ...").
std::string TypeText(const KeySpec& k, bool with_article) {
  auto art = [&](const char* a, const char* s) { return std::string(with_article ? a : "") + s; };
  switch (k.type) {
    case Type::Object: return art("an ", "object");
    case Type::ObjectArray: return art("an ", "array of objects");
    case Type::String:
      if (!k.choices.empty()) return "one of: " + ListText(k.choices);
      return art("a ", "string");
    case Type::Number: return art("a ", "number") + RangeText(k);
    case Type::Integer: return art("an ", "integer") + RangeText(k);
    case Type::Vec3: return art("an ", "array of 3 numbers [x, y, z]");
    case Type::Polyline: return art("an ", "array of >= 2 points [[x, y, z], ...]");
    case Type::Bool: return art("a ", "boolean (true or false)");
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

bool InRange(const KeySpec& k, double x) {
  if (std::isfinite(k.lo) && (k.lo_open ? !(x > k.lo) : !(x >= k.lo))) return false;
  if (std::isfinite(k.hi) && !(x <= k.hi)) return false;
  return true;
}

bool ValueOk(const KeySpec& k, const json& v) {
  switch (k.type) {
    case Type::Object: return v.is_object();
    case Type::ObjectArray: return v.is_array();
    case Type::String:
      if (!v.is_string()) return false;
      return k.choices.empty() ||
             std::find(k.choices.begin(), k.choices.end(), v.get<std::string>()) != k.choices.end();
    case Type::Number: return v.is_number() && std::isfinite(v.get<double>()) && InRange(k, v.get<double>());
    case Type::Integer: return IsInt(v) && InRange(k, AsInt(v));
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
    case Type::Bool: return v.is_boolean();
  }
  return false;
}

Eigen::Vector3d AsVec(const json& v) {
  return Eigen::Vector3d(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
}

// ------------------------------------------------------------------------------------------------
// JSON text -> json, with line:column syntax errors and duplicate-key detection
// ------------------------------------------------------------------------------------------------

json ParseText(const std::string& text, const std::string& source) {
  struct Frame {
    bool array = false;
    std::set<std::string> keys;
    std::string key;
    int index = 0;
  };
  std::vector<Frame> stack;
  auto path_of = [&](size_t n) {
    std::string p;
    for (size_t i = 0; i < n; ++i) {
      if (stack[i].array)
        p += "[" + std::to_string(stack[i].index) + "]";
      else
        p += (p.empty() ? "" : ".") + stack[i].key;
    }
    return p;
  };
  json::parser_callback_t cb = [&](int, json::parse_event_t ev, json& parsed) {
    switch (ev) {
      case json::parse_event_t::object_start: stack.push_back(Frame{}); break;
      case json::parse_event_t::array_start: {
        Frame f;
        f.array = true;
        stack.push_back(std::move(f));
        break;
      }
      case json::parse_event_t::key: {
        const std::string k = parsed.get<std::string>();
        Frame& f = stack.back();
        if (!f.keys.insert(k).second) {
          const std::string p = path_of(stack.size() - 1);
          throw std::invalid_argument(source + ": " + (p.empty() ? "" : p + ": ") +
                                      "duplicate key '" + k + "'; expected each key once");
        }
        f.key = k;
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        stack.pop_back();
        if (!stack.empty() && stack.back().array) ++stack.back().index;
        break;
      case json::parse_event_t::value:
        if (!stack.empty() && stack.back().array) ++stack.back().index;
        break;
    }
    return true;
  };
  try {
    return json::parse(text, cb);
  } catch (const json::parse_error& e) {
    // e.byte counts the characters read, the offending one included; turn it into line:column.
    size_t at = e.byte == 0 ? 0 : e.byte - 1;
    at = std::min(at, text.size());
    int line = 1;
    size_t line_start = 0;
    for (size_t i = 0; i < at; ++i)
      if (text[i] == '\n') {
        ++line;
        line_start = i + 1;
      }
    const size_t column = at - line_start + 1;
    std::string what = e.what();
    const auto pe = what.find("parse error");
    if (pe != std::string::npos) {
      const auto colon = what.find(": ", pe);
      if (colon != std::string::npos) what = what.substr(colon + 2);
    }
    throw std::invalid_argument(source + ":" + std::to_string(line) + ":" + std::to_string(column) +
                                ": invalid JSON: " + what);
  }
}

// ------------------------------------------------------------------------------------------------
// The scene builder
// ------------------------------------------------------------------------------------------------

class SceneParser {
 public:
  SceneParser(std::string source, std::string base_dir)
      : src_(std::move(source)), base_(std::move(base_dir)) {}

  Scene Build(const json& root);

 private:
  [[noreturn]] void Fail(const std::string& msg) const { throw std::invalid_argument(src_ + ": " + msg); }
  static std::string At(const std::string& path) { return path.empty() ? std::string() : path + ": "; }

  /// Specs of the keys of objects at `pattern` (e.g. "fixed[]") that apply to `role`.
  std::vector<const KeySpec*> Children(const std::string& pattern, const std::string& role) const {
    std::vector<const KeySpec*> out;
    for (const auto& k : KeyTable())
      if (ParentOf(k.path) == pattern && k.allows_role(role)) out.push_back(&k);
    return out;
  }
  const KeySpec* Spec(const std::string& pattern, const std::string& key, const std::string& role) const {
    if (key.find_first_of(".[]") != std::string::npos) return nullptr;  // "mesh.file" is no key
    for (const auto& k : KeyTable())
      if (k.path == Join(pattern, key) && k.allows_role(role)) return &k;
    return nullptr;
  }
  /// Value of key (or its default); the key must have been checked by CheckObject.
  json Get(const json& obj, const std::string& pattern, const std::string& key,
           const std::string& role = "") const {
    if (obj.contains(key)) return obj.at(key);
    const KeySpec* k = Spec(pattern, key, role);
    if (!k) throw std::logic_error("scene_json: no key " + Join(pattern, key) + " in the key table");
    return k->def;
  }

  void CheckValue(const KeySpec& k, const json& v, const std::string& path) const {
    if (!ValueOk(k, v)) Fail(path + ": expected " + TypeText(k, true) + ", got " + Got(v));
  }
  /// Checks one key of `obj` (presence if required, type, range) before the rest of the object.
  void CheckKey(const json& obj, const std::string& pattern, const std::string& path,
                const std::string& key) const {
    const KeySpec* k = Spec(pattern, key, "");
    if (!obj.contains(key)) {
      if (k->need == Need::Required)
        Fail(At(path) + "missing required key '" + key + "' (expected " + TypeText(*k, true) + ")");
      return;
    }
    CheckValue(*k, obj.at(key), Join(path, key));
  }

  /// Validates object `obj` found at `path` against the keys of `pattern`: unknown keys, keys not
  /// allowed for `role`, types and ranges, required keys and the selector group.
  void CheckObject(const json& obj, const std::string& pattern, const std::string& path,
                   const std::string& role = "") const {
    if (!obj.is_object())
      Fail(path.empty() ? "expected a JSON object at the top level, got " + Got(obj)
                        : path + ": expected an object, got " + Got(obj));
    const auto kids = Children(pattern, role);
    std::vector<std::string> allowed;
    for (const KeySpec* k : kids)
      if (std::find(allowed.begin(), allowed.end(), LeafOf(k->path)) == allowed.end())
        allowed.push_back(LeafOf(k->path));
    for (const auto& [key, value] : obj.items()) {
      const KeySpec* k = Spec(pattern, key, role);
      if (!k) {
        const KeySpec* any_role = Spec(pattern, key, "");
        bool known = false;
        std::vector<std::string> roles;
        for (const auto& s : KeyTable())
          if (s.path == Join(pattern, key) && key.find_first_of(".[]") == std::string::npos) {
            known = true;
            roles.insert(roles.end(), s.roles.begin(), s.roles.end());
          }
        if (known && !any_role)
        {
          const std::string word =
              (pattern == "motions[]" || pattern == "obstacles[]") ? "type" : "role";
          Fail(Join(path, key) + ": not allowed for " + word + " '" + role + "' (only for " + word +
               " " + ListText(roles) + "; expected one of: " + ListText(allowed) + ")");
        }
        std::string hint;
        for (const auto& a : allowed)
          if (EditDistance(key, a) <= 2) {
            hint = "did you mean '" + a + "'? ";
            break;
          }
        Fail(At(path) + "unknown key '" + key + "' (" + hint + "expected one of: " +
             ListText(allowed) + ")");
      }
      if (!k->with.empty() && !obj.contains(k->with))
        Fail(Join(path, key) + ": only allowed together with '" + k->with + "'");
      CheckValue(*k, value, Join(path, key));
    }
    std::vector<std::string> selectors, present;
    for (const KeySpec* k : kids) {
      const std::string leaf = LeafOf(k->path);
      if (k->need == Need::Required && !obj.contains(leaf))
        Fail(At(path) + "missing required key '" + leaf + "' (expected " + TypeText(*k, true) + ")");
      if (k->need == Need::Selector) {
        selectors.push_back(leaf);
        if (obj.contains(leaf)) present.push_back(leaf);
      }
    }
    if (!selectors.empty() && present.size() != 1)
      Fail(At(path) + "expected exactly one of: " + ListText(selectors) +
           (present.empty() ? std::string(", got none")
                            : ", got both '" + present[0] + "' and '" + present[1] + "'"));
  }

  fs::path Resolve(const std::string& file) const {
    fs::path p(file);
    if (p.is_relative() && !base_.empty()) p = fs::path(base_) / p;
    return p.lexically_normal();
  }

  void ReadMeshSection(const json& m, Scene* scene) const;
  void ReadRegions(const json& regions, Scene* scene) const;
  void ReadFixed(const json& fixed, Scene* scene) const;
  void ReadMotions(const json& motions, Scene* scene) const;
  /// The vertices chosen by the selector key (region | box | plane | file) of an object at
  /// `pattern` ("fixed[]" or "motions[]"), already checked by CheckObject.
  std::vector<int> ReadSelection(const json& entry, const std::string& pattern,
                                 const std::string& path, const Mesh& mesh) const;
  std::vector<int> ReadIndexFile(const json& entry, const std::string& pattern,
                                 const std::string& path, const Mesh& mesh) const;
  std::vector<Marker> ReadMarkers(const json& markers, const Mesh& mesh) const;
  std::vector<TriangleSurface> ReadObstacles(const json& obstacles) const;
  void ReadBox(const json& box, const std::string& pattern, const std::string& path,
               Eigen::Vector3d* lo, Eigen::Vector3d* hi) const;
  std::string BoundsText(const Mesh& mesh) const {
    if (mesh.num_vertices() == 0) return "the mesh has no vertices";
    return "the mesh spans " + VecText(mesh.vertices.colwise().minCoeff().transpose()) + " to " +
           VecText(mesh.vertices.colwise().maxCoeff().transpose());
  }

  std::string src_;
  std::string base_;
};

void SceneParser::ReadMeshSection(const json& m, Scene* scene) const {
  CheckObject(m, "mesh", "mesh");
  const std::string file_key = m.at("file").get<std::string>();
  if (file_key.empty()) Fail("mesh.file: expected a file name, got \"\"");
  const fs::path file = Resolve(file_key);
  std::string format = Get(m, "mesh", "format").get<std::string>();
  const std::string labels = Get(m, "mesh", "labels").get<std::string>();
  const std::string tag_array = Get(m, "mesh", "tag_array").get<std::string>();
  if (format == "auto") {
    std::string ext = file.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext == ".tet") format = "tet";
    else if (ext == ".node" || ext == ".ele") format = "tetgen";
    else if (ext == ".msh") format = "gmsh";
    else if (ext == ".vtk") format = "vtk";
    else if (ext.empty() && fs::exists(file.string() + ".node")) format = "tetgen";
    else
      Fail("mesh.format: cannot tell the mesh format of '" + file.string() +
           "' from its extension; expected a .tet, .node, .ele, .msh or .vtk file, or mesh.format "
           "set to one of: tet, tetgen, gmsh, vtk");
  }
  if (!labels.empty() && format != "tet")
    Fail("mesh.labels: only used by the tet format (the mesh is read as " + format + ")");
  if (!tag_array.empty() && format != "vtk")
    Fail("mesh.tag_array: only used by the vtk format (the mesh is read as " + format + ")");

  fs::path read_path = file;
  if (format == "tetgen") {
    const std::string ext = file.extension().string();
    fs::path base = (ext == ".node" || ext == ".ele") ? fs::path(file).replace_extension() : file;
    for (const char* e : {".node", ".ele"})
      if (!fs::is_regular_file(base.string() + e))
        Fail("mesh.file: file not found: '" + base.string() + e + "' (from mesh.file \"" + file_key +
             "\"; expected an existing TetGen .node and .ele pair)");
    read_path = base;
  } else if (!fs::is_regular_file(file)) {
    Fail("mesh.file: file not found: '" + file.string() + "' (from mesh.file \"" + file_key +
         "\", relative to '" + (base_.empty() ? std::string(".") : base_) + "')");
  }
  fs::path labels_path;
  if (!labels.empty()) {
    labels_path = Resolve(labels);
    if (!fs::is_regular_file(labels_path))
      Fail("mesh.labels: file not found: '" + labels_path.string() + "' (from mesh.labels \"" +
           labels + "\")");
  }

  try {
    if (format == "tet") scene->mesh = ReadTet(read_path.string(), labels_path.string());
    else if (format == "tetgen") scene->mesh = ReadTetGen(read_path.string());
    else if (format == "gmsh") scene->mesh = ReadGmsh(read_path.string());
    else scene->mesh = ReadVtk(read_path.string(), tag_array);
  } catch (const std::exception& e) {
    // Keep the reader's "<file>:<line>: ..." message intact; add the key it came from.
    const std::string what = e.what();
    const bool from_labels = !labels_path.empty() && what.rfind(labels_path.string(), 0) == 0;
    Fail(std::string(from_labels ? "mesh.labels" : "mesh.file") + ": cannot read the " + format +
         " mesh: " + what);
  }
  const double scale = Get(m, "mesh", "scale").get<double>();
  if (scale != 1.0) scene->mesh.vertices *= scale;
}

void SceneParser::ReadRegions(const json& regions, Scene* scene) const {
  if (regions.empty()) Fail("regions: expected at least one region entry, got []");
  const std::vector<int> mesh_tags = scene->mesh.regions();
  std::map<int, std::string> tag_path;
  struct Given { double value; std::string path; };
  struct ActInfo {
    int index;
    std::string role, role_path;
    std::string negative_path;  ///< the first region with side "negative" (signed actuator)
    std::map<std::string, Given> given;
  };
  std::map<std::string, ActInfo> acts;

  for (size_t i = 0; i < regions.size(); ++i) {
    const std::string path = "regions[" + std::to_string(i) + "]";
    const json& r = regions[i];
    if (!r.is_object()) Fail(path + ": expected an object, got " + Got(r));
    CheckKey(r, "regions[]", path, "role");
    const std::string role = r.at("role").get<std::string>();
    CheckObject(r, "regions[]", path, role);

    const int tag = AsInt(r.at("tag"));
    if (auto it = tag_path.find(tag); it != tag_path.end())
      Fail(path + ".tag: region " + std::to_string(tag) + " is already described by " + it->second +
           "; expected each tag once");
    tag_path[tag] = path;
    if (!std::binary_search(mesh_tags.begin(), mesh_tags.end(), tag))
      Fail(path + ".tag: no element of the mesh has region tag " + std::to_string(tag) +
           " (the mesh's tags: " + IntListText(mesh_tags) + ")");

    if (role == "body") {
      Material mat;
      mat.name = Get(r, "regions[]", "material", role).get<std::string>();
      mat.r_omega = Get(r, "regions[]", "r_omega", role).get<double>();
      mat.weight = Get(r, "regions[]", "weight", role).get<double>();
      mat.law = Get(r, "regions[]", "law", role).get<std::string>();
      const bool has_c = r.contains("c1") || r.contains("c2");
      if (has_c && !mat.hyperelastic())
        Fail(path + ": c1 / c2 are given but law is \"" + mat.law +
             "\"; expected law \"mooney-rivlin\" with them");
      if (mat.hyperelastic()) {
        MooneyRivlin mr;
        const bool named = NamedMooneyRivlin(mat.name, &mr);
        if (!named && !(r.contains("c1") && r.contains("c2"))) {
          std::string names;
          for (const auto& n : NamedMooneyRivlinNames()) names += (names.empty() ? "" : ", ") + n;
          Fail(path + ": law mooney-rivlin needs c1 and c2 (MPa), or 'material' naming one of " +
               names + "; got material \"" + mat.name + "\"");
        }
        mat.c1 = r.contains("c1") ? r.at("c1").get<double>() : mr.c1;
        mat.c2 = r.contains("c2") ? r.at("c2").get<double>() : mr.c2;
        if (!(mat.c1 + mat.c2 > 0)) Fail(path + ": expected c1 + c2 > 0 for law mooney-rivlin");
        if (!(mat.r_omega > 0)) Fail(path + ".r_omega: expected a zero-strain R_omega > 0 for law mooney-rivlin");
      }
      scene->body[tag] = mat;
      continue;
    }

    const std::string name = r.at("name").get<std::string>();
    if (name.empty()) Fail(path + ".name: expected a non-empty actuator name, got \"\"");
    auto it = acts.find(name);
    if (it == acts.end()) {
      Actuator a;
      a.name = name;
      if (!ActuatorTypeFromString(role, &a.type))
        throw std::logic_error("scene_json: role '" + role + "' is not an actuator type");
      scene->actuators.push_back(a);
      it = acts.emplace(name, ActInfo{scene->num_actuators() - 1, role, path + ".role", "", {}}).first;
    } else if (it->second.role != role) {
      Fail(path + ".role: actuator '" + name + "' is " + it->second.role + " in " +
           it->second.role_path + ", got \"" + role +
           "\"; regions sharing an actuator name must have the same role");
    }
    const bool negative =
        role == "pneumatic" && Get(r, "regions[]", "side", role).get<std::string>() == "negative";
    if (negative) {
      scene->actuators[it->second.index].negative_regions.push_back(tag);
      if (it->second.negative_path.empty()) it->second.negative_path = path + ".side";
    } else {
      scene->actuators[it->second.index].regions.push_back(tag);
    }
    if (role == "cable") {
      std::vector<Eigen::Vector3d> pts;
      for (const auto& p : r.at("path")) pts.push_back(AsVec(p));
      auto& a = scene->actuators[it->second.index];
      if (a.path.empty())
        a.path = pts;
      else if (a.path != pts)
        Fail(path + ".path: cable '" + name +
             "' already has a different path; regions sharing a cable name must give the same "
             "path");
    }
    for (const char* key : {"min", "max", "rest", "weight", "gain"}) {
      if (!r.contains(key)) continue;
      const double v = r.at(key).get<double>();
      const std::string kp = path + "." + key;
      auto g = it->second.given.find(key);
      if (g == it->second.given.end())
        it->second.given[key] = Given{v, kp};
      else if (g->second.value != v)
        Fail(kp + ": actuator '" + name + "' already has " + key + " " + Num(g->second.value) +
             " from " + g->second.path + ", got " + Num(v) +
             "; regions sharing an actuator name must agree");
    }
  }

  for (auto& [name, info] : acts) {
    Actuator& a = scene->actuators[info.index];
    auto value = [&](const char* key) {
      auto g = info.given.find(key);
      return g != info.given.end() ? g->second.value : Spec("regions[]", key, info.role)->def.get<double>();
    };
    const std::string entry = info.role_path.substr(0, info.role_path.size() - 5);
    auto where = [&](const char* key) {
      auto g = info.given.find(key);
      return g != info.given.end() ? g->second.path : std::string("default");
    };
    a.weight = value("weight");
    if (info.role == "pneumatic") a.gain = value("gain");
    if (!info.negative_path.empty()) {
      // Signed pneumatic actuator: rest 0, an explicit range around it.
      for (const char* key : {"min", "max"})
        if (!info.given.count(key))
          Fail(entry + ": signed actuator '" + name + "' (negative side from " + info.negative_path +
               ") needs '" + key + "'; expected min <= 0 <= max");
      a.min = value("min");
      a.max = value("max");
      a.rest = info.given.count("rest") ? value("rest") : 0.0;
      if (a.rest != 0.0)
        Fail(where("rest") + ": signed actuator '" + name + "': expected rest 0, got " + Num(a.rest));
      if (!(a.min <= 0.0))
        Fail(where("min") + ": signed actuator '" + name + "': expected min <= 0, got " + Num(a.min));
      if (!(a.max >= 0.0))
        Fail(where("max") + ": signed actuator '" + name + "': expected max >= 0, got " + Num(a.max));
      if (a.regions.empty())
        Fail(entry + ": signed actuator '" + name +
             "' has only negative-side regions; expected at least one region with side \"positive\"");
      continue;
    }
    if (info.given.count("gain"))
      Fail(where("gain") + ": actuator '" + name +
           "' is not signed (no region with side \"negative\"); gain applies to signed actuators only");
    a.min = value("min");
    a.max = value("max");
    a.rest = value("rest");
    for (const char* key : {"min", "max", "rest"})
      if (!(value(key) > 0.0))
        Fail(where(key) + ": actuator '" + name + "': expected a ratio > 0, got " + Num(value(key)));
    if (!(a.min <= a.rest && a.rest <= a.max)) {
      Fail(entry + ": actuator '" + name +
           "': expected min <= rest <= max, got min " + Num(a.min) + " (" + where("min") +
           "), rest " + Num(a.rest) + " (" + where("rest") + "), max " + Num(a.max) + " (" +
           where("max") + ")");
    }
  }
}

void SceneParser::ReadBox(const json& box, const std::string& pattern, const std::string& path,
                          Eigen::Vector3d* lo, Eigen::Vector3d* hi) const {
  CheckObject(box, pattern, path);
  *lo = AsVec(box.at("min"));
  *hi = AsVec(box.at("max"));
  if (!((lo->array() <= hi->array()).all()))
    Fail(path + ": expected min <= max in every coordinate, got min " + VecText(*lo) + ", max " +
         VecText(*hi));
}

std::vector<int> SceneParser::ReadIndexFile(const json& entry, const std::string& pattern,
                                            const std::string& path, const Mesh& mesh) const {
  const std::string name = entry.at("file").get<std::string>();
  const int base = AsInt(Get(entry, pattern, "base"));
  const fs::path file = Resolve(name);
  std::ifstream in(file);
  if (!in) Fail(path + ".file: cannot open '" + file.string() + "' (from \"" + name + "\")");
  const int n = mesh.num_vertices();
  std::vector<int> out;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream tokens(line);
    std::string tok;
    while (tokens >> tok) {
      long long v = 0;
      const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
      const std::string where = path + ".file: " + file.string() + ":" + std::to_string(line_no) + ": ";
      if (ec != std::errc() || ptr != tok.data() + tok.size())
        Fail(where + "expected an integer vertex index, got '" + tok + "'");
      if (v - base < 0 || v - base >= n)
        Fail(where + "vertex index " + tok + " is out of range; expected " + std::to_string(base) +
             " to " + std::to_string(n - 1 + base) + " (" + std::to_string(n) +
             " vertices, base " + std::to_string(base) + ")");
      out.push_back(static_cast<int>(v - base));
    }
  }
  if (in.bad()) Fail(path + ".file: error while reading '" + file.string() + "'");
  if (out.empty()) Fail(path + ".file: '" + file.string() + "' lists no vertex index");
  return out;
}

std::vector<int> SceneParser::ReadSelection(const json& f, const std::string& pattern,
                                            const std::string& path, const Mesh& mesh) const {
  std::vector<int> sel;
  if (f.contains("region")) {
    const int tag = AsInt(f.at("region"));
    sel = VerticesOfRegions(mesh, {tag});
    if (sel.empty())
      Fail(path + ".region: no element of the mesh has region tag " + std::to_string(tag) +
           " (the mesh's tags: " + IntListText(mesh.regions()) + ")");
  } else if (f.contains("box")) {
    Eigen::Vector3d lo, hi;
    ReadBox(f.at("box"), pattern + ".box", path + ".box", &lo, &hi);
    sel = VerticesInBox(mesh, lo, hi);
    if (sel.empty()) Fail(path + ".box selects no vertex (" + BoundsText(mesh) + ")");
  } else if (f.contains("plane")) {
    const json& p = f.at("plane");
    CheckObject(p, pattern + ".plane", path + ".plane");
    const Eigen::Vector3d point = AsVec(p.at("point")), normal = AsVec(p.at("normal"));
    if (!(normal.norm() > 0.0))
      Fail(path + ".plane.normal: expected a non-zero vector, got " + VecText(normal));
    const double tol = Get(p, pattern + ".plane", "tolerance").get<double>();
    sel = VerticesOnPlane(mesh, point, normal, tol);
    if (sel.empty())
      Fail(path + ".plane selects no vertex (tolerance " + Num(tol) + "; " + BoundsText(mesh) + ")");
  } else {
    sel = ReadIndexFile(f, pattern, path, mesh);
  }
  std::sort(sel.begin(), sel.end());
  sel.erase(std::unique(sel.begin(), sel.end()), sel.end());
  return sel;
}

void SceneParser::ReadFixed(const json& fixed, Scene* scene) const {
  if (fixed.empty()) Fail("fixed: expected at least one selection, got []");
  std::vector<int> all;
  std::array<std::vector<int>, 3> axis;
  for (size_t i = 0; i < fixed.size(); ++i) {
    const std::string path = "fixed[" + std::to_string(i) + "]";
    const json& f = fixed[i];
    CheckObject(f, "fixed[]", path);
    const std::string axes = Get(f, "fixed[]", "axes").get<std::string>();
    std::array<bool, 3> held = {false, false, false};
    for (char c : axes) {
      const int d = c == 'x' ? 0 : c == 'y' ? 1 : c == 'z' ? 2 : -1;
      if (d < 0 || held[d])
        Fail(path + ".axes: expected some of the letters x, y, z, each at most once (e.g. \"xyz\", "
             "\"z\"), got \"" + axes + "\"");
      held[d] = true;
    }
    if (axes.empty())
      Fail(path + ".axes: expected some of the letters x, y, z, each at most once, got \"\"");
    const std::vector<int> sel = ReadSelection(f, "fixed[]", path, scene->mesh);
    if (held[0] && held[1] && held[2]) {
      all.insert(all.end(), sel.begin(), sel.end());
    } else {
      for (int d = 0; d < 3; ++d)
        if (held[d]) axis[d].insert(axis[d].end(), sel.begin(), sel.end());
    }
  }
  auto sort_unique = [](std::vector<int>* v) {
    std::sort(v->begin(), v->end());
    v->erase(std::unique(v->begin(), v->end()), v->end());
  };
  sort_unique(&all);
  scene->fixed = all;
  for (int d = 0; d < 3; ++d) {
    sort_unique(&axis[d]);
    // A fully fixed vertex needs no per-axis entry.
    std::vector<int> only;
    std::set_difference(axis[d].begin(), axis[d].end(), all.begin(), all.end(),
                        std::back_inserter(only));
    scene->fixed_axis[d] = only;
  }
}

void SceneParser::ReadMotions(const json& motions, Scene* scene) const {
  std::map<std::string, std::string> name_path;
  for (size_t i = 0; i < motions.size(); ++i) {
    const std::string path = "motions[" + std::to_string(i) + "]";
    const json& m = motions[i];
    if (!m.is_object()) Fail(path + ": expected an object, got " + Got(m));
    CheckKey(m, "motions[]", path, "type");
    const std::string type = m.at("type").get<std::string>();
    CheckObject(m, "motions[]", path, type);
    Actuator a;
    a.name = m.at("name").get<std::string>();
    if (a.name.empty()) Fail(path + ".name: expected a non-empty actuator name, got \"\"");
    if (scene->actuator_index(a.name) >= 0)
      Fail(path + ".name: actuator '" + a.name + "' is already defined" +
           (name_path.count(a.name) ? " by " + name_path[a.name] : std::string(" in regions")) +
           "; expected unique actuator names");
    name_path[a.name] = path;
    if (!ActuatorTypeFromString(type, &a.type))
      throw std::logic_error("scene_json: motion type '" + type + "' is not an actuator type");
    a.vertices = ReadSelection(m, "motions[]", path, scene->mesh);
    a.axis = AsVec(m.at("axis"));
    if (!(a.axis.norm() > 0.0))
      Fail(path + ".axis: expected a non-zero vector, got " + VecText(a.axis));
    a.axis.normalize();
    if (a.type == ActuatorType::Twist) a.centre = AsVec(Get(m, "motions[]", "centre", type));
    a.min = m.at("min").get<double>();
    a.max = m.at("max").get<double>();
    a.rest = 0.0;
    if (!(a.min <= 0.0)) Fail(path + ".min: expected a number <= 0 (rest is 0), got " + Num(a.min));
    if (!(a.max >= 0.0)) Fail(path + ".max: expected a number >= 0 (rest is 0), got " + Num(a.max));
    for (int v : a.vertices)
      if (std::binary_search(scene->fixed.begin(), scene->fixed.end(), v))
        Fail(path + ": vertex " + std::to_string(v) + " (at " +
             VecText(scene->mesh.vertices.row(v).transpose()) +
             ") is also in `fixed`; expected moved vertices not to be fixed");
    for (int d = 0; d < 3; ++d)
      for (int v : a.vertices)
        if (std::binary_search(scene->fixed_axis[d].begin(), scene->fixed_axis[d].end(), v))
          Fail(path + ": vertex " + std::to_string(v) + " (at " +
               VecText(scene->mesh.vertices.row(v).transpose()) + ") is also held on axis " +
               "xyz"[d] + " by `fixed`; expected moved vertices not to be held");
    scene->actuators.push_back(std::move(a));
  }
}

std::vector<TriangleSurface> SceneParser::ReadObstacles(const json& obstacles) const {
  std::vector<TriangleSurface> out;
  for (size_t i = 0; i < obstacles.size(); ++i) {
    const std::string path = "obstacles[" + std::to_string(i) + "]";
    const json& o = obstacles[i];
    if (!o.is_object()) Fail(path + ": expected an object, got " + Got(o));
    CheckKey(o, "obstacles[]", path, "type");
    const std::string type = o.at("type").get<std::string>();
    CheckObject(o, "obstacles[]", path, type);
    fs::path file;
    if (type == "file") {
      file = Resolve(o.at("file").get<std::string>());
      if (!fs::is_regular_file(file))
        Fail(path + ".file: file not found: '" + file.string() + "' (relative to '" +
             (base_.empty() ? std::string(".") : base_) + "')");
    }
    TriangleSurface s;
    try {
      if (type == "box") {
        s = MakeBoxSurface(AsVec(o.at("min")), AsVec(o.at("max")));
      } else if (type == "cylinder") {
        s = MakeCylinderSurface(AsVec(o.at("base")), AsVec(o.at("axis")), o.at("radius").get<double>(),
                                o.at("height").get<double>(),
                                AsInt(Get(o, "obstacles[]", "segments", type)));
      } else {
        s = ReadSurfaceMesh(file.string());
      }
      CheckClosedSurface(&s);
    } catch (const std::invalid_argument& e) {
      Fail(path + ": " + e.what());
    }
    s.source = path + " (" + (s.source.empty() ? type : s.source) + ")";
    out.push_back(std::move(s));
  }
  return out;
}

std::vector<Marker> SceneParser::ReadMarkers(const json& markers, const Mesh& mesh) const {
  std::vector<Marker> out;
  std::map<std::string, std::string> name_path;
  for (size_t i = 0; i < markers.size(); ++i) {
    const std::string path = "markers[" + std::to_string(i) + "]";
    const json& m = markers[i];
    CheckObject(m, "markers[]", path);
    Marker mk;
    mk.name = m.at("name").get<std::string>();
    if (mk.name.empty()) Fail(path + ".name: expected a non-empty marker name, got \"\"");
    if (auto it = name_path.find(mk.name); it != name_path.end())
      Fail(path + ".name: marker '" + mk.name + "' is already defined by " + it->second +
           "; expected unique names");
    name_path[mk.name] = path;
    if (m.contains("vertex")) {
      const int v = AsInt(m.at("vertex"));
      if (v < 0 || v >= mesh.num_vertices())
        Fail(path + ".vertex: expected a vertex index in [0, " +
             std::to_string(mesh.num_vertices() - 1) + "], got " + std::to_string(v));
      mk.vertices = {v};
    } else if (m.contains("nearest")) {
      if (mesh.num_vertices() == 0) Fail(path + ".nearest: the mesh has no vertices");
      mk.vertices = {NearestVertex(mesh, AsVec(m.at("nearest")))};
    } else {
      Eigen::Vector3d lo, hi;
      ReadBox(m.at("box"), "markers[].box", path + ".box", &lo, &hi);
      mk.vertices = VerticesInBox(mesh, lo, hi);
      if (mk.vertices.empty()) Fail(path + ".box selects no vertex (" + BoundsText(mesh) + ")");
    }
    out.push_back(std::move(mk));
  }
  return out;
}

Scene SceneParser::Build(const json& root) {
  CheckObject(root, "", "");
  Scene scene;
  scene.name = Get(root, "", "name").get<std::string>();
  if (scene.name.empty()) scene.name = fs::path(src_).stem().string();

  ReadMeshSection(root.at("mesh"), &scene);
  ReadRegions(root.at("regions"), &scene);
  ReadFixed(root.at("fixed"), &scene);
  ReadMotions(Get(root, "", "motions"), &scene);
  scene.markers = ReadMarkers(Get(root, "", "markers"), scene.mesh);
  scene.obstacles = ReadObstacles(Get(root, "", "obstacles"));

  const json solver = Get(root, "", "solver");
  CheckObject(solver, "solver", "solver");
  FkOptions& o = scene.solver;
  o.solver = Get(solver, "solver", "solver").get<std::string>();
  o.max_iterations = AsInt(Get(solver, "solver", "max_iterations"));
  o.tolerance = Get(solver, "solver", "tolerance").get<double>();
  o.gradient_tolerance = Get(solver, "solver", "gradient_tolerance").get<double>();
  o.anderson_window = AsInt(Get(solver, "solver", "anderson_window"));
  o.anderson_safeguard = Get(solver, "solver", "anderson_safeguard").get<std::string>();
  o.continuation_steps = AsInt(Get(solver, "solver", "continuation_steps"));
  o.threads = AsInt(Get(solver, "solver", "threads"));
  const json col = Get(solver, "solver", "collision");
  CheckObject(col, "solver.collision", "solver.collision");
  o.collision.self = Get(col, "solver.collision", "self").get<bool>();
  o.collision.obstacles = Get(col, "solver.collision", "obstacles").get<bool>();
  o.collision.epsilon = Get(col, "solver.collision", "epsilon").get<double>();
  o.collision.stiffness = Get(col, "solver.collision", "stiffness").get<double>();
  o.collision.check_interval = AsInt(Get(col, "solver.collision", "check_interval"));
  o.collision.update = Get(col, "solver.collision", "update").get<std::string>();
  o.collision.self_target = Get(col, "solver.collision", "self_target").get<std::string>();
  o.collision.self_spring = Get(col, "solver.collision", "self_spring").get<std::string>();
  o.collision.obstacle_spring = Get(col, "solver.collision", "obstacle_spring").get<std::string>();
  std::string why;
  if (!o.IsValid(&why)) Fail("solver." + why);

  try {
    scene.validate();
  } catch (const std::invalid_argument& e) {
    Fail(e.what());
  }
  return scene;
}

}  // namespace

Scene ParseSceneJson(const std::string& text, const std::string& source, const std::string& base_dir) {
  const json root = ParseText(text, source);
  return SceneParser(source, base_dir).Build(root);
}

Scene LoadSceneJson(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::invalid_argument(path + ": cannot open the scene file (resolved: '" +
                                fs::absolute(path).lexically_normal().string() + "')");
  std::ostringstream ss;
  ss << in.rdbuf();
  fs::path dir = fs::path(path).parent_path();
  return ParseSceneJson(ss.str(), path, dir.empty() ? std::string(".") : dir.string());
}

std::string SceneSchema() {
  std::ostringstream o;
  o << "SoftKin scene JSON\n"
       "==================\n"
       "Key paths: a.b is key b of object a; a[] is each element of array a.\n"
       "Relative file paths are relative to the scene JSON's folder. Coordinates are in mesh units\n"
       "after mesh.scale. Unknown keys, duplicate keys and wrong types are errors. Keys marked\n"
       "'selector' form a group: each object needs exactly one key of its group.\n"
       "Each key: key path, type, default (or required / selector) [condition]; then its doc line.\n"
       "\n"
       "Keys:\n";
  for (const auto& k : KeyTable()) {
    std::string def;
    switch (k.need) {
      case Need::Required: def = "required"; break;
      case Need::Selector: def = "selector"; break;
      case Need::Optional: def = "default " + (k.def_text.empty() ? k.def.dump() : k.def_text); break;
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
