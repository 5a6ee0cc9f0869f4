#include <cmath>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/units.h>
#include "tests/test_support.h"

namespace scanplan::kinematics {
namespace {

using test::bundledRobot;
using test::randomJoints;

// Acceptance bounds for FK(IK(X)) = X.
constexpr double kPositionTol = 1e-9;  // m (1e-6 mm)
constexpr double kRotationTol = 1e-9;  // rad
// Joint-space agreement for IK(FK(q)) ∋ q; looser than the pose bound because joint error
// near a singularity is amplified while the pose stays exact.
constexpr double kJointTol = 1e-6;  // rad

JointVector degrees(std::initializer_list<double> values) {
  JointVector q;
  int i = 0;
  for (double v : values) q(i++) = deg(v);
  return q;
}

::testing::AssertionResult posesMatch(const Eigen::Isometry3d& A, const Eigen::Isometry3d& B) {
  const double dp = (A.translation() - B.translation()).norm();
  const double dr = rotationDistance(A.linear(), B.linear());
  if (dp <= kPositionTol && dr <= kRotationTol) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "position differs by " << dp << " m, rotation by " << dr << " rad\nA=\n"
         << A.matrix() << "\nB=\n"
         << B.matrix();
}

bool sameJointsModTurn(const JointVector& a, const JointVector& b) {
  for (int i = 0; i < kNumJoints; ++i) {
    if (std::abs(wrapToPi(a(i) - b(i))) > kJointTol) return false;
  }
  return true;
}

TEST(ViperFk, GoldenValuesFromDesignDoc) {
  const RobotModel robot = bundledRobot("viper_s650");
  // docs/design.md §3.1: q = 0 puts the flange at (255, 0, 710) mm: x = a1 + a2 + a3 = 75 + 270 −
  // 90, z = d1 + d4 + d6 = 335 + 295 + 80 (upper arm horizontal, forearm vertical).
  EXPECT_TRUE(robot.fk(JointVector::Zero())
                  .translation()
                  .isApprox(Eigen::Vector3d(0.255, 0, 0.710), 1e-12));

  const Eigen::Isometry3d down = robot.fk(degrees({0, -90, 180, 0, 90, 0}));
  EXPECT_NEAR((down.translation() - Eigen::Vector3d(0.370, 0, 0.615)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((down.linear().col(2) - Eigen::Vector3d(0, 0, -1)).norm(), 0.0, 1e-12);

  // V+ TRANS(450, 0, 695, 0, 90, 0).
  const Eigen::Isometry3d forward = robot.fk(degrees({0, -90, 180, 0, 0, 0}));
  EXPECT_NEAR((forward.translation() - Eigen::Vector3d(0.450, 0, 0.695)).norm(), 0.0, 1e-12);
  EXPECT_LT(rotationDistance(forward.linear(), rotationFromZyz({0, deg(90), 0})), 1e-12);
}

TEST(KukaFk, ZeroPoseMatchesOpwDimensions) {
  const RobotModel robot = bundledRobot("kuka_kr6_r900_sixx");
  // A2 = −90° stands the upper arm up, A3 = +90° lays the forearm forward:
  // x = a1 + c3 + c4 = 25 + 420 + 80, z = c1 + c2 − a2 = 400 + 455 + 35; approach along +x.
  const Eigen::Isometry3d X = robot.fk(degrees({0, -90, 90, 0, 0, 0}));
  EXPECT_NEAR((X.translation() - Eigen::Vector3d(0.525, 0, 0.890)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((X.linear().col(2) - Eigen::Vector3d(1, 0, 0)).norm(), 0.0, 1e-12);
}

class BundledRobot : public ::testing::TestWithParam<const char*> {};

TEST_P(BundledRobot, FkOfEveryIkSolutionReproducesTheTarget) {
  const RobotModel robot = bundledRobot(GetParam());
  std::mt19937 rng(20261122);
  std::size_t checked = 0;
  for (int k = 0; k < 10000; ++k) {
    const Eigen::Isometry3d X = robot.fk(randomJoints(robot, rng));
    const auto solutions = robot.ik(X);
    ASSERT_FALSE(solutions.empty()) << "pose " << k << " is FK of an in-limit q, so reachable";
    for (const IkSolution& s : solutions) {
      ASSERT_TRUE(s.q.allFinite());
      ASSERT_TRUE(posesMatch(robot.fk(s.q), X)) << "pose " << k << ", branch " << s.branch.words();
      ASSERT_EQ(s.within_limits, robot.withinLimits(s.q));
      ASSERT_EQ(s.branch, robot.branchOf(s.q));
      ++checked;
    }
  }
  EXPECT_GT(checked, 40000u);  // several branches per pose, so the check is not vacuous
}

// chain(i, j, q) is frame j seen from frame i: the same as the two frames of linkFrames.
TEST_P(BundledRobot, ChainIsTheRelativePoseOfTwoLinkFrames) {
  const RobotModel robot = bundledRobot(GetParam());
  std::mt19937 rng(11);
  for (int k = 0; k < 200; ++k) {
    const JointVector q = randomJoints(robot, rng);
    const auto frames = robot.linkFrames(q);
    for (int i = 0; i <= 6; ++i) {
      for (int j = i; j <= 6; ++j) {
        const Eigen::Isometry3d expected =
            frames[static_cast<std::size_t>(i)].inverse() * frames[static_cast<std::size_t>(j)];
        ASSERT_LT((robot.chain(i, j, q).matrix() - expected.matrix()).norm(), 1e-12)
            << "frames " << i << " to " << j;
      }
    }
  }
}

TEST_P(BundledRobot, IkOfFkContainsTheOriginalJoints) {
  const RobotModel robot = bundledRobot(GetParam());
  std::mt19937 rng(7);
  for (int k = 0; k < 10000; ++k) {
    const JointVector q = randomJoints(robot, rng);
    const auto solutions = robot.ik(robot.fk(q), {.within_limits_only = true});
    bool found = false;
    for (const IkSolution& s : solutions) found = found || sameJointsModTurn(s.q, q);
    ASSERT_TRUE(found) << "q (deg) = " << (q * kRadToDeg).transpose();
  }
}

TEST_P(BundledRobot, GenericPoseHasEightDistinctBranches) {
  const RobotModel robot = bundledRobot(GetParam());
  // A pose well inside the workspace, not near any singularity: all eight branches exist
  // geometrically (some may lie outside the joint limits).
  std::mt19937 rng(3);
  int generic_poses = 0;
  for (int k = 0; k < 200; ++k) {
    const JointVector q = randomJoints(robot, rng);
    const SingularityMeasures m = robot.singularity(q);
    if (m.wrist < 0.3 || m.elbow < 0.3 || m.shoulder < 0.15) continue;
    std::set<int> branches;
    for (const IkSolution& s : robot.ik(robot.fk(q))) branches.insert(s.branch.index());
    if (branches.size() == 8) ++generic_poses;
  }
  EXPECT_GT(generic_poses, 0);
}

TEST_P(BundledRobot, JacobianMatchesFiniteDifferences) {
  const RobotModel robot = bundledRobot(GetParam());
  std::mt19937 rng(11);
  constexpr double h = 1e-6;
  for (int k = 0; k < 50; ++k) {
    const JointVector q = randomJoints(robot, rng);
    const Jacobian J = robot.jacobian(q);
    for (int i = 0; i < kNumJoints; ++i) {
      JointVector qp = q, qm = q;
      qp(i) += h;
      qm(i) -= h;
      const Eigen::Isometry3d Xp = robot.fk(qp), Xm = robot.fk(qm);
      const Eigen::Vector3d v = (Xp.translation() - Xm.translation()) / (2 * h);
      const Eigen::AngleAxisd dR(Xp.linear() * Xm.linear().transpose());
      const Eigen::Vector3d w = dR.axis() * dR.angle() / (2 * h);
      EXPECT_LT((J.block<3, 1>(0, i) - v).norm(), 1e-6) << "joint " << i + 1;
      EXPECT_LT((J.block<3, 1>(3, i) - w).norm(), 1e-6) << "joint " << i + 1;
    }
  }
}

TEST_P(BundledRobot, SingularityFactorsExplainTheJacobianDeterminant) {
  // For an ortho-parallel arm with a spherical wrist, det J = det J_arm · det J_wrist with
  // |det J_arm| = r · c2 · k · |sin(elbow)| (r: wrist centre's distance from the J1 axis,
  // k: forearm length) and |det J_wrist| = |sin q5|. So the three factors must reproduce
  // |det J| exactly, independently of how each is computed.
  const RobotModel robot = bundledRobot(GetParam());
  const auto& p = robot.definition().opw;
  const double k = std::hypot(p.a2, p.c3);
  std::mt19937 rng(5);
  for (int n = 0; n < 2000; ++n) {
    const JointVector q = randomJoints(robot, rng);
    const SingularityMeasures m = robot.singularity(q);
    const double predicted = m.shoulder * p.c2 * k * m.elbow * m.wrist;
    const double det = std::abs(robot.jacobian(q).determinant());
    ASSERT_NEAR(det, predicted, 1e-9 + 1e-9 * predicted) << "q = " << (q * kRadToDeg).transpose();
    ASSERT_GE(m.manipulability, 0.0);
    ASSERT_LE(m.manipulability, 1.5);
  }
}

TEST_P(BundledRobot, UnreachableAndInvalidTargetsGiveNoSolutions) {
  const RobotModel robot = bundledRobot(GetParam());
  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translation() << 2.0, 0.0, 0.5;
  EXPECT_TRUE(robot.ik(far).empty());
  Eigen::Isometry3d nan_pose = Eigen::Isometry3d::Identity();
  nan_pose.translation().x() = std::nan("");
  EXPECT_TRUE(robot.ik(nan_pose).empty());
}

TEST_P(BundledRobot, RandomPosesInABoxNeverGiveNaNOrWrongSolutions) {
  // Targets not made by FK: many unreachable, some near the workspace boundary.
  const RobotModel robot = bundledRobot(GetParam());
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> pos(-1.2, 1.2);
  int reachable = 0;
  for (int k = 0; k < 5000; ++k) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() << pos(rng), pos(rng), pos(rng);
    X.linear() = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
    const auto solutions = robot.ik(X);
    reachable += solutions.empty() ? 0 : 1;
    for (const IkSolution& s : solutions) {
      ASSERT_TRUE(s.q.allFinite());
      ASSERT_TRUE(posesMatch(robot.fk(s.q), X));
    }
  }
  EXPECT_GT(reachable, 100);
  EXPECT_LT(reachable, 5000);
}

INSTANTIATE_TEST_SUITE_P(Robots,
                         BundledRobot,
                         ::testing::Values("viper_s650", "kuka_kr6_r900_sixx"));

TEST(ViperIk, WristSingularityStillReproducesThePose) {
  const RobotModel robot = bundledRobot("viper_s650");
  for (double q5 : {0.0, 1e-12, 1e-9, -1e-7, 1e-4}) {
    JointVector q = degrees({20, -60, 150, 35, 0, -40});
    q(4) = q5;
    const Eigen::Isometry3d X = robot.fk(q);
    const auto solutions = robot.ik(X);
    ASSERT_FALSE(solutions.empty()) << "q5 = " << q5;
    for (const IkSolution& s : solutions)
      EXPECT_TRUE(posesMatch(robot.fk(s.q), X)) << "q5 = " << q5;
    EXPECT_LT(robot.singularity(q).wrist, std::abs(q5) + 1e-12);
  }
}

TEST(ViperIk, StretchedElbowStillReproducesThePose) {
  const RobotModel robot = bundledRobot("viper_s650");
  // Elbow singular where the forearm (a3, d4) lines up with the upper arm:
  // q3 = 90° − atan2(a3, d4) = 90° + 16.965° (inside J3's range).
  const double q3 = deg(90.0) - std::atan2(-0.090, 0.295);
  for (double eps : {0.0, 1e-10, -1e-8, 1e-5}) {
    JointVector q = degrees({-30, -45, 0, 10, 60, 5});
    q(2) = q3 + eps;
    EXPECT_LT(robot.singularity(q).elbow, std::abs(eps) + 1e-12);
    // |det J| = r·c2·k·|sin q5|·|elbow| ≈ 0.04 m³ · |eps| here.
    EXPECT_LT(std::abs(robot.jacobian(q).determinant()), 0.1 * (std::abs(eps) + 1e-12));
    const Eigen::Isometry3d X = robot.fk(q);
    const auto solutions = robot.ik(X);
    ASSERT_FALSE(solutions.empty()) << "eps = " << eps;
    for (const IkSolution& s : solutions)
      EXPECT_TRUE(posesMatch(robot.fk(s.q), X)) << "eps = " << eps;
  }
}

TEST(ViperIk, WristCentreOnTheJ1AxisStillReproducesThePose) {
  const RobotModel robot = bundledRobot("viper_s650");
  // Approach along +x with the wrist centre at (0, 0, 0.6): flange = centre + d6·z.
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = rotY(deg(90));
  X.translation() = Eigen::Vector3d(0, 0, 0.6) + 0.080 * X.linear().col(2);
  const auto solutions = robot.ik(X);
  ASSERT_FALSE(solutions.empty());
  for (const IkSolution& s : solutions) {
    EXPECT_TRUE(posesMatch(robot.fk(s.q), X));
    EXPECT_LT(robot.singularity(s.q).shoulder, 1e-9);
  }
}

TEST(ViperIk, JointSixRangeBeyondOneTurnGivesBothVariants) {
  const RobotModel robot = bundledRobot("viper_s650");
  const JointVector q = degrees({10, -70, 160, 20, 45, 100});
  int with_100 = 0, with_minus_260 = 0;
  for (const IkSolution& s : robot.ik(robot.fk(q), {.within_limits_only = true})) {
    if ((s.q.head<5>() - q.head<5>()).norm() > 1e-9) continue;
    with_100 += std::abs(s.q(5) - deg(100)) < 1e-9 ? 1 : 0;
    with_minus_260 += std::abs(s.q(5) - deg(-260)) < 1e-9 ? 1 : 0;
  }
  EXPECT_EQ(with_100, 1);
  EXPECT_EQ(with_minus_260, 1);
}

TEST(ViperIk, BranchWordsFollowTheGeometry) {
  const RobotModel robot = bundledRobot("viper_s650");
  // docs/design.md §3.1's "facing down" anchor: wrist in front of J1, elbow up, q5 = +90°.
  EXPECT_EQ(robot.branchOf(degrees({0, -90, 180, 0, 90, 0})).words(), "RIGHTY ABOVE NOFLIP");
  EXPECT_EQ(robot.branchOf(degrees({0, -90, 180, 0, -90, 0})).words(), "RIGHTY ABOVE FLIP");
  // Every branch index maps back to itself through fromIndex.
  for (int i = 0; i < 8; ++i) EXPECT_EQ(IkBranch::fromIndex(i).index(), i);
}

TEST(RobotModel, RejectsOpwThatDisagreesWithDh) {
  RobotDefinition def = bundledRobot("viper_s650").definition();
  def.opw.c2 += 0.001;  // 1 mm longer upper arm in the OPW description only
  try {
    RobotModel robot(def);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("disagree"), std::string::npos) << e.what();
  }
  def = bundledRobot("viper_s650").definition();
  def.opw.offsets[2] = 0.0;  // a wrong joint offset
  EXPECT_THROW(RobotModel{def}, InputError);
}

TEST(Pose, EulerConventionsRoundTrip) {
  std::mt19937 rng(1);
  for (int k = 0; k < 1000; ++k) {
    const Eigen::Matrix3d R = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
    EXPECT_LT(rotationDistance(rotationFromZyz(zyzFromRotation(R)), R), 1e-12);
    EXPECT_LT(rotationDistance(rotationFromRpy(rpyFromRotation(R)), R), 1e-12);
  }
  // Degenerate ZYZ (p = 0 and p = π) still round-trips.
  for (const Eigen::Matrix3d& R :
       {rotZ(0.3), Eigen::Matrix3d(rotZ(0.3) * rotY(std::numbers::pi))}) {
    EXPECT_LT(rotationDistance(rotationFromZyz(zyzFromRotation(R)), R), 1e-12);
  }
  EXPECT_NEAR(rotationDistance(rotX(0.0), rotX(1e-8)), 1e-8, 1e-20);
}

}  // namespace
}  // namespace scanplan::kinematics
