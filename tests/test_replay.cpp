// OUT/replay.html: the poses it animates are the trajectory's (recomputed here from
// trajectory.csv through the robot's own FK and the table model), its cloud is the plan's, and
// — in headless Chromium (Debian's chromium, playwright-core from web/node_modules; skipped
// without them) — it loads without errors, draws a non-blank cell that changes as the slider
// moves, colours the part as the scan covers it, plays, and shows the closest approach.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <scanplan/config/job.h>
#include <scanplan/kinematics/trajectory.h>
#include "cli_support.h"
#include "test_support.h"

namespace {

using namespace scanplan;
using namespace scanplan::test;
using Json = nlohmann::json;

std::vector<std::uint8_t> unbase64(const std::string& text) {
  static const std::string kAlphabet =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::vector<std::uint8_t> out;
  unsigned buffer = 0;
  int bits = 0;
  for (const char c : text) {
    if (c == '=') break;
    const auto v = kAlphabet.find(c);
    if (v == std::string::npos) continue;
    buffer = (buffer << 6u) | static_cast<unsigned>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<std::uint8_t>((buffer >> bits) & 0xFFu));
    }
  }
  return out;
}

std::vector<float> floats(const std::string& b64) {
  const std::vector<std::uint8_t> b = unbase64(b64);
  std::vector<float> out(b.size() / 4);
  std::memcpy(out.data(), b.data(), out.size() * 4);
  return out;
}

// The text of the scene data inside replay.html.
std::string replayDataText(const std::string& html) {
  const std::string open = "<script type=\"application/json\" id=\"scanplan-data\">";
  const auto from = html.find(open);
  const auto to = html.find("</script>", from);
  if (from == std::string::npos || to == std::string::npos) return {};
  return html.substr(from + open.size(), to - from - open.size());
}

// The scene data inside replay.html.
Json replayData(const std::string& html) {
  return Json::parse(replayDataText(html), nullptr, false);
}

class Replay : public Cli {
 protected:
  // The light demo planned into dir_/out; false when it failed.
  bool plan() {
    std::vector<std::string> args{"plan", (sourceDir() / "data/jobs/demo_rings.yaml").string(),
                                  "-o", (dir_ / "out").string()};
    for (const std::string& o : kLightDemo) {
      args.push_back("--set");
      args.push_back(o);
    }
    const Result run = scanplan(args);
    EXPECT_EQ(run.exit_code, 0) << describe(run);
    if (!fs::exists(dir_ / "out/replay.html")) {
      ADD_FAILURE() << "no replay.html (three.js missing? run ./bootstrap.sh)\n" << describe(run);
      return false;
    }
    return run.exit_code == 0;
  }
};

