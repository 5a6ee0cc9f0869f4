// Robot programs (docs/design.md §7): golden files of every format on a small hand-built
// trajectory, the CSV and V+ round trips to the printed precision (and validation of what is read
// back), the V+ and KRL speed settings against the planned timing, each language's structure, and
// bad input.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <scanplan/collision/scene.h>
#include <scanplan/config/job.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/trajectory.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/planner/validation.h>
#include <scanplan/programs/detail/program_text.h>
#include <scanplan/programs/programs.h>
#include "test_support.h"

namespace {

using namespace scanplan;
using kinematics::JointVector;
using kinematics::RobotModel;
using kinematics::Trajectory;
using kinematics::TrajectorySample;
using programs::ProgramFiles;
using programs::ProgramFormat;
using programs::ProgramOptions;
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

const std::string& content(const programs::ProgramFiles& files, const std::string& name) {
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

// KRL's times come from TIME_BLOCK PARTs (percent, 6 decimals, REAL on the controller): over a
// block of hundreds of steps they add up to a few 1e-7 s, beyond the printed times' 5e-7 s.
constexpr double kKrlTimeTol = 1e-5;  // s

::testing::AssertionResult sameToPrintedPrecision(const Trajectory& read,
                                                  const Trajectory& written,
                                                  double time_tol = kPrintedTol) {
  if (read.samples.size() != written.samples.size()) {
    return ::testing::AssertionFailure()
           << read.samples.size() << " samples read, " << written.samples.size() << " written";
  }
  for (std::size_t k = 0; k < read.samples.size(); ++k) {
    const TrajectorySample &a = read.samples[k], &b = written.samples[k];
    const double dq = toDeg((a.q - b.q).cwiseAbs().maxCoeff());
    if (std::abs(a.t - b.t) > time_tol || std::abs(toDeg(a.theta - b.theta)) > kPrintedTol ||
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
  for (const std::string& name : programs::programFormatNames()) {
    const auto format = programs::parseProgramFormat(name);
    ASSERT_TRUE(format) << name;
    EXPECT_EQ(programs::programFormatName(*format), name);
  }
  EXPECT_EQ(programs::parseProgramFormat("VPlus"), programs::ProgramFormat::kVplus);
  EXPECT_FALSE(programs::parseProgramFormat("v+"));
  EXPECT_FALSE(programs::parseProgramFormat(""));
}

TEST_F(Programs, EveryFormatMatchesItsGoldenFiles) {
  programs::ProgramOptions options;
  options.name = "scan";
  options.job = "golden";
  options.table_max_speed = deg(30.0);
  options.tool.translation() = Eigen::Vector3d(0.0, 0.02, 0.11);
  options.tool.linear() = Eigen::AngleAxisd(deg(90.0), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  options.payload_kg = 0.9;
  options.payload_cog = Eigen::Vector3d(0.05, 0.0, 0.085);
  options.trigger.output = 3;
  options.table_endless = true;
  options.servo_period = 0.05;  // a short golden file
  const Trajectory tr = smallTrajectory();
  for (const std::string& name : programs::programFormatNames()) {
    const programs::ProgramFiles files =
        programs::writeProgram(tr, viper_, *programs::parseProgramFormat(name), options);
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
  programs::ProgramOptions options;
  options.name = "3D part #1";

  const programs::ProgramFiles vplus =
      programs::writeProgram(tr, viper_, programs::ProgramFormat::kVplus, options);
  ASSERT_EQ(vplus.files.size(), 2u);
  EXPECT_EQ(vplus.files[0].first, "p3d_part__1.v2");
  EXPECT_EQ(vplus.files[1].first, "p3d_part__1_table.csv");
  // A plain CSV: the header row first, no comment lines a CSV reader would take for data.
  EXPECT_EQ(vplus.files[1].second.rfind("t_s,table_deg,scanning\n", 0), 0u);
  EXPECT_EQ(count(vplus.files[1].second, "#"), 0u);
  const std::string& v2 = vplus.files[0].second;
  EXPECT_EQ(v2.rfind(".PROGRAM p3d_part__1()\n", 0), 0u) << v2.substr(0, 80);
  EXPECT_TRUE(v2.ends_with("    BREAK\n.END\n"));
  EXPECT_EQ(count(v2, "MOVE #PPOINT("), n);
  EXPECT_EQ(count(v2, "; t="), n);
  EXPECT_EQ(count(v2, "\n    DURATION "), n - 1);
  EXPECT_NE(v2.find("\n; Start configuration: " + viper_.branchOf(tr.samples[0].q).words()),
            std::string::npos);
  EXPECT_EQ(lines(vplus.files[1].second).size(), 1 + n);  // the header row, then the rows

  const programs::ProgramFiles krl =
      programs::writeProgram(tr, viper_, programs::ProgramFormat::kKrl, options);
  const std::string& src = content(krl, "p3D_part__1.src");
  EXPECT_EQ(src.rfind("DEF p3D_part__1( )\n", 0), 0u);
  EXPECT_EQ(count(src, "\n  PTP {A1 "), 1u);  // the approach, then one SPTP per step
  EXPECT_EQ(count(src, "\n    SPTP {A1 "), n - 1);
  EXPECT_EQ(count(src, ", E1 "), n);
  EXPECT_EQ(count(src, "\n  PTP_SPLINE\n    TIME_BLOCK START\n"), 1u);
  EXPECT_EQ(count(src, "\n    TIME_BLOCK END="), 1u);
  EXPECT_EQ(count(src, "\n  ENDSPLINE\n"), 1u);
  EXPECT_EQ(count(src, "\n  $TOOL={X "), 1u);
  EXPECT_EQ(count(src, "\nEND\n"), 2u);  // the program and its velocity subroutine
  EXPECT_TRUE(src.ends_with("END\n"));

  const programs::ProgramFiles rapid =
      programs::writeProgram(tr, viper_, programs::ProgramFormat::kRapid, options);
  const std::string& mod = content(rapid, "p3D_part__1.mod");
  EXPECT_EQ(mod.rfind("MODULE MOD_p3D_part__1\n", 0), 0u);
  EXPECT_NE(mod.find("\n  PROC p3D_part__1()\n"), std::string::npos);
  EXPECT_NE(mod.find("\n  PROC main()\n    p3D_part__1;\n  ENDPROC\n"), std::string::npos);
  EXPECT_TRUE(mod.ends_with("  ENDPROC\nENDMODULE\n"));
  EXPECT_EQ(count(mod, "MoveAbsJ [["), n);
  EXPECT_EQ(count(mod, ",9E9,9E9,9E9,9E9,9E9]]\\NoEOffs, "), n);
  EXPECT_EQ(count(mod, "v1000\\T:=0.100000, "), n - 1);
  EXPECT_EQ(count(mod, ", fine, tool0;\n"), 2u);

  const programs::ProgramFiles ur =
      programs::writeProgram(tr, viper_, programs::ProgramFormat::kUrscript, options);
  const std::string& script = content(ur, "p3D_part__1.script");
  EXPECT_EQ(script.rfind("def p3D_part__1():\n", 0), 0u);
  EXPECT_TRUE(script.ends_with("\nend\np3D_part__1()\n"));  // defined, then run
  EXPECT_EQ(count(script, "\n  movej(["), 1u);
  EXPECT_EQ(count(script, "\n  a = [0, "), 1u);                    // the start's row
  EXPECT_EQ(count(script, "\n  a = seg(a, ["), n - 1);             // a row per later sample
  EXPECT_EQ(count(script, "\n    table_move(d[1], d[0])\n"), 1u);  // in seg(), once per row
  EXPECT_EQ(programs::readProgram(script, programs::ProgramFormat::kUrscript, "p")
                .trajectory.samples.size(),
            static_cast<std::size_t>(std::round(tr.duration() / 0.008)) + 1);
  EXPECT_EQ(count(script, "\n  table_start("), 1u);
  EXPECT_EQ(count(script, "\n  set_tcp(p["), 1u);
  EXPECT_EQ(count(script, "\n  stopj("), 1u);

  const programs::ProgramFiles csv =
      programs::writeProgram(tr, viper_, programs::ProgramFormat::kCsv, options);
  ASSERT_EQ(csv.files.size(), 1u);
  EXPECT_EQ(csv.files[0].first, "p3D_part__1.csv");
  EXPECT_EQ(csv.files[0].second, kinematics::trajectoryToCsv(tr));
}

TEST_F(Programs, CsvAndVplusReadBackEqualToThePrintedPrecision) {
  std::mt19937 rng(7);
  const Trajectory tr = randomTrajectory(viper_, rng, 200);
  ASSERT_GT(toDeg(tr.samples.back().theta), 360.0 + 180.0);

  const programs::ProgramFiles csv =
      programs::writeProgram(tr, viper_, programs::ProgramFormat::kCsv, {});
  const Trajectory from_csv = kinematics::parseTrajectoryCsv(csv.files[0].second, "scan.csv");
  EXPECT_TRUE(sameToPrintedPrecision(from_csv, tr));

  const programs::ProgramFiles vplus =
      programs::writeProgram(tr, viper_, programs::ProgramFormat::kVplus, {});
  const Trajectory from_vplus = programs::readVplusProgram(vplus.files[0].second, "scan.v2");
  EXPECT_TRUE(sameToPrintedPrecision(from_vplus, tr));
  for (const TrajectorySample& s : from_vplus.samples) {
    EXPECT_TRUE(std::isnan(s.f));
    EXPECT_TRUE(s.X_PS.isApprox(Eigen::Isometry3d::Identity()));
    EXPECT_TRUE(s.limit.empty());
  }
  // The table list has the same angles as the program's comments.
  const std::vector<std::string> rows = lines(vplus.files[1].second);
  ASSERT_EQ(rows.size(), 1 + tr.samples.size());
  for (std::size_t k = 0; k < tr.samples.size(); ++k) {
    const std::vector<double> v = numbers(rows[1 + k]);
    ASSERT_EQ(v.size(), 3u) << rows[1 + k];
    EXPECT_NEAR(v[0], tr.samples[k].t, kPrintedTol);
    EXPECT_NEAR(v[1], toDeg(tr.samples[k].theta), kPrintedTol);
    EXPECT_EQ(v[2], tr.samples[k].scanning ? 1.0 : 0.0);
  }
}

// At each step's percentage of its maximum speed, the limiting joint covers its Δq in the planned
// Δt, and one rounding step less would not: the step takes its planned time as closely as the
// language's resolution allows (V+ SPEED: 0.01), never more than
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
  const programs::ProgramFiles files =
      programs::writeProgram(tr, viper_, programs::ProgramFormat::kVplus, {});
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

// KRL: TIME_BLOCK END and PART put every SPTP segment at its planned time; the joints and E1
// are the plan's (E1 as planned: the table is not endless here).
TEST_F(Programs, KrlTimeBlocksReproduceThePlannedTiming) {
  std::mt19937 rng(4);
  const Trajectory tr = randomTrajectory(viper_, rng, 200);
  const programs::ProgramFiles files =
      programs::writeProgram(tr, viper_, programs::ProgramFormat::kKrl, {});
  EXPECT_EQ(files.over_speed_segments, 4u);
  const std::string& text = files.files[0].second;
  EXPECT_EQ(count(text, "\n; WARNING: step "), files.over_speed_segments);
  EXPECT_EQ(count(text, "\n  PTP {"), 1u);
  EXPECT_EQ(count(text, "\n    SPTP {"), tr.samples.size() - 1);
  EXPECT_EQ(count(text, "\n    TIME_BLOCK PART="), tr.samples.size() - 1);
  const programs::ProgramReading back =
      programs::readProgram(text, programs::ProgramFormat::kKrl, "scan.src");
  EXPECT_TRUE(sameToPrintedPrecision(back.trajectory, tr, kKrlTimeTol));
}

// Past kKrlMaxSegments steps the motion goes into several PTP_SPLINE blocks, each ending where
// the scanner is not scanning (between passes), each timed on its own.
TEST_F(Programs, KrlSplitsLongMotionsIntoBlocksBetweenPasses) {
  std::mt19937 rng(5);
  const Trajectory tr = randomTrajectory(viper_, rng, 2 * programs::kKrlMaxSegments + 300);
  const std::string text =
      programs::writeProgram(tr, viper_, programs::ProgramFormat::kKrl, {}).files[0].second;
  const std::vector<std::string> all = lines(text);
  std::size_t segments = 0, blocks = 0;
  std::vector<std::size_t> ends;  // the sample each block ends at
  for (const std::string& line : all) {
    if (line == "  PTP_SPLINE") {
      ++blocks;
      segments = 0;
    }
    if (line.rfind("    SPTP {", 0) == 0) ++segments;
    if (line == "  ENDSPLINE") {
      EXPECT_LE(segments, programs::kKrlMaxSegments);
      ends.push_back(ends.empty() ? segments : ends.back() + segments);
    }
  }
  EXPECT_EQ(blocks, 3u);
  ASSERT_EQ(ends.size(), blocks);
  EXPECT_EQ(ends.back(), tr.samples.size() - 1);
  for (std::size_t b = 0; b + 1 < ends.size(); ++b) {
    EXPECT_FALSE(tr.samples[ends[b]].scanning) << "block " << b << " ends at " << ends[b];
  }
  const programs::ProgramReading back =
      programs::readProgram(text, programs::ProgramFormat::kKrl, "scan.src");
  EXPECT_TRUE(sameToPrintedPrecision(back.trajectory, tr, kKrlTimeTol));
}

// The plan's joints linearly at time t (the programs' path between samples).
JointVector plannedJoints(const Trajectory& tr, double t) {
  const auto& s = tr.samples;
  if (t <= s.front().t) return s.front().q;
  for (std::size_t k = 1; k < s.size(); ++k) {
    if (t <= s[k].t) {
      const double w = (t - s[k - 1].t) / (s[k].t - s[k - 1].t);
      return s[k - 1].q + w * (s[k].q - s[k - 1].q);
    }
  }
  return s.back().q;
}

// Controllers read programs in their own code page (KUKA: Windows-1252): every file is 7-bit
// ASCII, the header's symbols spelled out, even for a job named in another script.
TEST_F(Programs, EveryFileIsAsciiWhateverTheJobIsCalled) {
  std::mt19937 rng(12);
  const Trajectory tr = randomTrajectory(viper_, rng, 20);
  programs::ProgramOptions options;
  options.job = "Gehäuse · 3°";
  options.trigger.output = 1;
  options.payload_kg = 0.5;
  for (const programs::ProgramFormat format :
       {programs::ProgramFormat::kVplus, programs::ProgramFormat::kKrl,
        programs::ProgramFormat::kRapid, programs::ProgramFormat::kUrscript,
        programs::ProgramFormat::kCsv}) {
    const programs::ProgramFiles files = programs::writeProgram(tr, viper_, format, options);
    for (const auto& [name, content] : files.files) {
      const auto bad =
          std::find_if(content.begin(), content.end(), [](char ch) { return (ch & 0x80) != 0; });
      EXPECT_EQ(bad, content.end()) << name << " at byte " << (bad - content.begin());
    }
    if (format == programs::ProgramFormat::kKrl) {
      const std::string& src = files.files[0].second;
      EXPECT_NE(src.find("(A, B, C: Rz*Ry*Rx)"), std::string::npos);
      // The helper's declaration section holds its declarations only (no comment before them).
      EXPECT_NE(src.find("(ARM_PCT:IN, E1_PCT:IN)\n  INT ARM_PCT, E1_PCT, AXIS\n"),
                std::string::npos);
      EXPECT_NE(src.find("Geh?use * 3 deg"), std::string::npos);
    }
    // Read back, the same motion (the readers need no more than ASCII).
    if (format != programs::ProgramFormat::kCsv) {
      EXPECT_NO_THROW(programs::readProgram(files.files[0].second, format, "p"));
    }
  }
  EXPECT_EQ(programs::detail::asciiText("a\u2264b \u2192 c\u00b2 \u4e2d"), "a<=b -> c^2 ?");
}

// URScript: the program is defined, then run; it uses the current function names (UR's script
// manual marks set_digital_out and set_payload deprecated), and reads back the same.
TEST_F(Programs, UrscriptRunsWhatItDefinesWithCurrentFunctionNames) {
  std::mt19937 rng(9);
  const Trajectory tr = randomTrajectory(viper_, rng, 20);
  programs::ProgramOptions options;
  options.trigger.output = 2;
  options.payload_kg = 0.9;
  const std::string text =
      programs::writeProgram(tr, viper_, programs::ProgramFormat::kUrscript, options)
          .files[0]
          .second;
  ASSERT_EQ(text.rfind("def scan():\n", 0), 0u);
  const std::string tail = "\nend\nscan()\n";
  ASSERT_GE(text.size(), tail.size());
  EXPECT_EQ(text.substr(text.size() - tail.size()), tail);
  EXPECT_GT(count(text, "\n  set_standard_digital_out(2, "), 0u);
  EXPECT_EQ(count(text, "\n  set_target_payload(0.900, ["), 1u);
  EXPECT_EQ(count(text, "set_digital_out("), 0u);
  EXPECT_EQ(count(text, "set_payload("), 0u);
  const programs::ProgramReading back =
      programs::readProgram(text, programs::ProgramFormat::kUrscript, "p");
  EXPECT_NEAR(back.payload_kg, 0.9, 1e-12);
  EXPECT_FALSE(back.trajectory.samples.empty());
}

// URScript for a scan as long as the automatic demo's (2 800 samples over 448 s): within the
// size a controller loads, and read back it equals the plan at every planned sample to 0.01°.
TEST_F(Programs, UrscriptOfADemoLongScanFitsAndReadsBackToThePlan) {
  std::mt19937 rng(21);
  Trajectory tr = randomTrajectory(viper_, rng, 2800);
  for (TrajectorySample& s : tr.samples) s.t *= 1.6;
  programs::ProgramOptions options;
  options.trigger.output = 1;
  const std::string text =
      programs::writeProgram(tr, viper_, programs::ProgramFormat::kUrscript, options)
          .files[0]
          .second;
  EXPECT_LE(text.size(), programs::kUrscriptMaxBytes);
  EXPECT_TRUE(text.ends_with("\nend\nscan()\n"));
  const programs::ProgramReading back =
      programs::readProgram(text, programs::ProgramFormat::kUrscript, "scan.script");
  const Trajectory at = programs::atStepTimes(back);
  ASSERT_EQ(at.samples.size(), tr.samples.size());
  double worst = 0.0;
  for (std::size_t k = 0; k < tr.samples.size(); ++k) {
    EXPECT_NEAR(at.samples[k].t, tr.samples[k].t, 1e-6) << k;
    worst = std::max(worst, (at.samples[k].q - tr.samples[k].q).cwiseAbs().maxCoeff());
    worst = std::max(worst, std::abs(at.samples[k].theta - tr.samples[k].theta));
  }
  EXPECT_LT(worst, deg(0.01));
}

// URScript: movej to the first sample, then one data row per sample, which seg() plays as one
// servoj per controller period on the joint-linear path between the samples, in radians, ending
// at the last sample within a period.
TEST_F(Programs, UrscriptServoStepsFollowThePlannedPath) {
  std::mt19937 rng(6);
  const Trajectory tr = randomTrajectory(viper_, rng, 60);
  for (const double period : {0.008, 0.002, 0.03}) {
    programs::ProgramOptions options;
    options.servo_period = period;
    const std::string text =
        programs::writeProgram(tr, viper_, programs::ProgramFormat::kUrscript, options)
            .files[0]
            .second;
    const std::size_t steps =
        static_cast<std::size_t>(std::ceil((tr.duration() - tr.samples[0].t) / period - 1e-9));
    EXPECT_EQ(count(text, "\n  a = seg(a, ["), tr.samples.size() - 1) << period;
    EXPECT_EQ(count(text, "\n  movej(["), 1u);
    std::ostringstream t;
    t << std::fixed << std::setprecision(4) << period;
    EXPECT_EQ(count(text, "], t=" + t.str() + ", lookahead_time=0.03, gain=300)"), 2u);
    const programs::ProgramReading back =
        programs::readProgram(text, programs::ProgramFormat::kUrscript, "scan.script");
    ASSERT_EQ(back.trajectory.samples.size(), steps + 1);
    for (std::size_t i = 0; i < back.trajectory.samples.size(); ++i) {
      const TrajectorySample& b = back.trajectory.samples[i];
      EXPECT_NEAR(b.t, tr.samples[0].t + static_cast<double>(i) * period, 1e-9) << i;
      const JointVector want = plannedJoints(tr, std::min(b.t, tr.duration()));
      EXPECT_LT((b.q - want).cwiseAbs().maxCoeff(), 1e-8) << "servo step " << i;
    }
    EXPECT_LT((back.trajectory.samples.back().q - tr.samples.back().q).cwiseAbs().maxCoeff(), 1e-8);
    EXPECT_LT(back.trajectory.duration() - tr.duration(), period + 1e-9);
    EXPECT_GE(back.trajectory.duration() - tr.duration(), -1e-9);
  }
}

// The seed's point (§7.3): a program is checked before it is sent. A smooth motion in the demo
// cell, written in every format and read back, passes validation like the plan itself.
TEST(ProgramsValidate, ReadBackProgramsPassValidation) {
  const config::JobSpec job = config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml",
                                              {"scan.dt_s=0.2", "map.angle_step_deg=2"});
  const kinematics::CellModel cell = config::buildCell(job);
  const collision::Scene scene(cell, config::clearanceConfig(job));
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

  programs::ProgramOptions options;
  options.table_max_speed = cell.table.max_speed;
  for (const std::string& name : programs::programFormatNames()) {
    const programs::ProgramFormat format = *programs::parseProgramFormat(name);
    const programs::ProgramFiles files = programs::writeProgram(tr, cell.robot, format, options);
    EXPECT_EQ(files.over_speed_segments, 0u);
    // URScript's servo steps lie between the samples: checked at the step comments' times, where
    // the servo path cuts the table's corners by a fraction of its speed change times a period.
    // Read as `scanplan validate` reads it: with the cell's robot, whose joint speeds time V+
    // SPEED.
    const Trajectory back = programs::atStepTimes(
        programs::readProgram(files.files[0].second, format, name, &cell.robot));
    if (format != programs::ProgramFormat::kUrscript) {
      EXPECT_TRUE(sameToPrintedPrecision(back, tr)) << name;
    } else {
      ASSERT_EQ(back.samples.size(), tr.samples.size());
      for (std::size_t k = 0; k < tr.samples.size(); ++k) {
        EXPECT_NEAR(back.samples[k].t, tr.samples[k].t, 1e-9);
        EXPECT_NEAR(toDeg(back.samples[k].theta - tr.samples[k].theta), 0.0, 0.01) << k;
        EXPECT_LT(toDeg((back.samples[k].q - tr.samples[k].q).cwiseAbs().maxCoeff()), 1e-5) << k;
      }
    }
    const planner::ValidationReport report = planner::validateTrajectory(scene, back, settings);
    EXPECT_TRUE(report.valid) << programs::programFormatName(format) << ": "
                              << (report.violations.empty()
                                      ? std::string()
                                      : planner::describe(report.violations.front()));
  }
}

// The switches a trigger must make: on at each pass's first sample, off at its last.
std::vector<programs::TriggerSwitch> passSwitches(const Trajectory& tr,
                                                  int output,
                                                  bool on_at_start) {
  std::vector<programs::TriggerSwitch> out;
  const auto& s = tr.samples;
  for (std::size_t k = 0; k < s.size(); ++k) {
    if (!s[k].scanning || (k > 0 && s[k - 1].scanning)) continue;
    std::size_t last = k;
    while (last + 1 < s.size() && s[last + 1].scanning) ++last;
    if (last == k) continue;  // the random walks have no one-sample passes
    out.push_back({s[k].t, output, on_at_start});
    if (last + 1 < s.size()) out.push_back({s[last].t, output, !on_at_start});
  }
  return out;
}

// Every language sets the tool, the payload and the trigger, and reads back to them: the tool
// through each language's own angle convention (V+ Rz·Ry·Rz, KRL Rz·Ry·Rx, RAPID's quaternion,
// URScript's rotation vector, including their singular poses), the switches at each pass's first
// and last sample (URScript: at the servo step that reaches it), the output idle before and after.
TEST_F(Programs, EveryLanguageSetsToolPayloadAndTriggerAtThePasses) {
  std::mt19937 rng(8);
  const Trajectory ends_idle = randomTrajectory(viper_, rng, 120);
  ASSERT_FALSE(ends_idle.samples.back().scanning);
  Trajectory ends_scanning = ends_idle;  // a pass that runs to the end
  ends_scanning.samples.back().scanning = true;
  using Eigen::AngleAxisd;
  using Eigen::Vector3d;
  std::vector<Eigen::Matrix3d> rotations = {
      Eigen::Matrix3d::Identity(),
      AngleAxisd(M_PI, Vector3d::UnitX()).toRotationMatrix(),      // V+ pitch 180
      AngleAxisd(M_PI / 2, Vector3d::UnitY()).toRotationMatrix(),  // KRL B = 90
      AngleAxisd(-M_PI / 2, Vector3d::UnitY()).toRotationMatrix() *
          AngleAxisd(0.3, Vector3d::UnitX()).toRotationMatrix(),
      AngleAxisd(M_PI, Vector3d(1, 1, 0).normalized()).toRotationMatrix(),  // 180° about an axis
  };
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 5; ++i) {
    rotations.push_back(
        AngleAxisd(3.0 * u(rng), Vector3d(u(rng), u(rng), u(rng)).normalized()).toRotationMatrix());
  }
  int case_number = 0;
  for (const Eigen::Matrix3d& R : rotations) {
    programs::ProgramOptions options;
    options.tool.linear() = R;
    options.tool.translation() = Vector3d(0.0123, -0.0456, 0.1105);
    options.payload_kg = 1.25;
    options.payload_cog = Vector3d(0.01, -0.02, 0.075);
    options.trigger.output = 7;
    options.trigger.on_at_scan_start = case_number % 2 == 0;
    const Trajectory& tr = case_number++ % 3 == 0 ? ends_scanning : ends_idle;
    const std::vector<programs::TriggerSwitch> want =
        passSwitches(tr, 7, options.trigger.on_at_scan_start);
    ASSERT_GE(want.size(), 30u);
    for (const programs::ProgramFormat format :
         {programs::ProgramFormat::kVplus, programs::ProgramFormat::kKrl,
          programs::ProgramFormat::kRapid, programs::ProgramFormat::kUrscript}) {
      const std::string name = programs::programFormatName(format);
      const programs::ProgramFiles files = programs::writeProgram(tr, viper_, format, options);
      const programs::ProgramReading back =
          programs::readProgram(files.files[0].second, format, name);
      ASSERT_TRUE(back.tool) << name;
      EXPECT_LT((back.tool->linear() - R).cwiseAbs().maxCoeff(), 1e-7) << name << "\n" << R;
      EXPECT_LT((back.tool->translation() - options.tool.translation()).norm(), 1e-6) << name;
      if (format == programs::ProgramFormat::kVplus) {
        EXPECT_EQ(back.payload_kg, 0.0);  // V+ has no payload in kg: a comment
        EXPECT_NE(files.files[0].second.find("1.250 kg, centre of gravity (10.0, -20.0, 75.0) mm"),
                  std::string::npos);
      } else {
        EXPECT_NEAR(back.payload_kg, 1.25, 1e-9) << name;
        EXPECT_LT((back.payload_cog - options.payload_cog).norm(), 1e-6) << name;
      }
      // Idle first; then each pass's switches, every one a change (no output switched twice the
      // same way); idle last: after the last pass's end, or after the motion when it runs on.
      const bool runs_on = tr.samples.back().scanning;
      ASSERT_EQ(back.triggers.size(), want.size() + (runs_on ? 2 : 1)) << name;
      const bool idle = !options.trigger.on_at_scan_start;
      EXPECT_EQ(back.triggers.front().on, idle) << name;
      EXPECT_EQ(back.triggers.back().on, idle) << name;
      for (std::size_t i = 1; i < back.triggers.size(); ++i) {
        EXPECT_NE(back.triggers[i].on, back.triggers[i - 1].on) << name << " switch " << i;
      }
      if (runs_on) {
        EXPECT_NEAR(back.triggers.back().t, tr.duration(),
                    format == programs::ProgramFormat::kUrscript ? options.servo_period : 1e-6);
      }
      const double tol = format == programs::ProgramFormat::kUrscript ? options.servo_period : 1e-4;
      for (std::size_t i = 0; i < want.size(); ++i) {
        const programs::TriggerSwitch& got = back.triggers[i + 1];
        EXPECT_EQ(got.output, 7) << name;
        EXPECT_EQ(got.on, want[i].on) << name << " switch " << i;
        EXPECT_LE(got.t, want[i].t + 1e-6) << name << " switch " << i;
        EXPECT_GE(got.t, want[i].t - tol) << name << " switch " << i;
      }
    }
  }
}

// An endless table is written within (-180, 180] in every language and reads back as the same
// motion (the shorter way between steps), 360° multiples apart from the unwrapped plan.
TEST_F(Programs, AnEndlessTableIsWrittenWrappedAndReadsBackTheSameMotion) {
  std::mt19937 rng(9);
  const Trajectory tr = randomTrajectory(viper_, rng, 400);
  ASSERT_GT(toDeg(tr.samples.back().theta - tr.samples.front().theta), 360.0);
  programs::ProgramOptions options;
  options.table_endless = true;
  for (const programs::ProgramFormat format :
       {programs::ProgramFormat::kVplus, programs::ProgramFormat::kKrl,
        programs::ProgramFormat::kRapid, programs::ProgramFormat::kUrscript}) {
    const std::string name = programs::programFormatName(format);
    const programs::ProgramFiles files = programs::writeProgram(tr, viper_, format, options);
    if (format ==
        programs::ProgramFormat::kVplus) {  // the table list: every angle within (-180, 180]
      std::size_t rows = 0;
      for (const std::string& line : lines(files.files[1].second)) {
        if (line.empty() || line[0] == '#' || line[0] == 't') continue;
        const double table = numbers(line)[1];
        EXPECT_GT(table, -180.0) << line;
        EXPECT_LE(table, 180.0) << line;
        ++rows;
      }
      EXPECT_EQ(rows, tr.samples.size());
    }
    const programs::ProgramReading back =
        programs::readProgram(files.files[0].second, format, name);
    const double offset = back.trajectory.samples[0].theta - tr.samples[0].theta;
    EXPECT_NEAR(std::remainder(offset, 2.0 * M_PI), 0.0, 1e-8) << name;
    EXPECT_LT(std::abs(toDeg(back.trajectory.samples[0].theta)), 180.0 + 1e-9) << name;
    for (const TrajectorySample& b : back.trajectory.samples) {
      const double want = b.t <= tr.samples[0].t ? tr.samples[0].theta : [&] {
        for (std::size_t k = 1; k < tr.samples.size(); ++k) {
          if (b.t <= tr.samples[k].t + 1e-9) {
            const double w = (b.t - tr.samples[k - 1].t) / (tr.samples[k].t - tr.samples[k - 1].t);
            return tr.samples[k - 1].theta +
                   std::min(w, 1.0) * (tr.samples[k].theta - tr.samples[k - 1].theta);
          }
        }
        return tr.samples.back().theta;
      }();
      // (KRL: its times within kKrlTimeTol, at up to 40°/s of the table)
      EXPECT_NEAR(toDeg(b.theta - offset - want), 0.0, 1e-5 + 40.0 * kKrlTimeTol)
          << name << " t " << b.t;
    }
  }
  Trajectory jump = smallTrajectory();
  jump.samples[2].theta += deg(200.0);
  EXPECT_THROW(programs::writeProgram(jump, viper_, programs::ProgramFormat::kKrl, options),
               InputError);
}

TEST_F(Programs, EmptyOrBackwardsTrajectoryIsAnInputError) {
  for (const std::string& name : programs::programFormatNames()) {
    const programs::ProgramFormat format = *programs::parseProgramFormat(name);
    EXPECT_THROW(programs::writeProgram(Trajectory{}, viper_, format, {}), InputError) << name;
    Trajectory backwards = smallTrajectory();
    backwards.samples[2].t = backwards.samples[1].t;
    try {
      programs::writeProgram(backwards, viper_, format, {});
      ADD_FAILURE() << name << ": no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("sample 2"), std::string::npos) << e.what();
    }
  }
  // URScript over the size a controller loads is refused, naming the limit, not written.
  std::mt19937 rng(3);
  try {
    programs::writeProgram(randomTrajectory(viper_, rng, 9000), viper_,
                           programs::ProgramFormat::kUrscript, {});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("expected at most 1000000 bytes"), std::string::npos)
        << e.what();
  }
  programs::ProgramOptions bad;
  bad.approach_speed_percent = 0.0;
  EXPECT_THROW(
      programs::writeProgram(smallTrajectory(), viper_, programs::ProgramFormat::kVplus, bad),
      InputError);
}

TEST_F(Programs, MalformedVplusNamesTheLine) {
  const std::string good =
      programs::writeProgram(smallTrajectory(), viper_, programs::ProgramFormat::kVplus, {})
          .files[0]
          .second;
  ASSERT_NO_THROW(programs::readVplusProgram(good, "scan.v2"));
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
       "5 values: expected 6"},
      {"not a number", lineOf("    MOVE", 4), "    MOVE #PPOINT(1, 2, x, 4, 5, 6)",
       "'x' is not a finite number"},
      {"absurd joint", lineOf("    MOVE", 4), "    MOVE #PPOINT(1, 2, 1e300, 4, 5, 6)",
       "joint 3 1e+300 deg: expected an angle within ±1000000 deg"},
      {"absurd table angle", lineOf("; t=", 2), "; t=0.1 s table=5e6 deg scan=1",
       "table=5e6 deg: expected an angle within ±1000000 deg"},
      {"bad step comment", lineOf("; t=", 2), "; t=0.1 s table=abc deg scan=1",
       "expected 't=<s> s table=<deg> deg scan=<0|1>'"},
      {"comment and timing disagree", lineOf("; t=", 3), "; t=0.050000 s table=360.0 deg scan=1",
       "its step comment (line " + std::to_string(lineOf("; t=", 3)) + ") at 0.050000 s"},
      {"time backwards", lineOf("    DURATION", 2), "    DURATION 0",
       "the program's timing puts this move at t = 0.100000 s"},
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
      programs::readVplusProgram(text, "scan.v2");
      ADD_FAILURE() << c.what << ": no error";
    } catch (const InputError& e) {
      const std::string message = e.what();
      // The MOVE the edited comment or DURATION belongs to.
      const std::size_t expected_line =
          c.what == "move without comment" ? lineOf("    MOVE", 2)
          : c.what == "comment and timing disagree" || c.what == "time backwards"
              ? lineOf("    MOVE", 3)
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
      programs::readVplusProgram(text, "x.v2");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("").find("x.v2:0: no '.PROGRAM name()' line"), std::string::npos) << error("");
  EXPECT_NE(error("    MOVE #PPOINT(1,2,3,4,5,6)\n").find("x.v2:1: "), std::string::npos);
  const std::string no_end = good.substr(0, good.rfind(".END"));
  EXPECT_NE(error(no_end).find("has no .END"), std::string::npos) << error(no_end);
  EXPECT_NE(error(".PROGRAM a()\n.END\n").find("x.v2:2: no moves"), std::string::npos);
  EXPECT_NE(error(".PROGRAM a()\n; t=0 s table=0 deg scan=0\n.END\n")
                .find("x.v2:2: step comment without its MOVE"),
            std::string::npos);
}

}  // namespace

