#include "softkin/solver/baselines/calculix_pressure.hpp"

#include "softkin/solver/baselines/calculix.hpp"
#include "softkin/solver/baselines/ccx_run.hpp"
#include "softkin/solver/mesh/element_faces.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <stdexcept>

namespace softkin {
namespace fs = std::filesystem;

namespace {

/// Local edge-midpoint slots of C3D10 (nodes 5..10 on edges 12, 23, 31, 14, 24, 34).
const int kEdges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};

/// The nodes the deck prints and the reader expects: every corner node (the scene's vertices)
/// and the cavities' edge-midpoint nodes (for their volume).
std::vector<bool> PrintedNodes(const PressureFemMesh& fem) {
  std::vector<bool> printed(fem.rest.rows(), false);
  for (int n = 0; n < fem.rest.rows(); ++n) printed[n] = fem.node_vertex[n] >= 0;
  for (const auto& cav : fem.cavities)
    for (const auto& f : cav)
      for (int m : f.mids)
        if (m >= 0) printed[m] = true;
  return printed;
}

}  // namespace

PressureFemMesh BuildPressureFemMesh(const Model& model, const std::string& element_type) {
  const Scene& s = model.scene();
  const Mesh& mesh = s.mesh;
  if (element_type != "C3D4" && element_type != "C3D10")
    throw std::invalid_argument("calculix-pressure: element: expected C3D10 or C3D4, got '" +
                                element_type + "'");
  if (!s.region_rest.regions.empty())
    throw std::invalid_argument("calculix-pressure: scene '" + s.name +
                                "' has regions with their own rest shape; the FEM needs one rest "
                                "mesh");
  for (const auto& a : s.actuators)
    if (a.type != ActuatorType::Pneumatic)
      throw std::invalid_argument("calculix-pressure: actuator '" + a.name + "' is " +
                                  ActuatorTypeToString(a.type) +
                                  "; the pressure FEM supports pneumatic actuators only");
  for (int i = 0; i < mesh.num_elements(); ++i)
    if (mesh.elements[i].k() != 4)
      throw std::invalid_argument("calculix-pressure: element " + std::to_string(i) +
                                  " is a prism; the pressure FEM supports tets only");
  const auto& els = model.elements();
  PressureFemMesh fem;
  fem.element_type = element_type;
  // Corner nodes: the vertices of body elements, in vertex order.
  fem.vertex_node.assign(mesh.num_vertices(), -1);
  for (int i = 0; i < mesh.num_elements(); ++i)
    if (els[i].group < 0)
      for (int j = 0; j < 4; ++j) fem.vertex_node[mesh.elements[i].v[j]] = 0;
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (fem.vertex_node[v] == 0) {
      fem.vertex_node[v] = static_cast<int>(fem.node_vertex.size());
      fem.node_vertex.push_back(v);
    }
  // Elements, with edge-midpoint nodes for C3D10 (shared through an edge map).
  std::map<std::pair<int, int>, int> mid;
  std::vector<std::pair<int, int>> mid_ends;
  const int corners = static_cast<int>(fem.node_vertex.size());
  auto midpoint = [&](int a, int b) {
    const auto key = std::minmax(a, b);
    auto [it, fresh] = mid.emplace(key, corners + static_cast<int>(mid_ends.size()));
    if (fresh) mid_ends.push_back(key);
    return it->second;
  };
  std::vector<int> fem_of_scene(mesh.num_elements(), -1);
  for (int i = 0; i < mesh.num_elements(); ++i) {
    if (els[i].group >= 0) continue;
    std::vector<int> conn(4);
    for (int j = 0; j < 4; ++j) conn[j] = fem.vertex_node[mesh.elements[i].v[j]];
    if (element_type == "C3D10")
      for (const auto& e : kEdges) conn.push_back(midpoint(conn[e[0]], conn[e[1]]));
    fem_of_scene[i] = static_cast<int>(fem.connectivity.size());
    fem.connectivity.push_back(std::move(conn));
    fem.element_scene.push_back(i);
    fem.element_region.push_back(mesh.elements[i].region);
  }
  fem.rest.resize(corners + static_cast<int>(mid_ends.size()), 3);
  for (int n = 0; n < corners; ++n) fem.rest.row(n) = mesh.vertices.row(fem.node_vertex[n]);
  for (size_t q = 0; q < mid_ends.size(); ++q)
    fem.rest.row(corners + q) =
        0.5 * (fem.rest.row(mid_ends[q].first) + fem.rest.row(mid_ends[q].second));
  fem.node_vertex.resize(fem.rest.rows(), -1);

  // Cavities: the faces a group's elements share with body elements. SortedMeshFaces puts the
  // two elements of an interior face side by side; a chamber face found once is on the outside.
  fem.cavities.assign(model.num_groups(), {});
  fem.cavity_rest_volume.assign(model.num_groups(), 0.0);
  auto chamber = [&](int g) {
    const int side = model.group_side(g);
    return s.actuators[model.group_actuator(g)].name + (side > 0   ? " (positive side)"
                                                        : side < 0 ? " (negative side)"
                                                                   : "");
  };
  const std::vector<MeshFace> faces = SortedMeshFaces(mesh);
  for (size_t q = 0; q < faces.size(); ++q) {
    const int i = faces[q].element, g = els[i].group;
    if (g < 0) continue;
    const bool next_same = q + 1 < faces.size() && faces[q + 1].key == faces[q].key;
    const bool prev_same = q > 0 && faces[q - 1].key == faces[q].key;
    if (!next_same && !prev_same)
      throw std::invalid_argument("calculix-pressure: chamber '" + chamber(g) +
                                  "' is open to the outside at a face of element " +
                                  std::to_string(i) + "; the pressure FEM needs closed cavities");
    const MeshFace& wall = faces[next_same ? q + 1 : q - 1];
    const int gw = els[wall.element].group;
    if (gw == g) continue;  // inside the chamber
    if (gw >= 0)
      throw std::invalid_argument("calculix-pressure: chamber '" + chamber(g) +
                                  "' touches chamber '" + chamber(gw) +
                                  "' at the face of elements " + std::to_string(i) + " and " +
                                  std::to_string(wall.element) +
                                  " with no wall between them; the pressure FEM needs a body wall "
                                  "around each chamber");
    // The chamber element's face in its outward order points out of the cavity, into the wall.
    // The wall element's LocalFaces index 0..3 is CalculiX's tet face 1..4 (1-2-3, 1-4-2, 2-4-3,
    // 3-4-1: the same vertex sets).
    const LocalFace& lf = kTetFaces[faces[q].local];
    const auto& v = mesh.elements[i].v;
    CavityFace cf;
    cf.element = fem_of_scene[wall.element];
    cf.face = wall.local + 1;
    cf.corners = {fem.vertex_node[v[lf.a]], fem.vertex_node[v[lf.b]], fem.vertex_node[v[lf.c]]};
    if (element_type == "C3D10")
      for (int e = 0; e < 3; ++e)
        cf.mids[e] = mid.at(std::minmax(cf.corners[e], cf.corners[(e + 1) % 3]));
    fem.cavities[g].push_back(cf);
  }
  for (int g = 0; g < model.num_groups(); ++g) {
    if (fem.cavities[g].empty())
      throw std::invalid_argument("calculix-pressure: chamber '" + chamber(g) +
                                  "' has no elements");
    fem.cavity_rest_volume[g] = CavityVolume(fem.cavities[g], fem.rest);
  }
  return fem;
}

