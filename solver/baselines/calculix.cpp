#include "softkin/solver/baselines/calculix.hpp"

#include "softkin/solver/fk/energy.hpp"
#include "softkin/solver/fk/targets.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include <unistd.h>

namespace softkin {
namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;
}  // namespace

std::string InpNumber(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.12g", v);
  return buf;
}

void WriteInpIds(std::ostream& o, const std::vector<int>& ids) {
  for (size_t q = 0; q < ids.size(); ++q) {
    o << ids[q] + 1;
    o << ((q + 1) % 8 == 0 || q + 1 == ids.size() ? "\n" : ", ");
  }
}

void WriteCalculixMaterial(std::ostream& o, const std::string& name, const std::string& law,
                           double E, double nu, const Material* mr) {
  o << "*MATERIAL, NAME=" << name << "\n";
  if (law == "linear") {
    o << "*ELASTIC\n" << InpNumber(E) << ", " << InpNumber(nu) << "\n";
  } else if (mr) {
    // A Mooney-Rivlin body region keeps its c1 : c2 ratio, scaled to the small-strain modulus E.
    const double sc = E / (6.0 * (mr->c1 + mr->c2));
    const double d1 = 6.0 * (1.0 - 2.0 * nu) / E;
    o << "*HYPERELASTIC, MOONEY-RIVLIN\n"
      << InpNumber(sc * mr->c1) << ", " << InpNumber(sc * mr->c2) << ", " << InpNumber(d1) << "\n";
  } else {
    const double c10 = E / (4.0 * (1.0 + nu));
    const double d1 = 6.0 * (1.0 - 2.0 * nu) / E;
    o << "*HYPERELASTIC, NEO HOOKE\n" << InpNumber(c10) << ", " << InpNumber(d1) << "\n";
  }
}

void WriteCalculixInput(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& c,
                        const CalculixOptions& opt, const std::string& path) {
  const Scene& s = model.scene();
  const Mesh& mesh = s.mesh;
  CheckActuation(model, c);
  if (opt.law != "linear" && opt.law != "neo-hooke")
    throw std::invalid_argument("calculix: law: expected linear or neo-hooke, got '" + opt.law +
                                "'");
  if (!(opt.young > 0) || !(opt.poisson >= 0 && opt.poisson < 0.5) || opt.increments < 1)
    throw std::invalid_argument(
        "calculix: expected young > 0, 0 <= poisson < 0.5, increments >= 1");
  if (!s.region_rest.regions.empty())
    throw std::invalid_argument("calculix: scene '" + s.name +
                                "' has regions with their own rest shape (a remeshed "
                                "chamber); the CalculiX export needs one rest mesh");
  for (int i = 0; i < mesh.num_elements(); ++i)
    if (mesh.elements[i].k() != 4)
      throw std::invalid_argument("calculix: element " + std::to_string(i) +
                                  " is a prism; the CalculiX export supports tets only (C3D4)");
  for (const auto& a : s.actuators)
    if (a.type != ActuatorType::Pneumatic)
      throw std::invalid_argument("calculix: actuator '" + a.name + "' is " +
                                  ActuatorTypeToString(a.type) +
                                  "; the CalculiX export supports pneumatic actuators only");

  std::ofstream o(path);
  if (!o) throw std::runtime_error("calculix: cannot write '" + path + "'");
  o << "** SoftKin scene '" << s.name
    << "' exported for CalculiX (solver/baselines/calculix.hpp)\n";
  o << "*NODE, NSET=NALL\n";
  for (int v = 0; v < mesh.num_vertices(); ++v)
    o << v + 1 << ", " << InpNumber(mesh.vertices(v, 0)) << ", " << InpNumber(mesh.vertices(v, 1))
      << ", " << InpNumber(mesh.vertices(v, 2)) << "\n";

  // Element sets: one per body region, one per actuation group.
  std::map<std::string, std::vector<int>> sets;
  std::vector<int> elem_group(mesh.num_elements(), -1);
  for (int g = 0; g < model.num_groups(); ++g)
    for (int i : model.group_elements(g)) elem_group[i] = g;
  for (int i = 0; i < mesh.num_elements(); ++i) {
    const std::string name = elem_group[i] >= 0 ? "G" + std::to_string(elem_group[i])
                                                : "R" + std::to_string(mesh.elements[i].region);
    sets[name].push_back(i);
  }
  for (const auto& [name, ids] : sets) {
    o << "*ELEMENT, TYPE=C3D4, ELSET=" << name << "\n";
    for (int i : ids) {
      const auto& e = mesh.elements[i];
      o << i + 1 << ", " << e.v[0] + 1 << ", " << e.v[1] + 1 << ", " << e.v[2] + 1 << ", "
        << e.v[3] + 1 << "\n";
    }
  }
  // Boundary conditions.
  if (!s.fixed.empty()) {
    o << "*NSET, NSET=FIXED\n";
    WriteInpIds(o, s.fixed);
    o << "*BOUNDARY\nFIXED, 1, 3, 0.\n";
  }
  for (int d = 0; d < 3; ++d) {
    if (s.fixed_axis[d].empty()) continue;
    o << "*NSET, NSET=HELD"
      << "XYZ"[d] << "\n";
    WriteInpIds(o, s.fixed_axis[d]);
    o << "*BOUNDARY\nHELD"
      << "XYZ"[d] << ", " << d + 1 << ", " << d + 1 << ", 0.\n";
  }
  for (const auto& a : s.actuators)
    if (a.is_motion())
      throw std::invalid_argument("calculix: motion actuator '" + a.name + "' is not exported");

  // Materials and sections.
  auto material = [&](const std::string& name, double E, double expansion, const Material* mr) {
    WriteCalculixMaterial(o, name, opt.law, E, opt.poisson, mr);
    o << "*EXPANSION\n" << InpNumber(expansion) << "\n";
  };
  for (const auto& [name, ids] : sets) {
    double E = opt.young, a = 0.0;
    const Material* mr = nullptr;
    if (name[0] == 'R') {
      const Material& mat = s.body.at(std::stoi(name.substr(1)));
      E = mat.weight * opt.young;
      if (mat.hyperelastic()) mr = &mat;
    } else {
      const int g = std::stoi(name.substr(1));
      const Actuator& act = s.actuators[model.group_actuator(g)];
      if (model.GroupVented(g, c)) {
        E = 1e-3 * opt.young;
      } else {
        E = act.weight * opt.young;
        a = std::cbrt(model.GroupRatio(g, c)) - 1.0;
      }
    }
    material("M" + name, E, a, mr);
    o << "*SOLID SECTION, ELSET=" << name << ", MATERIAL=M" << name << "\n";
  }
  const double dt = 1.0 / opt.increments;
  o << "*INITIAL CONDITIONS, TYPE=TEMPERATURE\nNALL, 0.\n";
  o << "*STEP, NLGEOM, INC=" << 100 * opt.increments << "\n";
  o << "*STATIC\n"
    << InpNumber(dt) << ", 1., " << InpNumber(1e-4 * dt) << ", " << InpNumber(dt) << "\n";
  o << "*TEMPERATURE\nNALL, 1.\n";
  o << "*NODE PRINT, NSET=NALL\nU\n";
  o << "*END STEP\n";
  if (!o) throw std::runtime_error("calculix: error while writing '" + path + "'");
}

