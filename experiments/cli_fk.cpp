#include "softkin/experiments/cli_fk.hpp"

#include "softkin/experiments/cli_args.hpp"
#include "softkin/experiments/results.hpp"
#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/common/text_format.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/robots/robots.hpp"
#include "softkin/solver/scene/scene_json.hpp"
#include "softkin/solver/scene/solver_options_json.hpp"

#include <nlohmann/json.hpp>

#include <iostream>
#include <memory>
#include <set>
#include <stdexcept>

namespace softkin {

CLI::App* AddFkCommand(CLI::App* app, FkCommandArgs* a) {
  auto* fk = app->add_subcommand("fk", "Solve forward kinematics for one actuation");
  auto* o_robot = fk->add_option("--robot", a->robot, "Embedded robot name (see `softkin robots`)");
  auto* o_scene =
      fk->add_option("--scene", a->scene, "Scene JSON file (see `softkin scene --schema`)");
  o_robot->excludes(o_scene);
  fk->add_option("--res", a->res, "Robot resolution (default: the robot's own)")
      ->needs(o_robot)
      ->check(CLI::Range(1, 1 << 20));
  fk->add_option("--param", a->params,
                 "Robot design parameter NAME=VALUE (repeatable; see `softkin robots`)")
      ->needs(o_robot);
  fk->add_option("--actuation", a->actuation, "Actuation values v1,v2,... in actuator order")
      ->required();
  // One flag per solver option of the table; --continuation and --aa-safeguard are the short
  // names older command lines use.
  AddFkOptionFlags(
      fk, &a->options, {},
      {{"continuation_steps", "--continuation"}, {"anderson_safeguard", "--aa-safeguard"}});
  fk->add_option("--set", a->set,
                 "Any solver option KEY=VALUE, keys as in `softkin scene --schema` without the "
                 "'solver.' prefix (e.g. --set time_limit_s=60 --set collision.self=true); "
                 "repeatable")
      ->type_name("KEY=VALUE");
  fk->add_option("--json", a->json_out, "Write the result as JSON to this file");
  fk->add_option("--vtu", a->vtu_out, "Write the deformed mesh as ParaView .vtu");
  fk->add_option("--obj", a->obj_out, "Write the deformed surface as .obj");
  return fk;
}

namespace {

/// The --set KEY=VALUE options over `opt`, read by the scene JSON's reader. VALUE is JSON (a
/// number, true, false) or, if it does not parse as JSON, a string (CommandLineValue).
FkOptions ApplySetOptions(const std::vector<std::string>& sets, const FkOptions& opt,
                          const FkOptionFlags& flags) {
  nlohmann::json j = nlohmann::json::object();
  std::set<std::string> seen;
  for (const std::string& kv : sets) {
    const auto eq = kv.find('=');
    if (eq == std::string::npos || eq == 0)
      throw std::invalid_argument("--set '" + kv + "': expected KEY=VALUE");
    const std::string key = kv.substr(0, eq);
    // One value per option: a second --set, or --set beside the option's own flag, is refused
    // rather than one of them silently winning.
    if (!seen.insert(key).second)
      throw std::invalid_argument("--set: expected each option once, got '" + key + "' twice");
    if (flags.given.count(key))
      throw std::invalid_argument("--set " + key + ": the option is also given as " +
                                  FkOptionFlagName(key) + "; expected one of the two");
    const nlohmann::json v = CommandLineValue(kv.substr(eq + 1));
    nlohmann::json* at = &j;
    std::string rest = key;
    for (auto dot = rest.find('.'); dot != std::string::npos; dot = rest.find('.')) {
      at = &(*at)[rest.substr(0, dot)];
      rest = rest.substr(dot + 1);
    }
    (*at)[rest] = v;
  }
  return sets.empty() ? opt : ReadSolverOptionsJson(j, "--set: solver", opt);
}

/// The result as `softkin fk --json` writes it.
nlohmann::json FkResultJson(const Scene& scene, const Eigen::VectorXd& c, const FkResult& r) {
  nlohmann::json j;
  j["status"] = FkStatusToString(r.status);
  j["message"] = r.message;
  j["solver"] = r.solver;
  j["iterations"] = r.iterations;
  j["energy"] = r.energy;
  j["time_s"] = r.time_s;
  j["local_time_s"] = r.local_time_s;
  j["global_time_s"] = r.global_time_s;
  if (r.load_steps > 0) {  // newton
    j["linear_iterations"] = r.linear_iterations;
    j["load_steps"] = r.load_steps;
  }
  j["inverted_elements"] = r.inverted_elements;  // body elements: > 0 is a wrong state
  j["inverted_actuation_elements"] = r.inverted_actuation_elements;
  j["min_volume_ratio"] = r.min_volume_ratio;
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
    // The exact check of the final state (docs/collision_response.md, "Stopping and the final
    // check") and the response's work.
    nlohmann::json col = CollisionCheckJson(r.collision);
    col["springs"] = r.springs;
    col["unresolved_contacts"] = r.collision_stats.unresolved;
    col["check_s"] = r.collision_stats.check_s;
    col["response_s"] = r.collision_stats.response_s;
    j["collision"] = col;
  }
  return j;
}

}  // namespace

