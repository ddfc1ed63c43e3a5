#include "softkin/experiments/cli_run.hpp"

#include "softkin/experiments/mpi_job.hpp"
#include "softkin/experiments/runner.hpp"

namespace softkin {

CLI::App* AddRunCommand(CLI::App* app, RunCommandArgs* a) {
  std::string sweeps;
  for (const auto& t : MpiExperimentTypes()) sweeps += (sweeps.empty() ? "" : ", ") + t;
  auto* run = app->add_subcommand(
      "run",
      "Run an experiment config (experiments/configs/<name>.json) into RESULTS/<name>/. "
      "Under mpirun -n N the sweeps (" +
          sweeps + ") share their units over the ranks (docs/cluster.md; " + MpiSupportNote() +
          ")");
  run->add_option("config", a->config, "Experiment config JSON")->required();
  run->add_flag("--quick", a->options.quick,
                "Quick mode: the config's small 'quick' settings (for CI)");
  run->add_flag("--no-plot", a->no_plot, "Do not run the paper_figs plot script");
  run->add_option("--results", a->options.results_root, "Results root folder (default: results)");
  return run;
}

int RunRunCommand(const RunCommandArgs& a) {
  RunOptions options = a.options;
  options.plot = !a.no_plot;
  RunExperiment(a.config, options);
  return 0;
}

}  // namespace softkin
