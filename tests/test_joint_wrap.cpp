// Joint wrap: the nearest whole-turn equivalent, continuous joints through
// ±180° in the trajectory, its validation and its programs, the maps' joint-wrap sheets, a long
// pass on which J6 turns more than a whole turn, and Ray Shooting executable wherever DP is.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <scanplan/config/job.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/joint_wrap.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/pipeline/plan_scan.h>
#include <scanplan/planner/trajectory_builder.h>
#include <scanplan/planner/validation.h>
#include <scanplan/planner/wrap_sheets.h>
#include <scanplan/programs/programs.h>
#include "cli_support.h"
#include "test_support.h"

namespace scanplan {
namespace {

using kinematics::JointVector;
using kinematics::nearestTurn;
using kinematics::Trajectory;
using kinematics::TrajectorySample;

constexpr double kPi = std::numbers::pi;
// nearestTurn adds a multiple of 2π: exact to a few ulps of the turn.
constexpr double kTurnTol = 1e-12;

TEST(NearestTurn, IsTheEquivalentNearestTheReference) {
  // 170° after −175°: the path crosses −180°, so −190°.
  EXPECT_NEAR(nearestTurn(deg(170.0), deg(-175.0)), deg(-190.0), kTurnTol);
  // −170° after 175°: 190°.
  EXPECT_NEAR(nearestTurn(deg(-170.0), deg(175.0)), deg(190.0), kTurnTol);
  // Several turns away: 10° near 725° is 730°.
  EXPECT_NEAR(nearestTurn(deg(10.0), deg(725.0)), deg(730.0), kTurnTol);
  EXPECT_NEAR(nearestTurn(deg(10.0), deg(-700.0)), deg(-710.0), kTurnTol);
  // Already nearest: unchanged (bit for bit).
  EXPECT_EQ(nearestTurn(0.3, 0.2), 0.3);
  EXPECT_EQ(nearestTurn(-2.0, -2.5), -2.0);
  // Halfway: the larger value.
  EXPECT_NEAR(nearestTurn(0.0, kPi), 2.0 * kPi, kTurnTol);
}

TEST(NearestTurn, PropertyWithinHalfATurnAndWholeTurnsAway) {
  std::mt19937 rng(18);
  std::uniform_real_distribution<double> any(-20.0, 20.0);
  for (int k = 0; k < 1000; ++k) {
    const double q = any(rng), ref = any(rng);
    const double u = nearestTurn(q, ref);
    EXPECT_LE(std::abs(u - ref), kPi + kTurnTol) << q << " " << ref;
    const double turns = (u - q) / kinematics::kTurn;
    EXPECT_NEAR(turns, std::round(turns), 1e-9) << q << " " << ref;
  }
}

TEST(UnwrapNear, MovesEveryJointOnItsOwn) {
  JointVector q, ref;
  q << deg(-170.0), deg(10.0), deg(179.0), deg(-179.0), deg(0.0), deg(90.0);
  ref << deg(175.0), deg(20.0), deg(-179.0), deg(179.0), deg(350.0), deg(-300.0);
  const JointVector u = kinematics::unwrapNear(q, ref);
  JointVector want;
  want << deg(190.0), deg(10.0), deg(-181.0), deg(181.0), deg(360.0), deg(-270.0);
  EXPECT_LT((u - want).cwiseAbs().maxCoeff(), kTurnTol) << u.transpose();
}

TEST(TurnsMoreThanOnce, OnlyRangesBeyondAWholeTurn) {
  kinematics::DhJoint j;
  j.min = deg(-200.0);
  j.max = deg(200.0);
  EXPECT_TRUE(kinematics::turnsMoreThanOnce(j));
  j.min = deg(-180.0);
  j.max = deg(180.0);
  EXPECT_FALSE(kinematics::turnsMoreThanOnce(j));  // ±180°: one equivalent inside (the end)
  j.min = deg(-170.0);
  j.max = deg(170.0);
  EXPECT_FALSE(kinematics::turnsMoreThanOnce(j));
}

// The demo cell's Viper (J4 ±190°), scanner spinning clear of everything: J4 from 170° to 188°.
struct Cell {
  config::JobSpec job;
  kinematics::CellModel cell;
};
Cell demoCell() {
  config::JobSpec job =
      config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml", test::kLightDemo);
  kinematics::CellModel cell = config::buildCell(job);
  return {std::move(job), std::move(cell)};
}

Trajectory j4Through180(bool wrapped) {
  Trajectory tr;
  for (int k = 0; k <= 9; ++k) {
    TrajectorySample s;
    s.t = 0.1 * k;
    s.q << deg(-90.0), deg(-90.0), deg(180.0), deg(170.0 + 2.0 * k), deg(90.0), deg(-4.0);
    if (wrapped) s.q(3) = nearestTurn(s.q(3), 0.0);  // what an IK in (−180°, 180°] gives
    s.f = 0.5;
    tr.samples.push_back(s);
  }
  return tr;
}

// Validation takes the joint values as they are: limits on the unwrapped values, speeds on their
// differences. J4 through 180° unwrapped is valid; the same poses wrapped to ±180° are a
// whole-turn jump in 0.1 s, far over J4's speed.
TEST(JointWrapValidation, UnwrappedCrossingIsValidAWrappedOneIsAJump) {
  const Cell d = demoCell();
  const collision::Scene scene(d.cell, config::clearanceConfig(d.job));
  const planner::ValidationReport ok =
      planner::validateTrajectory(scene, j4Through180(false), {.sample_dt = 0.01});
  EXPECT_TRUE(ok.valid) << (ok.violations.empty() ? "" : planner::describe(ok.violations[0]));
  const planner::ValidationReport jump =
      planner::validateTrajectory(scene, j4Through180(true), {.sample_dt = 0.01});
  EXPECT_FALSE(jump.valid);
  bool speed = false;
  for (const planner::Violation& v : jump.violations)
    speed = speed || (v.kind == planner::Violation::Kind::kJointSpeed && v.joint == 3);
  EXPECT_TRUE(speed);
}

// A path whose IK (in (−180°, 180°]) jumps from 180° to −178° on J4: the trajectory follows J4
// continuously to 188°, inside the Viper's ±190°, and reproduces every pose.
TEST(JointWrapTrajectory, FollowsJ4Through180) {
  const Cell d = demoCell();
  const collision::Scene scene(d.cell, config::clearanceConfig(d.job));
  const Trajectory want = j4Through180(false);
  kinematics::ScanPath path;
  path.dt = 0.1;
  const double theta = 0.0;
  const Eigen::Isometry3d X_PW = (d.cell.table.X_WR(theta) * d.cell.part.X_RP).inverse();
  for (const TrajectorySample& s : want.samples) {
    path.samples.push_back(
        {s.t, X_PW * d.cell.X_WB * d.cell.robot.fk(s.q) * d.cell.scanner.X_FS, true});
  }
  const std::vector<double> thetas(path.samples.size(), theta);
  const planner::TrajectoryBuild built =
      planner::buildTrajectory(scene, config::constraintSettings(d.job), path, thetas,
                               d.cell.robot.branchOf(want.samples.front().q));
  ASSERT_TRUE(built.ok) << built.reason;
  ASSERT_EQ(built.trajectory.samples.size(), want.samples.size());
  for (std::size_t k = 0; k < want.samples.size(); ++k) {
    EXPECT_LT((built.trajectory.samples[k].q - want.samples[k].q).cwiseAbs().maxCoeff(), 1e-9)
        << k << ": " << built.trajectory.samples[k].q.transpose() * 180.0 / kPi;
  }
  // On to 194°: past J4's limit from 170°, so the track starts on the other equivalent, −190°
  // (at the limit), and ends at −166°.
  kinematics::ScanPath on = path;
  for (int k = 1; k <= 3; ++k) {
    JointVector q = want.samples.back().q;
    q(3) += deg(2.0 * k);
    on.samples.push_back({path.samples.back().t + 0.1 * k,
                          X_PW * d.cell.X_WB * d.cell.robot.fk(q) * d.cell.scanner.X_FS, true});
  }
  const planner::TrajectoryBuild other = planner::buildTrajectory(
      scene, config::constraintSettings(d.job), on, std::vector<double>(on.samples.size(), theta),
      d.cell.robot.branchOf(want.samples.front().q));
  ASSERT_TRUE(other.ok) << other.reason;
  EXPECT_NEAR(other.trajectory.samples.front().q(3), deg(-190.0), 1e-9);
  EXPECT_NEAR(other.trajectory.samples.back().q(3), deg(-166.0), 1e-9);
}

// The programs write the trajectory's unwrapped values: 188°, never −172°.
TEST(JointWrapPrograms, WriteTheUnwrappedValues) {
  const Cell d = demoCell();
  const Trajectory tr = j4Through180(false);
  for (const std::string& name : programs::programFormatNames()) {
    const programs::ProgramFiles files =
        programs::writeProgram(tr, d.cell.robot, *programs::parseProgramFormat(name), {});
    const std::string& text = files.files.front().second;
    const std::string want = name == "urscript" ? "3.281218994" : "188";  // 188° in rad, 9 dp
    EXPECT_NE(text.find(want), std::string::npos) << name << "\n" << text;
    EXPECT_EQ(text.find("-172"), std::string::npos) << name << "\n" << text;
  }
}

pipeline::ScanPlan plan(const std::string& job_file,
                        const std::vector<std::string>& overrides,
                        const std::string& method = "") {
  std::vector<std::string> all = {"simulation.enabled=false"};
  all.insert(all.end(), overrides.begin(), overrides.end());
  const config::JobSpec job = config::loadJob(test::sourceDir() / job_file, all);
  return pipeline::planScan(config::toProblem(job), {.method = method});
}

// The largest step of joint j between samples, and its range, rad.
struct JointRun {
  double max_step = 0.0, lo = 0.0, hi = 0.0;
};
JointRun jointRun(const Trajectory& tr, int j) {
  JointRun r{0.0, tr.samples.front().q(j), tr.samples.front().q(j)};
  for (std::size_t k = 1; k < tr.samples.size(); ++k) {
    const double q = tr.samples[k].q(j);
    r.max_step = std::max(r.max_step, std::abs(q - tr.samples[k - 1].q(j)));
    r.lo = std::min(r.lo, q);
    r.hi = std::max(r.hi, q);
  }
  return r;
}

// A long table-synchronised pass: the scanner looks down (80°) at the housing's hub and circles
// it three whole turns in 27 s (40°/s) while the table gives 30°/s at most, so the arm's J6
// (±360°) turns the rest. The first path (on the map) would take J6 past −360°; on a joint-wrap
// sheet of J6 the planner keeps it inside, and J6 passes +180° on the way.
TEST(JointWrapPlan, LongSynchronisedPassTurnsJ6Past180) {
  const pipeline::ScanPlan p =
      plan("data/jobs/demo_rings.yaml",
           {"scan.dt_s=0.2", "map.angle_step_deg=4",
            "scan.paths=[{type: ring, height_mm: 105, tilt_deg: 80, extent_deg: 1080, "
            "speed_deg_s: 40}]"});
  ASSERT_TRUE(p.planned()) << p.reason;
  ASSERT_TRUE(p.validation);
  EXPECT_TRUE(p.validation->valid);
  EXPECT_FALSE(p.choice.wrap_sheet.empty());
  const Trajectory& tr = p.trajectory->trajectory;
  const JointRun j6 = jointRun(tr, 5);
  EXPECT_GT(std::max(-j6.lo, j6.hi), kPi) << toDeg(j6.lo) << " … " << toDeg(j6.hi);
  EXPECT_GT(j6.hi - j6.lo, deg(270.0)) << toDeg(j6.lo) << " … " << toDeg(j6.hi);
  EXPECT_LT(j6.max_step, deg(20.0));
  for (const TrajectorySample& s : tr.samples) {
    EXPECT_TRUE(p.prepared->scene->cell().robot.withinLimits(s.q));
  }
  std::printf("J6 %.1f … %.1f deg; %s\n", toDeg(j6.lo), toDeg(j6.hi), p.choice.why_chosen.c_str());
}

// Ray Shooting gives an executable (valid) plan on every job where DP does: each planner's path
// on a branch whose joint would pass its limit is planned again on that branch's sheets.
TEST(JointWrapPlan, RayShootingIsExecutableWhereverDpIs) {
  const std::string rings = "data/jobs/demo_rings.yaml", two = test::kLightDemo[1];
  const std::string spin =
      "scan.paths=[{type: ring, height_mm: 105, tilt_deg: 80, extent_deg: 1080, speed_deg_s: "
      "40}]";
  const std::string irb = "robot=../robots/urdf/abb_irb2400.urdf";
  const std::vector<std::pair<std::string, std::vector<std::string>>> jobs = {
      {rings, {two}},
      {rings, {two, "table.max_speed_deg_s=20", "table.max_accel_deg_s2=40"}},
      {rings, {two, "map.branch=RIGHTY ABOVE NOFLIP"}},
      {rings, {two, irb, "table.axis.xyz_mm=[900,0,0]"}},
      {rings, {spin}},
      {rings, {spin, irb, "table.axis.xyz_mm=[900,0,0]"}},
      {"data/jobs/kuka_demo.yaml", {}},
  };
  for (const auto& [file, sets] : jobs) {
    std::vector<std::string> all = {"simulation.enabled=false", "scan.dt_s=0.25",
                                    "map.angle_step_deg=4"};
    all.insert(all.end(), sets.begin(), sets.end());
    const pipeline::ScanProblem problem =
        config::toProblem(config::loadJob(test::sourceDir() / file, all));
    const auto prepared = pipeline::prepareScan(problem);
    const pipeline::ScanPlan dp = pipeline::planPrepared(problem, prepared, {.method = "dp"});
    const pipeline::ScanPlan ray = pipeline::planPrepared(problem, prepared, {.method = "ray"});
    std::string what = file;
    for (const std::string& x : sets) what += " " + x;
    std::printf("%s: dp %s, ray %s\n", what.c_str(),
                std::string(pipeline::scanStatusName(dp.status)).c_str(),
                std::string(pipeline::scanStatusName(ray.status)).c_str());
    if (dp.planned()) {
      EXPECT_TRUE(ray.planned()) << what << ": " << ray.reason;
    }
  }
}

}  // namespace
}  // namespace scanplan
