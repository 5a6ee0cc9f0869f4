// A serial chain (URDF's joint origins and axes) to DH rows and OPW parameters
// (kinematics/serial_chain.h). The chains here are the bundled robots' DH tables written the way
// a URDF might: every joint frame turned about and shifted along its axis at random, some axes
// written backwards. The DH rows and OPW parameters derived from them must reproduce the chain's
// own forward kinematics, computed by composing its joint transforms directly.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/serial_chain.h>
#include <scanplan/kinematics/units.h>
#include "test_support.h"

namespace scanplan::kinematics {
namespace {

constexpr double kPi = std::numbers::pi;
// FK of two descriptions of the same chain: the same up to rounding (m, rad).
constexpr double kFkTol = 1e-9;

// The frame of joint i as a URDF might place it: DH frame i−1, shifted along and turned about
// its z axis, and upside down (the axis then written as 0 0 −1) when `flip`.
Eigen::Isometry3d reexpression(std::mt19937& rng, bool flip) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Isometry3d R = Eigen::Isometry3d::Identity();
  R.translation().z() = 0.3 * u(rng);
  R.linear() = rotZ(kPi * u(rng)) * (flip ? rotX(kPi) : Eigen::Matrix3d::Identity());
  return R;
}

// The chain of a DH table with joint frames J_i = DH_{i−1} · R_i (R_i from reexpression()).
SerialChain chainFromDh(const RobotDefinition& def, std::mt19937& rng, bool random_frames) {
  SerialChain chain;
  Eigen::Isometry3d X_B_prevJ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d X_B_dh = Eigen::Isometry3d::Identity();  // DH frame i−1 at q = 0
  for (std::size_t i = 0; i < kNumJoints; ++i) {
    const DhJoint& d = def.joints[i];
    // Frame 0 is the base: J1's frame may only turn about the base z (never flip or shift).
    Eigen::Isometry3d R =
        random_frames ? reexpression(rng, i > 0 && (rng() & 1)) : Eigen::Isometry3d::Identity();
    if (i == 0) R.translation().setZero(), R.linear() = rotZ(std::atan2(R(1, 0), R(0, 0)));
    ChainJoint& j = chain.joints[i];
    j.name = "joint_" + std::to_string(i + 1);
    j.X_prev = X_B_prevJ.inverse() * X_B_dh * R;
    j.axis = R.linear().transpose() * Eigen::Vector3d(0, 0, d.direction);
    j.min = d.min;
    j.max = d.max;
    j.max_speed = d.max_speed;
    X_B_prevJ = X_B_dh * R;
    X_B_dh = X_B_dh * dhTransform(d, 0.0);
  }
  chain.X_J6T = X_B_prevJ.inverse() * X_B_dh;
  return chain;
}

RobotModel modelFromChain(const SerialChain& chain) {
  RobotDefinition def;
  def.name = "chain";
  def.joints = dhFromChain(chain);
  def.opw = opwFromChain(chain);
  return RobotModel(def);
}

::testing::AssertionResult sameFrame(const Eigen::Isometry3d& a,
                                     const Eigen::Isometry3d& b,
                                     double* max_error = nullptr) {
  return test::samePose(a, b, kFkTol, max_error);
}

class ChainOfBundledRobot : public ::testing::TestWithParam<std::string> {};

TEST_P(ChainOfBundledRobot, DerivedDhAndOpwReproduceTheChainsForwardKinematics) {
  const RobotModel original = test::bundledRobot(GetParam());
  std::mt19937 rng(7);
  for (int variant = 0; variant < 6; ++variant) {
    const SerialChain chain = chainFromDh(original.definition(), rng, variant > 0);
    for (int k = 0; k < 10; ++k) {  // the chain is the robot
      const JointVector q = test::randomJoints(original, rng);
      ASSERT_TRUE(sameFrame(original.fk(q), chainFrames(chain, q).X_BT)) << "variant " << variant;
    }
    const RobotModel derived = modelFromChain(chain);  // throws if OPW disagrees with DH
    for (int k = 0; k < 300; ++k) {
      const JointVector q = test::randomJoints(original, rng);
      ASSERT_TRUE(sameFrame(derived.fk(q), chainFrames(chain, q).X_BT)) << "variant " << variant;
      // FK(IK(x)) = x on the derived OPW, and the IK finds q itself.
      const Eigen::Isometry3d X = derived.fk(q);
      bool found = false;
      for (const IkSolution& s : derived.ik(X)) {
        ASSERT_TRUE(sameFrame(derived.fk(s.q), X));
        JointVector d = s.q - q;
        for (int i = 0; i < kNumJoints; ++i) d(i) = wrapToPi(d(i));
        found = found || d.norm() < 1e-6;
      }
      EXPECT_TRUE(found) << "q not among the IK solutions, variant " << variant;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Bundled,
                         ChainOfBundledRobot,
                         ::testing::Values("viper_s650", "kuka_kr6_r900_sixx"));

TEST(SerialChain, AnAxisWrittenBackwardsIsDirectionMinusOne) {
  const RobotModel viper = test::bundledRobot("viper_s650");
  std::mt19937 rng(1);
  SerialChain chain = chainFromDh(viper.definition(), rng, false);
  // J4 written as 0 0 −1 in a frame turned upside down: the same joint.
  chain.joints[3].X_prev.linear() = chain.joints[3].X_prev.linear() * rotX(kPi);
  chain.joints[4].X_prev = Eigen::Isometry3d(rotX(kPi)) * chain.joints[4].X_prev;
  chain.joints[3].axis = -Eigen::Vector3d::UnitZ();
  const auto rows = dhFromChain(chain);
  EXPECT_EQ(rows[3].direction, -1);
  EXPECT_EQ(rows[0].direction, 1);
  const RobotModel derived = modelFromChain(chain);
  for (int k = 0; k < 100; ++k) {
    const JointVector q = test::randomJoints(viper, rng);
    ASSERT_TRUE(sameFrame(derived.fk(q), viper.fk(q)));
  }
}

// UR5 (standard DH, Universal Robots' published table): J2, J3 and J4 are parallel and the wrist
// axes do not meet in one point (J5 crosses J4 and J6 d5 = 94.65 mm apart): not ortho-parallel.
TEST(SerialChain, ANonOrthoParallelArmIsRefusedNamingTheConditions) {
  RobotDefinition ur5;
  const double a[] = {0, -0.425, -0.39225, 0, 0, 0};
  const double d[] = {0.089159, 0, 0, 0.10915, 0.09465, 0.0823};
  const double alpha[] = {kPi / 2, 0, 0, kPi / 2, -kPi / 2, 0};
  for (std::size_t i = 0; i < kNumJoints; ++i) {
    ur5.joints[i] = {a[i], d[i], alpha[i], 0.0, 1, -2 * kPi, 2 * kPi, kPi};
  }
  std::mt19937 rng(3);
  const SerialChain chain = chainFromDh(ur5, rng, true);
  EXPECT_NO_THROW(dhFromChain(chain));  // a DH table it has
  EXPECT_TRUE(test::throwsInputError(
      [&] { opwFromChain(chain); },
      {"not an ortho-parallel arm",
       "J4 (joint_4) is not perpendicular to J3 (joint_3): the "
       "axes are 0 deg apart, expected 90",
       "the J4, J5 and J6 axes do not meet in one point: J4 crosses J5 94.65 mm "
       "from where J6 does"}));
}

TEST(SerialChain, AWristWhoseAxesMissEachOtherIsRefusedWithTheDistance) {
  const RobotModel viper = test::bundledRobot("viper_s650");
  std::mt19937 rng(5);
  SerialChain chain = chainFromDh(viper.definition(), rng, true);
  // Move J5 sideways by 5 mm (perpendicular to J4 and J5): J4 and J5 no longer intersect.
  const auto axes = chainAxes(chain, JointVector::Zero());
  const Eigen::Vector3d side = axes[3].direction.cross(axes[4].direction).normalized();
  const Eigen::Isometry3d X_BJ4 = chainFrames(chain, JointVector::Zero()).X_BJ[3];
  chain.joints[4].X_prev.translation() += X_BJ4.linear().transpose() * side * 0.005;
  EXPECT_TRUE(test::throwsInputError(
      [&] { opwFromChain(chain); }, {"the J4 and J5 axes do not intersect: they pass 5 mm apart"}));
  // Tilt J3 by 2 degrees: no longer parallel to J2.
  chain = chainFromDh(viper.definition(), rng, false);
  chain.joints[2].X_prev.linear() = chain.joints[2].X_prev.linear() * rotX(scanplan::deg(2.0));
  EXPECT_TRUE(test::throwsInputError(
      [&] { opwFromChain(chain); }, {"J3 (joint_3) is not parallel to J2 (joint_2): 2 deg apart"}));
}

TEST(SerialChain, ABaseOffTheJ1AxisOrASkewTipIsAClearError) {
  const RobotModel viper = test::bundledRobot("viper_s650");
  std::mt19937 rng(9);
  SerialChain chain = chainFromDh(viper.definition(), rng, false);
  chain.joints[0].X_prev.translation() = Eigen::Vector3d(0.01, 0, 0);
  EXPECT_TRUE(test::throwsInputError([&] { dhFromChain(chain); },
                                     {"J1 (joint_1): its axis is 0 deg from the base z axis and "
                                      "passes 10 mm from the base origin"}));
  chain = chainFromDh(viper.definition(), rng, false);
  chain.X_J6T.linear() = chain.X_J6T.linear() * rotY(scanplan::deg(30.0));
  EXPECT_TRUE(test::throwsInputError([&] { dhFromChain(chain); },
                                     {"the tip frame cannot be DH frame 6", "30 deg"}));
}

}  // namespace
}  // namespace scanplan::kinematics