namespace {

// KRL and RAPID through a public grammar's parser where one is installed: no grammar is packaged
// for Debian 12, so the parser is named by the environment — SCANPLAN_KRL_PARSER and
// SCANPLAN_RAPID_PARSER, each a command that takes a file and exits 0 when it parses (e.g. an
// ANTLR parser built from the grammars-v4 krl.g4). Skipped without them.
TEST(ProgramsGrammar, KrlAndRapidParseWithAPublicGrammarWhereOneIsInstalled) {
  const char* krl = std::getenv("SCANPLAN_KRL_PARSER");
  const char* rapid = std::getenv("SCANPLAN_RAPID_PARSER");
  if (krl == nullptr && rapid == nullptr) {
    GTEST_SKIP() << "no KRL or RAPID grammar installed (set SCANPLAN_KRL_PARSER / "
                    "SCANPLAN_RAPID_PARSER to a parser command)";
  }
  const RobotModel viper = test::bundledRobot("viper_s650");
  std::mt19937 rng(12);
  const Trajectory tr = randomTrajectory(viper, rng, 300);
  programs::ProgramOptions options;
  options.trigger.output = 1;
  options.payload_kg = 0.9;
  options.table_endless = true;
  const fs::path dir = fs::temp_directory_path() / ("scanplan_grammar_" + std::to_string(getpid()));
  fs::create_directories(dir);
  for (const auto& [parser, format] : {std::pair{krl, programs::ProgramFormat::kKrl},
                                       std::pair{rapid, programs::ProgramFormat::kRapid}}) {
    if (parser == nullptr) continue;
    const programs::ProgramFiles files = programs::writeProgram(tr, viper, format, options);
    const fs::path file = dir / files.files[0].first;
    std::ofstream(file, std::ios::binary) << files.files[0].second;
    const std::string command = std::string(parser) + " '" + file.string() + "'";
    EXPECT_EQ(std::system(command.c_str()), 0) << command;
  }
  fs::remove_all(dir);
}

}  // namespace

