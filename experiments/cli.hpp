#pragma once
/// \file cli.hpp
/// The `softkin` command line: robots, fk, run, calibrate, scene, tessellate, ik, dataset, train,
/// each in its own experiments/cli_<command>.{hpp,cpp} (an Add*Command that registers its options
/// and a Run*Command that runs it). Returns the process exit code (0 ok, 1 a solve did not
/// converge or a job failed, 2 bad input).
namespace softkin {
int RunCli(int argc, char** argv);
}
