// The 7-DOF trajectory: the CSV interchange format (round trip, every malformed-row error) and
// buildTrajectory() on the demo cell — the joints reproduce the target scanner poses through FK
// and the table transform, stay continuous, and carry their true f.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <scanplan/collision/scene.h>
#include <scanplan/config/job.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/joint_wrap.h>
#include <scanplan/kinematics/trajectory.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/pipeline/plan_scan.h>
#include <scanplan/planner/config_map.h>
#include <scanplan/planner/trajectory_builder.h>
#include "cli/commands/commands.h"
#include "cli/io/axis_stream.h"
#include "test_support.h"

namespace {

using namespace scanplan;
using kinematics::Trajectory;
using kinematics::TrajectorySample;

Trajectory randomTrajectory(std::mt19937& rng, std::size_t n) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Trajectory tr;
  for (std::size_t k = 0; k < n; ++k) {
    TrajectorySample s;
    s.t = 0.1 * static_cast<double>(k) + 0.01 * (1.0 + u(rng));
    s.theta = 20.0 * u(rng);  // several turns, unwrapped
    for (int j = 0; j < kinematics::kNumJoints; ++j) s.q(j) = 3.0 * u(rng);
    s.f = k == 3 ? std::nan("") : 0.5 + 0.5 * u(rng);
    s.scanning = k % 2 == 0;
    s.X_PS.linear() = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().matrix();
    s.X_PS.translation() = Eigen::Vector3d(u(rng), u(rng), u(rng)) * 0.3;
    s.limit = k % 3 == 0 ? "clearance scanner - part" : "joint 5";
    tr.samples.push_back(s);
  }
  return tr;
}

TEST(TrajectoryCsv, RoundTripsToThePrintedPrecision) {
  std::mt19937 rng(5);
  const Trajectory a = randomTrajectory(rng, 40);
  const std::string csv = kinematics::trajectoryToCsv(a);
  ASSERT_EQ(csv.substr(0, csv.find('\n')),
            "t_s,table_deg,j1_deg,j2_deg,j3_deg,j4_deg,j5_deg,j6_deg,f,scanning,px_mm,py_mm,pz_mm,"
            "qw,qx,qy,qz,limit");
  const Trajectory b = kinematics::parseTrajectoryCsv(csv, "t.csv");
  ASSERT_EQ(b.samples.size(), a.samples.size());
  for (std::size_t k = 0; k < a.samples.size(); ++k) {
    const TrajectorySample &x = a.samples[k], &y = b.samples[k];
    // 12 significant digits: within 5e-12 relative of the printed value.
    EXPECT_NEAR(y.t, x.t, 1e-11 * std::max(1.0, std::abs(x.t)));
    EXPECT_NEAR(y.theta, x.theta,
                1e-11 * std::max(1.0, std::abs(x.theta) * 180 / std::numbers::pi));
    EXPECT_LT((y.q - x.q).cwiseAbs().maxCoeff(), 1e-11 * 180);
    if (std::isnan(x.f)) {
      EXPECT_TRUE(std::isnan(y.f));
    } else {
      EXPECT_NEAR(y.f, x.f, 1e-11);
    }
    EXPECT_EQ(y.scanning, x.scanning);
    EXPECT_LT((y.X_PS.translation() - x.X_PS.translation()).norm(), 1e-12);
    EXPECT_LT((y.X_PS.linear() - x.X_PS.linear()).cwiseAbs().maxCoeff(), 1e-11);
    EXPECT_EQ(y.limit, x.limit);
  }
  // Written again, the text is identical (the format is a fixed point).
  EXPECT_EQ(kinematics::trajectoryToCsv(b), csv);
}

TEST(TrajectoryCsv, EveryNumberIsPrintfsTwelveSignificantDigits) {
  // The file's numbers as they were written with snprintf("%.12g") (written faster now): values
  // of every magnitude, ties, zeros of both signs, NaN.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-30, 30);
  std::vector<double> values = {0.0, -0.0, 0.5, 1e-5, 123456789012.5, 1e12, 0.1, 2.5e-300};
  for (int i = 0; i < 20000; ++i) values.push_back(std::ldexp(mantissa(rng), exponent(rng)));
  Trajectory tr;
  for (std::size_t k = 0; k < values.size(); ++k) {
    TrajectorySample s;
    s.t = static_cast<double>(k);
    s.f = values[k];
    tr.samples.push_back(s);
  }
  tr.samples[1].f = std::nan("");
  const std::string csv = kinematics::trajectoryToCsv(tr);
  std::size_t at = csv.find('\n') + 1;
  for (const TrajectorySample& s : tr.samples) {
    const std::size_t end = csv.find('\n', at);
    const std::string row = csv.substr(at, end - at);
    at = end + 1;
    std::size_t from = 0;
    for (int column = 0; column < 8; ++column) from = row.find(',', from) + 1;  // to f
    const std::string f = row.substr(from, row.find(',', from) - from);
    char want[40];
    std::snprintf(want, sizeof want, "%.12g", s.f == 0.0 ? 0.0 : s.f);
    ASSERT_EQ(f, std::isnan(s.f) ? std::string("nan") : std::string(want)) << s.t;
  }
}

