// `scanplan watch` from the shell: a log of a joint move that reaches a contact is warned and
// stopped before the contact (found independently along the true motion), from a file and from
// standard input; a move away is silent; bad streams and options are errors that name the line,
// the column and the value.
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <scanplan/collision/clearance.h>
#include <scanplan/collision/scene.h>
#include <scanplan/config/job.h>
#include "cli_support.h"
#include "test_support.h"

namespace {

using namespace scanplan;
using namespace scanplan::test;
using kinematics::JointVector;

const std::string kJob = (fs::path(SCANPLAN_SOURCE_DIR) / "data/jobs/demo_rings.yaml").string();
constexpr double kDt = 0.004;  // 250 Hz

struct Move {
  JointVector start;
  JointVector rate;      // rad/s
  double contact = 0.0;  // s, first contact along the move (1 ms steps)
};

// A constant-speed move of joint 2 or 3 from a folded pose that reaches a contact after 2–6 s.
std::optional<Move> contactMove() {
  const config::JobSpec job = config::loadJob(kJob, kLightDemo);
  const kinematics::CellModel cell = config::buildCell(job);
  const collision::Scene scene(cell, config::clearanceConfig(job));
  collision::ClearanceEvaluator evaluator(scene);
  JointVector start;
  start << 0.0, -60.0, 150.0, 0.0, 60.0, 0.0;
  start *= M_PI / 180.0;
  for (const int j : {1, 2}) {
    for (const double sign : {1.0, -1.0}) {
      JointVector rate = JointVector::Zero();
      rate(j) = sign * 0.25;
      for (double t = 0.0; t <= 6.0; t += 1e-3) {
        if (!evaluator.evaluate(0.0, start + t * rate).collision) continue;
        if (t >= 2.0) return Move{start, rate, t};
        break;
      }
    }
  }
  return std::nullopt;
}

std::string logOf(const JointVector& start, const JointVector& rate, double until) {
  std::string text = "# a 250 Hz log\nt_s,table_deg,j1_deg,j2_deg,j3_deg,j4_deg,j5_deg,j6_deg\n";
  for (int i = 0; i * kDt <= until; ++i) {
    const JointVector q = (start + i * kDt * rate) * (180.0 / M_PI);
    text += fmt::format("{:.3f},0,{:.9f},{:.9f},{:.9f},{:.9f},{:.9f},{:.9f}\n", i * kDt, q(0), q(1),
                        q(2), q(3), q(4), q(5));
  }
  return text;
}

// The time on the first line of `out` that holds `word`.
std::optional<double> firstTime(const std::string& out, const std::string& word) {
  const std::size_t at = out.find(word);
  if (at == std::string::npos) return std::nullopt;
  const std::size_t line = out.rfind('\n', at) + 1;  // npos + 1 = 0 on the first line
  if (out.compare(line, 2, "t=") != 0) return std::nullopt;
  return std::stod(out.substr(line + 2));
}

class CliWatch : public Cli {};

TEST_F(CliWatch, AMoveIntoTheCellIsWarnedAndStoppedBeforeTheContact) {
  const auto move = contactMove();
  ASSERT_TRUE(move) << "no joint move from the start pose reaches a contact within 2-6 s";
  const fs::path log = dir_ / "towards.csv";
  writeFile(log, logOf(move->start, move->rate, move->contact + 0.2));
  const Result run = scanplan(
      {"watch", kJob, "--log", log.string(), "--stop-distance-mm", "0", "--stop-time-s", "0.2"});
  ASSERT_EQ(run.exit_code, 5) << describe(run);
  const auto warned = firstTime(run.out, "WARN");
  const auto stopped = firstTime(run.out, "STOP");
  ASSERT_TRUE(warned && stopped) << run.out;
  EXPECT_GE(move->contact - *warned, 0.9);  // the 1 s horizon, less a step and a sample
  EXPECT_GE(move->contact - *stopped, 0.17);
  EXPECT_LE(*stopped, move->contact);
  EXPECT_TRUE(contains(run.out, "contact in")) << run.out;
  EXPECT_TRUE(contains(run.out, "joint move")) << run.out;
  EXPECT_TRUE(contains(run.out, "watch: stop needed at t=")) << run.out;

  // The same log on standard input, line by line, gives the same lines.
  const std::string piped = runCommand(fmt::format(
      "'{}' watch '{}' --stop-distance-mm 0 --stop-time-s 0.2 < '{}' 2>/dev/null; echo exit=$?",
      SCANPLAN_BINARY, kJob, log.string()));
  EXPECT_TRUE(contains(piped, "exit=5")) << piped;
  const auto cut = [](const std::string& text) { return text.substr(0, text.find("watch: stop")); };
  EXPECT_EQ(cut(piped), cut(run.out));
}

TEST_F(CliWatch, AMoveAwayIsSilent) {
  const auto move = contactMove();
  ASSERT_TRUE(move);
  const fs::path log = dir_ / "away.csv";
  writeFile(log, logOf(move->start + (move->contact - 0.05) * move->rate, -move->rate, 2.0));
  const Result run = scanplan({"watch", kJob, "--log", log.string(), "--stop-distance-mm", "0"});
  EXPECT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_FALSE(contains(run.out, "WARN")) << run.out;
  EXPECT_TRUE(contains(run.out, "samples over 2.0")) << run.out;
}

TEST_F(CliWatch, BadStreamsAreErrorsNamingLineColumnAndValue) {
  const fs::path log = dir_ / "bad.csv";
  const auto error = [&](const std::string& text, std::vector<std::string> parts) {
    writeFile(log, text);
    const Result run = scanplan({"watch", kJob, "--log", log.string()});
    EXPECT_EQ(run.exit_code, 4) << describe(run);
    for (const std::string& p : parts) EXPECT_TRUE(contains(run.err, p)) << p << "\n" << run.err;
  };
  error("0,0,0,-60,150,0,60,0\n0.004,0,0,-60,abc,0,60,0\n", {"bad.csv:2", "j3_deg", "'abc'"});
  error("0,0,0,-60,150,0,60,0\n0,0,0,-60,150,0,60,0\n",
        {"bad.csv:2", "t_s", "strictly increasing"});
  error("0,0,0,-60,150,0,60\n", {"bad.csv:1", "7 columns", "at least 8"});
  error("t_s,table_deg,j1_deg,j2_deg\n", {"bad.csv:1", "no column j3_deg"});
  error("0,0,0,-60,150,0,60,1e300\n", {"j6_deg", "finite number within"});
  error(std::string(100000, '1'), {"bad.csv:1", "longer than 65536 bytes"});
  const Result window = scanplan({"watch", kJob, "--log", log.string(), "--window", "2"});
  EXPECT_EQ(window.exit_code, 4);
  EXPECT_TRUE(contains(window.err, "--window: 2 samples: expected 3")) << window.err;
  for (const auto& [option, value] :
       std::vector<std::pair<std::string, std::string>>{{"--horizon-s", "-1"},
                                                        {"--step-s", "0"},
                                                        {"--warn-distance-mm", "-5"},
                                                        {"--stop-distance-mm", "-1"},
                                                        {"--stop-time-s", "0"},
                                                        {"--repeat-s", "-1"}}) {
    const Result run = scanplan({"watch", kJob, "--log", log.string(), option, value});
    EXPECT_EQ(run.exit_code, 4) << option;
    EXPECT_TRUE(contains(run.err, option + ": " + value)) << run.err;
  }
}

}  // namespace
