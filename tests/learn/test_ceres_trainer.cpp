// The Ceres peer of the LM trainer: it reaches the loss the in-house trainer reaches, on the same
// network, data and start.
#include "softkin/learn/ceres_trainer.hpp"
#include "softkin/learn/lm_trainer.hpp"

#include "learn_test_util.hpp"

namespace softkin {
namespace {

TEST(CeresFitOptions, Validation) {
  std::string why;
  EXPECT_TRUE(CeresFitOptions().IsValid(&why)) << why;
  CeresFitOptions o;
  o.linear_solver = "sparse_schur";
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why.rfind("linear_solver", 0), 0u) << why;
  o = CeresFitOptions();
  o.num_threads = 0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why.rfind("num_threads", 0), 0u) << why;
}

TEST(CeresTrainer, ReachesTheLossOfTheInHouseTrainer) {
  // Teacher data (exactly fittable) and a start near the teacher, so that both methods stay in the
  // same basin; the in-house trainer runs a few epochs, Ceres must reach the loss it reached.
  const Fnn teacher = test::RandomNetwork({2, 5, 2}, 501);
  const SampleSet data = test::TeacherData(teacher, 120, 502);
  Fnn start = teacher;
  const Eigen::VectorXd w = teacher.parameters();
  start.set_parameters(w + 0.2 * test::UniformSamples(static_cast<int>(w.size()), 1, -1, 1, 503));

  Fnn lm_net = start;
  LmOptions lo;
  lo.initialize = false;
  lo.max_epochs = 4;
  const LmSummary ls = TrainLevenbergMarquardt(lm_net, data, nullptr, lo);
  ASSERT_LT(ls.final_train_mse, 1e-4 * ls.train_mse.front()) << ls.BriefReport();

  Fnn ceres_net = start;
  CeresFitOptions co;
  co.initialize = false;
  co.target_mse = ls.final_train_mse;
  co.max_iterations = 200;
  const CeresFitSummary cs = FitFnnWithCeres(ceres_net, data, co);
  EXPECT_DOUBLE_EQ(cs.initial_mse, ls.train_mse.front());  // same start, same loss definition
  EXPECT_TRUE(cs.reached_target) << cs.BriefReport() << "\n" << cs.ceres_report;
  EXPECT_LE(cs.final_mse, ls.final_train_mse);
  EXPECT_GE(cs.time_to_target_s, 0.0);
  // The reported mse is the network's own.
  EXPECT_NEAR(NormalizedMse(ceres_net, data), cs.final_mse, 1e-10 * cs.initial_mse);
  ASSERT_EQ(cs.train_mse.size(), cs.time_s.size());
  for (std::size_t k = 1; k < cs.train_mse.size(); ++k)
    EXPECT_LE(cs.train_mse[k], cs.train_mse[k - 1]) << k;
}

}  // namespace
}  // namespace softkin
