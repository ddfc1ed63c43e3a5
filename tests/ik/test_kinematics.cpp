// The Kinematics interface's shared pieces: input checks and point lookup.
#include "softkin/ik/kinematics.hpp"

#include <gtest/gtest.h>

namespace softkin {
namespace {

// A linear map p = A c + b with two points, for testing the interface's own helpers.
class LinearKinematics : public Kinematics {
 public:
  LinearKinematics() : names_{"a", "b"}, lo_(Eigen::Vector2d(0, -1)), hi_(Eigen::Vector2d(2, 1)) {}
  std::string name() const override { return "linear"; }
  int num_actuators() const override { return 2; }
  const std::vector<std::string>& point_names() const override { return names_; }
  const Eigen::VectorXd& lower() const override { return lo_; }
  const Eigen::VectorXd& upper() const override { return hi_; }
  Eigen::VectorXd rest() const override { return Eigen::Vector2d(0, 0); }
  KinematicsEval Evaluate(const Eigen::Ref<const Eigen::VectorXd>& c, bool) override {
    KinematicsEval e;
    e.message = CheckKinematicsInput(*this, c);
    e.ok = e.message.empty();
    return e;
  }
  long long total_fk_solves() const override { return 0; }

 private:
  std::vector<std::string> names_;
  Eigen::VectorXd lo_, hi_;
};

TEST(Kinematics, PointIndexFindsNamesAndReportsMissingOnes) {
  LinearKinematics k;
  EXPECT_EQ(k.num_points(), 2);
  EXPECT_EQ(k.point_index("b"), 1);
  EXPECT_EQ(k.point_index("c"), -1);
}

TEST(Kinematics, InputCheckNamesTheActuatorAndTheRange) {
  LinearKinematics k;
  EXPECT_EQ(CheckKinematicsInput(k, Eigen::Vector2d(1, 0)), "");
  EXPECT_EQ(CheckKinematicsInput(k, Eigen::Vector2d(2, 1)), "");  // bounds are inclusive
  EXPECT_NE(CheckKinematicsInput(k, Eigen::Vector3d(1, 0, 0)).find("expected 2"),
            std::string::npos);
  const std::string out = CheckKinematicsInput(k, Eigen::Vector2d(1, 1.5));
  EXPECT_NE(out.find("actuator 1"), std::string::npos) << out;
  EXPECT_NE(out.find("[-1, 1]"), std::string::npos) << out;
  EXPECT_NE(CheckKinematicsInput(k, Eigen::Vector2d(std::nan(""), 0)), "");
  EXPECT_FALSE(k.Evaluate(Eigen::Vector2d(3, 0), false).ok);
}

}  // namespace
}  // namespace softkin