std::vector<std::pair<double, Eigen::MatrixX3d>> ReadCalculixDisplacements(
    const std::string& dat, int nv, const std::vector<bool>* printed) {
  if (printed && static_cast<int>(printed->size()) != nv)
    throw std::invalid_argument("ReadCalculixDisplacements: printed must have one entry per node");
  std::ifstream in(dat);
  if (!in) throw std::runtime_error("calculix: cannot open '" + dat + "'");
  std::vector<std::pair<double, Eigen::MatrixX3d>> out;
  std::string line;
  int line_no = 0;
  Eigen::MatrixX3d* cur = nullptr;
  std::vector<bool> seen;
  auto finish = [&]() {
    if (!cur) return;
    for (int v = 0; v < nv; ++v)
      if (!seen[v] && (!printed || (*printed)[v]))
        throw std::runtime_error(dat + ": the block ending before line " + std::to_string(line_no) +
                                 " lacks node " + std::to_string(v + 1));
    cur = nullptr;
  };
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find("displacements (vx,vy,vz)") != std::string::npos) {
      finish();
      const auto p = line.find("time");
      double t = 0;
      if (p == std::string::npos || std::sscanf(line.c_str() + p + 4, "%lf", &t) != 1)
        throw std::runtime_error(dat + ":" + std::to_string(line_no) + ": expected 'time T'");
      out.emplace_back(
          t, printed ? Eigen::MatrixX3d::Constant(nv, 3, std::numeric_limits<double>::quiet_NaN())
                     : Eigen::MatrixX3d::Zero(nv, 3));
      cur = &out.back().second;
      seen.assign(nv, false);
      continue;
    }
    if (!cur) continue;
    std::istringstream ss(line);
    long node;
    double x, y, z;
    if (!(ss >> node)) {
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;  // blank line
      finish();                                                            // another kind of block
      continue;
    }
    if (!(ss >> x >> y >> z))
      throw std::runtime_error(dat + ":" + std::to_string(line_no) + ": expected node ux uy uz");
    if (node < 1 || node > nv)
      throw std::runtime_error(dat + ":" + std::to_string(line_no) + ": node " +
                               std::to_string(node) + " out of range 1.." + std::to_string(nv));
    cur->row(node - 1) << x, y, z;
    seen[node - 1] = true;
  }
  finish();
  return out;
}

