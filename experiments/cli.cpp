#include "softkin/experiments/cli.hpp"

#include "softkin/experiments/cli_calibrate.hpp"
#include "softkin/experiments/cli_dataset.hpp"
#include "softkin/experiments/cli_fk.hpp"
#include "softkin/experiments/cli_ik.hpp"
#include "softkin/experiments/cli_robots.hpp"
#include "softkin/experiments/cli_run.hpp"
#include "softkin/experiments/cli_scene.hpp"
#include "softkin/experiments/cli_tessellate.hpp"
#include "softkin/experiments/cli_train.hpp"
#include "softkin/experiments/mpi_job.hpp"

#include <CLI/CLI.hpp>

#include <functional>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

namespace softkin {

namespace {

/// argv joined by spaces, recorded as provenance by `dataset` and `train`.
std::string CommandLine(int argc, char** argv) {
  std::string command_line;
  for (int i = 0; i < argc; ++i) command_line += (i ? " " : "") + std::string(argv[i]);
  return command_line;
}

/// A subcommand and what runs it once the command line has been parsed into its arguments.
struct Command {
  CLI::App* app;
  std::function<int()> run;
};

}  // namespace

int RunCli(int argc, char** argv, bool rethrow) {
  CLI::App app{
      "SoftKin: geometry-based kinematics of soft robots (forward kinematics, "
      "experiments). Units: mm."};
  app.require_subcommand(1);
  app.set_help_all_flag("--help-all", "Help for every command");

  // Each command's options are bound to its arguments (experiments/cli_<command>.cpp); the order
  // here is the order of `softkin --help`.
  RobotsCommandArgs robots;
  FkCommandArgs fk;
  RunCommandArgs run;
  CalibrateCommandArgs calibrate;
  SceneCommandArgs scene;
  TessellateCommandArgs tessellate;
  IkCommandArgs ik;
  DatasetCommandArgs dataset;
  TrainCommandArgs train;
  const std::vector<Command> commands = {
      {AddRobotsCommand(&app, &robots), [&] { return RunRobotsCommand(robots); }},
      {AddFkCommand(&app, &fk), [&] { return RunFkCommand(fk); }},
      {AddRunCommand(&app, &run), [&] { return RunRunCommand(run); }},
      {AddCalibrateCommand(&app, &calibrate), [&] { return RunCalibrateCommand(calibrate); }},
      {AddSceneCommand(&app, &scene), [&] { return RunSceneCommand(scene); }},
      {AddTessellateCommand(&app, &tessellate), [&] { return RunTessellateCommand(tessellate); }},
      {AddIkCommand(&app, &ik), [&] { return RunIkCommand(ik); }},
      {AddDatasetCommand(&app, &dataset), [&] { return RunDatasetCommand(dataset); }},
      {AddTrainCommand(&app, &train), [&] { return RunTrainCommand(train); }},
  };
  dataset.command_line = train.command_line = CommandLine(argc, argv);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (rethrow && e.get_exit_code() != 0) throw std::invalid_argument(e.what());
    return app.exit(e) == 0 ? 0 : 2;
  }

  const auto run_parsed = [&commands] {
    for (const Command& c : commands)
      if (c.app->parsed()) {
        // Only `dataset` and `run` share their work over MPI ranks; any other command started by
        // a launcher with several processes would run once per process on the same files.
        const std::string name = c.app->get_name();
        if (LaunchedMpiSize() > 1 && name != "dataset" && name != "run")
          throw std::invalid_argument(
              name + ": started by an MPI launcher with " + std::to_string(LaunchedMpiSize()) +
              " processes, but only `softkin dataset` and `softkin run` (sweeps) share work over "
              "MPI ranks; run `softkin " +
              name + "` as one process");
        // An empty value (an unset shell variable, --json "") is never a silent default.
        for (const CLI::Option* o : c.app->get_options())
          if (o->get_expected_min() > 0)
            for (const std::string& v : o->results())
              if (v.empty())
                throw std::invalid_argument(o->get_name() +
                                            ": expected a value, got an empty string");
        return c.run();
      }
    return 0;
  };
  if (rethrow) return run_parsed();
  try {
    return run_parsed();
  } catch (const std::exception& e) {
    // In an MPI job the other ranks may wait for this one: the whole job stops.
    if (MpiStarted()) MpiAbortJob(e);
    std::cerr << "softkin: error: " << e.what() << "\n";
    return dynamic_cast<const std::invalid_argument*>(&e) ? 2 : 1;
  }
}

}  // namespace softkin