TEST_F(Replay, ItsPosesAreTheTrajectorysThroughTheRobotsOwnKinematics) {
  ASSERT_TRUE(plan());
  const std::string html = readFile(dir_ / "out/replay.html");
  const Json data = replayData(html);
  ASSERT_TRUE(data.is_object());
  // Written member by member: the text is the one compact line nlohmann::json writes for it.
  const std::string text = replayDataText(html);
  EXPECT_TRUE(nlohmann::ordered_json::parse(text).dump() + "\n" == text);
  const config::JobSpec job =
      config::loadJob(sourceDir() / "data/jobs/demo_rings.yaml", kLightDemo);
  const kinematics::CellModel cell = config::buildCell(job);
  const kinematics::Trajectory tr =
      kinematics::parseTrajectoryCsv(readFile(dir_ / "out/trajectory.csv"), "trajectory.csv");
  const std::vector<float> t = floats(data["frames"]["t"]);
  const std::vector<float> poses = floats(data["frames"]["poses"]);
  ASSERT_EQ(poses.size(), t.size() * 9 * 7);
  ASSERT_GE(t.size(), std::min<std::size_t>(tr.samples.size(), 2000));
  const auto pose = [&](std::size_t f, int k) {
    const std::size_t o = (f * 9 + static_cast<std::size_t>(k)) * 7;
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() << poses[o], poses[o + 1], poses[o + 2];
    X.linear() = Eigen::Quaterniond(poses[o + 6], poses[o + 3], poses[o + 4], poses[o + 5])
                     .normalized()
                     .toRotationMatrix();
    return X;
  };
  std::size_t k = 0;
  double worst = 0.0;
  for (std::size_t f = 0; f < t.size(); ++f) {
    while (k + 1 < tr.samples.size() && std::abs(tr.samples[k].t - t[f]) > 1e-3) ++k;
    ASSERT_LT(std::abs(tr.samples[k].t - t[f]), 1e-3) << "frame " << f << " at " << t[f];
    const auto links = cell.robot.linkFrames(tr.samples[k].q);
    std::vector<Eigen::Isometry3d> want;
    for (const auto& X : links) want.push_back(cell.X_WB * X);
    want.push_back(cell.X_WB * links.back() * cell.scanner.X_FS);
    want.push_back(cell.table.X_WR(tr.samples[k].theta));
    for (int c = 0; c < 9; ++c) {
      worst = std::max(
          worst,
          (pose(f, c).matrix() - want[static_cast<std::size_t>(c)].matrix()).cwiseAbs().maxCoeff());
    }
  }
  EXPECT_LT(worst, 2e-5) << "float precision of the stored poses";
  // The cloud: a time-ordered subsample of the plan's.
  const std::vector<float> cloud_t = floats(data["cloud_t"]);
  EXPECT_GT(cloud_t.size(), 1000u);
  EXPECT_LE(cloud_t.size(), data["cloud_total"].get<std::size_t>());
  EXPECT_TRUE(std::is_sorted(cloud_t.begin(), cloud_t.end()));
  EXPECT_EQ(floats(data["cloud"]).size(), 3 * cloud_t.size());
  // Every body the collision scene has, the part coloured per triangle.
  std::vector<std::string> names;
  for (const Json& b : data["bodies"]) names.push_back(b["name"]);
  for (const char* name : {"base", "link6", "scanner", "table", "part"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), name), names.end()) << name;
  }
  for (const Json& b : data["bodies"]) {
    if (b["name"] != "part") continue;
    EXPECT_EQ(unbase64(b["colours"]).size(), unbase64(b["triangles"]).size() / 4);
  }
  EXPECT_FALSE(data["closest"].empty());
}

TEST_F(Replay, ChromiumDrawsTheCellMovesWithTheSliderAndPlays) {
  const fs::path modules = sourceDir() / "web/node_modules";
  if (!fs::exists("/usr/bin/chromium") || test::runCommand("command -v node").empty() ||
      !fs::exists(modules / "playwright-core")) {
    GTEST_SKIP() << "chromium, node or web/node_modules/playwright-core absent";
  }
  ASSERT_TRUE(plan());
  const std::string out =
      test::runCommand("SCANPLAN_WEB_MODULES='" + modules.string() + "' timeout 300 node '" +
                       (sourceDir() / "tests/js/replay_test.mjs").string() + "' '" +
                       (dir_ / "out/replay.html").string() + "' '" + dir_.string() + "' 2>&1");
  const Json result = Json::parse(
      out.substr(out.rfind("\n{") == std::string::npos ? 0 : out.rfind("\n{") + 1), nullptr, false);
  ASSERT_TRUE(result.is_object()) << out;
  EXPECT_TRUE(result["errors"].empty()) << result["errors"].dump();
  const Json& shots = result["shots"];
  ASSERT_EQ(shots.size(), 3u);
  for (const Json& s : shots) {
    EXPECT_GT(s["spread"].get<double>(), 10.0) << s.dump() << ": a blank canvas";
    EXPECT_TRUE(fs::exists(dir_ / (s["name"].get<std::string>() + ".png")));
  }
  // The slider moved the scene: other frames, other pictures, other labels.
  EXPECT_EQ(shots[0]["frame"], 0);
  EXPECT_GT(shots[1]["frame"].get<int>(), 0);
  EXPECT_EQ(shots[2]["frame"].get<int>(), result["frames"].get<int>() - 1);
  EXPECT_NE(shots[0]["hash"], shots[1]["hash"]);
  EXPECT_NE(shots[1]["hash"], shots[2]["hash"]);
  EXPECT_NE(shots[0]["label"], shots[2]["label"]);
  EXPECT_GT(result["after"].get<int>(), result["before"].get<int>()) << "Play advances";
  // The part's coverage grows with time: fewer triangles coloured as covered at the first frame
  // than at the last, and some at the last.
  EXPECT_LT(shots[0]["coloured"].get<int>(), shots[2]["coloured"].get<int>()) << shots.dump();
  EXPECT_GT(shots[2]["coloured"].get<int>(), 0) << shots.dump();
  // "closest approach" jumps to one and says so in red.
  EXPECT_FALSE(result["closest"]["note"].get<std::string>().empty()) << result["closest"].dump();
}

}  // namespace