double CalculixRatioAtLoad(double alpha, double load) {
  const double r = 1.0 + (std::cbrt(alpha) - 1.0) * load;
  return r * r * r;
}

CalculixSolver::CalculixSolver(std::shared_ptr<const Model> model, const FkOptions& fk,
                               CalculixOptions options)
    : FkSolver(std::move(model)), name_(ToString(fk.solver)), options_(std::move(options)) {
  if (fk.time_limit_s > 0 && options_.time_limit_s <= 0) options_.time_limit_s = fk.time_limit_s;
  if (fk.continuation_steps > 1) options_.increments = fk.continuation_steps;
}

FkResult CalculixSolver::SolveImpl(const Eigen::Ref<const Eigen::VectorXd>& c,
                                   const Eigen::MatrixX3d*) {
  const Model& m = *model_;
  const auto t0 = Clock::now();
  FkResult r;
  history_.clear();
  const bool input_ok = StartResult(c, nullptr, &r);  // FEM loads from rest: no warm start
  auto finish = [&](FkStatus st, const std::string& msg) {
    r.status = st;
    r.message = msg;
    if (st != FkStatus::InvalidInput) {
      std::vector<double> ratios;
      ComputeLocalRatios(m, r.positions, c, &ratios, &r.volume_ratios);
      Eigen::MatrixX3d G;
      r.energy = FixedRatioEnergyAndGradient(m, r.positions, ratios, &G);
    }
    r.time_s = Seconds(t0, Clock::now());
    return r;
  };
  if (!input_ok) return finish(FkStatus::InvalidInput, r.message);
  const std::string ccx = FindCcx();
  if (ccx.empty()) return finish(FkStatus::InvalidInput, CcxMissingMessage());
  const CcxWorkFolder folder(options_.keep_files);
  if (folder.path().empty())
    return finish(FkStatus::InvalidInput, "cannot create a temporary folder");
  const fs::path& work = folder.path();
  try {
    WriteCalculixInput(m, c, options_, (work / "job.inp").string());
  } catch (const std::invalid_argument& e) {
    return finish(FkStatus::InvalidInput, e.what());
  } catch (const std::runtime_error& e) {
    return finish(FkStatus::InvalidInput, e.what());
  }
  const CcxRun run = RunCcxJob(ccx, work, options_.time_limit_s, t0);
  if (!run.started) return finish(FkStatus::Diverged, run.last_error);
  const bool timed_out = run.timed_out;
  const std::vector<double>& stamps = run.increment_wall_s;
  std::vector<std::pair<double, Eigen::MatrixX3d>> blocks;
  try {
    blocks = ReadCalculixDisplacements((work / "job.dat").string(), m.num_vertices());
  } catch (const std::runtime_error& e) {
    if (!timed_out) return finish(FkStatus::Diverged, std::string("ccx output: ") + e.what());
  }
  // Block k of job.dat is converged increment k of job.sta; a block ccx wrote after the last
  // poll (possible only at the very end) gets the end time.
  const double end_s = Seconds(t0, Clock::now());
  for (size_t k = 0; k < blocks.size(); ++k)
    history_.push_back({blocks[k].first, k < stamps.size() ? stamps[k] : end_s,
                        blocks[k].second + m.rest_positions()});
  r.iterations = static_cast<int>(history_.size());
  if (!history_.empty()) r.positions = history_.back().positions;
  if (timed_out)
    return finish(FkStatus::TimeLimit,
                  "time limit of " + std::to_string(options_.time_limit_s) + " s reached");
  const bool reached = !history_.empty() && std::abs(history_.back().load - 1.0) < 1e-6;
  if (reached && r.positions.allFinite()) return finish(FkStatus::Converged, "");
  // The last error line of the log says why.
  const std::string& last = run.last_error;
  if (!r.positions.allFinite()) r.positions = m.rest_positions();
  char buf[64];
  std::snprintf(buf, sizeof(buf), "ccx stopped at time %.4g of 1",
                history_.empty() ? 0.0 : history_.back().load);
  return finish(FkStatus::Diverged, std::string(buf) + (last.empty() ? "" : ": " + last));
}

}  // namespace softkin