namespace {

std::string replaceFirst(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// What a reader does not model it refuses, naming the line: an edited program must not read
// back as the plan while the controller would run something else.
TEST(ProgramReaders, RefuseWhatTheyDoNotModel) {
  const RobotModel viper = test::bundledRobot("viper_s650");
  std::mt19937 rng(13);
  const Trajectory tr = randomTrajectory(viper, rng, 30);
  programs::ProgramOptions options;
  options.servo_period = 0.05;
  const auto text = [&](programs::ProgramFormat f) {
    return programs::writeProgram(tr, viper, f, options).files[0].second;
  };
  struct Case {
    programs::ProgramFormat format;
    std::string edited;
    std::string message;
  };
  const std::string v2 = text(programs::ProgramFormat::kVplus),
                    src = text(programs::ProgramFormat::kKrl),
                    mod = text(programs::ProgramFormat::kRapid),
                    script = text(programs::ProgramFormat::kUrscript);
  // The random trajectory at a fifth of its pace keeps to the joints' top speeds: no V+ SPEED is
  // capped at 100 short of its step's time.
  Trajectory slow = tr;
  for (auto& sample : slow.samples) sample.t *= 5.0;
  const std::string slow_v2 =
      programs::writeProgram(slow, viper, programs::ProgramFormat::kVplus, options).files[0].second;
  const std::vector<Case> cases = {
      {programs::ProgramFormat::kVplus, replaceFirst(v2, "    DURATION 0.100000\n", ""),
       "MOVE without DURATION"},
      {programs::ProgramFormat::kVplus,
       replaceFirst(v2, "    DURATION 0.100000\n", "    DURATION 0.1 ALWAYS\n"),
       "DURATION ... ALWAYS is not read"},
      {programs::ProgramFormat::kKrl,
       replaceFirst(src, "  ENDSPLINE\n",
                    "    SPTP {A1 1, A2 2, A3 3, A4 4, A5 5, A6 6, E1 7}\n  ENDSPLINE\n"),
       "SPTP outside a timed PTP_SPLINE block"},
      {programs::ProgramFormat::kKrl, replaceFirst(src, "    SPTP {", "    SPTP_REL {"),
       "not an instruction this reader knows"},
      {programs::ProgramFormat::kRapid, replaceFirst(mod, "v1000\\T:=0.100000, z0", "v1000, z0"),
       "without \\T"},
      {programs::ProgramFormat::kRapid,
       replaceFirst(mod, "  PROC scan()\n", "  PROC scan()\n    Stop;\n"),
       "a call outside PROC main()"},
      {programs::ProgramFormat::kRapid, replaceFirst(mod, "    scan;\n", "    other;\n"),
       "'OTHER;': expected 'SCAN;'"},
      {programs::ProgramFormat::kRapid, replaceFirst(mod, "    scan;\n", "    scan;\n    scan;\n"),
       "a second call in main() (the first is on line"},
      {programs::ProgramFormat::kRapid, replaceFirst(mod, "    scan;\n", ""),
       "PROC main() calls nothing"},
      {programs::ProgramFormat::kRapid, replaceFirst(mod, "  PROC main()\n", "  PROC start()\n"),
       "a call outside PROC main()"},
      {programs::ProgramFormat::kRapid,
       replaceFirst(mod, "  PROC main()\n    scan;\n  ENDPROC\n", ""), "no PROC main()"},
      {programs::ProgramFormat::kRapid,
       replaceFirst(mod, "    scan;\n", "    scan;\n  ENDPROC\n  PROC extra()\n"),
       "3 procedures: expected two"},
      {programs::ProgramFormat::kRapid,
       replaceFirst(mod, "    scan;\n",
                    "    scan;\n    MoveAbsJ [[0,0,90,0,0,0],[0,9E9,9E9,9E9,9E9,9E9]]\\NoEOffs, "
                    "v100\\T:=1, fine, tool0;\n"),
       "outside the scan procedure"},
      {programs::ProgramFormat::kVplus,
       replaceFirst(v2, "    DURATION 0.100000\n", "    SPEED 0.01\n    DURATION 0.100000\n"),
       "SPEED 0.01 (line "},
      {programs::ProgramFormat::kVplus,
       replaceFirst(v2, "    DURATION 0.100000\n", "    SPEED 50 MMPS\n    DURATION 0.100000\n"),
       "SPEED in mm/s applies to straight-line moves"},
      {programs::ProgramFormat::kVplus,
       replaceFirst(v2, "    DURATION 0.100000\n", "    SPEED 120\n    DURATION 0.100000\n"),
       "expected SPEED in (0, 100] percent"},
      {programs::ProgramFormat::kVplus, slow_v2 + ".PROGRAM other()\n.END\n",
       "after .END: expected nothing"},
      {programs::ProgramFormat::kKrl,
       replaceFirst(src, "SCANPLAN_VEL(100, 100)", "SCANPLAN_VEL(50, 50)"),
       "a timed PTP_SPLINE block after SCANPLAN_VEL(50, 50)"},
      {programs::ProgramFormat::kKrl,
       replaceFirst(src, "$VEL_AXIS[AXIS]=ARM_PCT", "$VEL_AXIS[AXIS]=5"),
       "'$VEL_AXIS[AXIS]=5' after the program's END: expected '$VEL_AXIS[AXIS]=ARM_PCT'"},
      {programs::ProgramFormat::kKrl,
       replaceFirst(src, "  PTP_SPLINE\n", "  BAS(#VEL_PTP,20)\n  PTP_SPLINE\n"),
       "expected BAS(#INITMOV,0) alone, before the first motion"},
      {programs::ProgramFormat::kUrscript,
       replaceFirst(script, "      i = i + 1\n", "      sleep(0.1)\n      i = i + 1\n"),
       "seg() function: 'sleep(0.1)' where scanplan writes 'i = i + 1'"},
      {programs::ProgramFormat::kUrscript, replaceFirst(script, "i * 0.0500 <=", "i * 0.0500 <"),
       "the reader models only the seg() function scanplan writes"},
      {programs::ProgramFormat::kUrscript,
       replaceFirst(script, "  a = seg(a, [", "  a = seg(a, [1, "),
       "the data row: 11 values: expected 10"},
      {programs::ProgramFormat::kUrscript, replaceFirst(script, "  stopj(2.0)\n", "  a = [0, 1]\n"),
       "after the last step"},
      {programs::ProgramFormat::kUrscript, replaceFirst(script, "\nscan()\n", "\n"),
       "defined but never run: expected a line 'scan()' after its end"},
      {programs::ProgramFormat::kUrscript, script + "scan()\n", "expected only 'scan()' after"},
      {programs::ProgramFormat::kUrscript,
       replaceFirst(script, "\nscan()\n", "\nmovej([0,0,0,0,0,0])\n"),
       "expected only 'scan()' after"},
  };
  for (const Case& c : cases) {
    const std::string name = programs::programFormatName(c.format);
    ASSERT_NE(c.edited, text(c.format)) << name << ": the edit did not apply: " << c.message;
    try {
      programs::readProgram(c.edited, c.format, "p", &viper);
      ADD_FAILURE() << name << ": no error for " << c.message;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).rfind("p:", 0), 0u) << e.what();
    }
  }
  // Written programs read back with the robot's speeds: every V+ SPEED covers its step where the
  // trajectory keeps to the joints' top speeds.
  for (const programs::ProgramFormat f :
       {programs::ProgramFormat::kVplus, programs::ProgramFormat::kKrl,
        programs::ProgramFormat::kRapid}) {
    EXPECT_NO_THROW(programs::readProgram(
        programs::writeProgram(slow, viper, f, options).files[0].second, f, "p", &viper))
        << programs::programFormatName(f);
  }
  // A program without its last step: the motion would end short of the last sample.
  std::string cut = script;
  const auto last = cut.find("\n  if a[0] * ");
  cut.erase(last, cut.find("  stopj") - last - 1);
  EXPECT_THROW(programs::readProgram(cut, programs::ProgramFormat::kUrscript, "p"), InputError);
}

}  // namespace

