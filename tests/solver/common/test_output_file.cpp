// Output files are written whole or not at all, and output paths are checked before any work.
#include "softkin/solver/common/output_file.hpp"

#include "softkin/solver/mesh/io/mesh_io.hpp"
#include "softkin/solver/mesh/mesh_gen.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace softkin {
namespace {

namespace fs = std::filesystem;

fs::path FreshDir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("softkin_output_file_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string Read(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

/// Runs f and returns the message of the exception of type E it throws ("" if none).
template <typename E, typename F>
std::string MessageOf(F f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "";
}

// A committed file has the new content and no temporary is left beside it; a write abandoned
// before Commit() (an exception in the writer) leaves the old file as it was.
TEST(OutputFile, ReplacesTheFileOnlyOnCommit) {
  const fs::path d = FreshDir("commit");
  const fs::path p = d / "out.json";
  WriteTextFile(p.string(), "old\n");
  try {
    OutputFile f(p.string());
    f.stream() << "half of a new fi";
    throw std::runtime_error("interrupted");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(Read(p), "old\n");
  {
    OutputFile f(p.string());
    f.stream() << "new\n";
    EXPECT_EQ(Read(p), "old\n");  // not yet
    f.Commit();
  }
  EXPECT_EQ(Read(p), "new\n");
  int files = 0;
  for (const auto& e : fs::directory_iterator(d)) files += e.is_regular_file();
  EXPECT_EQ(files, 1) << "a temporary was left behind";
}

// A full device: the write error is reported with the path and the system's reason (it used to
// exit 0 with nothing written). The same holds for the mesh writers, which use OutputFile.
TEST(OutputFile, ReportsWriteErrorsOfAFullDevice) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full here";
  std::string msg = MessageOf<std::runtime_error>([] {
    OutputFile f("/dev/full");
    for (int i = 0; i < 1000; ++i) f.stream() << "0123456789abcdef\n";
    f.Commit();
  });
  EXPECT_NE(msg.find("/dev/full"), std::string::npos) << msg;
  EXPECT_NE(msg.find("write error"), std::string::npos) << msg;
  EXPECT_NE(msg.find("No space left"), std::string::npos) << msg;
  const Mesh cube = VoxelTetMesh(Eigen::Vector3d::Zero(), 1.0, Eigen::Vector3i(2, 2, 2),
                                 [](const Eigen::Vector3d&, const Eigen::Vector3i&) { return 0; });
  msg = MessageOf<std::runtime_error>([&] { WriteVtu("/dev/full", cube, cube.vertices); });
  EXPECT_NE(msg.find("/dev/full: write error"), std::string::npos) << msg;
}

TEST(OutputFile, RefusesAFolderOrAMissingFolder) {
  const fs::path d = FreshDir("refuse");
  std::string msg = MessageOf<std::runtime_error>([&] { OutputFile f(d.string()); });
  EXPECT_NE(msg.find("is a folder"), std::string::npos) << msg;
  msg = MessageOf<std::runtime_error>([&] { OutputFile f((d / "no" / "x.json").string()); });
  EXPECT_NE(msg.find("cannot write"), std::string::npos) << msg;
  EXPECT_NE(msg.find("x.json"), std::string::npos) << msg;
}

// Each reason an output cannot be written is named before any work starts.
TEST(CheckOutputPath, NamesTheOptionThePathAndTheReason) {
  const fs::path d = FreshDir("check");
  EXPECT_NO_THROW(CheckOutputPath({"--json", (d / "new.json").string()}));
  EXPECT_NO_THROW(CheckOutputPath({"--json", "/dev/null"}));
  const std::string missing = MessageOf<std::invalid_argument>([&] {
    CheckOutputPath({"--vtu", (d / "nodir" / "x.vtu").string()});
  });
  EXPECT_NE(missing.find("--vtu '"), std::string::npos) << missing;
  EXPECT_NE(missing.find("does not exist"), std::string::npos) << missing;
  const std::string folder = MessageOf<std::invalid_argument>([&] {
    CheckOutputPath({"--json", d.string()});
  });
  EXPECT_NE(folder.find("is a folder"), std::string::npos) << folder;
  WriteTextFile((d / "file").string(), "x");
  const std::string under_file = MessageOf<std::invalid_argument>([&] {
    CheckOutputPath({"--obj", (d / "file" / "x.obj").string()});
  });
  EXPECT_NE(under_file.find("is not a folder"), std::string::npos) << under_file;
  const std::string empty = MessageOf<std::invalid_argument>([] {
    CheckOutputPath({"--out", ""});
  });
  EXPECT_NE(empty.find("empty path"), std::string::npos) << empty;
}

// The same file under two spellings, or through a symbolic link, is one file.
TEST(CheckDistinctPaths, FindsTheSameFileUnderAnyName) {
  const fs::path d = FreshDir("distinct");
  const fs::path scene = d / "s.json";
  WriteTextFile(scene.string(), "{}\n");
  fs::create_symlink(scene, d / "link.json");
  const std::string same = MessageOf<std::invalid_argument>([&] {
    CheckDistinctPaths({{"--scene", (d / "link.json").string()}},
                       {{"--json", (d / "." / "s.json").string()}});
  });
  EXPECT_NE(same.find("--json"), std::string::npos) << same;
  EXPECT_NE(same.find("same file as the input --scene"), std::string::npos) << same;
  const std::string twice = MessageOf<std::invalid_argument>([&] {
    CheckDistinctPaths(
        {}, {{"--json", (d / "o").string()}, {"--vtu", (d / "x" / ".." / "o").string()}});
  });
  EXPECT_NE(twice.find("same file as the output --json"), std::string::npos) << twice;
  EXPECT_NO_THROW(
      CheckDistinctPaths({{"--scene", scene.string()}}, {{"--json", (d / "o.json").string()},
                                                         {"--vtu", (d / "o.vtu").string()},
                                                         {"--obj", ""},
                                                         {"--out", "/dev/stdout"}}));
}

}  // namespace
}  // namespace softkin