FkOptions FkOptionsFromArgs(const FkCommandArgs& a, const FkOptions& base) {
  return ApplySetOptions(a.set, ApplyFkOptionFlags(a.options, base), a.options);
}

int RunFkCommand(const FkCommandArgs& a) {
  if (a.robot.empty() == a.scene.empty())
    throw std::invalid_argument("fk: give exactly one of --robot NAME or --scene FILE");
  if (a.res < 0) throw std::invalid_argument("--res: expected a positive integer");
  // Before any work: no output overwrites an input or another output, and each can be written.
  CheckCommandPaths(SceneInputs(a.scene),
                    {{"--json", a.json_out}, {"--vtu", a.vtu_out}, {"--obj", a.obj_out}});
  const RobotParams params = ParseRobotParams(a.params);
  Scene scene = a.robot.empty() ? LoadSceneJson(a.scene) : MakeRobot(a.robot, a.res, params);
  FkOptions opt = FkOptionsFromArgs(a, scene.solver);
  const Eigen::VectorXd c = ParseNumberList(a.actuation, "--actuation");
  if (opt.continuation_steps > 1)
    opt.on_step = [](int step, int steps, const std::string& status, int iterations, double sec) {
      std::cerr << "fk: step " << step << "/" << steps << ": " << status << ", " << iterations
                << " iterations so far, " << sec << " s\n";
    };
  // A long solve says how it is going (every 10 s; a short one prints nothing).
  opt.on_progress = [](int iterations, double ratio, double sec) {
    std::cerr << "fk: " << iterations << " iterations, residual ratio " << FormatNumber(ratio, 3)
              << ", " << FormatNumber(sec, 3) << " s\n";
  };
  auto model = std::make_shared<const Model>(scene);
  FkResult r = MakeFkSolver(model, opt)->Solve(c);
  if (r.status == FkStatus::InvalidInput) {
    // Bad values are the actuation's; anything else (a scene a solver cannot express, a missing
    // ccx) is the solver's.
    const bool actuation = r.message.rfind("actuation", 0) == 0;
    throw std::invalid_argument(
        (actuation ? "--actuation: " : "--solver " + ToString(opt.solver) + ": ") + r.message);
  }
  std::cerr << r.BriefReport() << "\n";
  const nlohmann::json j = FkResultJson(scene, c, r);
  if (!a.json_out.empty())
    WriteJson(a.json_out, j);
  else
    std::cout << j.dump(2) << "\n";
  if (!a.vtu_out.empty()) {
    const VtuSolveInfo info{r.status == FkStatus::Converged, r.iterations, r.gradient_ratio,
                            r.inverted_elements};
    WriteVtu(a.vtu_out, scene.mesh, r.positions, {}, nullptr, &info);
  }
  if (!a.obj_out.empty()) WriteSurfaceObj(a.obj_out, scene.mesh, r.positions);
  return r.status == FkStatus::Converged ? 0 : 1;
}

}  // namespace softkin