namespace {

// The 1-based number of the n-th line of `text` that starts with `prefix`.
int lineOf(const std::string& text, const std::string& prefix, int n = 1) {
  const std::vector<std::string> all = lines(text);
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (all[i].rfind(prefix, 0) == 0 && --n == 0) return static_cast<int>(i) + 1;
  }
  ADD_FAILURE() << "no line starting with '" << prefix << "'";
  return 0;
}

std::string lineText(const std::string& text, int line) {
  const std::vector<std::string> all = lines(text);
  return line >= 1 && static_cast<std::size_t>(line) <= all.size()
             ? all[static_cast<std::size_t>(line - 1)]
             : std::string();
}

// `text` with its line `line` (1-based) replaced by `with`: none removes it, several insert.
std::string withLine(const std::string& text, int line, const std::vector<std::string>& with) {
  std::vector<std::string> all = lines(text);
  if (line < 1 || static_cast<std::size_t>(line) > all.size()) return text;
  const auto at = all.begin() + (line - 1);
  all.insert(all.erase(at), with.begin(), with.end());
  std::string out;
  for (const std::string& l : all) out += l + "\n";
  return out;
}

// The error reading `text`, or "no error".
std::string readError(const std::string& text,
                      programs::ProgramFormat format,
                      const RobotModel* robot) {
  try {
    programs::readProgram(text, format, "p", robot);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

// An edited program and the error it must get: its line (0: not checked) and a fragment.
struct EditCase {
  std::string what;
  std::string edited;
  int line = 0;
  std::string message;
};

void expectRefused(const std::vector<EditCase>& cases,
                   programs::ProgramFormat format,
                   const std::string& original,
                   const RobotModel& robot) {
  ASSERT_EQ(readError(original, format, &robot), "no error");
  for (const EditCase& c : cases) {
    ASSERT_NE(c.edited, original) << c.what << ": the edit did not apply";
    const std::string error = readError(c.edited, format, &robot);
    const std::string prefix = c.line > 0 ? "p:" + std::to_string(c.line) + ": " : "p:";
    EXPECT_EQ(error.rfind(prefix, 0), 0u) << c.what << ": " << error;
    EXPECT_NE(error.find(c.message), std::string::npos) << c.what << ": " << error;
  }
}

// The random trajectory at a fifth of its pace: within the joints' top speeds at every step.
Trajectory slowTrajectory(const RobotModel& robot) {
  std::mt19937 rng(13);
  Trajectory tr = randomTrajectory(robot, rng, 30);
  for (auto& sample : tr.samples) sample.t *= 5.0;
  return tr;
}

// Programs written for the robot read back with its joint speeds at the planned times; a V+
// step the joints cannot keep (SPEED capped at 100) is refused with them and read without.
TEST(ProgramReaders, WrittenProgramsReadBackWithTheRobotsSpeedsAtThePlannedTimes) {
  const RobotModel viper = test::bundledRobot("viper_s650");
  const Trajectory slow = slowTrajectory(viper);
  for (const programs::ProgramFormat f :
       {programs::ProgramFormat::kVplus, programs::ProgramFormat::kKrl,
        programs::ProgramFormat::kRapid}) {
    const programs::ProgramFiles files = programs::writeProgram(slow, viper, f, {});
    EXPECT_EQ(files.over_speed_segments, 0u);
    const programs::ProgramReading back =
        programs::readProgram(files.files[0].second, f, "p", &viper);
    EXPECT_TRUE(sameToPrintedPrecision(
        back.trajectory, slow, f == programs::ProgramFormat::kKrl ? kKrlTimeTol : kPrintedTol))
        << programs::programFormatName(f);
  }
  std::mt19937 rng(13);
  const Trajectory fast = randomTrajectory(viper, rng, 30);  // step 25 needs some 130 %
  const programs::ProgramFiles files =
      programs::writeProgram(fast, viper, programs::ProgramFormat::kVplus, {});
  const std::string& v2 = files.files[0].second;
  ASSERT_EQ(files.over_speed_segments, 1u);
  ASSERT_NE(v2.find("; WARNING: step 25 needs"), std::string::npos);
  const std::string error = readError(v2, programs::ProgramFormat::kVplus, &viper);
  EXPECT_EQ(
      error.rfind("p:" + std::to_string(lineOf(v2, "    MOVE", 26)) + ": SPEED 100.00 (line " +
                      std::to_string(lineOf(v2, "    SPEED", 26)) + ") makes this MOVE take",
                  0),
      0u)
      << error;
  EXPECT_NE(error.find("of joint 2's top speed: re-plan it slower"), std::string::npos) << error;
  EXPECT_EQ(readError(v2, programs::ProgramFormat::kVplus, nullptr), "no error");
}

// V+ SPEED: the next MOVE's, or every later one's with ALWAYS; a move it makes outlast its
// DURATION is refused naming the MOVE and the SPEED. Without a robot, SPEED is not timed.
TEST(ProgramReaders, VplusSpeedTimesEachMoveAndNamesTheLines) {
  const RobotModel viper = test::bundledRobot("viper_s650");
  const std::string v2 =
      programs::writeProgram(slowTrajectory(viper), viper, programs::ProgramFormat::kVplus, {})
          .files[0]
          .second;
  const auto speedLine = [&](int n) { return lineOf(v2, "    SPEED", n); };  // the n-th MOVE's
  // A timed move that SPEED 0.2 cannot cover.
  int n = 2;
  while (n < 30 && std::stod(lineText(v2, speedLine(n)).substr(10)) <= 0.4) ++n;
  ASSERT_LT(n, 30);
  const double written = std::stod(lineText(v2, speedLine(n)).substr(10));
  const std::string one = withLine(v2, speedLine(n), {"    SPEED 0.2"});
  const std::string error = readError(one, programs::ProgramFormat::kVplus, &viper);
  EXPECT_EQ(error.rfind("p:" + std::to_string(lineOf(v2, "    MOVE", n)) + ": SPEED 0.20 (line " +
                            std::to_string(speedLine(n)) + ") makes this MOVE take",
                        0),
            0u)
      << error;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(error, m, std::regex("expected SPEED ≥ ([0-9.]+)\\)"))) << error;
  EXPECT_NEAR(std::stod(m[1].str()), written, 0.011) << error;  // the writer's, rounded up
  EXPECT_EQ(readError(one, programs::ProgramFormat::kVplus, nullptr), "no error");
  // SPEED ... ALWAYS before the approach holds for a later move without a SPEED of its own
  // (the moves between have theirs); SPEED without ALWAYS holds for the next move only.
  const std::string always =
      withLine(withLine(v2, speedLine(n), {}), speedLine(1), {"    SPEED 0.2 ALWAYS"});
  EXPECT_EQ(readError(always, programs::ProgramFormat::kVplus, &viper)
                .rfind("p:" + std::to_string(lineOf(always, "    MOVE", n)) +
                           ": SPEED 0.20 ALWAYS (line " + std::to_string(speedLine(1)) + ")",
                       0),
            0u)
      << readError(always, programs::ProgramFormat::kVplus, &viper);
  const std::string once =
      withLine(withLine(v2, speedLine(n), {}), speedLine(1), {"    SPEED 0.2"});
  EXPECT_EQ(readError(once, programs::ProgramFormat::kVplus, &viper), "no error");
  const int s3 = speedLine(3), m3 = lineOf(v2, "    MOVE", 3), end = lineOf(v2, ".END");
  expectRefused(
      {{"SPEED 0", withLine(v2, s3, {"    SPEED 0"}), s3, "expected SPEED in (0, 100] percent"},
       {"SPEED -5", withLine(v2, s3, {"    SPEED -5"}), s3, "expected SPEED in (0, 100] percent"},
       {"SPEED 150", withLine(v2, s3, {"    SPEED 150"}), s3, "expected SPEED in (0, 100] percent"},
       {"MMPS", withLine(v2, s3, {"    SPEED 50 MMPS"}), s3, "SPEED in mm/s applies to straight"},
       {"MMPS ALWAYS", withLine(v2, s3, {"    SPEED 50 MMPS ALWAYS"}), s3, "SPEED in mm/s"},
       {"BREAK between moves", withLine(v2, m3, {lineText(v2, m3), "    BREAK"}), m3 + 1,
        "BREAK between timed moves: the arm would stop here"},
       {"a program after .END", v2 + ".PROGRAM other()\n    MOVE #PPOINT(0, 0, 90, 0, 0, 0)\n",
        end + 1, "'.PROGRAM other()' after .END: expected nothing after the program"},
       {"an instruction after .END", withLine(v2, end, {".END", "", "    SPEED 5 ALWAYS"}), end + 2,
        "after .END"}},
      programs::ProgramFormat::kVplus, v2, viper);
  EXPECT_EQ(readError(v2 + "\n; a comment\n\n", programs::ProgramFormat::kVplus, &viper),
            "no error");
}

// KRL: the timed blocks at full axis velocity, the SCANPLAN_VEL routine as written, BAS only to
// initialise, one PTP (to the start); anything else that changes motion is refused.
TEST(ProgramReaders, KrlTimeBlocksRunAtFullVelocityUnderTheWrittenRoutine) {
  const RobotModel viper = test::bundledRobot("viper_s650");
  const std::string src =
      programs::writeProgram(slowTrajectory(viper), viper, programs::ProgramFormat::kKrl, {})
          .files[0]
          .second;
  const int vel = lineOf(src, "  SCANPLAN_VEL(100, 100)"), block = lineOf(src, "  PTP_SPLINE"),
            start = lineOf(src, "    TIME_BLOCK START"), end = lineOf(src, "  ENDSPLINE"),
            axis = lineOf(src, "    $VEL_AXIS[AXIS]=ARM_PCT"),
            extax = lineOf(src, "  $VEL_EXTAX[1]=E1_PCT");
  const auto before = [&](int line, const std::string& text) {
    return withLine(src, line, {text, lineText(src, line)});
  };
  const std::string other = "not an instruction this reader knows";
  expectRefused(
      {{"half velocity", withLine(src, vel, {"  SCANPLAN_VEL(50, 50)"}), block,
        "a timed PTP_SPLINE block after SCANPLAN_VEL(50, 50): TIME_BLOCK holds its times only"},
       {"approach velocity", withLine(src, vel, {}), block - 1,
        "a timed PTP_SPLINE block after SCANPLAN_VEL(10, 10)"},
       {"velocity in a block", before(start + 1, "    SCANPLAN_VEL(100, 100)"), start + 1,
        "inside a PTP_SPLINE block"},
       {"velocity 0", withLine(src, vel, {"  SCANPLAN_VEL(0, 100)"}), vel, "each 1 ... 100"},
       {"routine edited", withLine(src, axis, {"    $VEL_AXIS[AXIS]=5"}), axis,
        "'$VEL_AXIS[AXIS]=5' after the program's END: expected '$VEL_AXIS[AXIS]=ARM_PCT'"},
       {"routine grown", before(extax, "  $ACC_AXIS[1]=10"), extax,
        "'$ACC_AXIS[1]=10' after the program's END: expected '$VEL_EXTAX[1]=E1_PCT'"},
       {"routine missing", src.substr(0, src.find("\nEND\n") + 5), 0,
        "the SCANPLAN_VEL routine is missing or cut short"},
       {"a program after the routine", src + "DEF EXTRA( )\nEND\n", 0, "expected 'nothing'"},
       {"BAS velocity", before(block, "  BAS(#VEL_PTP,20)"), block,
        "BAS sets velocities and accelerations this reader does not model"},
       {"BAS after the start", before(vel, "  BAS(#INITMOV,0)"), vel,
        "expected BAS(#INITMOV,0) alone, before the first motion"},
       {"a second PTP",
        withLine(src, end,
                 {"  ENDSPLINE", "  PTP {A1 0, A2 -60, A3 150, A4 0, A5 45, A6 0, E1 0}"}),
        end + 1, "a PTP after the start"},
       {"loop", before(block, "  LOOP"), block, other},
       {"for", before(block, "  FOR I=1 TO 2"), block, other},
       {"while", before(block, "  WHILE TRUE"), block, other},
       {"wait", before(block, "  WAIT SEC 5"), block, other},
       {"override", before(block, "  $OV_PRO=10"), block, other},
       {"axis velocity", before(block, "  $VEL_AXIS[1]=10"), block, other},
       {"another call", before(block, "  OTHER()"), block, other}},
      programs::ProgramFormat::kKrl, src, viper);
}

// RAPID: main() calls the scan procedure once; the moves are there alone, passing through their
// points (z0); anything else that changes motion is refused.
TEST(ProgramReaders, RapidMainCallsTheScanProcedureOnce) {
  const RobotModel viper = test::bundledRobot("viper_s650");
  const std::string mod =
      programs::writeProgram(slowTrajectory(viper), viper, programs::ProgramFormat::kRapid, {})
          .files[0]
          .second;
  const int call = lineOf(mod, "    scan;"), main_proc = lineOf(mod, "  PROC main()"),
            scan = lineOf(mod, "  PROC scan()"), second = lineOf(mod, "    MoveAbsJ", 2);
  const std::string move =
      "    MoveAbsJ [[0,0,90,0,0,0],[0,9E9,9E9,9E9,9E9,9E9]]\\NoEOffs, v100\\T:=1, fine, tool0;";
  const auto zone = [&](const std::string& z) {
    return withLine(mod, second, {replaceFirst(lineText(mod, second), ", z0, ", z)});
  };
  const std::string other = "not an instruction this reader knows";
  expectRefused(
      {{"scan twice", withLine(mod, call, {"    scan;", "    scan;"}), call + 1,
        "a second call in main() (the first is on line " + std::to_string(call) + ")"},
       {"empty main", withLine(mod, call, {}), 0, "PROC main() calls nothing: expected one call"},
       {"no main",
        withLine(withLine(withLine(mod, main_proc + 2, {}), main_proc + 1, {}), main_proc, {}), 0,
        "no PROC main()"},
       {"a move in main", withLine(mod, call, {"    scan;", move}), call + 1,
        "outside the scan procedure"},
       {"a move outside a procedure", withLine(mod, scan, {move, "  PROC scan()"}), scan,
        "outside the scan procedure"},
       {"another procedure", withLine(mod, scan, {"  PROC extra()", "  ENDPROC", "  PROC scan()"}),
        0, "3 procedures: expected two"},
       {"a call in the scan", withLine(mod, scan, {"  PROC scan()", "    other;"}), scan + 1,
        "a call outside PROC main()"},
       {"a procedure inside another", withLine(mod, main_proc + 2, {}), scan - 1,
        "PROC inside PROC MAIN"},
       {"zone z50", zone(", z50, "), second, "zone z50 rounds the corner"},
       {"zone fine between moves", zone(", fine, "), second,
        "zone fine between timed moves: the arm would stop here"},
       {"VelSet", withLine(mod, call, {"    VelSet 10, 100;", "    scan;"}), call, other},
       {"WaitTime", withLine(mod, scan, {"  PROC scan()", "    WaitTime 5;"}), scan + 1, other}},
      programs::ProgramFormat::kRapid, mod, viper);
}

}  // namespace
