// Learned kinematics (Eq. 5.4): the Jacobian of the composed networks against finite differences,
// the network-directory format, and the whole chain dataset -> training -> learned IK on an
// analytical robot whose truth is known (the PCC cable finger).
#include "softkin/learn/net_kinematics.hpp"
#include "softkin/learn/train_nets.hpp"

#include "softkin/ik/ik_solver.hpp"
#include "softkin/ik/objectives.hpp"
#include "softkin/ik/pcc_kinematics.hpp"
#include "learn_test_util.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace softkin {
namespace {

/// Networks of a 3-actuator, 2-point robot with random weights (not trained): enough to check
/// the algebra of Eq. 5.4.
LearnedNets RandomNets(unsigned seed) {
  LearnedNets n;
  n.points = {"tip", "mid"};
  n.lower = Eigen::Vector3d(-2, -2, -2);
  n.upper = Eigen::Vector3d(3, 3, 3);
  n.rest = Eigen::Vector3d::Zero();
  n.fk = test::RandomNetwork({3, 7, 5, 6}, seed);
  n.jac = test::RandomNetwork({3, 8, 18}, seed + 10);
  n.s2r = test::RandomNetwork({6, 9, 6}, seed + 20);
  n.ik = test::RandomNetwork({3, 5, 3}, seed + 30);
  n.info["note"] = "random";
  return n;
}

TEST(NetKinematics, FkDerivativeSourceMatchesFiniteDifferencesWithAndWithoutS2r) {
  for (bool s2r : {false, true}) {
    NetKinematics k(RandomNets(3), JacobianSource::kFkDerivative, s2r);
    const Eigen::Vector3d c(0.3, -1.1, 2.0);
    const KinematicsEval e = k.Evaluate(c, true);
    ASSERT_TRUE(e.ok) << e.message;
    ASSERT_EQ(e.J.rows(), 6);
    ASSERT_EQ(e.J.cols(), 3);
    auto f = [&k](const Eigen::VectorXd& x) {
      const KinematicsEval ee = k.Evaluate(x, false);
      Eigen::VectorXd v(6);
      for (int q = 0; q < 2; ++q) v.segment<3>(3 * q) = ee.p.row(q).transpose();
      return v;
    };
    EXPECT_TRUE(test::NearMatrix(e.J, test::CentralDifferences(f, c, 1e-5), 1e-6, 1e-7))
        << "s2r " << s2r;
  }
}

TEST(NetKinematics, NetworkSourceIsTheRowMajorJacobianChainedThroughS2r) {
  const LearnedNets nets = RandomNets(5);
  const Eigen::Vector3d c(1.0, 0.5, -0.5);
  const Eigen::VectorXd flat = nets.jac.Forward(c);
  Eigen::MatrixXd Js(6, 3);
  for (int r = 0; r < 6; ++r)
    for (int a = 0; a < 3; ++a) Js(r, a) = flat[r * 3 + a];  // (3 q + d) m + a
  NetKinematics plain(nets, JacobianSource::kNetwork, false);
  const KinematicsEval e0 = plain.Evaluate(c, true);
  ASSERT_TRUE(e0.ok);
  EXPECT_TRUE(test::NearMatrix(e0.J, Js, 1e-14, 1e-14));
  NetKinematics real(nets, JacobianSource::kNetwork, true);
  const KinematicsEval e1 = real.Evaluate(c, true);
  ASSERT_TRUE(e1.ok);
  const Eigen::VectorXd ps = nets.fk.Forward(c);
  const Eigen::MatrixXd D = test::CentralDifferences(
      [&nets](const Eigen::VectorXd& x) { return Eigen::VectorXd(nets.s2r.Forward(x)); }, ps, 1e-5);
  EXPECT_TRUE(test::NearMatrix(e1.J, D * Js, 1e-6, 1e-7));  // Eq. 5.4: J^r = dN_s2r/dp^s J^s
  const Eigen::VectorXd pr = nets.s2r.Forward(ps);
  EXPECT_NEAR(e1.p(1, 2), pr[5], 1e-12);
}

TEST(NetKinematics, RejectsBadActuationAndMissingNetworks) {
  NetKinematics k(RandomNets(7), JacobianSource::kNetwork, false);
  EXPECT_FALSE(k.Evaluate(Eigen::Vector3d(0, 0, 9), false).ok);  // outside the box
  EXPECT_FALSE(k.Evaluate(Eigen::Vector2d(0, 0), false).ok);
  LearnedNets no_jac = RandomNets(7);
  no_jac.jac = Fnn();
  EXPECT_THROW(NetKinematics(no_jac, JacobianSource::kNetwork, false), std::invalid_argument);
  EXPECT_NO_THROW(NetKinematics(no_jac, JacobianSource::kFkDerivative, false));
  LearnedNets no_s2r = RandomNets(7);
  no_s2r.s2r = Fnn();
  EXPECT_THROW(NetKinematics(no_s2r, JacobianSource::kFkDerivative, true), std::invalid_argument);
  LearnedNets bad = RandomNets(7);
  bad.jac = test::RandomNetwork({3, 4, 17}, 1);
  EXPECT_NE(bad.Check().find("jac network"), std::string::npos) << bad.Check();
}

TEST(NetKinematics, DirectIkIsClampedToTheBox) {
  const LearnedNets nets = RandomNets(9);
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(1e4, -1e4, 1e4)}) {
    const Eigen::VectorXd c = DirectIk(nets, p);
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(c[a], nets.lower[a]);
      EXPECT_LE(c[a], nets.upper[a]);
    }
  }
  LearnedNets no_ik = RandomNets(9);
  no_ik.ik = Fnn();
  EXPECT_THROW(DirectIk(no_ik, Eigen::Vector3d::Zero()), std::invalid_argument);
}

