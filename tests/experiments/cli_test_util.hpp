#pragma once
// Helpers of the `softkin` command-line tests: run the binary (SOFTKIN_BIN, set by CMake) and
// capture its exit code and output; run a config written on the spot; check that bad input was
// refused; a fresh temporary folder; a whole file as a string.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <string>

namespace softkin::cli_test {

struct CliRun {
  int code;
  std::string out;
};

/// Runs `softkin ARGS` with stderr joined to stdout.
inline CliRun Cli(const std::string& args) {
  const std::string cmd = std::string(SOFTKIN_BIN) + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf{};
  while (p && fgets(buf.data(), buf.size(), p)) out += buf.data();
  const int status = p ? pclose(p) : -1;
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

/// Writes TEXT to the config file PATH and runs `softkin run PATH --no-plot --results RESULTS`.
inline CliRun RunConfig(const std::string& path, const std::string& text,
                        const std::string& results) {
  std::ofstream(path) << text;
  return Cli("run " + path + " --no-plot --results " + results);
}

/// Whether a run refused its input as a user's error (exit code 2) with each of NEEDLES in its
/// output; a failure shows the whole output.
inline ::testing::AssertionResult RefusedWith(const CliRun& r,
                                              std::initializer_list<std::string> needles) {
  if (r.code != 2)
    return ::testing::AssertionFailure() << "exit code " << r.code << ", expected 2:\n" << r.out;
  for (const std::string& n : needles)
    if (r.out.find(n) == std::string::npos)
      return ::testing::AssertionFailure() << "no \"" << n << "\" in:\n" << r.out;
  return ::testing::AssertionSuccess();
}

/// An empty folder softkin_cli_NAME in the system's temporary folder.
inline std::string TempDir(const std::string& name) {
  auto d = std::filesystem::temp_directory_path() / ("softkin_cli_" + name);
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d.string();
}

inline std::string ReadAll(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

inline int CountLines(const std::string& text) {
  int n = 0;
  for (char c : text) n += c == '\n';
  return n;
}

}  // namespace softkin::cli_test