double CavityVolume(const std::vector<CavityFace>& faces,
                    const Eigen::Ref<const Eigen::MatrixX3d>& X) {
  double v6 = 0;
  auto tri = [&](int a, int b, int c) {
    v6 += Eigen::Vector3d(X.row(a)).dot(Eigen::Vector3d(X.row(b)).cross(Eigen::Vector3d(X.row(c))));
  };
  for (const auto& f : faces) {
    const auto& n = f.corners;
    if (f.mids[0] < 0) {
      tri(n[0], n[1], n[2]);
      continue;
    }
    const auto& m = f.mids;  // on edges 01, 12, 20
    tri(n[0], m[0], m[2]);
    tri(m[0], n[1], m[1]);
    tri(m[2], m[1], n[2]);
    tri(m[0], m[1], m[2]);
  }
  return v6 / 6.0;
}

std::vector<double> GroupPressures(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& p) {
  std::vector<double> out(model.num_groups(), 0.0);
  for (int g = 0; g < model.num_groups(); ++g) {
    const double pa = p[model.group_actuator(g)];
    const int side = model.group_side(g);
    out[g] = side == 0 ? pa : std::max(0.0, side * pa);
  }
  return out;
}

void WritePressureFemInput(const Model& model, const PressureFemMesh& fem,
                           const Eigen::Ref<const Eigen::VectorXd>& p,
                           const PressureFemOptions& opt, const std::string& path) {
  const Scene& s = model.scene();
  if (p.size() != model.num_actuators() || !p.allFinite())
    throw std::invalid_argument("calculix-pressure: expected " +
                                std::to_string(model.num_actuators()) +
                                " finite pressures, one per actuator");
  if (opt.law != "linear" && opt.law != "neo-hooke")
    throw std::invalid_argument("calculix-pressure: law: expected linear or neo-hooke, got '" +
                                opt.law + "'");
  if (!(opt.young > 0) || !(opt.poisson >= 0 && opt.poisson < 0.5))
    throw std::invalid_argument("calculix-pressure: expected young > 0 and 0 <= poisson < 0.5");
  if (!(opt.max_increment > 0 && opt.max_increment <= 1) ||
      !(opt.min_increment > 0 && opt.min_increment <= opt.max_increment) || opt.max_increments < 1)
    throw std::invalid_argument(
        "calculix-pressure: expected 0 < min_increment <= max_increment <= 1, max_increments >= 1");
  std::ofstream o(path);
  if (!o) throw std::runtime_error("calculix-pressure: cannot write '" + path + "'");
  o << "** SoftKin scene '" << s.name
    << "', hollow chambers under pressure (solver/baselines/calculix_pressure.hpp)\n";
  o << "*NODE, NSET=NALL\n";
  for (int n = 0; n < fem.rest.rows(); ++n)
    o << n + 1 << ", " << InpNumber(fem.rest(n, 0)) << ", " << InpNumber(fem.rest(n, 1)) << ", "
      << InpNumber(fem.rest(n, 2)) << "\n";
  std::map<int, std::vector<int>> by_region;
  for (size_t e = 0; e < fem.connectivity.size(); ++e)
    by_region[fem.element_region[e]].push_back(static_cast<int>(e));
  for (const auto& [region, ids] : by_region) {
    o << "*ELEMENT, TYPE=" << fem.element_type << ", ELSET=R" << region << "\n";
    for (int e : ids) {
      o << e + 1;
      const auto& conn = fem.connectivity[e];
      for (size_t j = 0; j < conn.size(); ++j) o << (j == 8 ? ",\n" : ", ") << conn[j] + 1;
      o << "\n";
    }
  }
  // Boundary conditions on the vertices that are in the FEM mesh.
  auto fem_nodes = [&](const std::vector<int>& vertices) {
    std::vector<int> out;
    for (int v : vertices)
      if (fem.vertex_node[v] >= 0) out.push_back(fem.vertex_node[v]);
    return out;
  };
  const std::vector<int> fixed = fem_nodes(s.fixed);
  if (fixed.empty() && s.fixed_axis[0].empty() && s.fixed_axis[1].empty() &&
      s.fixed_axis[2].empty())
    throw std::invalid_argument("calculix-pressure: scene '" + s.name +
                                "' holds no vertex of the body; the FEM has no support");
  if (!fixed.empty()) {
    o << "*NSET, NSET=FIXED\n";
    WriteInpIds(o, fixed);
    o << "*BOUNDARY\nFIXED, 1, 3, 0.\n";
  }
  for (int d = 0; d < 3; ++d) {
    const std::vector<int> held = fem_nodes(s.fixed_axis[d]);
    if (held.empty()) continue;
    o << "*NSET, NSET=HELD"
      << "XYZ"[d] << "\n";
    WriteInpIds(o, held);
    o << "*BOUNDARY\nHELD"
      << "XYZ"[d] << ", " << d + 1 << ", " << d + 1 << ", 0.\n";
  }
  for (const auto& [region, ids] : by_region) {
    auto it = s.body.find(region);
    const Material mat = it == s.body.end() ? Material{} : it->second;
    WriteCalculixMaterial(o, "MR" + std::to_string(region), opt.law, mat.weight * opt.young,
                          opt.poisson, mat.hyperelastic() ? &mat : nullptr);
    o << "*SOLID SECTION, ELSET=R" << region << ", MATERIAL=MR" << region << "\n";
  }
  const std::vector<bool> printed = PrintedNodes(fem);
  std::vector<int> out_nodes;
  for (int n = 0; n < fem.rest.rows(); ++n)
    if (printed[n]) out_nodes.push_back(n);
  o << "*NSET, NSET=NOUT\n";
  WriteInpIds(o, out_nodes);
  o << "*STEP, NLGEOM, INC=" << opt.max_increments << "\n";
  o << "*STATIC\n"
    << InpNumber(opt.max_increment) << ", 1., " << InpNumber(opt.min_increment) << ", "
    << InpNumber(opt.max_increment) << "\n";
  const std::vector<double> gp = GroupPressures(model, p);
  bool any = false;
  for (int g = 0; g < model.num_groups(); ++g) {
    if (gp[g] == 0.0) continue;
    if (!any) o << "*DLOAD\n";
    any = true;
    o << "** chamber group " << g << " (actuator '" << s.actuators[model.group_actuator(g)].name
      << "')\n";
    for (const auto& f : fem.cavities[g])
      o << f.element + 1 << ", P" << f.face << ", " << InpNumber(gp[g]) << "\n";
  }
  o << "*NODE PRINT, NSET=NOUT\nU\n";
  o << "*END STEP\n";
  if (!o) throw std::runtime_error("calculix-pressure: error while writing '" + path + "'");
}