TEST(LearnedNetsIo, SaveLoadRoundTripIsExact) {
  test::TempDir dir;
  const LearnedNets a = RandomNets(11);
  a.Save(dir.file("nets"));
  const LearnedNets b = LearnedNets::Load(dir.file("nets"));
  EXPECT_EQ(b.points, a.points);
  EXPECT_EQ(b.lower, a.lower);
  EXPECT_EQ(b.upper, a.upper);
  EXPECT_EQ(b.rest, a.rest);
  EXPECT_EQ(b.info["note"], "random");
  ASSERT_TRUE(b.has_jac() && b.has_s2r() && b.has_ik());
  const Eigen::Vector3d c(0.1, 0.2, 0.3);
  EXPECT_EQ(b.fk.Forward(c), a.fk.Forward(c));
  EXPECT_EQ(b.jac.Forward(c), a.jac.Forward(c));
  EXPECT_EQ(b.ik.Forward(c), a.ik.Forward(c));
  // Saving without s2r removes the stale file.
  LearnedNets c2 = b;
  c2.s2r = Fnn();
  c2.Save(dir.file("nets"));
  EXPECT_FALSE(LearnedNets::Load(dir.file("nets")).has_s2r());
}

void ExpectLoadError(const std::string& dir, const std::string& fragment) {
  try {
    LearnedNets::Load(dir);
    ADD_FAILURE() << "expected an error containing '" << fragment << "'";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(LearnedNetsIo, CorruptDirectoriesAreRejectedNamingFileAndKey) {
  test::TempDir dir;
  const std::string d = dir.file("nets");
  ExpectLoadError(d, "nets.json: cannot open");
  RandomNets(13).Save(d);
  const std::string json = d + "/nets.json";
  std::ifstream in(json);
  const nlohmann::json good = nlohmann::json::parse(in);
  auto write = [&](const nlohmann::json& j) { std::ofstream(json) << j.dump(); };
  {
    std::ofstream(json) << "{ not json";
    ExpectLoadError(d, "not valid JSON");
  }
  nlohmann::json j = good;
  j.erase("lower");
  write(j);
  ExpectLoadError(d, "key 'lower'");
  j = good;
  j["version"] = 7;
  write(j);
  ExpectLoadError(d, "key 'version'");
  j = good;
  j["networks"]["fk"] = "missing.fnn";
  write(j);
  ExpectLoadError(d, "missing.fnn");
  j = good;
  j["upper"] = {3, 3};
  write(j);
  ExpectLoadError(d, "inconsistent");
  j = good;
  j["networks"]["xyz"] = "fk.fnn";
  write(j);
  ExpectLoadError(d, "networks.xyz");
  write(good);
  std::ofstream(d + "/jac.fnn") << "softkin-fnn 1\nlayers 3 8\n";  // truncated network file
  ExpectLoadError(d, "jac.fnn");
}

/// A dataset of the PCC cable finger on an N^3 grid, tip only, with Jacobians.
Dataset PccDataset(PccKinematics& k, int N) {
  Dataset d;
  d.point_names = {"tip"};
  d.num_actuators = 3;
  d.inputs.resize(N * N * N, 3);
  d.positions.resize(N * N * N, 3);
  d.jacobians.resize(N * N * N, 9);
  int i = 0;
  for (int a = 0; a < N; ++a)
    for (int b = 0; b < N; ++b)
      for (int c = 0; c < N; ++c, ++i) {
        const Eigen::Vector3d x = k.upper().cwiseProduct(Eigen::Vector3d(a, b, c)) / (N - 1);
        const KinematicsEval e = k.Evaluate(x, true);
        d.inputs.row(i) = x.transpose();
        d.positions.row(i) = e.p.row(0);
        for (int r = 0; r < 3; ++r)
          for (int s = 0; s < 3; ++s) d.jacobians(i, 3 * r + s) = e.J(r, s);
        d.index.push_back(i);
      }
  return d;
}

TEST(TrainNets, LearnedIkOnTrainedNetworksReachesTheTrueTarget) {
  PccParams pp;
  pp.backbone_points = 1;
  PccKinematics truth(pp);
  const Dataset d = PccDataset(truth, 8);
  NetsFromDatasetOptions o;
  o.fk_options.hidden = {16};
  o.jac_options.hidden = {16};
  o.ik_options.hidden = {12};
  for (NetTrainOptions* t : {&o.fk_options, &o.jac_options, &o.ik_options}) {
    t->lm.max_epochs = 150;
    t->lm.num_threads = 1;
  }
  const LearnedNets nets = TrainNetsFromDataset(d, "pcc-grid", o);
  ASSERT_TRUE(nets.has_fk() && nets.has_jac() && nets.has_ik());
  const double width = nets.info["dataset"]["workspace_width_mm"].get<double>();
  EXPECT_GT(width, 10.0);
  const double fk_pct = nets.info["fk"]["test_mean_pct_width"].get<double>();
  EXPECT_LT(fk_pct, 1.0) << nets.info["fk"].dump();
  EXPECT_EQ(nets.info["dataset"]["train"].get<int>() + nets.info["dataset"]["test"].get<int>(),
            512);

  // A target the truth reaches at a known actuation off the grid.
  const Eigen::Vector3d c_true(7.3, 2.1, 12.9);
  const Eigen::Vector3d target = truth.Evaluate(c_true, false).p.row(0).transpose();
  for (JacobianSource src : {JacobianSource::kNetwork, JacobianSource::kFkDerivative}) {
    NetKinematics k(nets, src, false);
    PointTrackingObjective obj(k.point_names(), "tip", target);
    IkOptions io;
    io.method = IkMethod::kGaussNewton;
    io.lambda = 1e-6;
    io.max_iterations = 50;
    const IkResult r = SolveIk(k, obj, Eigen::Vector3d(10, 10, 10), io);
    const Eigen::Vector3d reached = truth.Evaluate(r.c, false).p.row(0).transpose();
    EXPECT_LT((reached - target).norm(), 0.02 * width) << JacobianSourceToString(src);
    EXPECT_LT(std::sqrt(r.objective), 0.005 * width) << "the networks' own prediction";
  }
  const Eigen::VectorXd c_direct = DirectIk(nets, target);
  EXPECT_LT((truth.Evaluate(c_direct, false).p.row(0).transpose() - target).norm(), 0.05 * width);
}

TEST(TrainNets, SimToRealLayerReducesTheTwinError) {
  PccParams pp;
  pp.backbone_points = 1;
  PccKinematics sim(pp);
  PccParams tp = pp;
  tp.length = 104.0;  // the "hardware": longer and with a stiffer cable routing
  tp.cable_offset = 6.6;
  PccKinematics twin_k(tp);
  NetsFromDatasetOptions o;
  o.jac = o.ik = false;
  o.fk_options.hidden = {16};
  o.fk_options.lm.max_epochs = 150;
  o.fk_options.lm.num_threads = 1;
  LearnedNets nets = TrainNetsFromDataset(PccDataset(sim, 8), "sim", o);
  Dataset twin = PccDataset(twin_k, 7);  // 343 samples, as in Sec. 5.3.4
  twin.jacobians.resize(twin.inputs.rows(), 0);
  LmOptions lm;
  lm.max_epochs = 200;
  lm.num_threads = 1;
  const NetTrainResult r = TrainS2r(nets, twin, "twin", 0.25, lm);
  EXPECT_EQ(nets.s2r.layer_sizes(), (std::vector<int>{3, S2rNeurons(0.25, 240), 3}));
  const double without = nets.info["s2r"]["test_without_s2r"]["mean_dist"].get<double>();
  EXPECT_GT(without, 1.0);  // the twin really differs
  EXPECT_LT(r.test.mean_dist, without / 3.0) << nets.info["s2r"].dump();
  Dataset wrong = twin;
  wrong.point_names = {"other"};
  EXPECT_THROW(TrainS2r(nets, wrong, "wrong", 0.25, lm), std::invalid_argument);
}

TEST(TrainNets, RejectsDatasetsThatCannotProvideTheNetworks) {
  PccKinematics k;
  Dataset d = PccDataset(k, 3);
  d.jacobians.resize(d.inputs.rows(), 0);
  d.point_names = {"tip", "backbone[0]"};  // (positions still 3 columns: not reached)
  NetsFromDatasetOptions o;
  EXPECT_THROW(TrainNetsFromDataset(d, "nojac", o), std::invalid_argument);  // jac without J
  Dataset tiny = d;
  tiny.inputs = d.inputs.topRows(5);
  EXPECT_THROW(TrainNetsFromDataset(tiny, "tiny", o), std::invalid_argument);
  EXPECT_EQ(S2rNeurons(0.25, 343), 86);
  EXPECT_EQ(WorkspaceWidth(Eigen::MatrixXd(Eigen::Matrix3d::Identity() * 4.0)), 4.0);
}

}  // namespace
}  // namespace softkin
