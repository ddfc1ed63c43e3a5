#pragma once
/// \file scene_json_test_util.hpp
/// Helpers of the scene JSON tests (test_scene_json.cpp, test_scene_schema.cpp): temporary
/// directories, a tiny three-tet mesh and scenes over it, and expectations on error messages.
#include "softkin/solver/scene/scene_json.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace softkin {
namespace scene_test {

using json = nlohmann::json;
namespace fs = std::filesystem;

inline void WriteFile(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  ASSERT_TRUE(out) << p;
  out << text;
}

inline std::string ReadFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// A fresh directory per test, removed afterwards.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ =
        fs::temp_directory_path() / ("softkin_scene_json_" + std::string(info->test_suite_name()) +
                                     "_" + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// A triangular prism y in [0, 1] split into three positively oriented tets, one region each
// (tags 0, 1, 2).
// Vertices: 0 (0,0,0) 1 (1,0,0) 2 (0,0,1) at y = 0; 3 (0,1,0) 4 (1,1,0) 5 (0,1,1) at y = 1.
inline const char* const kTinyTet =
    "6 vertices\n"
    "3 tets\n"
    "0 0 0\n"
    "1 0 0\n"
    "0 0 1\n"
    "0 1 0\n"
    "1 1 0\n"
    "0 1 1\n"
    "4 0 2 1 3\n"
    "4 1 3 2 4\n"
    "4 2 4 3 5\n";

inline void WriteTinyMesh(const fs::path& dir) {
  WriteFile(dir / "tiny.tet", kTinyTet);
  WriteFile(dir / "tiny_labels.txt", "0\n1\n2\n");
  WriteFile(dir / "fixed.txt", "# one-based vertex indices\n6\n\n");
}

/// A scene over the tiny mesh using every selector, scale 2 and an actuator split over two regions.
/// After scaling: 0 (0,0,0) 1 (2,0,0) 2 (0,0,2) 3 (0,2,0) 4 (2,2,0) 5 (0,2,2).
inline json TinyScene() {
  return json::parse(R"({
    "name": "tiny",
    "mesh": {"file": "tiny.tet", "labels": "tiny_labels.txt", "scale": 2},
    "regions": [
      {"tag": 0, "role": "body", "material": "soft", "r_omega": 0.5, "weight": 2},
      {"tag": 1, "role": "pneumatic", "name": "chamber", "min": 1, "max": 3},
      {"tag": 2, "role": "pneumatic", "name": "chamber", "max": 3, "weight": 4}
    ],
    "fixed": [
      {"plane": {"point": [0, 0, 0], "normal": [0, 2, 0]}},
      {"box": {"min": [1.5, -1, -1], "max": [3, 3, 0.5]}},
      {"file": "fixed.txt", "base": 1}
    ],
    "markers": [
      {"name": "a", "vertex": 3},
      {"name": "b", "nearest": [2.1, 2.1, 0.1]},
      {"name": "tip", "box": {"min": [-1, 1.9, -1], "max": [3, 2.1, 3]}}
    ],
    "solver": {"solver": "lg", "max_iterations": 50, "tolerance": 1e-4, "gradient_tolerance": 0.01,
               "anderson_window": 3, "continuation_steps": 2, "threads": 1}
  })");
}

inline Scene LoadFrom(const fs::path& dir, const json& scene) {
  WriteFile(dir / "scene.json", scene.dump(2));
  return LoadSceneJson((dir / "scene.json").string());
}

/// Expects `f` to throw std::invalid_argument whose message contains every string in `parts`.
inline void ExpectError(const std::function<void()>& f, const std::vector<std::string>& parts) {
  try {
    f();
    ADD_FAILURE() << "expected std::invalid_argument containing '" << parts.front() << "'";
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    for (const auto& p : parts)
      EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
  }
}

/// Loads `scene` (written as scene.json into a directory with the tiny mesh) expecting an error.
inline void ExpectSceneError(const json& scene, const std::vector<std::string>& parts) {
  TempDir dir;
  WriteTinyMesh(dir.path());
  std::vector<std::string> all = {"scene.json: "};
  all.insert(all.end(), parts.begin(), parts.end());
  ExpectError([&] { LoadFrom(dir.path(), scene); }, all);
}

/// The tiny scene with a signed chamber pair, a per-axis hold and two motion actuators.
/// After scaling: 0 (0,0,0) 1 (2,0,0) 2 (0,0,2) 3 (0,2,0) 4 (2,2,0) 5 (0,2,2).
inline json SignedMotionScene() {
  return json::parse(R"({
    "mesh": {"file": "tiny.tet", "labels": "tiny_labels.txt", "scale": 2},
    "regions": [
      {"tag": 0, "role": "body"},
      {"tag": 1, "role": "pneumatic", "name": "s", "min": -2, "max": 3, "gain": 1.5},
      {"tag": 2, "role": "pneumatic", "name": "s", "side": "negative"}
    ],
    "fixed": [
      {"plane": {"point": [0, 0, 0], "normal": [0, 1, 0]}},
      {"file": "fixed.txt", "base": 1, "axes": "zx"}
    ],
    "motions": [
      {"name": "lift", "type": "displacement", "box": {"min": [1.5, 1.9, -1], "max": [3, 2.1, 1]},
       "axis": [0, 0, 2], "min": -1, "max": 1},
      {"name": "turn", "type": "twist", "box": {"min": [-1, 1.9, -1], "max": [0.5, 2.1, 0.5]},
       "axis": [0, 1, 0], "centre": [1, 0, 1], "min": -90, "max": 90}
    ]
  })");
}

}  // namespace scene_test
}  // namespace softkin