PressureFemRun RunPressureFem(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& p,
                              const PressureFemOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  PressureFemRun run;
  auto done = [&](const std::string& msg) {
    run.message = msg;
    run.time_s = Seconds(t0, std::chrono::steady_clock::now());
    return run;
  };
  PressureFemMesh fem;
  std::string ccx_path;
  const CcxWorkFolder folder(opt.keep_files);
  try {
    fem = BuildPressureFemMesh(model, opt.element);
    run.nodes = static_cast<int>(fem.rest.rows());
    run.elements = static_cast<int>(fem.connectivity.size());
    ccx_path = FindCcx();
    if (ccx_path.empty()) return done(CcxMissingMessage());
    if (folder.path().empty()) return done("cannot create a temporary folder");
    WritePressureFemInput(model, fem, p, opt, (folder.path() / "job.inp").string());
  } catch (const std::exception& e) {
    return done(e.what());
  }
  const fs::path& work = folder.path();
  const CcxRun ccx = RunCcxJob(ccx_path, work, opt.time_limit_s, t0);
  if (!ccx.started) return done(ccx.last_error);
  const std::vector<bool> printed = PrintedNodes(fem);
  std::vector<std::pair<double, Eigen::MatrixX3d>> blocks;
  try {
    blocks = ReadCalculixDisplacements((work / "job.dat").string(),
                                       static_cast<int>(fem.rest.rows()), &printed);
  } catch (const std::runtime_error& e) {
    if (!ccx.timed_out) return done(std::string("ccx output: ") + e.what());
  }
  const double end_s = Seconds(t0, std::chrono::steady_clock::now());
  const Eigen::MatrixX3d nan =
      Eigen::MatrixX3d::Constant(model.num_vertices(), 3, std::numeric_limits<double>::quiet_NaN());
  const std::vector<double> gp = GroupPressures(model, p);
  for (size_t k = 0; k < blocks.size(); ++k) {
    const Eigen::MatrixX3d X = fem.rest + blocks[k].second;
    bool finite = true;
    for (int n = 0; n < fem.rest.rows() && finite; ++n)
      finite = !printed[n] || X.row(n).allFinite();
    if (!finite) break;  // a diverged increment: keep the converged ones before it
    PressureFemIncrement inc;
    inc.load = blocks[k].first;
    inc.pressure = inc.load * p;
    inc.wall_s = k < ccx.increment_wall_s.size() ? ccx.increment_wall_s[k] : end_s;
    inc.positions = nan;
    for (int n = 0; n < fem.rest.rows(); ++n)
      if (fem.node_vertex[n] >= 0) inc.positions.row(fem.node_vertex[n]) = X.row(n);
    // Per actuator: the loaded side's cavity (the positive side when p = 0).
    inc.cavity_ratio.assign(model.num_actuators(), 1.0);
    for (int g = 0; g < model.num_groups(); ++g) {
      const int a = model.group_actuator(g), side = model.group_side(g);
      if (side != 0 && !(gp[g] > 0 || (p[a] == 0 && side > 0))) continue;
      inc.cavity_ratio[a] = CavityVolume(fem.cavities[g], X) / fem.cavity_rest_volume[g];
    }
    run.increments.push_back(std::move(inc));
  }
  run.ok = true;
  run.reached_end = !run.increments.empty() && std::abs(run.increments.back().load - 1.0) < 1e-6;
  if (run.reached_end) return done("");
  char buf[96];
  std::snprintf(buf, sizeof(buf), "ccx stopped at load %.4g of the pressure ramp",
                run.increments.empty() ? 0.0 : run.increments.back().load);
  std::string why = ccx.timed_out ? "time limit of " + InpNumber(opt.time_limit_s) + " s reached"
                                  : ccx.last_error;
  return done(std::string(buf) + (why.empty() ? "" : ": " + why));
}

}  // namespace softkin
