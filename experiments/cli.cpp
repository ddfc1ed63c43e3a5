#include "softkin/experiments/cli.hpp"

#include "softkin/experiments/cli_args.hpp"
#include "softkin/experiments/cli_dataset.hpp"
#include "softkin/experiments/cli_train.hpp"
#include "softkin/experiments/cli_ik.hpp"
#include "softkin/experiments/results.hpp"
#include "softkin/experiments/runner.hpp"
#include "softkin/solver/materials/calibration.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/scene/scene_json.hpp"
#include "softkin/solver/remesh/tessellation.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <iostream>
#include <sstream>

namespace softkin {

namespace {

nlohmann::json RobotsJson() {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& info : ListRobots()) {
    Scene s = MakeRobot(info.name, 0);
    nlohmann::json acts = nlohmann::json::array();
    for (const auto& a : s.actuators)
      acts.push_back({{"name", a.name}, {"type", ActuatorTypeToString(a.type)},
                      {"range", {a.min, a.max}}, {"rest", a.rest}});
    nlohmann::json markers = nlohmann::json::array();
    for (const auto& m : s.markers) markers.push_back(m.name);
    nlohmann::json params = nlohmann::json::array();
    for (const auto& p : info.params)
      params.push_back({{"name", p.name}, {"default", p.def}, {"range", {p.lo, p.hi}}, {"doc", p.doc}});
    out.push_back({{"name", info.name}, {"description", info.description}, {"params", params},
                   {"default_resolution", info.default_resolution},
                   {"resolution", info.resolution_doc}, {"actuators", acts}, {"markers", markers},
                   {"n_vertices", s.mesh.num_vertices()}, {"n_tets", s.mesh.num_tets()},
                   {"n_prisms", s.mesh.num_prisms()}, {"n_fixed", s.fixed.size()}});
  }
  return out;
}

}  // namespace

