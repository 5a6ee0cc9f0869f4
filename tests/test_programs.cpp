// Robot programs (DESIGN.md §7): golden files of every format on a small hand-built trajectory,
// the CSV and V+ round trips to the printed precision (and validation of what is read back), the
// V+ and KRL speed settings against the planned timing, each language's structure, and bad
// input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "cli/config/job.h"
#include "cli/programs/programs.h"
#include "collision/scene.h"
#include "kinematics/error.h"
#include "kinematics/trajectory.h"
#include "kinematics/units.h"
#include "planner/validation.h"
#include "test_support.h"

namespace {

using namespace scanplan;
using cli::ProgramFiles;
using cli::ProgramFormat;
using cli::ProgramOptions;
using kinematics::JointVector;
using kinematics::RobotModel;
using kinematics::Trajectory;
using kinematics::TrajectorySample;
namespace fs = std::filesystem;

// The programs print degrees, times and table angles with 6 decimals: a value read back is
// within half a unit of the last place (plus the double rounding of the conversions).
constexpr double kPrintedTol = 5e-7 + 1e-9;  // deg or s
// Planned times are sums of doubles: a percentage may pass a rounding step by this much.
constexpr double kRateTol = 1e-9;

std::string readFile(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Compares `actual` with tests/golden/<name>, or rewrites it under SCANPLAN_UPDATE_GOLDEN=1.
::testing::AssertionResult matchesGolden(const std::string& actual, const std::string& name) {
  const fs::path file = test::sourceDir() / "tests/golden" / name;
  const char* update = std::getenv("SCANPLAN_UPDATE_GOLDEN");
  if (update != nullptr && std::string(update) == "1") {
    fs::create_directories(file.parent_path());
    std::ofstream(file, std::ios::binary) << actual;
    return ::testing::AssertionSuccess() << "rewrote " << file;
  }
  if (!fs::exists(file)) {
    return ::testing::AssertionFailure()
           << file << " is missing: run with SCANPLAN_UPDATE_GOLDEN=1 to create it";
  }
  const std::string expected = readFile(file);
  if (actual == expected) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "output differs from " << file << "\n--- expected\n"
                                       << expected << "--- actual\n"
                                       << actual << "(SCANPLAN_UPDATE_GOLDEN=1 rewrites the file)";
}

JointVector jointsDeg(double q1, double q2, double q3, double q4, double q5, double q6) {
  JointVector q;
  q << deg(q1), deg(q2), deg(q3), deg(q4), deg(q5), deg(q6);
  return q;
}

TrajectorySample sample(double t, double theta_deg, const JointVector& q, bool scanning) {
  TrajectorySample s;
  s.t = t;
  s.theta = deg(theta_deg);
  s.q = q;
  s.scanning = scanning;
  s.f = 0.5;
  return s;
}

// Five samples 0.1 s apart on the Viper: the table crosses 360° at 20°/s; the last step turns
// J6 by 70° (700°/s > its 600°/s), which every program must flag.
Trajectory smallTrajectory() {
  Trajectory tr;
  tr.samples = {
      sample(0.0, 356.0, jointsDeg(10.0, -60.0, 150.0, 20.0, 45.0, 30.0), false),
      sample(0.1, 358.0, jointsDeg(12.0, -61.5, 151.25, 20.0, 44.0, 31.0), true),
      sample(0.2, 360.0, jointsDeg(14.5, -63.0, 152.5, 19.5, 43.0, 32.0), true),
      sample(0.3, 362.0, jointsDeg(17.0, -64.0, 153.0, 19.0, 42.0, 33.123456789), true),
      sample(0.4, 364.0, jointsDeg(17.0, -64.0, 153.0, 19.0, 42.0, 103.123456789), false),
  };
  return tr;
}

// A random walk of n samples 0.1 s apart within the Viper's limits, the table turning past
// 360° (unwrapped); every 50th step (k = 25, 75, …) asks joint 2 for 1.0 … 1.6× its maximum speed.
Trajectory randomTrajectory(const RobotModel& robot, std::mt19937& rng, std::size_t n) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Trajectory tr;
  JointVector q = jointsDeg(0.0, -60.0, 150.0, 0.0, 45.0, 0.0);
  double theta = deg(300.0);
  for (std::size_t k = 0; k < n; ++k) {
    if (k > 0) {
      for (int j = 0; j < kinematics::kNumJoints; ++j) {
        const double step = 0.1 * robot.joint(j).max_speed * 0.3 * u(rng);  // ≤ 30 %
        q(j) = std::clamp(q(j) + step, robot.joint(j).min + 0.2, robot.joint(j).max - 0.2);
      }
      if (k % 50 == 25) q(1) += (q(1) > 0.0 ? -1.0 : 1.0) * 1.3 * 0.1 * robot.joint(1).max_speed;
      theta += deg(2.0) * (1.0 + 0.5 * u(rng));
    }
    TrajectorySample s;
    s.t = 0.1 * static_cast<double>(k);
    s.theta = theta;
    s.q = q;
    s.scanning = k % 7 != 0;
    tr.samples.push_back(s);
  }
  return tr;
}

const std::string& content(const ProgramFiles& files, const std::string& name) {
  for (const auto& [file, text] : files.files) {
    if (file == name) return text;
  }
  static const std::string none;
  ADD_FAILURE() << "no file " << name;
  return none;
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

std::vector<double> numbers(const std::string& text) {
  static const std::regex number(R"([-+]?[0-9]+\.?[0-9]*(?:[eE][-+]?[0-9]+)?)");
  std::vector<double> out;
  for (std::sregex_iterator it(text.begin(), text.end(), number), end; it != end; ++it) {
    out.push_back(std::stod(it->str()));
  }
  return out;
}

::testing::AssertionResult sameToPrintedPrecision(const Trajectory& read,
                                                  const Trajectory& written) {
  if (read.samples.size() != written.samples.size()) {
    return ::testing::AssertionFailure()
           << read.samples.size() << " samples read, " << written.samples.size() << " written";
  }
  for (std::size_t k = 0; k < read.samples.size(); ++k) {
    const TrajectorySample &a = read.samples[k], &b = written.samples[k];
    const double dq = toDeg((a.q - b.q).cwiseAbs().maxCoeff());
    if (std::abs(a.t - b.t) > kPrintedTol || std::abs(toDeg(a.theta - b.theta)) > kPrintedTol ||
        dq > kPrintedTol || a.scanning != b.scanning) {
      return ::testing::AssertionFailure()
             << "sample " << k << ": t " << a.t << " vs " << b.t << ", table " << toDeg(a.theta)
             << " vs " << toDeg(b.theta) << " deg, joints differ by " << dq << " deg, scanning "
             << a.scanning << " vs " << b.scanning;
    }
  }
  return ::testing::AssertionSuccess();
}

class Programs : public ::testing::Test {
 protected:
  const RobotModel viper_ = test::bundledRobot("viper_s650");
};

TEST(ProgramFormatNames, ParseEveryNameAndRejectOthers) {
  for (const std::string& name : cli::programFormatNames()) {
    const auto format = cli::parseProgramFormat(name);
    ASSERT_TRUE(format) << name;
    EXPECT_EQ(cli::programFormatName(*format), name);
  }
  EXPECT_EQ(cli::parseProgramFormat("VPlus"), ProgramFormat::kVplus);
  EXPECT_FALSE(cli::parseProgramFormat("v+"));
  EXPECT_FALSE(cli::parseProgramFormat(""));
}

TEST_F(Programs, EveryFormatMatchesItsGoldenFiles) {
  ProgramOptions options;
  options.name = "scan";
  options.job = "golden";
  options.table_max_speed = deg(30.0);
  const Trajectory tr = smallTrajectory();
  for (const std::string& name : cli::programFormatNames()) {
    const ProgramFiles files =
        cli::writeProgram(tr, viper_, *cli::parseProgramFormat(name), options);
    ASSERT_FALSE(files.files.empty()) << name;
    EXPECT_EQ(files.over_speed_segments, 1u) << name;
    // J6: 70° in 0.1 s of 600°/s.
    EXPECT_NEAR(files.max_speed_percent, 100.0 * 700.0 / 600.0, 1e-6) << name;
    for (const auto& [file, text] : files.files) {
      EXPECT_TRUE(matchesGolden(text, "programs/" + file)) << name;
    }
  }
}

TEST_F(Programs, EachLanguageBeginsEndsAndMovesOncePerSample) {
  std::mt19937 rng(11);
  const Trajectory tr = randomTrajectory(viper_, rng, 40);
  const std::size_t n = tr.samples.size();
  ProgramOptions options;
  options.name = "3D part #1";

  const ProgramFiles vplus = cli::writeProgram(tr, viper_, ProgramFormat::kVplus, options);
  ASSERT_EQ(vplus.files.size(), 2u);
  EXPECT_EQ(vplus.files[0].first, "p3d_part__1.v2");
  EXPECT_EQ(vplus.files[1].first, "p3d_part__1_table.csv");
  const std::string& v2 = vplus.files[0].second;
  EXPECT_EQ(v2.rfind(".PROGRAM p3d_part__1()\n", 0), 0u) << v2.substr(0, 80);
  EXPECT_TRUE(v2.ends_with("    BREAK\n.END\n"));
  EXPECT_EQ(count(v2, "MOVE #PPOINT("), n);
  EXPECT_EQ(count(v2, "; t="), n);
  EXPECT_EQ(count(v2, "\n    DURATION "), n - 1);
  EXPECT_NE(v2.find("\n; Start configuration: " + viper_.branchOf(tr.samples[0].q).words()),
            std::string::npos);
  EXPECT_EQ(lines(vplus.files[1].second).size(), 4 + n);  // 3 comment lines, header, rows

  const ProgramFiles krl = cli::writeProgram(tr, viper_, ProgramFormat::kKrl, options);
  const std::string& src = content(krl, "p3D_part__1.src");
  EXPECT_EQ(src.rfind("DEF p3D_part__1( )\n", 0), 0u);
  EXPECT_EQ(count(src, "\n  PTP {A1 "), n);
  EXPECT_EQ(count(src, ", E1 "), n);
  EXPECT_EQ(count(src, "} C_PTP\n"), n - 2);  // the first and the last stop exactly
  EXPECT_EQ(count(src, "\n  SCANPLAN_VEL("), n);
  EXPECT_EQ(count(src, "\nEND\n"), 2u);  // the program and its velocity subroutine
  EXPECT_TRUE(src.ends_with("END\n"));

  const ProgramFiles rapid = cli::writeProgram(tr, viper_, ProgramFormat::kRapid, options);
  const std::string& mod = content(rapid, "p3D_part__1.mod");
  EXPECT_EQ(mod.rfind("MODULE MOD_p3D_part__1\n", 0), 0u);
  EXPECT_NE(mod.find("\n  PROC p3D_part__1()\n"), std::string::npos);
  EXPECT_TRUE(mod.ends_with("  ENDPROC\nENDMODULE\n"));
  EXPECT_EQ(count(mod, "MoveAbsJ [["), n);
  EXPECT_EQ(count(mod, ",9E9,9E9,9E9,9E9,9E9]]\\NoEOffs, "), n);
  EXPECT_EQ(count(mod, "v1000\\T:=0.100000, "), n - 1);
  EXPECT_EQ(count(mod, ", fine, tool0;\n"), 2u);

  const ProgramFiles ur = cli::writeProgram(tr, viper_, ProgramFormat::kUrscript, options);
  const std::string& script = content(ur, "p3D_part__1.script");
  EXPECT_EQ(script.rfind("def p3D_part__1():\n", 0), 0u);
  EXPECT_TRUE(script.ends_with("\nend\n"));
  EXPECT_EQ(count(script, "\n  movej(["), n);
  EXPECT_EQ(count(script, ", t=0.100000, r=0)\n"), n - 1);
  EXPECT_EQ(count(script, "\n  table_move("), n - 1);
  EXPECT_EQ(count(script, "\n  table_start("), 1u);

  const ProgramFiles csv = cli::writeProgram(tr, viper_, ProgramFormat::kCsv, options);
  ASSERT_EQ(csv.files.size(), 1u);
  EXPECT_EQ(csv.files[0].first, "p3D_part__1.csv");
  EXPECT_EQ(csv.files[0].second, kinematics::trajectoryToCsv(tr));
}

// URScript takes radians: the movej joints are the trajectory's q to 9 decimals.
TEST_F(Programs, UrscriptJointsAreRadians) {
  const Trajectory tr = smallTrajectory();
  const ProgramFiles ur = cli::writeProgram(tr, viper_, ProgramFormat::kUrscript, {});
  const std::string& script = content(ur, "scan.script");
  std::size_t k = 0;
  for (const std::string& line : lines(script)) {
    if (line.rfind("  movej([", 0) != 0) continue;
    const std::vector<double> v = numbers(line.substr(0, line.find(']')));
    ASSERT_EQ(v.size(), 6u) << line;
    for (int j = 0; j < kinematics::kNumJoints; ++j) {
      EXPECT_NEAR(v[static_cast<std::size_t>(j)], tr.samples[k].q(j), 5e-10) << line;
    }
    ++k;
  }
  EXPECT_EQ(k, tr.samples.size());
}

TEST_F(Programs, CsvAndVplusReadBackEqualToThePrintedPrecision) {
  std::mt19937 rng(7);
  const Trajectory tr = randomTrajectory(viper_, rng, 200);
  ASSERT_GT(toDeg(tr.samples.back().theta), 360.0 + 180.0);

  const ProgramFiles csv = cli::writeProgram(tr, viper_, ProgramFormat::kCsv, {});
  const Trajectory from_csv = kinematics::parseTrajectoryCsv(csv.files[0].second, "scan.csv");
  EXPECT_TRUE(sameToPrintedPrecision(from_csv, tr));

  const ProgramFiles vplus = cli::writeProgram(tr, viper_, ProgramFormat::kVplus, {});
  const Trajectory from_vplus = cli::readVplusProgram(vplus.files[0].second, "scan.v2");
  EXPECT_TRUE(sameToPrintedPrecision(from_vplus, tr));
  for (const TrajectorySample& s : from_vplus.samples) {
    EXPECT_TRUE(std::isnan(s.f));
    EXPECT_TRUE(s.X_PS.isApprox(Eigen::Isometry3d::Identity()));
    EXPECT_TRUE(s.limit.empty());
  }
  // The table list has the same angles as the program's comments.
  const std::vector<std::string> rows = lines(vplus.files[1].second);
  ASSERT_EQ(rows.size(), 4 + tr.samples.size());
  for (std::size_t k = 0; k < tr.samples.size(); ++k) {
    const std::vector<double> v = numbers(rows[4 + k]);
    ASSERT_EQ(v.size(), 3u) << rows[4 + k];
    EXPECT_NEAR(v[0], tr.samples[k].t, kPrintedTol);
    EXPECT_NEAR(v[1], toDeg(tr.samples[k].theta), kPrintedTol);
    EXPECT_EQ(v[2], tr.samples[k].scanning ? 1.0 : 0.0);
  }
}

// At each step's percentage of its maximum speed, the limiting joint covers its Δq in the planned
// Δt, and one rounding step less would not: the step takes its planned time as closely as the
// language's resolution allows (V+ SPEED: 0.01; KRL $VEL_AXIS: whole percent), never more than
// 100 %. A step needing more is capped at 100 and flagged.
::testing::AssertionResult speedReproducesTiming(const RobotModel& robot,
                                                 const TrajectorySample& a,
                                                 const TrajectorySample& b,
                                                 double dt,
                                                 double percent,
                                                 double resolution) {
  if (!(percent >= resolution - kRateTol && percent <= 100.0 + kRateTol)) {
    return ::testing::AssertionFailure() << percent << " % is out of range";
  }
  double needed = 0.0;
  for (int j = 0; j < kinematics::kNumJoints; ++j) {
    needed = std::max(needed, 100.0 * std::abs(b.q(j) - a.q(j)) / (dt * robot.joint(j).max_speed));
  }
  if (needed > 100.0) {
    if (std::abs(percent - 100.0) > kRateTol) {
      return ::testing::AssertionFailure() << "needs " << needed << " %, set " << percent;
    }
    return ::testing::AssertionSuccess();
  }
  const bool covers = percent >= needed * (1.0 - kRateTol);
  const bool smallest =
      percent - resolution < needed * (1.0 + kRateTol) || std::abs(percent - resolution) < kRateTol;
  if (covers && smallest) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "needs " << needed << " %, set " << percent << " (resolution " << resolution << ")";
}

TEST_F(Programs, VplusSpeedsReproduceThePlannedTiming) {
  std::mt19937 rng(3);
  const Trajectory tr = randomTrajectory(viper_, rng, 200);
  const ProgramFiles files = cli::writeProgram(tr, viper_, ProgramFormat::kVplus, {});
  EXPECT_EQ(files.over_speed_segments, 4u);  // k = 25, 75, 125, 175
  const std::string& text = files.files[0].second;
  EXPECT_EQ(count(text, "\n; WARNING: step "), files.over_speed_segments);
  std::vector<double> speed, duration;
  for (const std::string& line : lines(text)) {
    if (line.rfind("    SPEED ", 0) == 0) speed.push_back(std::stod(line.substr(10)));
    if (line.rfind("    DURATION ", 0) == 0) duration.push_back(std::stod(line.substr(13)));
  }
  ASSERT_EQ(speed.size(), tr.samples.size());
  ASSERT_EQ(duration.size(), tr.samples.size() - 1);
  EXPECT_EQ(speed[0], 10.0);  // the approach
  std::size_t at_100 = 0;
  for (std::size_t k = 1; k < tr.samples.size(); ++k) {
    const double dt = tr.samples[k].t - tr.samples[k - 1].t;
    EXPECT_NEAR(duration[k - 1], dt, kPrintedTol);
    EXPECT_TRUE(speedReproducesTiming(viper_, tr.samples[k - 1], tr.samples[k], dt, speed[k], 0.01))
        << "step " << k;
    at_100 += speed[k] == 100.0;
  }
  EXPECT_EQ(at_100, files.over_speed_segments);
}

TEST_F(Programs, KrlVelocitiesReproduceThePlannedTiming) {
  std::mt19937 rng(4);
  const Trajectory tr = randomTrajectory(viper_, rng, 200);
  const ProgramFiles files = cli::writeProgram(tr, viper_, ProgramFormat::kKrl, {});
  EXPECT_EQ(files.over_speed_segments, 4u);
  const std::string& text = files.files[0].second;
  EXPECT_EQ(count(text, "\n; WARNING: step "), files.over_speed_segments);
  std::vector<std::vector<double>> vel, ptp;
  for (const std::string& line : lines(text)) {
    if (line.rfind("  SCANPLAN_VEL(", 0) == 0) vel.push_back(numbers(line));
    if (line.rfind("  PTP {", 0) == 0) ptp.push_back(numbers(line));
  }
  ASSERT_EQ(vel.size(), tr.samples.size());
  ASSERT_EQ(ptp.size(), tr.samples.size());
  for (std::size_t k = 0; k < tr.samples.size(); ++k) {
    // "A1 x, A2 x, … A6 x, E1 x": axis numbers and values alternate.
    ASSERT_EQ(ptp[k].size(), 14u);
    for (int j = 0; j < kinematics::kNumJoints; ++j) {
      EXPECT_NEAR(ptp[k][static_cast<std::size_t>(2 * j + 1)], toDeg(tr.samples[k].q(j)),
                  kPrintedTol);
    }
    EXPECT_NEAR(ptp[k][13], toDeg(tr.samples[k].theta), kPrintedTol);  // E1, unwrapped
    ASSERT_EQ(vel[k].size(), 2u);
    if (k == 0) continue;
    const double dt = tr.samples[k].t - tr.samples[k - 1].t;
    EXPECT_EQ(vel[k][1], 100.0);  // the table's speed is unknown: E1 at 100 %
    EXPECT_EQ(vel[k][0], std::round(vel[k][0]));
    EXPECT_TRUE(speedReproducesTiming(viper_, tr.samples[k - 1], tr.samples[k], dt, vel[k][0], 1.0))
        << "step " << k;
  }
}

// With the table's maximum speed known, KRL drives E1 with the arm's percentage and the table
// can lead: 2°/step at 30°/s in 0.1 s needs 66.7 % → 67.
TEST_F(Programs, KrlTableCanLeadWhenItsSpeedIsKnown) {
  Trajectory tr;
  for (int k = 0; k < 3; ++k) {
    tr.samples.push_back(
        sample(0.1 * k, 2.0 * k, jointsDeg(0.1 * k, -60.0, 150.0, 0.0, 45.0, 0.0), true));
  }
  ProgramOptions options;
  options.table_max_speed = deg(30.0);
  const ProgramFiles files = cli::writeProgram(tr, viper_, ProgramFormat::kKrl, options);
  EXPECT_EQ(count(files.files[0].second, "\n  SCANPLAN_VEL(67, 67)\n"), 2u);
  EXPECT_NEAR(files.max_speed_percent, 200.0 / 3.0, 1e-9);
  EXPECT_EQ(files.over_speed_segments, 0u);
  options.table_max_speed = deg(15.0);  // now 133 %: flagged, capped
  const ProgramFiles fast = cli::writeProgram(tr, viper_, ProgramFormat::kKrl, options);
  EXPECT_EQ(fast.over_speed_segments, 2u);
  EXPECT_EQ(count(fast.files[0].second, "\n  SCANPLAN_VEL(100, 100)\n"), 2u);
  EXPECT_EQ(count(fast.files[0].second, "of the table's maximum speed"), 2u);
}

// The seed's point (§7.3): a program is checked before it is sent. A smooth motion in the demo
// cell, written as CSV and V+ and read back, passes validation like the plan itself.
TEST(ProgramsValidate, ReadBackProgramsPassValidation) {
  const cli::JobSpec job = cli::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml",
                                        {"scan.dt_s=0.2", "map.angle_step_deg=2"});
  const kinematics::CellModel cell = cli::buildCell(job);
  const collision::Scene scene(cell, cli::clearanceConfig(job));
  Trajectory tr;
  for (int k = 0; k <= 20; ++k) {
    const double t = 0.1 * k;
    // The folded home pose (scanner down) turning J1 at 5°/s; the table θ = 0.1·t²:
    // α = 0.2 rad/s² < 60°/s², ω ≤ 0.4 rad/s < 30°/s.
    tr.samples.push_back(sample(t, toDeg(0.1 * t * t),
                                jointsDeg(-90.0 + 5.0 * t, -90.0, 180.0, 0.0, 90.0, 0.0), true));
  }
  const planner::ValidationSettings settings{.sample_dt = 0.01};
  ASSERT_TRUE(planner::validateTrajectory(scene, tr, settings).valid);

  ProgramOptions options;
  options.table_max_speed = cell.table.max_speed;
  for (const ProgramFormat format : {ProgramFormat::kCsv, ProgramFormat::kVplus}) {
    const ProgramFiles files = cli::writeProgram(tr, cell.robot, format, options);
    EXPECT_EQ(files.over_speed_segments, 0u);
    const Trajectory back = format == ProgramFormat::kCsv
                                ? kinematics::parseTrajectoryCsv(files.files[0].second, "scan.csv")
                                : cli::readVplusProgram(files.files[0].second, "scan.v2");
    EXPECT_TRUE(sameToPrintedPrecision(back, tr));
    const planner::ValidationReport report = planner::validateTrajectory(scene, back, settings);
    EXPECT_TRUE(report.valid) << cli::programFormatName(format) << ": "
                              << (report.violations.empty()
                                      ? std::string()
                                      : planner::describe(report.violations.front()));
  }
}

TEST_F(Programs, EmptyOrBackwardsTrajectoryIsAnInputError) {
  for (const std::string& name : cli::programFormatNames()) {
    const ProgramFormat format = *cli::parseProgramFormat(name);
    EXPECT_THROW(cli::writeProgram(Trajectory{}, viper_, format, {}), InputError) << name;
    Trajectory backwards = smallTrajectory();
    backwards.samples[2].t = backwards.samples[1].t;
    try {
      cli::writeProgram(backwards, viper_, format, {});
      ADD_FAILURE() << name << ": no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("sample 2"), std::string::npos) << e.what();
    }
  }
  ProgramOptions bad;
  bad.approach_speed_percent = 0.0;
  EXPECT_THROW(cli::writeProgram(smallTrajectory(), viper_, ProgramFormat::kVplus, bad),
               InputError);
}

TEST_F(Programs, MalformedVplusNamesTheLine) {
  const std::string good =
      cli::writeProgram(smallTrajectory(), viper_, ProgramFormat::kVplus, {}).files[0].second;
  ASSERT_NO_THROW(cli::readVplusProgram(good, "scan.v2"));
  const std::vector<std::string> original = lines(good);
  // The line of the n-th occurrence of `prefix` (1-based line numbers).
  const auto lineOf = [&](const std::string& prefix, int n) {
    for (std::size_t i = 0; i < original.size(); ++i) {
      if (original[i].rfind(prefix, 0) == 0 && --n == 0) return i + 1;
    }
    ADD_FAILURE() << "no " << prefix;
    return std::size_t{0};
  };
  struct Case {
    std::string what;
    std::size_t line;  // 1-based, replaced by `text` (or dropped when text is empty)
    std::string text;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"truncated move", lineOf("    MOVE", 3), "    MOVE #PPOINT(1.0, 2.0, 3.0",
       "expected 'MOVE #PPOINT(j1, j2, j3, j4, j5, j6)'"},
      {"five joints", lineOf("    MOVE", 2), "    MOVE #PPOINT(1, 2, 3, 4, 5)",
       "5 joint values: expected 6"},
      {"not a number", lineOf("    MOVE", 4), "    MOVE #PPOINT(1, 2, x, 4, 5, 6)",
       "joint 3 'x' is not a finite number"},
      {"absurd joint", lineOf("    MOVE", 4), "    MOVE #PPOINT(1, 2, 1e300, 4, 5, 6)",
       "joint 3 1e+300 deg: expected an angle within ±1000000 deg"},
      {"absurd table angle", lineOf("; t=", 2), "; t=0.1 s table=5e6 deg scan=1",
       "table=5e6 deg: expected an angle within ±1000000 deg"},
      {"bad step comment", lineOf("; t=", 2), "; t=0.1 s table=abc deg scan=1",
       "expected '; t=<s> s table=<deg> deg scan=<0|1>'"},
      {"time backwards", lineOf("; t=", 3), "; t=0.050000 s table=360.0 deg scan=1",
       "not after the previous step's 0.100000 s"},
      {"unknown instruction", lineOf("    SPEED", 2), "    SPEEED 50",
       "not an instruction this reader knows"},
      {"bad speed", lineOf("    SPEED", 2), "    SPEED fast", "expected 'SPEED <value> [ALWAYS]'"},
      {"move without comment", lineOf("; t=", 2), "; a plain comment",
       "MOVE without its step comment"},
      // 30 kB in one line overflowed std::regex's recursion (exit 139) before the bound.
      {"huge move line", lineOf("    MOVE", 2),
       "    MOVE #PPOINT(" + std::string(30000, ' ') + "1, 2, 3, 4, 5, 6)",
       "… (30034 characters)': expected a line of at most 1000 characters"},
      {"long non-matching line", lineOf("    MOVE", 2), "    MOVE #PPOINT(" + std::string(900, '1'),
       "expected 'MOVE #PPOINT(j1, j2, j3, j4, j5, j6)'"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> edited = original;
    edited[c.line - 1] = c.text;
    std::string text;
    for (const std::string& line : edited) text += line + "\n";
    try {
      cli::readVplusProgram(text, "scan.v2");
      ADD_FAILURE() << c.what << ": no error";
    } catch (const InputError& e) {
      const std::string message = e.what();
      const std::size_t expected_line = c.what == "move without comment"
                                            ? lineOf("    MOVE", 2)  // the MOVE it belonged to
                                            : c.line;
      EXPECT_EQ(message.rfind("scan.v2:" + std::to_string(expected_line) + ": ", 0), 0u)
          << c.what << ": " << message;
      EXPECT_NE(message.find(c.message), std::string::npos) << c.what << ": " << message;
      EXPECT_LT(message.size(), 400u) << c.what << ": the line is echoed clipped";
    }
  }
  // Whole-file errors.
  const auto error = [](const std::string& text) {
    try {
      cli::readVplusProgram(text, "x.v2");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("").find("x.v2:0: no '.PROGRAM name()' line"), std::string::npos) << error("");
  EXPECT_NE(error("    MOVE #PPOINT(1,2,3,4,5,6)\n").find("x.v2:1: "), std::string::npos);
  const std::string no_end = good.substr(0, good.rfind(".END"));
  EXPECT_NE(error(no_end).find("has no .END"), std::string::npos) << error(no_end);
  EXPECT_NE(error(".PROGRAM a()\n.END\n").find("x.v2:2: no MOVE"), std::string::npos);
  EXPECT_NE(error(".PROGRAM a()\n; t=0 s table=0 deg scan=0\n.END\n")
                .find("x.v2:2: step comment without its MOVE"),
            std::string::npos);
}

}  // namespace
