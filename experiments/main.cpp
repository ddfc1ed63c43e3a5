#include "softkin/experiments/cli.hpp"

int main(int argc, char** argv) { return softkin::RunCli(argc, argv); }