int RunCli(int argc, char** argv) {
  CLI::App app{"SoftKin: geometry-based kinematics of soft robots (forward kinematics, "
               "experiments). Units: mm."};
  app.require_subcommand(1);
  app.set_help_all_flag("--help-all", "Help for every command");

  // robots
  auto* robots = app.add_subcommand("robots", "List the embedded robots: actuators, markers, sizes");
  bool robots_json = false;
  robots->add_flag("--json", robots_json, "Print JSON instead of a table");

  // fk
  auto* fk = app.add_subcommand("fk", "Solve forward kinematics for one actuation");
  std::string robot, scene_file, actuation, solver_name, json_out, vtu_out, obj_out, safeguard;
  int res = 0, continuation = 0, max_iter = 0;
  double tolerance = 0, gradient_tolerance = 0;
  auto* o_robot = fk->add_option("--robot", robot, "Embedded robot name (see `softkin robots`)");
  auto* o_scene = fk->add_option("--scene", scene_file, "Scene JSON file (see `softkin scene --schema`)");
  o_robot->excludes(o_scene);
  fk->add_option("--res", res, "Robot resolution (default: the robot's own)")->needs(o_robot);
  std::vector<std::string> robot_params;
  fk->add_option("--param", robot_params,
                 "Robot design parameter NAME=VALUE (repeatable; see `softkin robots`)")
      ->needs(o_robot);
  fk->add_option("--actuation", actuation, "Actuation values v1,v2,... in actuator order")->required();
  fk->add_option("--solver", solver_name,
                 "FK solver: lg (plain local-global), lg-aa (Anderson), ceres, ipopt-lbfgs, "
                 "ipopt-newton, ipopt-hard, calculix-linear or calculix-nonlinear (docs/solvers.md)");
  fk->add_option("--continuation", continuation, "Apply the actuation in this many steps");
  fk->add_option("--max-iterations", max_iter, "Iteration cap");
  fk->add_option("--tolerance", tolerance, "Per-iteration vertex move tolerance, relative to model size");
  fk->add_option("--gradient-tolerance", gradient_tolerance,
                 "Residual tolerance, relative to its reference value");
  fk->add_option("--aa-safeguard", safeguard,
                 "Anderson safeguard: hybrid (energy or residual), energy, or none");
  fk->add_option("--json", json_out, "Write the result as JSON to this file");
  fk->add_option("--vtu", vtu_out, "Write the deformed mesh as ParaView .vtu");
  fk->add_option("--obj", obj_out, "Write the deformed surface as .obj");

  // run
  auto* run = app.add_subcommand("run", "Run an experiment config (experiments/<name>.json)");
  std::string config;
  RunOptions ropt;
  bool no_plot = false;
  run->add_option("config", config, "Experiment config JSON")->required();
  run->add_flag("--quick", ropt.quick, "Quick mode: the config's small 'quick' settings (for CI)");
  run->add_flag("--no-plot", no_plot, "Do not run the paper_figs plot script");
  run->add_option("--results", ropt.results_root, "Results root folder (default: results)");

  // calibrate
  auto* cal = app.add_subcommand(
      "calibrate",
      "Calibrate R_omega^A / R_omega^B from a measured elasticity ratio R_m (thesis Eq. 2.9, "
      "Table 2.1) by elongation tests on bimaterial_bar (docs/calibration.md)");
  double cal_rm = 0;
  BarTestOptions bar_opt;
  std::string cal_json;
  bool cal_twist = false;
  cal->add_option("--rm", cal_rm, "Measured elasticity ratio R_m = E_A / E_B (> 0)")->required();
  cal->add_option("--res", bar_opt.res, "bimaterial_bar resolution (default: its own)");
  cal->add_option("--interface", bar_opt.interface,
                  "Interface position, fraction of the length from the fixed end (default 0.5)");
  cal->add_option("--stretch", bar_opt.stretch_mm, "End displacement of the elongation test, mm (default 8)");
  cal->add_flag("--twist", cal_twist, "Also run the twisting test (Fig. 2.6d) with the result");
  cal->add_option("--twist-deg", bar_opt.twist_deg, "End rotation of the twisting test, degrees (default 90)");
  cal->add_option("--json", cal_json, "Write the result as JSON to this file");

  // scene
  auto* scene_cmd = app.add_subcommand("scene", "Check a scene JSON, or print its schema");
  bool schema = false;
  std::string scene_check;
  scene_cmd->add_flag("--schema", schema, "Print every key with its type, default and doc");
  scene_cmd->add_option("file", scene_check, "Scene JSON to load and summarise");

  // tessellate
  auto* tess = app.add_subcommand(
      "tessellate",
      "Volume tessellation T(S_c, S_b) (thesis Sec. 3.2.1): a labelled tet mesh of a closed body "
      "surface with a closed chamber surface inside it, by CGAL Mesh_3 (docs/remeshing.md). "
      "Region 0 = body, 1 = chamber");
  std::string tess_body, tess_chamber, tess_out, tess_json;
  TessellationOptions tess_opt;
  tess->add_option("--body", tess_body, "Outer surface S_b: closed, .obj or .stl, mm")->required();
  tess->add_option("--chamber", tess_chamber, "Chamber surface S_c strictly inside S_b: closed, .obj or .stl, mm")
      ->required();
  tess->add_option("--out", tess_out,
                   "Output mesh by extension: .vtu (ParaView), .vtk (legacy VTK), .msh (Gmsh 2.2) or "
                   ".node (TetGen .node + .ele)")
      ->required();
  tess->add_option("--size", tess_opt.cell_size, "Largest tet: bound on its circumradius (Mesh_3 cell_size), mm (default 2)");
  tess->add_option("--facet-size", tess_opt.facet_size, "Bound on surface facet size, mm (default: --size)");
  tess->add_option("--facet-distance", tess_opt.facet_distance,
                   "Bound on the distance of a facet to the input surface, mm (default: --size / 10)");
  tess->add_option("--feature-angle", tess_opt.feature_angle,
                   "Protect input edges sharper than this dihedral angle, degrees (0: none; default 60)");
  tess->add_option("--seed", tess_opt.seed, "Seed of Mesh_3's random choices (default 1)");
  tess->add_option("--json", tess_json, "Write the report (tets per region, volumes, time) as JSON to this file");

  // ik (experiments/cli_ik.cpp)
  IkCommandArgs ik_args;
  auto* ik_cmd = AddIkCommand(&app, &ik_args);

  // dataset (experiments/cli_dataset.cpp)
  DatasetCommandArgs ds_args;
  auto* ds_cmd = AddDatasetCommand(&app, &ds_args);

  // train (experiments/cli_train.cpp)
  TrainCommandArgs train_args;
  auto* train_cmd = AddTrainCommand(&app, &train_args);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }

  try {
    if (robots->parsed()) {
      nlohmann::json j = RobotsJson();
      if (robots_json) {
        std::cout << j.dump(2) << "\n";
      } else {
        for (const auto& r : j) {
          std::cout << r["name"].get<std::string>() << ": ";
          if (r["n_tets"].get<int>() > 0) std::cout << r["n_tets"] << " tets, ";
          if (r["n_prisms"].get<int>() > 0) std::cout << r["n_prisms"] << " prisms, ";
          std::cout << r["n_vertices"] << " vertices (default res " << r["default_resolution"]
                    << ")\n  " << r["description"].get<std::string>() << "\n  actuators:";
          for (const auto& a : r["actuators"])
            std::cout << " " << a["name"].get<std::string>() << " (" << a["type"].get<std::string>()
                      << ", [" << a["range"][0] << ", " << a["range"][1] << "])";
          std::cout << "\n  markers:";
          for (const auto& m : r["markers"]) std::cout << " " << m.get<std::string>();
          for (const auto& p : r["params"])
            std::cout << "\n  param " << p["name"].get<std::string>() << " = " << p["default"]
                      << " in [" << p["range"][0] << ", " << p["range"][1]
                      << "]: " << p["doc"].get<std::string>();
          std::cout << "\n";
        }
      }
      return 0;
    }
    if (scene_cmd->parsed()) {
      if (schema) {
        std::cout << SceneSchema();
        return 0;
      }
      if (scene_check.empty()) throw std::invalid_argument("scene: give a scene JSON file or --schema");
      Scene s = LoadSceneJson(scene_check);
      std::cout << scene_check << ": " << s.mesh.num_vertices() << " vertices, "
                << s.mesh.num_elements() << " elements, " << s.num_actuators() << " actuator(s), "
                << s.fixed.size() << " fixed vertices, " << s.markers.size() << " marker(s)\n";
      return 0;
    }
    if (fk->parsed()) {
      if (robot.empty() == scene_file.empty())
        throw std::invalid_argument("fk: give exactly one of --robot NAME or --scene FILE");
      if (res < 0) throw std::invalid_argument("--res: expected a positive integer");
      const RobotParams params = ParseRobotParams(robot_params);
      Scene scene = robot.empty() ? LoadSceneJson(scene_file) : MakeRobot(robot, res, params);
      FkOptions opt = scene.solver;
      if (!solver_name.empty()) opt.solver = solver_name;
      // Options given on the command line override the scene's (a given 0 is validated, not ignored).
      if (fk->count("--continuation")) opt.continuation_steps = continuation;
      if (fk->count("--max-iterations")) opt.max_iterations = max_iter;
      if (fk->count("--tolerance")) opt.tolerance = tolerance;
      if (fk->count("--gradient-tolerance")) opt.gradient_tolerance = gradient_tolerance;
      if (fk->count("--aa-safeguard")) opt.anderson_safeguard = safeguard;
      std::string why;
      if (!opt.IsValid(&why)) throw std::invalid_argument("option " + why);
      const Eigen::VectorXd c = ParseNumberList(actuation, "--actuation");
      if (opt.continuation_steps > 1)
        opt.on_step = [](int step, int steps, const std::string& status, int iterations, double sec) {
          std::cerr << "fk: step " << step << "/" << steps << ": " << status << ", " << iterations
                    << " iterations so far, " << sec << " s\n";
        };
      auto model = std::make_shared<const Model>(scene);
      FkResult r = MakeFkSolver(model, opt)->Solve(c);
      if (r.status == FkStatus::InvalidInput) {
        // Bad values are the actuation's; anything else (a scene a solver cannot express, a
        // missing ccx) is the solver's.
        const bool actuation = r.message.rfind("actuation", 0) == 0;
        throw std::invalid_argument((actuation ? "--actuation: " : "--solver " + opt.solver + ": ") +
                                    r.message);
      }
      std::cerr << r.BriefReport() << "\n";
      nlohmann::json j;
      j["status"] = FkStatusToString(r.status);
      j["message"] = r.message;
      j["solver"] = r.solver;
      j["iterations"] = r.iterations;
      j["energy"] = r.energy;
      j["time_s"] = r.time_s;
      j["local_time_s"] = r.local_time_s;
      j["global_time_s"] = r.global_time_s;
      j["n_vertices"] = scene.mesh.num_vertices();
      j["n_elements"] = scene.mesh.num_elements();
      j["actuation"] = std::vector<double>(c.data(), c.data() + c.size());
      j["volume_ratios"] = r.volume_ratios;
      j["residual_ratio"] = r.gradient_ratio;
      const Eigen::MatrixX3d P = scene.marker_positions(r.positions);
      nlohmann::json markers = nlohmann::json::object();
      for (size_t i = 0; i < scene.markers.size(); ++i)
        markers[scene.markers[i].name] = {P(i, 0), P(i, 1), P(i, 2)};
      j["markers"] = markers;
      if (r.collision_active) {
        // The exact check of the final state (docs/collision_response.md, "Stopping and the
        // final check") and the response's work.
        nlohmann::json c = CollisionCheckJson(r.collision);
        c["springs"] = r.springs;
        c["unresolved_contacts"] = r.collision_stats.unresolved;
        c["check_s"] = r.collision_stats.check_s;
        c["response_s"] = r.collision_stats.response_s;
        j["collision"] = c;
      }
      if (!json_out.empty()) WriteJson(json_out, j);
      else std::cout << j.dump(2) << "\n";
      if (!vtu_out.empty()) WriteVtu(vtu_out, scene.mesh, r.positions);
      if (!obj_out.empty()) WriteSurfaceObj(obj_out, scene.mesh, r.positions);
      return r.status == FkStatus::Converged ? 0 : 1;
    }
    if (cal->parsed()) {
      const CalibrationResult c = CalibrateROmega(cal_rm, bar_opt);
      nlohmann::json j = {{"rm", c.target_rm},           {"r_omega_ratio", c.ratio},
                          {"r_omega_a", c.r_omega_a},    {"r_omega_b", c.r_omega_b},
                          {"achieved_rm", c.achieved_rm}, {"evaluations", c.evaluations},
                          {"interface", bar_opt.interface}, {"stretch_mm", bar_opt.stretch_mm},
                          {"res", bar_opt.res}};
      std::cout << "R_omega^A / R_omega^B = " << c.ratio << "  (R_omega^A = " << c.r_omega_a
                << ", R_omega^B = " << c.r_omega_b << "; simulated R_m = " << c.achieved_rm << " after "
                << c.evaluations << " elongation tests)\n";
      if (cal_twist) {
        const TwistResult t = RunTwistTest(c.r_omega_a, c.r_omega_b, bar_opt);
        j["twist"] = {{"twist_deg", t.twist_deg}, {"angle_a_deg", t.angle_a_deg},
                      {"angle_b_deg", t.angle_b_deg}};
        std::cout << "twisting test: end turned " << t.twist_deg << " deg; material A turns "
                  << t.angle_a_deg << " deg, material B " << t.angle_b_deg << " deg\n";
      }
      if (!cal_json.empty()) WriteJson(cal_json, j);
      return 0;
    }
    if (tess->parsed()) {
      auto flag = [&](const char* name, bool ok, const std::string& expected, double got) {
        if (!ok) {
          std::ostringstream os;
          os << name << ": expected " << expected << ", got " << got;
          throw std::invalid_argument(os.str());
        }
      };
      flag("--size", tess_opt.cell_size > 0 && std::isfinite(tess_opt.cell_size), "a size > 0 mm", tess_opt.cell_size);
      flag("--facet-size", tess_opt.facet_size >= 0, "a size >= 0 mm (0: --size)", tess_opt.facet_size);
      flag("--facet-distance", tess_opt.facet_distance >= 0, "a distance >= 0 mm (0: --size / 10)", tess_opt.facet_distance);
      flag("--feature-angle", tess_opt.feature_angle >= 0 && tess_opt.feature_angle < 180,
           "an angle in [0, 180) degrees", tess_opt.feature_angle);
      const auto dot = tess_out.find_last_of('.');
      const std::string ext = dot == std::string::npos ? "" : tess_out.substr(dot);
      if (ext != ".vtu" && ext != ".vtk" && ext != ".msh" && ext != ".node")
        throw std::invalid_argument("--out: expected a file name ending in .vtu, .vtk, .msh or .node, got '" +
                                    tess_out + "'");
      const TriangleSurface body = ReadSurfaceMesh(tess_body);
      const TriangleSurface chamber = ReadSurfaceMesh(tess_chamber);
      TessellationReport rep;
      const Mesh mesh = Tessellate(chamber, body, tess_opt, &rep);
      if (ext == ".vtu") WriteVtu(tess_out, mesh, mesh.vertices);
      else if (ext == ".vtk") WriteVtk(tess_out, mesh);
      else if (ext == ".msh") WriteGmsh(tess_out, mesh);
      else WriteTetGen(tess_out.substr(0, dot), mesh);
      std::cout << "wrote " << tess_out << ": " << rep.tets << " tets (body " << rep.body_tets << ", chamber "
                << rep.chamber_tets << "), " << rep.vertices << " vertices; volume body " << rep.body_volume
                << " mm^3 (surfaces enclose " << rep.body_enclosed << "), chamber " << rep.chamber_volume
                << " mm^3 (" << rep.chamber_enclosed << "); " << rep.seconds << " s\n";
      if (!tess_json.empty())
        WriteJson(tess_json, {{"out", tess_out}, {"tets", rep.tets}, {"body_tets", rep.body_tets},
                              {"chamber_tets", rep.chamber_tets}, {"vertices", rep.vertices},
                              {"body_volume", rep.body_volume}, {"chamber_volume", rep.chamber_volume},
                              {"body_enclosed", rep.body_enclosed}, {"chamber_enclosed", rep.chamber_enclosed},
                              {"seconds", rep.seconds}, {"cell_size", tess_opt.cell_size}, {"seed", tess_opt.seed}});
      return 0;
    }
    if (ik_cmd->parsed()) return RunIkCommand(ik_args);
    if (ds_cmd->parsed()) {
      std::string command_line;
      for (int i = 0; i < argc; ++i) command_line += (i ? " " : "") + std::string(argv[i]);
      return RunDatasetCommand(ds_args, command_line);
    }
    if (train_cmd->parsed()) {
      std::string command_line;
      for (int i = 0; i < argc; ++i) command_line += (i ? " " : "") + std::string(argv[i]);
      return RunTrainCommand(train_args, command_line);
    }
    if (run->parsed()) {
      ropt.plot = !no_plot;
      RunExperiment(config, ropt);
      return 0;
    }
  } catch (const std::invalid_argument& e) {
    std::cerr << "softkin: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "softkin: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace softkin