TEST(TrajectoryCsv, HandWrittenFileWithoutLimitColumnAndUnknownF) {
  const std::string text =
      "# written by hand\n"
      "t_s,table_deg,j1_deg,j2_deg,j3_deg,j4_deg,j5_deg,j6_deg,f,scanning,px_mm,py_mm,pz_mm,qw,qx,"
      "qy,qz\r\n"
      "0, 10, 0,-30,120,0,40,0, ,1, 100,0,150, 1,0,0,0\r\n"
      "0.5,12,1,-30,120,0,40,0,nan,0,100,0,150,0,1,0,0\n";
  const Trajectory t = kinematics::parseTrajectoryCsv(text, "hand.csv");
  ASSERT_EQ(t.samples.size(), 2u);
  EXPECT_TRUE(std::isnan(t.samples[0].f));
  EXPECT_DOUBLE_EQ(t.samples[1].theta, deg(12.0));
  EXPECT_DOUBLE_EQ(t.samples[0].q(1), deg(-30.0));
  EXPECT_TRUE(t.samples[0].scanning);
  EXPECT_FALSE(t.samples[1].scanning);
  EXPECT_NEAR(t.samples[0].X_PS.translation().z(), 0.15, 1e-15);
  EXPECT_NEAR(t.samples[1].X_PS.linear()(1, 1), -1.0, 1e-15);  // 180° about x
}

TEST(TrajectoryCsv, MalformedInputNamesFileLineAndColumn) {
  const std::string header =
      "t_s,table_deg,j1_deg,j2_deg,j3_deg,j4_deg,j5_deg,j6_deg,f,scanning,px_mm,py_mm,pz_mm,qw,qx,"
      "qy,qz\n";
  const std::string good = "0,0,0,0,0,0,0,0,1,1,0,0,0,1,0,0,0\n";
  struct Case {
    std::string text, expect;
  };
  const std::vector<Case> cases{
      {"", "empty file"},
      {"time,angle\n", "header 'time,angle'"},
      {header, "no samples"},
      {header + good + "0.1,0,0,0\n", "t.csv:3: 4 columns: expected 17"},
      {header + good + "0.1,0,0,0,abc,0,0,0,1,1,0,0,0,1,0,0,0\n", "column j3_deg: 'abc'"},
      {header + good + "0.1,0,0,0,0,0,0,0,1,1,0,0,nan,1,0,0,0\n", "column pz_mm: 'nan'"},
      {header + "nan,0,0,0,0,0,0,0,1,1,0,0,0,1,0,0,0\n", "t.csv:2: column t_s"},
      {header + good + "0,0,0,0,0,0,0,0,1,1,0,0,0,1,0,0,0\n", "strictly increasing"},
      {header + good + "0.1,0,0,0,0,0,0,0,1,2,0,0,0,1,0,0,0\n", "expected 0 or 1"},
      {header + good + "0.1,0,0,0,0,0,0,0,1,1,0,0,0,1,1,0,0\n", "unit quaternion"},
      {header + good + "0.1,0,0,0,0,0,0,0,1e999,1,0,0,0,1,0,0,0\n", "column f"},
      // Finite but absurd (a joint at 1e300° made validation split its interval
      // without end, until the memory ran out).
      {header + good + "0.1,0,0,1e300,0,0,0,0,1,1,0,0,0,1,0,0,0\n",
       "t.csv:3: column j2_deg: 1e+300: expected an angle within ±1000000 deg"},
      {header + good + "0.1,-2e6,0,0,0,0,0,0,1,1,0,0,0,1,0,0,0\n", "column table_deg: -2000000"},
      {header + good + "0.1,0,0,0,0,0,0,0,1,1,0,3e6,0,1,0,0,0\n",
       "column py_mm: 3000000: expected a position within ±1000000 mm"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    try {
      kinematics::parseTrajectoryCsv(c.text, "t.csv");
      ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.expect), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).rfind("t.csv:", 0), 0u) << e.what();
    }
  }
}

