#include <cmath>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include <scanplan/kinematics/cell.h>
#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/rotary_table.h>
#include <scanplan/kinematics/units.h>
#include "tests/test_support.h"

namespace scanplan::kinematics {
namespace {

constexpr double kTol = 1e-12;

Eigen::Isometry3d randomPose(std::mt19937& rng, double extent) {
  std::uniform_real_distribution<double> d(-extent, extent);
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = rotationFromRpy({d(rng), d(rng), d(rng)});
  X.translation() << d(rng), d(rng), d(rng);
  return X;
}

// The same chain written out as plain 4x4 homogeneous matrices, independent of Isometry3d and
// of flangeTarget's implementation.
Eigen::Matrix4d homogeneous(const Eigen::Matrix3d& R, const Eigen::Vector3d& p) {
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  M.topLeftCorner<3, 3>() = R;
  M.topRightCorner<3, 1>() = p;
  return M;
}

TEST(RotaryTable, ChainEqualsTheHandComposedProduct) {
  std::mt19937 rng(42);
  for (int k = 0; k < 200; ++k) {
    RotaryTableModel table;
    table.X_WA = randomPose(rng, 1.0);
    table.eccentricity << 0.002, -0.001;
    table.tilt << deg(0.3), deg(-0.2);
    const Eigen::Isometry3d X_WB = randomPose(rng, 0.5), X_RP = randomPose(rng, 0.2),
                            X_PS = randomPose(rng, 0.3), X_FS = randomPose(rng, 0.1);
    const double theta = std::uniform_real_distribution<double>(-4, 4)(rng);

    const Eigen::Matrix4d turn =
        homogeneous(Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()).toRotationMatrix(),
                    Eigen::Vector3d::Zero());
    const Eigen::Matrix4d error = homogeneous(
        Eigen::AngleAxisd(table.tilt.y(), Eigen::Vector3d::UnitY()).toRotationMatrix() *
            Eigen::AngleAxisd(table.tilt.x(), Eigen::Vector3d::UnitX()).toRotationMatrix(),
        Eigen::Vector3d(table.eccentricity.x(), table.eccentricity.y(), 0));
    const Eigen::Matrix4d expected = X_WB.matrix().inverse() * table.X_WA.matrix() * turn * error *
                                     X_RP.matrix() * X_PS.matrix() * X_FS.matrix().inverse();
    const Eigen::Isometry3d X_BF = flangeTarget(X_WB, table, theta, X_RP, X_PS, X_FS);
    ASSERT_LT((X_BF.matrix() - expected).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(RotaryTable, IdealTableKeepsTheAxisFixedAndTurnsPointsOnCircles) {
  RotaryTableModel table;
  table.X_WA.translation() << 0.6, 0.1, 0.05;
  const Eigen::Vector3d p_R(0.12, -0.05, 0.03);  // a point on the part, table-top frame
  const Eigen::Vector3d axis_point = table.X_WA * Eigen::Vector3d(0, 0, 0.03);
  for (double theta : {0.0, 0.5, 2.0, -3.0}) {
    const Eigen::Isometry3d X_WR = table.X_WR(theta);
    EXPECT_LT((X_WR * Eigen::Vector3d(0, 0, 0.03) - axis_point).norm(), kTol);
    EXPECT_NEAR((X_WR * p_R - axis_point).norm(), p_R.head<2>().norm(), kTol);
    EXPECT_LT(rotationDistance(X_WR.linear(), rotZ(theta)), kTol);
  }
  EXPECT_LT((table.X_WR(2 * std::numbers::pi).matrix() - table.X_WR(0).matrix()).norm(), kTol);
}

TEST(RotaryTable, EccentricityMakesTheTopCentreCircleTheAxis) {
  RotaryTableModel table;
  table.eccentricity << 0.003, 0.004;  // 5 mm off the axis
  for (double theta = 0; theta < 6.3; theta += 0.7) {
    const Eigen::Vector3d c = table.X_WR(theta).translation();
    EXPECT_NEAR(c.head<2>().norm(), 0.005, kTol);
    EXPECT_NEAR(c.z(), 0.0, kTol);
  }
}

TEST(RotaryTable, TiltTiltsTheTopNormalByTheTiltAngle) {
  RotaryTableModel table;
  table.tilt << deg(0.3), deg(0.4);
  // Small rotations about x then y: the normal's angle from the axis is acos(cos a · cos b).
  const double expected = std::acos(std::cos(deg(0.3)) * std::cos(deg(0.4)));
  for (double theta : {0.0, 1.0, 2.5}) {
    const Eigen::Vector3d n = table.X_WR(theta).linear().col(2);
    EXPECT_NEAR(std::acos(std::clamp(n.z(), -1.0, 1.0)), expected, 1e-9);
  }
}

TEST(RotaryTable, MovingTheWholeCellLeavesTheFlangeTargetUnchanged) {
  // Frame invariance (FCL's QueryWithVaryingWorldFrames idea): X_BF is relative to the robot
  // base, so re-expressing the world by any G must not change it.
  std::mt19937 rng(9);
  for (int k = 0; k < 100; ++k) {
    RotaryTableModel table;
    table.X_WA = randomPose(rng, 1.0);
    table.eccentricity << 0.001, 0.002;
    const Eigen::Isometry3d X_WB = randomPose(rng, 1.0), X_RP = randomPose(rng, 0.2),
                            X_PS = randomPose(rng, 0.3), X_FS = randomPose(rng, 0.1);
    const Eigen::Isometry3d G = randomPose(rng, 3.0);
    RotaryTableModel moved = table;
    moved.X_WA = G * table.X_WA;
    const double theta = 0.7 * k;
    const Eigen::Isometry3d a = flangeTarget(X_WB, table, theta, X_RP, X_PS, X_FS);
    const Eigen::Isometry3d b = flangeTarget(G * X_WB, moved, theta, X_RP, X_PS, X_FS);
    ASSERT_LT((a.matrix() - b.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(CellChain, IkOfTheChainPutsTheSensorOnTheRequestedPartPose) {
  // The 7-DOF round trip: for a sensor pose on the part and a table angle, every in-limit IK
  // solution, carried forward through FK and the mount, lands the sensor on X_PS.
  CellModel cell("test", test::bundledRobot("viper_s650"));
  cell.table.X_WA.translation() << 0.52, 0.0, 0.0;
  cell.scanner.X_FS.translation() << 0.0, 0.0, 0.11;
  Eigen::Isometry3d X_PS = Eigen::Isometry3d::Identity();
  X_PS.linear() = Eigen::Vector3d(1, -1, -1).asDiagonal();  // looking down
  X_PS.translation() << 0.05, 0.02, 0.25;
  int solved = 0;
  for (double theta_deg = 0; theta_deg < 360; theta_deg += 15) {
    const double theta = deg(theta_deg);
    for (const IkSolution& s :
         cell.robot.ik(cell.flangeTarget(theta, X_PS), {.within_limits_only = true})) {
      const Eigen::Isometry3d X_PS_back = (cell.table.X_WR(theta) * cell.part.X_RP).inverse() *
                                          cell.X_WB * cell.robot.fk(s.q) * cell.scanner.X_FS;
      ASSERT_LT((X_PS_back.matrix() - X_PS.matrix()).cwiseAbs().maxCoeff(), 1e-9);
      ++solved;
    }
  }
  EXPECT_GT(solved, 24);
}

}  // namespace
}  // namespace scanplan::kinematics
