// Datasets: serpentine order, resume and shard identities (bit for bit), the loader's checks and
// the seeded split. The kinematics is the analytical PCC model wrapped so that its output depends
// on its warm-start history, which makes the block replay of resume and shards observable.
#include "softkin/learn/dataset.hpp"

#include "softkin/ik/pcc_kinematics.hpp"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace softkin {
namespace {

namespace fs = std::filesystem;

/// PCC positions plus 1e-3 mm times the evaluations since the last Reset (a stand-in for a
/// warm-started simulator, whose answer depends on where it started); fails (ok = false) when
/// c0 > fail_above, and reports 2 inverted body elements when c1 > invert_above.
class HistoryKinematics : public Kinematics {
 public:
  explicit HistoryKinematics(double fail_above = 1e300, double invert_above = 1e300)
      : fail_above_(fail_above), invert_above_(invert_above) {}
  std::string name() const override { return "history(pcc)"; }
  int num_actuators() const override { return 3; }
  const std::vector<std::string>& point_names() const override { return names_; }
  const Eigen::VectorXd& lower() const override { return pcc_.lower(); }
  const Eigen::VectorXd& upper() const override { return pcc_.upper(); }
  Eigen::VectorXd rest() const override { return pcc_.rest(); }
  KinematicsEval Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c, bool with_j) override {
    ++evals_;
    if (c[0] > fail_above_) {
      KinematicsEval e;
      e.message = "did not converge, at c0 = " + std::to_string(c[0]) + "\nsecond line";
      return e;
    }
    KinematicsEval e = pcc_.Evaluate(c, with_j);
    const int rows[2] = {0, 3};  // tip and backbone[2]
    Eigen::MatrixX3d p(2, 3);
    Eigen::MatrixXd J(6, 3);
    for (int q = 0; q < 2; ++q) {
      p.row(q) = e.p.row(rows[q]).array() + 1e-3 * since_reset_;
      if (with_j) J.middleRows(3 * q, 3) = e.J.middleRows(3 * rows[q], 3);
    }
    e.p = p;
    e.J = with_j ? J : Eigen::MatrixXd();
    if (c[1] > invert_above_) {
      e.inverted_elements = 2;
      e.min_volume_ratio = -0.25;
    }
    ++since_reset_;
    return e;
  }
  long long total_fk_solves() const override { return evals_; }
  void Reset() { since_reset_ = 0; }

 private:
  PccKinematics pcc_;
  std::vector<std::string> names_ = {"tip", "backbone[2]"};
  double fail_above_, invert_above_;
  long long evals_ = 0, since_reset_ = 0;
};

class DatasetTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("softkin_dataset_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& f) const { return (dir_ / f).string(); }
  static std::string Read(const std::string& f) {
    std::ifstream in(f, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  static void Write(const std::string& f, const std::string& text) {
    std::ofstream o(f, std::ios::binary | std::ios::trunc);
    o << text;
  }
  /// Runs a generation with a fresh kinematics (as a new process would).
  DatasetRunSummary Run(const DatasetSampling& s, DatasetRunOptions o, double fail_above = 1e300,
                        double invert_above = 1e300) {
    HistoryKinematics k(fail_above, invert_above);
    o.reset = [&k] { k.Reset(); };
    o.progress = false;
    o.source = {{"kind", "test"}};
    return GenerateDataset(k, s, o);
  }
  fs::path dir_;
};

DatasetSampling Grid(int n, int block) {
  DatasetSampling s;
  s.grid = n;
  s.block = block;
  return s;
}

TEST(DatasetSampling, SerpentineVisitsEveryGridPointOnceWithUnitSteps) {
  for (const auto& [n, m] :
       std::vector<std::pair<int, int>>{{4, 3}, {5, 2}, {3, 4}, {7, 1}, {2, 5}}) {
    DatasetSampling s;
    s.grid = n;
    const long long total = DatasetSize(s, m);
    std::set<std::vector<int>> seen;
    std::vector<int> prev;
    for (long long i = 0; i < total; ++i) {
      const std::vector<int> d = SerpentineDigits(i, n, m);
      for (int x : d) ASSERT_TRUE(x >= 0 && x < n);
      ASSERT_TRUE(seen.insert(d).second) << "grid point visited twice at sample " << i;
      if (i > 0) {
        int changed = 0, step = 0;
        for (int a = 0; a < m; ++a)
          if (d[a] != prev[a]) {
            ++changed;
            step = std::abs(d[a] - prev[a]);
          }
        ASSERT_EQ(changed, 1) << "n " << n << " m " << m << " sample " << i;
        ASSERT_EQ(step, 1) << "n " << n << " m " << m << " sample " << i;
      }
      prev = d;
    }
    EXPECT_EQ(static_cast<long long>(seen.size()), total);
  }
}

TEST(DatasetSampling, GridHitsTheBoundsExactlyAndRandomStaysInside) {
  const Eigen::Vector3d lo(1, -3, 0), hi(3, 3, 0.7);
  DatasetSampling g;
  g.grid = 5;
  Eigen::Vector3d mn = hi, mx = lo;
  for (long long i = 0; i < DatasetSize(g, 3); ++i) {
    const Eigen::VectorXd c = DatasetActuation(g, lo, hi, i);
    mn = mn.cwiseMin(c);
    mx = mx.cwiseMax(c);
  }
  EXPECT_EQ(mn, lo);
  EXPECT_EQ(mx, hi);
  DatasetSampling r;
  r.kind = DatasetSampling::Kind::kRandom;
  r.random = 500;
  r.seed = 9;
  for (long long i = 0; i < r.random; ++i) {
    const Eigen::VectorXd c = DatasetActuation(r, lo, hi, i);
    EXPECT_TRUE((c.array() >= lo.array()).all() && (c.array() < hi.array()).all());
    EXPECT_EQ(c, DatasetActuation(r, lo, hi, i));  // sample i does not depend on the others
  }
  DatasetSampling r2 = r;
  r2.seed = 10;
  EXPECT_NE(DatasetActuation(r, lo, hi, 0), DatasetActuation(r2, lo, hi, 0));
}

TEST(DatasetSampling, ShardsAreWholeBlocksCoveringTheOrder) {
  for (int n = 1; n <= 7; ++n) {
    long long next = 0;
    for (int k = 0; k < n; ++k) {
      const ShardRange r = DatasetShard(1000, 64, k, n);
      EXPECT_EQ(r.first, next);
      EXPECT_EQ(r.first % 64, 0);
      next += r.count;
    }
    EXPECT_EQ(next, 1000);
  }
}

TEST_F(DatasetTest, ResumedRunEqualsUninterruptedRun) {
  const DatasetSampling s = Grid(5, 16);  // 125 samples, blocks of 16
  DatasetRunOptions o;
  o.jacobian = true;
  o.out = Path("full.csv");
  const DatasetRunSummary full = Run(s, o);
  EXPECT_EQ(full.written, 125);
  const std::string want = Read(o.out);

  for (const long long k : {0LL, 1LL, 16LL, 37LL, 124LL}) {
    o.out = Path("part" + std::to_string(k) + ".csv");
    o.stop_after = k;
    Run(s, o);
    // Interrupted mid-line: half of the next line's bytes are there.
    const std::string text = Read(o.out);
    const size_t start = text.size();
    const size_t end = want.find('\n', start);
    ASSERT_NE(end, std::string::npos);
    Write(o.out, text + want.substr(start, (end - start) / 2));
    o.stop_after = -1;
    const DatasetRunSummary r = Run(s, o);
    EXPECT_EQ(r.already, k);
    EXPECT_EQ(r.written, 125 - k);
    EXPECT_EQ(Read(o.out), want) << "interrupted after " << k << " samples";
    // Running again on a complete file writes nothing.
    EXPECT_EQ(Run(s, o).written, 0);
    EXPECT_EQ(Read(o.out), want);
  }
}

// Two writers of one file: the second stops with the reason, and the first's file is untouched.
TEST_F(DatasetTest, ASecondWriterOfTheSameFileIsRefused) {
  const DatasetSampling s = Grid(3, 8);  // 27 samples
  DatasetRunOptions o;
  o.out = Path("busy.csv");
  o.stop_after = 5;
  Run(s, o);
  const std::string before = Read(o.out);
  // Another process writing the file holds its lock (here: another open file description).
  const int fd = ::open(o.out.c_str(), O_RDWR | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  o.stop_after = -1;
  try {
    Run(s, o);
    ADD_FAILURE() << "a second writer was let in";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("busy.csv is being written by another process"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(Read(o.out), before);
  // A new file is refused as well while it is locked, and left empty.
  const std::string fresh = Path("fresh.csv");
  const int fd2 = ::open(fresh.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  ASSERT_EQ(::flock(fd2, LOCK_EX | LOCK_NB), 0);
  o.out = fresh;
  EXPECT_THROW(Run(s, o), std::runtime_error);
  ::close(fd2);
  // Once the other writer is gone, the run resumes (an empty file without a sidecar is fresh).
  EXPECT_EQ(Run(s, o).written, 27);
  ::close(fd);
  o.out = Path("busy.csv");
  EXPECT_EQ(Run(s, o).written, 22);
}

// A resume keeps only valid complete rows: a row with a corrupt number, a missing field or an
// unknown status in the part already written stops the run with its file and line (it used to be
// kept, and the dataset reported complete).
TEST_F(DatasetTest, ResumeRefusesACorruptRowBeforeTheEnd) {
  const DatasetSampling s = Grid(3, 8);  // 27 samples
  DatasetRunOptions o;
  o.jacobian = true;
  o.out = Path("part.csv");
  o.stop_after = 12;
  Run(s, o);
  const std::string part = Read(o.out);
  o.stop_after = -1;
  // Line 6 of the file is sample 4: "4,ok,c0,...".
  size_t l6 = 0;
  for (int k = 1; k < 6; ++k) l6 = part.find('\n', l6) + 1;
  const size_t end6 = part.find('\n', l6);
  const size_t c0 = part.find(',', part.find(',', l6) + 1) + 1;  // after index and status
  std::string spoiled = part, short_row = part, bad_status = part;
  spoiled[c0] = 'x';                                       // a corrupt number
  short_row.erase(c0 - 1, end6 - (c0 - 1));                // "4,ok": fields missing
  bad_status.replace(part.find(',', l6) + 1, 2, "maybe");  // an unknown status
  for (const auto& [text, what] : std::vector<std::pair<std::string, std::string>>{
           {spoiled, "expected a number"},
           {short_row, "fields, found 2"},
           {bad_status, "expected ok, inverted or failed"}}) {
    Write(o.out, text);
    try {
      Run(s, o);
      ADD_FAILURE() << "resumed over a corrupt row (" << what << ")";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(o.out + ":6: "), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
    EXPECT_EQ(Read(o.out), text);  // nothing lost or appended
  }
}

TEST_F(DatasetTest, MergedShardsEqualTheUnshardedRun) {
  const DatasetSampling s = Grid(4, 8);  // 64 samples, 8 blocks
  DatasetRunOptions o;
  o.out = Path("full.csv");
  Run(s, o);
  const std::vector<int> order = {2, 0, 1};
  std::vector<std::string> files;
  for (int k : order) {
    DatasetRunOptions so = o;
    so.out = Path("shard" + std::to_string(k) + ".csv");
    so.shard = k;
    so.shards = 3;
    Run(s, so);
    files.push_back(so.out);
  }
  EXPECT_EQ(MergeDatasets(files, Path("merged.csv")), 64);
  EXPECT_EQ(Read(Path("merged.csv")), Read(o.out));
  const Dataset a = LoadDataset(Path("merged.csv")), b = LoadDataset(o.out);
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.meta["shard"]["n"], 1);

  // A missing shard, a duplicated one, and an incomplete one are errors.
  EXPECT_THROW(MergeDatasets({files[0], files[1]}, Path("m2.csv")), std::invalid_argument);
  EXPECT_THROW(MergeDatasets({files[0], files[1], files[1]}, Path("m3.csv")),
               std::invalid_argument);
  const std::string t = Read(Path("shard1.csv"));
  Write(Path("shard1.csv"), t.substr(0, t.rfind('\n', t.size() - 2) + 1));
  try {
    MergeDatasets(files, Path("m4.csv"));
    FAIL() << "an incomplete shard was merged";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("shard1.csv is incomplete"), std::string::npos)
        << e.what();
  }
}

TEST_F(DatasetTest, AnotherConfigOnTheSameFileIsAnError) {
  DatasetRunOptions o;
  o.out = Path("d.csv");
  Run(Grid(3, 4), o);
  const std::string before = Read(o.out);
  // A row whose actuation is not its index's sample is not resumed over.
  {
    std::string edited = before;
    const size_t row2 = edited.find('\n', edited.find('\n') + 1) + 1;  // line 3: sample 1
    const size_t c0 = edited.find(',', edited.find(',', row2) + 1) + 1;
    edited.replace(c0, edited.find(',', c0) - c0, "0.123");
    Write(o.out, edited.substr(0, edited.find('\n', row2) + 1));
    try {
      Run(Grid(3, 4), o);
      ADD_FAILURE() << "resumed over a row with another actuation";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(o.out + ":3: c0 = 0.123, expected "), std::string::npos)
          << e.what();
    }
    Write(o.out, before);
  }
  // A sidecar of something else beside a new output: refused, and no empty CSV is left.
  Write(Path("other.csv.json"), "{\"x\": 1}");
  DatasetRunOptions other = o;
  other.out = Path("other.csv");
  EXPECT_THROW(Run(Grid(3, 4), other), std::invalid_argument);
  EXPECT_FALSE(fs::exists(other.out));
  try {
    Run(Grid(4, 4), o);
    FAIL() << "a different grid overwrote the file";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("config.sampling.grid"), std::string::npos) << e.what();
  }
  o.jacobian = true;
  EXPECT_THROW(Run(Grid(3, 4), o), std::invalid_argument);
  EXPECT_EQ(Read(o.out), before);
}

TEST_F(DatasetTest, LoaderReturnsTheSamplesAndSkipsFailedOnes) {
  const DatasetSampling s = Grid(4, 64);
  DatasetRunOptions o;
  o.jacobian = true;
  o.out = Path("d.csv");
  const DatasetRunSummary r = Run(s, o, /*fail_above=*/12.0);  // c0 in {0, 6.67, 13.3, 20}
  EXPECT_EQ(r.failed, 32);
  const std::string text = Read(o.out);
  EXPECT_EQ(text.find("nan"), std::string::npos);
  const Dataset d = LoadDataset(o.out);
  EXPECT_EQ(d.failed, 32);
  ASSERT_EQ(d.inputs.rows(), 32);
  EXPECT_EQ(d.num_actuators, 3);
  EXPECT_EQ(d.point_names, (std::vector<std::string>{"tip", "backbone[2]"}));
  ASSERT_EQ(d.positions.cols(), 6);
  ASSERT_EQ(d.jacobians.cols(), 18);
  // Every row is the kinematics at that actuation, and J is flattened row-major.
  HistoryKinematics k;
  for (Eigen::Index i = 0; i < d.inputs.rows(); ++i) {
    const Eigen::VectorXd c = DatasetActuation(s, k.lower(), k.upper(), d.index[i]);
    EXPECT_EQ(Eigen::VectorXd(d.inputs.row(i).transpose()), c);
    k.Reset();
    const KinematicsEval e = k.Evaluate(c, true);
    for (int q = 0; q < 2; ++q)
      for (int dd = 0; dd < 3; ++dd)
        EXPECT_NEAR(d.positions(i, 3 * q + dd), e.p(q, dd), 1e-3 * 64 + 1e-12);
    for (int row = 0; row < 6; ++row)
      for (int a = 0; a < 3; ++a) EXPECT_EQ(d.jacobians(i, row * 3 + a), e.J(row, a));
  }
  // The same file with CRLF line ends (saved on Windows or by a spreadsheet) loads the same.
  std::string crlf;
  for (char ch : text) crlf += ch == '\n' ? std::string("\r\n") : std::string(1, ch);
  std::ofstream(Path("crlf.csv"), std::ios::binary) << crlf;
  const Dataset w = LoadDataset(Path("crlf.csv"));
  EXPECT_EQ(w.failed, d.failed);
  EXPECT_EQ(w.point_names, d.point_names);
  EXPECT_EQ(w.inputs, d.inputs);
  EXPECT_EQ(w.positions, d.positions);
  EXPECT_EQ(w.jacobians, d.jacobians);
}

// A sample whose simulated state has inverted body elements keeps its numbers but is marked
// `inverted` (with the count in the message), and the loader leaves it out of training.
TEST_F(DatasetTest, SamplesWithInvertedElementsAreMarkedAndLeftOutOfTraining) {
  const DatasetSampling s = Grid(4, 64);
  DatasetRunOptions o;
  o.out = Path("d.csv");
  // c0 in {0, 6.67, 13.3, 20}: 32 fail; c1 in {0, 6.67, 13.3, 20}: of the rest, 16 invert.
  const DatasetRunSummary r = Run(s, o, /*fail_above=*/12.0, /*invert_above=*/12.0);
  EXPECT_EQ(r.failed, 32);
  EXPECT_EQ(r.inverted, 16);
  const std::string text = Read(o.out);
  std::istringstream lines(text);
  std::string line;
  int marked = 0;
  while (std::getline(lines, line))
    if (line.find(",inverted,") != std::string::npos) {
      ++marked;
      EXPECT_NE(line.find("2 inverted body elements (smallest volume ratio -0.25)"),
                std::string::npos)
          << line;
      EXPECT_EQ(line.find(",,"), std::string::npos) << "an inverted row keeps its numbers";
    }
  EXPECT_EQ(marked, 16);
  const Dataset d = LoadDataset(o.out);
  EXPECT_EQ(d.failed, 32);
  EXPECT_EQ(d.inverted, 16);
  ASSERT_EQ(d.inputs.rows(), 16);
  for (Eigen::Index i = 0; i < d.inputs.rows(); ++i) {
    EXPECT_LT(d.inputs(i, 0), 12.0);
    EXPECT_LT(d.inputs(i, 1), 12.0);
  }
}

TEST_F(DatasetTest, CorruptFilesAreRejectedWithFileAndLine) {
  DatasetRunOptions o;
  o.out = Path("good.csv");
  Run(Grid(3, 64), o);
  const std::string good = Read(o.out);
  std::vector<std::string> lines;
  {
    std::stringstream ss(good);
    std::string l;
    while (std::getline(ss, l)) lines.push_back(l);
  }
  auto join = [](const std::vector<std::string>& ls) {
    std::string t;
    for (const auto& l : ls) t += l + "\n";
    return t;
  };
  struct Case {
    std::string name, text, expect;
  };
  std::vector<Case> cases;
  {
    auto l = lines;
    l[3].replace(l[3].find(",ok,") + 4, 1, "x");
    cases.push_back({"not_a_number", join(l), ":4: column c0"});
  }
  {
    auto l = lines;
    l[2] += ",1";
    cases.push_back({"extra_field", join(l), ":3: expected"});
  }
  {
    auto l = lines;
    l[5] = l[4];
    cases.push_back({"duplicate_index", join(l), ":6: sample index"});
  }
  {
    auto l = lines;
    l[2].replace(l[2].find(",ok,"), 4, ",maybe,");
    cases.push_back({"bad_status", join(l), ":3: column status"});
  }
  {
    auto l = lines;
    const size_t p = l[7].find(",ok,") + 4;
    l[7].replace(p, l[7].find(',', p) - p, "nan");
    cases.push_back({"nan", join(l), ":8: column c0: expected a finite number"});
  }
  cases.push_back(
      {"truncated", good.substr(0, good.size() - 5), ":28: the last line has no line break"});
  {
    auto l = lines;
    l[0] = "index,status,c0,c1,c2,tip_x,tip_y,message";
    cases.push_back({"bad_header", join(l), ":1:"});
  }
  for (const auto& c : cases) {
    const std::string f = Path(c.name + ".csv");
    Write(f, c.text);
    try {
      LoadDataset(f);
      ADD_FAILURE() << c.name << ": accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(f + c.expect), std::string::npos)
          << c.name << ": " << e.what();
    }
  }
  EXPECT_EQ(LoadDataset(o.out).inputs.rows(), 27);
}

TEST(DatasetSplit, SeededDisjointAndComplete) {
  SampleSet all;
  all.X = Eigen::VectorXd::LinSpaced(1000, 0.0, 999.0);  // row i holds i
  all.Y = 2.0 * all.X;
  const TrainTestSets a = SplitTrainTest(all, 5), b = SplitTrainTest(all, 5),
                      c = SplitTrainTest(all, 6);
  EXPECT_EQ(a.train_rows, b.train_rows);
  EXPECT_EQ(a.train.X, b.train.X);
  EXPECT_NE(a.train_rows, c.train_rows);
  EXPECT_EQ(a.train.size(), 700);
  EXPECT_EQ(a.test.size(), 300);
  std::set<int> seen;
  for (int i = 0; i < a.train.size(); ++i) {
    EXPECT_EQ(a.train.X(i, 0), a.train_rows[i]);  // the rows travel with their samples
    EXPECT_EQ(a.train.Y(i, 0), 2.0 * a.train_rows[i]);
    seen.insert(a.train_rows[i]);
  }
  for (int r : a.test_rows) EXPECT_TRUE(seen.insert(r).second) << r << " in both";
  EXPECT_EQ(seen.size(), 1000u);
  EXPECT_NE(a.train_rows.back(), 699);  // shuffled, not a prefix
}

}  // namespace
}  // namespace softkin