// A column named twice is ambiguous (which one holds the values?): refused naming the name and
// both positions, in a trajectory CSV and in a `watch` axis log; plan's header still reads.
TEST(TrajectoryCsv, AColumnNamedTwiceIsRefusedNamingBothPositions) {
  const std::string header =
      "t_s,table_deg,j1_deg,j2_deg,j3_deg,j4_deg,j5_deg,j6_deg,f,scanning,px_mm,py_mm,pz_mm,qw,qx,"
      "qy,qz\n";
  const std::string good = "0,0,0,0,0,0,0,0,1,1,0,0,0,1,0,0,0\n";
  const auto edited = [&](const std::string& from, const std::string& to) {
    std::string text = header;
    return text.replace(text.find(from), from.size(), to) + good;
  };
  EXPECT_TRUE(test::throwsInputError(
      [&] { kinematics::parseTrajectoryCsv(edited(",j5_deg,", ",j4_deg,"), "t.csv"); },
      {"t.csv:1: header: column 'j4_deg' twice, as columns 6 and 7", "expected each column once"}));
  EXPECT_TRUE(test::throwsInputError(
      [&] { kinematics::parseTrajectoryCsv(edited(",f,", ",t_s,"), "t.csv"); },
      {"t.csv:1: header: column 't_s' twice, as columns 1 and 9"}));
  EXPECT_EQ(kinematics::parseTrajectoryCsv(header + good, "t.csv").samples.size(), 1u);
}

std::optional<kinematics::AxisSample> firstAxisSample(const std::string& log) {
  std::istringstream in(log);
  cli::AxisStreamReader reader(in, "log.csv");
  return reader.next();
}

TEST(AxisStream, AColumnNamedTwiceIsRefusedNamingBothPositions) {
  const std::string eight = "t_s,table_deg,j1_deg,j2_deg,j3_deg,j4_deg,j5_deg,j6_deg";
  const std::string row = "0,1,2,3,4,5,6,7,99\n";
  EXPECT_TRUE(test::throwsInputError([&] { firstAxisSample(eight + ",j4_deg\n" + row); },
                                     {"log.csv:1: the header has column j4_deg twice, as "
                                      "columns 6 and 9",
                                      "expected each of t_s,table_deg,j1_deg,…,j6_deg once"}));
  EXPECT_TRUE(test::throwsInputError([&] { firstAxisSample("# log\nt_s,t_s," + eight + "\n"); },
                                     {"log.csv:2: the header has column t_s twice, as columns "
                                      "1 and 2"}));
  // Other columns may repeat: they are not read.
  const auto sample = firstAxisSample(eight + ",note,note\n" + row);
  ASSERT_TRUE(sample.has_value());
  EXPECT_DOUBLE_EQ(sample->q(3), deg(5.0));
}

// The demo cell on a coarse map (2° × 0.2 s) so the test stays quick.
struct DemoPlan {
  config::JobSpec job;
  kinematics::CellModel cell;
  scanner::GeneratedPath path;
};

DemoPlan demo() {
  config::JobSpec job =
      config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml", test::kLightDemo);
  kinematics::CellModel cell = config::buildCell(job);
  scanner::GeneratedPath path = cli::generateScanPath(job, cell);
  return {std::move(job), std::move(cell), std::move(path)};
}

