#pragma once
/// \file cli.hpp
/// The `softkin` command line: robots, fk, run, calibrate, scene, tessellate, ik, dataset, train,
/// each in its own experiments/cli_<command>.{hpp,cpp} (an Add*Command that registers its options
/// and a Run*Command that runs it). Returns the process exit code (0 ok, 1 a solve did not
/// converge or a job failed, 2 bad input). With `rethrow` (the Python module's softkin.cli),
/// errors are thrown instead of printed: std::invalid_argument for bad input (a command-line
/// parse error included), the others as they come; --help still prints and returns 0.
namespace softkin {
int RunCli(int argc, char** argv, bool rethrow = false);
}
