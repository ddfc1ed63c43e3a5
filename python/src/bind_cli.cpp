/// \file bind_cli.cpp
/// The softkin command line in-process (experiments/cli.hpp): softkin.cli(args), and through it
/// softkin.dataset and softkin.train, with the commands' own options, checks, progress and files
/// (one definition of each option). Errors are raised, not printed: ValueError for bad input.
#include "bindings.hpp"
#include "softkin/experiments/cli.hpp"

#include <pybind11/stl.h>

#include <string>
#include <vector>

namespace softkin {
namespace python {

namespace py = pybind11;

void BindCli(py::module_& m) {
  m.def(
      "_cli",
      [](const std::vector<std::string>& args) {
        std::vector<std::string> owned;
        owned.reserve(args.size() + 1);
        owned.push_back("softkin");
        owned.insert(owned.end(), args.begin(), args.end());
        std::vector<char*> argv;
        for (std::string& s : owned) argv.push_back(s.data());
        argv.push_back(nullptr);
        py::gil_scoped_release release;
        return RunCli(static_cast<int>(owned.size()), argv.data(), /*rethrow=*/true);
      },
      py::arg("args"));
}

}  // namespace python
}  // namespace softkin