TEST(BuildTrajectory, JointsReproduceTheTargetPosesAndStayContinuous) {
  const DemoPlan d = demo();
  const collision::Scene scene(d.cell, config::clearanceConfig(d.job));
  const cli::MapRun run = cli::computeMap(d.job, scene, d.path.path);
  // As `plan` does: a branch's path is accepted only when it can be followed continuously.
  planner::TrajectoryBuild built;
  const pipeline::PathChoice plan = pipeline::choosePath(
      run.map, config::planSettings(d.job), {.method = "ray"},
      [&](std::size_t b, const std::vector<double>& theta) {
        built = planner::buildTrajectory(scene, config::constraintSettings(d.job), d.path.path,
                                         theta, run.map.branches[b]);
        return built.ok && built.min_f > 0.0 ? std::string() : "not ok: " + built.reason;
      });
  ASSERT_TRUE(plan.solved()) << plan.chosen.result.reason;
  ASSERT_TRUE(built.ok) << built.reason;
  for (const auto& [b, why] : plan.rejected) {
    EXPECT_NE(b, plan.chosen.result.branch);
    EXPECT_FALSE(why.empty());
  }
  const auto& samples = built.trajectory.samples;
  ASSERT_EQ(samples.size(), d.path.path.samples.size());
  EXPECT_GT(built.min_f, 0.0);
  double worst_mm = 0.0;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const TrajectorySample& s = samples[k];
    EXPECT_EQ(s.t, d.path.path.samples[k].t);
    EXPECT_EQ(s.theta, plan.theta[k]);
    EXPECT_TRUE(d.cell.robot.withinLimits(s.q)) << k;
    EXPECT_EQ(d.cell.robot.branchOf(s.q), run.map.branches[plan.chosen.result.branch]) << k;
    // Independent chain: world ← base ← flange ← sensor vs world ← table ← part ← sensor.
    const Eigen::Isometry3d by_robot = d.cell.X_WB * d.cell.robot.fk(s.q) * d.cell.scanner.X_FS;
    const Eigen::Isometry3d by_table = d.cell.table.X_WR(s.theta) * d.cell.part.X_RP * s.X_PS;
    worst_mm = std::max(worst_mm, toMm((by_robot.translation() - by_table.translation()).norm()));
    EXPECT_LT((by_robot.linear() - by_table.linear()).cwiseAbs().maxCoeff(), 1e-9) << k;
    if (k > 0) {
      // Continuous: no whole-turn jumps; a 0.2 s step moves no joint by more than 45°.
      EXPECT_LT((s.q - samples[k - 1].q).cwiseAbs().maxCoeff(), deg(45.0)) << k;
    }
    EXPECT_GT(s.f, 0.0) << k;
    EXPECT_FALSE(s.limit.empty());
  }
  EXPECT_LT(worst_mm, 1e-6);
}

TEST(BuildTrajectory, UnreachableSampleIsNotOkAndNamed) {
  const DemoPlan d = demo();
  const collision::Scene scene(d.cell, config::clearanceConfig(d.job));
  // Every target 3 m above the part: out of the Viper's reach.
  kinematics::ScanPath far = d.path.path;
  for (auto& s : far.samples) s.X_PS.translation() += Eigen::Vector3d(0.0, 0.0, 3.0);
  const std::vector<double> theta(far.samples.size(), 0.0);
  const planner::TrajectoryBuild built = planner::buildTrajectory(
      scene, config::constraintSettings(d.job), far, theta, kinematics::IkBranch{});
  EXPECT_FALSE(built.ok);
  EXPECT_NE(built.reason.find("time sample 0 "), std::string::npos) << built.reason;
  EXPECT_NE(built.reason.find("unreachable"), std::string::npos) << built.reason;
}

// The first table angle in 5° steps where the pose X_PS is reachable on `branch` within the
// joint limits, and that solution; the angle is negative where there is none.
std::pair<double, kinematics::JointVector> reachableOn(const DemoPlan& d,
                                                       const Eigen::Isometry3d& X_PS,
                                                       const kinematics::IkBranch& branch) {
  for (double a = 0.0; a < 360.0; a += 5.0) {
    for (const auto& s : d.cell.robot.ik(d.cell.flangeTarget(deg(a), X_PS), {true}))
      if (s.branch == branch) return {deg(a), s.q};
  }
  return {-1.0, kinematics::JointVector::Zero()};
}

