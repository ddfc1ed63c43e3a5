// Folders, devices and FIFOs given as input files are named for what they are, by every reader.
#include "softkin/solver/common/input_file.hpp"

#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/scene/scene_json.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace softkin {
namespace {

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(InputFile, NamesWhatAPathIsInsteadOfAFile) {
  namespace fs = std::filesystem;
  const fs::path d = fs::temp_directory_path() / "softkin_input_file";
  fs::remove_all(d);
  fs::create_directories(d);
  const std::string fifo = (d / "pipe").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(ErrorOf([&] { CheckInputFile(d.string(), "a mesh file"); }),
            d.string() + ": is a folder; expected a mesh file");
  EXPECT_EQ(ErrorOf([&] { CheckInputFile(fifo, "a mesh file"); }),
            fifo + ": is a FIFO (a named pipe); expected a mesh file");
  EXPECT_EQ(ErrorOf([] { CheckInputFile("/dev/null", "a scene file"); }),
            "/dev/null: is a character device; expected a scene file");
  // A missing file passes (its reader says "cannot open"), and so does a regular file.
  EXPECT_EQ(ErrorOf([&] { CheckInputFile((d / "missing").string(), "x"); }), "");
  // The readers use it: before, a folder gave a bare stream error and a FIFO made them wait.
  const std::string folder_msh = (d / "folder.msh").string(), fifo_msh = (d / "pipe.msh").string();
  fs::create_directories(folder_msh);
  ASSERT_EQ(::mkfifo(fifo_msh.c_str(), 0600), 0);
  for (const std::string& p : {folder_msh, fifo_msh}) {
    const std::string mesh = ErrorOf([&] { (void)ReadMesh(p); });
    EXPECT_NE(mesh.find(p + ": is a"), std::string::npos) << mesh;
    const std::string scene = ErrorOf([&] { (void)LoadSceneJson(p); });
    EXPECT_NE(scene.find(p + ": is a"), std::string::npos) << scene;
  }
}

}  // namespace
}  // namespace softkin
