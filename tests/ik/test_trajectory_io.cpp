// Waypoint files (the thesis group's flower path included) and the streamed CSV: errors name the
// file and the line.
#include "softkin/ik/trajectory_io.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <unistd.h>

namespace softkin {
namespace {

std::string Write(const std::string& name, const std::string& text) {
  const std::string path =
      ::testing::TempDir() + "/softkin_" + std::to_string(::getpid()) + "_" + name;
  std::ofstream(path) << text;
  return path;
}

void ExpectError(const std::string& text, const std::string& line_tag, const std::string& what) {
  const std::string path = Write("bad.txt", text);
  try {
    ReadWaypoints(path);
    FAIL() << "no throw for: " << text;
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(path + line_tag), std::string::npos) << m;
    EXPECT_NE(m.find(what), std::string::npos) << m;
  }
  std::remove(path.c_str());
}

TEST(WaypointFile, ReadsTheFlowerTrajectory) {
  const Eigen::MatrixX3d w =
      ReadWaypoints(std::string(SOFTKIN_THESIS_DATA) + "/flower_trajectory.txt");
  // 121 lines (the README says 120): the last one, without a newline, closes the loop.
  ASSERT_EQ(w.rows(), 121);
  EXPECT_EQ(w.row(120), w.row(0));
  EXPECT_DOUBLE_EQ(w(0, 1), 133.707);
  EXPECT_DOUBLE_EQ(w(1, 0), 1.428591);
  EXPECT_GT(w.col(1).minCoeff(), 119.0);  // y is the long axis, ~120-134
  EXPECT_LT(w.col(1).maxCoeff(), 135.0);
}

TEST(WaypointFile, AcceptsCommasSpacesCommentsAndAHeader) {
  const std::string path = Write("ok.txt",
                                 "# a path\n"
                                 "x, y, z\n"
                                 "1, 2, 3   # first\n"
                                 "\n"
                                 "4\t5 6\n"
                                 "  7,8,9e-1\r\n");
  const Eigen::MatrixX3d w = ReadWaypoints(path);
  ASSERT_EQ(w.rows(), 3);
  EXPECT_EQ(w.row(0), Eigen::RowVector3d(1, 2, 3));
  EXPECT_EQ(w.row(1), Eigen::RowVector3d(4, 5, 6));
  EXPECT_EQ(w.row(2), Eigen::RowVector3d(7, 8, 0.9));
  std::remove(path.c_str());
}

TEST(WaypointFile, ErrorsNameFileLineAndWhatWasExpected) {
  ExpectError("1 2 3\n4 5\n", ":2:", "expected 3 values");
  ExpectError("1 2 3 4\n", ":1:", "found 4");
  ExpectError("# c\n1 2 nan\n", ":2:", "not finite");
  ExpectError("1 inf 3\n", ":1:", "not finite");
  ExpectError("1 2 3\n\n1.2.3 4 5\n", ":3:", "column 1 '1.2.3' is not a number");
  ExpectError("1,,3\n", ":1:", "column 2 '' is not a number");
  ExpectError("abc 2 3\n", ":1:", "not a number");
  ExpectError("# only comments\n", ":", "no waypoints");
  EXPECT_THROW(ReadWaypoints("/nonexistent/path.txt"), std::invalid_argument);
}

TEST(WaypointCsv, RowsRoundTripForResuming) {
  WaypointResult w;
  w.index = 7;
  w.target = Eigen::Vector3d(1, 2, 3);
  w.c = Eigen::Vector3d(0.1, 1.0 / 3.0, 19.999999999999);
  w.reached = Eigen::Vector3d(1, 2, 3.1);
  w.error_mm = 0.1;
  w.objective = 0.01;
  w.converged = true;
  const std::string row = WaypointCsvRow(w);
  const std::string header = WaypointCsvHeader(3);
  int commas_h = 0, commas_r = 0;
  for (char ch : header) commas_h += ch == ',';
  for (char ch : row) commas_r += ch == ',';
  EXPECT_EQ(commas_h, commas_r);
  const std::string path = Write("out.csv", header + "\n" + row + "\n" + "8,1,2,3,0.5");  // partial
  const WaypointCsvResume r = ReadWaypointCsvForResume(path, 3);
  EXPECT_EQ(r.next_index, 8);
  EXPECT_EQ(r.last_c, w.c);  // exact: 17 digits
  const std::string other = Write("other.csv", WaypointCsvHeader(2) + "\n");
  try {
    ReadWaypointCsvForResume(other, 3);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(other + ":1:"), std::string::npos) << e.what();
  }
  const std::string bad = Write("bad.csv", header + "\n" + row + "\n1,2\n");
  try {
    ReadWaypointCsvForResume(bad, 3);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(bad + ":3:"), std::string::npos) << e.what();
  }
  const std::string empty_run = Write("empty.csv", header + "\n");
  EXPECT_EQ(ReadWaypointCsvForResume(empty_run, 3).next_index, 0);
  for (const auto& p : {path, other, bad, empty_run}) std::remove(p.c_str());
}

}  // namespace
}  // namespace softkin
