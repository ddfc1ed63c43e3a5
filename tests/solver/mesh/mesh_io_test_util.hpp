#pragma once
// Shared by the mesh reader tests: a per-test temporary folder with file helpers, and the message
// of a reader's error.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <string>

namespace softkin {
namespace mesh_test {

namespace fs = std::filesystem;

/// Per-test temporary folder, removed afterwards.
class MeshIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("softkin_mesh_io_" + std::string(info->test_suite_name()) + "_" + info->name() + "_" +
            std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  /// Writes `text` (any bytes) to the folder's file `name`; returns its path.
  std::string WriteText(const std::string& name, const std::string& text) const {
    const std::string p = Path(name);
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }
  static std::string ReadText(const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  fs::path dir_;
};

/// Message of the std::runtime_error thrown by f, or "<no exception>".
inline std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "<no exception>";
}

/// `msg` contains `text`.
inline void ExpectHas(const std::string& msg, const std::string& text) {
  EXPECT_NE(msg.find(text), std::string::npos) << "expected '" << text << "' in: " << msg;
}

}  // namespace mesh_test
}  // namespace softkin
