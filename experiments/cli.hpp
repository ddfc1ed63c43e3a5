#pragma once
/// \file cli.hpp
/// The `softkin` command line: robots, fk, ik, run, calibrate, scene, tessellate. Returns the process exit code
/// (0 ok, 1 a solve did not converge or a job failed, 2 bad input).
namespace softkin {
int RunCli(int argc, char** argv);
}