// The head rolling three whole turns about its laser axis in place: joint 6 (±360°) cannot follow
// it continuously. While the path does not scan, the wrist unwinds a turn over the stretch
// instead (the flange rolls off the planned pose there); while it scans, the track breaks.
TEST(BuildTrajectory, WristUnwindsAWholeTurnOnlyWhereThePathDoesNotScan) {
  const DemoPlan d = demo();
  const collision::Scene scene(d.cell, config::clearanceConfig(d.job));
  const Eigen::Isometry3d X0 = d.path.path.samples.front().X_PS;
  // A table angle where the first pose is reachable on the demo's usual branch.
  const kinematics::IkBranch branch = *config::parseBranch("RIGHTY ABOVE NOFLIP");
  const double theta = reachableOn(d, X0, branch).first;
  ASSERT_GE(theta, 0.0);
  kinematics::ScanPath roll;
  roll.dt = 0.1;
  for (int k = 0; k <= 300; ++k) {  // 30 s, 36°/s about z_S
    const double t = 0.1 * k;
    Eigen::Isometry3d X = X0;
    X.linear() =
        X0.linear() * Eigen::AngleAxisd(deg(36.0) * t, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    roll.samples.push_back({t, X, k == 0});
  }
  const std::vector<double> thetas(roll.samples.size(), theta);
  const planner::TrajectoryBuild moving =
      planner::buildTrajectory(scene, config::constraintSettings(d.job), roll, thetas, branch);
  ASSERT_TRUE(moving.ok) << moving.reason;
  const auto& q = moving.trajectory.samples;
  for (std::size_t k = 0; k < q.size(); ++k) {
    EXPECT_TRUE(d.cell.robot.withinLimits(q[k].q)) << k;
    if (k > 0) {
      EXPECT_LT((q[k].q - q[k - 1].q).cwiseAbs().maxCoeff(), deg(10.0)) << k;
    }
  }
  // Joints 1–5 are the IK's throughout: the flange sits where planned, only rolled about z.
  for (std::size_t k = 0; k < q.size(); k += 10) {
    const Eigen::Isometry3d want = d.cell.flangeTarget(theta, roll.samples[k].X_PS);
    const Eigen::Isometry3d got = d.cell.robot.fk(q[k].q);
    EXPECT_LT((got.translation() - want.translation()).norm(), 1e-9) << k;
    EXPECT_LT((got.linear().col(2) - want.linear().col(2)).norm(), 1e-9) << k;
  }
  for (auto& s : roll.samples) s.scanning = true;
  const planner::TrajectoryBuild scanning =
      planner::buildTrajectory(scene, config::constraintSettings(d.job), roll, thetas, branch);
  EXPECT_FALSE(scanning.ok);
  EXPECT_NE(scanning.reason.find("joint 6 would have to pass its limit"), std::string::npos)
      << scanning.reason;
}

// The unwinding turns joint 6 evenly over the stretch; where the joint itself swings towards the
// other limit first, the evenly unwound values would leave the limits there: the track breaks
// instead (before, it was kept with those samples outside the limits).
TEST(BuildTrajectory, UnwindingThatWouldLeaveTheLimitsBreaksTheTrack) {
  const DemoPlan d = demo();
  const collision::Scene scene(d.cell, config::clearanceConfig(d.job));
  const Eigen::Isometry3d X0 = d.path.path.samples.front().X_PS;
  const kinematics::IkBranch branch = *config::parseBranch("RIGHTY ABOVE NOFLIP");
  const auto [theta, q0] = reachableOn(d, X0, branch);
  ASSERT_GE(theta, 0.0);
  // Which way joint 6 turns as the head rolls about z_S.
  const auto rolled = [&](double r) {
    Eigen::Isometry3d X = X0;
    X.linear() = X0.linear() * Eigen::AngleAxisd(r, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    return X;
  };
  const Eigen::Isometry3d X_small = d.cell.flangeTarget(theta, rolled(deg(1.0)));
  double sign = 0.0;
  for (const auto& s : d.cell.robot.ik(X_small))
    if (s.branch == branch && std::abs(s.q(0) - q0(0)) < deg(1.0)) {
      sign = kinematics::unwrapNear(s.q, q0)(5) > q0(5) ? 1.0 : -1.0;
    }
  ASSERT_NE(sign, 0.0);
  // Over 30 s (not scanning after t = 0): joint 6 swings to 10° short of its limit one way in
  // 10 s, then back and past the other limit, where the equivalent a turn away is inside.
  const auto& j6 = d.cell.robot.joint(5);
  const double near_end = sign > 0.0 ? j6.min + deg(10.0) : j6.max - deg(10.0);
  const double dip = (near_end - q0(5)) * sign;                    // roll angle to get there
  const double climb = (j6.max - j6.min) - deg(10.0) + deg(15.0);  // past the far limit by 15°
  kinematics::ScanPath roll;
  roll.dt = 0.1;
  for (int k = 0; k <= 300; ++k) {
    const double t = 0.1 * k;
    const double r = t <= 10.0 ? dip * t / 10.0 : dip + climb * (t - 10.0) / 20.0;
    roll.samples.push_back({t, rolled(r), k == 0});
  }
  const std::vector<double> thetas(roll.samples.size(), theta);
  const planner::TrajectoryBuild built =
      planner::buildTrajectory(scene, config::constraintSettings(d.job), roll, thetas, branch);
  for (const auto& s : built.trajectory.samples) {
    EXPECT_TRUE(d.cell.robot.withinLimits(s.q)) << s.t;
  }
  EXPECT_FALSE(built.ok);
  EXPECT_NE(built.reason.find("joint 6 would have to pass its limit"), std::string::npos)
      << built.reason;
}

// Robustness catalogue: a 5 MB first line was quoted whole in the message.
TEST(TrajectoryCsv, LongLinesAreClippedInMessages) {
  try {
    kinematics::parseTrajectoryCsv(std::string(5 << 20, '1') + "\n", "t.csv");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_LT(std::string(e.what()).size(), 400u);
    EXPECT_NE(std::string(e.what()).find("characters"), std::string::npos) << e.what();
  }
}

}  // namespace
