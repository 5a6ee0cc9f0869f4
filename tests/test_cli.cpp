// Black-box tests of the `scanplan` executable (ccache style): run it, check the exit code,
// stdout and stderr. Golden files live in tests/golden/; SCANPLAN_UPDATE_GOLDEN=1 rewrites them.
#include <gtest/gtest.h>

#include <sys/mount.h>
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <scanplan/config/job.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/trajectory.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/programs/programs.h>
#include "cli/commands/commands.h"
#include "cli/io/output.h"
#include "cli_support.h"
#include "test_support.h"

namespace {

using namespace scanplan::test;

const fs::path kSourceDir = SCANPLAN_SOURCE_DIR;
const std::string kViper = (kSourceDir / "data/robots/viper_s650.yaml").string();
const std::string kDemoJob = (kSourceDir / "data/jobs/demo_rings.yaml").string();

// The JSON prints 17 significant digits and the DH chain is a handful of products of mm-sized
// numbers, so the golden poses of docs/design.md §3.1 come out within rounding noise (~1e-13 mm).
constexpr double kPositionTolMm = 1e-9;
constexpr double kRotationTol = 1e-9;  // unitless matrix entries, same reasoning
constexpr double kAngleTolDeg = 1e-9;

// Minimal JSON reading: every number between `"key": ` and the bracket that closes its value
// (nested arrays such as rotation_matrix come out flattened, row by row).
std::vector<std::vector<double>> allArrays(const std::string& json, const std::string& key) {
  std::vector<std::vector<double>> arrays;
  const std::string tag = "\"" + key + "\": [";
  for (auto at = json.find(tag); at != std::string::npos; at = json.find(tag, at + 1)) {
    std::vector<double> numbers;
    int depth = 0;
    for (std::size_t i = at + tag.size() - 1; i < json.size(); ++i) {
      const char c = json[i];
      if (c == '[') {
        ++depth;
      } else if (c == ']') {
        if (--depth == 0) break;
      } else if (c == '-' || (c >= '0' && c <= '9')) {
        char* end = nullptr;
        numbers.push_back(std::strtod(json.c_str() + i, &end));
        i = static_cast<std::size_t>(end - json.c_str()) - 1;
      }
    }
    arrays.push_back(numbers);
  }
  return arrays;
}

std::vector<double> array(const std::string& json, const std::string& key) {
  const auto arrays = allArrays(json, key);
  return arrays.empty() ? std::vector<double>{} : arrays.front();
}

std::vector<bool> allBools(const std::string& json, const std::string& key) {
  std::vector<bool> values;
  const std::string tag = "\"" + key + "\": ";
  for (auto at = json.find(tag); at != std::string::npos; at = json.find(tag, at + 1)) {
    values.push_back(json.compare(at + tag.size(), 4, "true") == 0);
  }
  return values;
}

std::string join(const std::vector<double>& v) {
  std::ostringstream s;
  s.precision(17);
  for (std::size_t i = 0; i < v.size(); ++i) s << (i ? ", " : "") << v[i];
  return "[" + s.str() + "]";
}

::testing::AssertionResult near(const std::vector<double>& actual,
                                const std::vector<double>& expected,
                                double tol) {
  bool ok = actual.size() == expected.size();
  for (std::size_t i = 0; ok && i < actual.size(); ++i)
    ok = std::abs(actual[i] - expected[i]) <= tol;
  if (ok) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "actual " << join(actual) << "\n  expected "
                                       << join(expected) << " (tolerance " << tol << ")";
}

std::vector<double> column(const std::vector<double>& rotation_row_major, std::size_t c) {
  if (rotation_row_major.size() != 9) return {};
  return {rotation_row_major[c], rotation_row_major[3 + c], rotation_row_major[6 + c]};
}

std::string joinedDeg(const std::vector<double>& q) {
  std::ostringstream s;
  s.precision(17);
  for (std::size_t i = 0; i < q.size(); ++i) s << (i ? "," : "") << q[i];
  return s.str();
}

// Compares `actual` with tests/golden/<name>, or rewrites it under SCANPLAN_UPDATE_GOLDEN=1.
::testing::AssertionResult matchesGolden(const std::string& actual, const std::string& name) {
  const fs::path file = kSourceDir / "tests/golden" / name;
  const char* update = std::getenv("SCANPLAN_UPDATE_GOLDEN");
  if (update != nullptr && std::string(update) == "1") {
    fs::create_directories(file.parent_path());
    writeFile(file, actual);
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

TEST_F(Cli, VersionPrintsNameAndSemanticVersion) {
  const Result run = scanplan({"--version"});
  EXPECT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_TRUE(std::regex_match(run.out, std::regex(R"(scanplan \d+\.\d+\.\d+\n)"))) << run.out;
}

TEST_F(Cli, HelpOnTheAppAndEverySubcommandNamesItsOptions) {
  struct Case {
    std::vector<std::string> args;
    std::vector<std::string> mentions;
  };
  const std::vector<Case> cases = {
      {{"--help"}, {"--version", "--verbose", "--quiet", "plan", "job", "fk", "ik"}},
      {{"plan", "--help"}, {"--out", "job"}},
      {{"job", "--help"}, {"show"}},
      {{"job", "show", "--help"}, {"job", "Job file"}},
      {{"fk", "--help"}, {"--robot", "--job", "--joints", "--json"}},
      {{"ik", "--help"}, {"--robot", "--job", "--trans", "--matrix", "--within-limits", "--json"}},
  };
  for (const Case& c : cases) {
    const Result run = scanplan(c.args);
    std::string what;
    for (const auto& a : c.args) what += a + " ";
    EXPECT_EQ(run.exit_code, 0) << what << "\n" << describe(run);
    for (const auto& m : c.mentions) EXPECT_TRUE(contains(run.out, m)) << what << " lacks " << m;
  }
}

// Every command's help ends with examples on the bundled data. Their data/ files exist, and the
// ones that need no earlier output (fk, ik, check, job show) run as printed, from the
// repository root (here: with data/ made absolute).
TEST_F(Cli, HelpExamplesNameBundledFilesAndRun) {
  const std::vector<std::vector<std::string>> commands = {{"plan"},
                                                          {"validate"},
                                                          {"simulate"},
                                                          {"export"},
                                                          {"path"},
                                                          {"map"},
                                                          {"batch"},
                                                          {"batch", "report"},
                                                          {"batch", "merge"},
                                                          {"job", "show"},
                                                          {"check"},
                                                          {"fk"},
                                                          {"ik"},
                                                          {"watch"}};
  int ran = 0;
  for (const auto& command : commands) {
    std::vector<std::string> args = command;
    args.push_back("--help");
    const Result help = scanplan(args);
    ASSERT_EQ(help.exit_code, 0) << describe(help);
    const std::size_t at = help.out.find("Example");
    ASSERT_NE(at, std::string::npos) << command.front() << " --help has no example\n" << help.out;
    std::istringstream lines(help.out.substr(at));
    std::string line;
    int examples = 0;
    while (std::getline(lines, line)) {
      const std::size_t start = line.find("scanplan ");
      if (start == std::string::npos) continue;
      ++examples;
      std::istringstream words(line.substr(start + 9));
      std::vector<std::string> example;
      for (std::string w; words >> w;) {
        if (w.starts_with("data/")) {
          EXPECT_TRUE(fs::exists(kSourceDir / w)) << line;
          w = (kSourceDir / w).string();
        }
        example.push_back(w);
      }
      ASSERT_GE(example.size(), command.size()) << line;
      for (std::size_t i = 0; i < command.size(); ++i) EXPECT_EQ(example[i], command[i]) << line;
      const std::string& name = command.front();
      if (name == "fk" || name == "ik" || name == "check" || name == "job") {
        const Result run = scanplan(example);
        EXPECT_EQ(run.exit_code, 0) << line << "\n" << describe(run);
        ++ran;
      }
    }
    EXPECT_GE(examples, 1) << command.front();
  }
  EXPECT_EQ(ran, 6);
}

// `completion bash` completes commands, subcommands, options and file names, run in a real bash
// through its completion function (zsh reuses it through bashcompinit; tested where zsh is).
TEST_F(Cli, CompletionScriptCompletesCommandsOptionsAndFiles) {
  const Result script = scanplan({"completion", "bash"});
  ASSERT_EQ(script.exit_code, 0) << describe(script);
  writeFile(dir_ / "scanplan.bash", script.out);
  fs::create_directories(dir_ / "jobs");
  writeFile(dir_ / "jobs/demo.yaml", "x");
  const std::string harness = R"(cd ")" + dir_.string() + R"("
source scanplan.bash
t() { COMP_WORDS=("$@"); COMP_CWORD=$((${#COMP_WORDS[@]} - 1)); COMPREPLY=(); _scanplan;
      echo "${COMPREPLY[*]}"; }
t scanplan pl
t scanplan job s
t scanplan plan jobs/demo.yaml --pla
t scanplan plan jobs/demo.yaml -o out --planner dp --js
t scanplan robot ""
t scanplan plan jobs/de
t scanplan plan -o job
complete -p scanplan
)";
  writeFile(dir_ / "harness.sh", harness);
  std::string out;
  {
    const std::unique_ptr<FILE, int (*)(FILE*)> pipe(
        popen(("bash '" + (dir_ / "harness.sh").string() + "' 2>&1").c_str(), "r"), pclose);
    ASSERT_TRUE(pipe);
    std::array<char, 4096> buffer{};
    while (std::fgets(buffer.data(), buffer.size(), pipe.get()) != nullptr) out += buffer.data();
  }
  const std::vector<std::string> want = {
      "plan",         "show schema",    "--planner", "--json",
      "import check", "jobs/demo.yaml", "jobs",      "complete -o filenames -F _scanplan scanplan"};
  std::istringstream lines(out);
  std::size_t i = 0;
  for (std::string line; std::getline(lines, line); ++i) {
    ASSERT_LT(i, want.size()) << out;
    EXPECT_EQ(line, want[i]) << out;
  }
  EXPECT_EQ(i, want.size()) << out;
  const Result zsh = scanplan({"completion", "zsh"});
  EXPECT_EQ(zsh.exit_code, 0);
  EXPECT_TRUE(contains(zsh.out, "bashcompinit") && contains(zsh.out, "_scanplan()"));
  EXPECT_EQ(scanplan({"completion", "fish"}).exit_code, 2);
}

// A mistyped command or option names what was meant; one that is nothing like any names what
// there is.
TEST_F(Cli, MistypedCommandsAndOptionsSayWhatWasMeant) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"plna", kDemoJob}, "unknown command 'plna'; did you mean 'plan'?"},
      {{"job", "shwo", kDemoJob}, "unknown job command 'shwo'; did you mean 'show'?"},
      {{"robot", "chek", kViper}, "unknown robot command 'chek'; did you mean 'check'?"},
      {{"plan", kDemoJob, "-o", "x", "--plannr", "dp"},
       "unknown option '--plannr' for 'plan'; did you mean '--planner'?"},
      {{"validate", kDemoJob, "-t", "x.csv", "--jsn"},
       "unknown option '--jsn' for 'validate'; did you mean '--json'?"},
      {{"frobnicate"}, "unknown command 'frobnicate' (expected one of: plan, validate"},
      {{"job"}, "'job' needs a command: show, schema"},
  };
  for (const auto& [args, message] : cases) {
    const Result run = scanplan(args);
    EXPECT_EQ(run.exit_code, 2) << describe(run);
    EXPECT_TRUE(contains(run.err, message)) << run.err;
    EXPECT_FALSE(contains(run.err, "did you mean") && contains(message, "frobnicate")) << run.err;
  }
}

// plan --json: one JSON document on stdout, report.json's content with the output folder, the
// exit code and the summary's lines; --quiet does not silence it.
TEST_F(Cli, PlanJsonPrintsOneDocumentWithTheReport) {
  const fs::path out = dir_ / "json";
  std::vector<std::string> args{"plan", kDemoJob, "-o", out.string(), "--json", "--quiet"};
  for (const std::string& o : scanplan::test::kLightDemo) {
    args.push_back("--set");
    args.push_back(o);
  }
  const Result run = scanplan(args);
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  const auto doc = nlohmann::json::parse(run.out, nullptr, false);
  ASSERT_FALSE(doc.is_discarded()) << run.out.substr(0, 400);
  EXPECT_EQ(doc["exit_code"], 0);
  EXPECT_EQ(doc["out_dir"], out.string());
  ASSERT_TRUE(doc["summary"].is_array());
  EXPECT_GT(doc["summary"].size(), 5u);
  const auto report = nlohmann::json::parse(readFile(out / "report.json"));
  for (const auto& [key, value] : report.items()) {
    if (key == "times_s") continue;  // the report's own timing
    EXPECT_EQ(doc[key], value) << key;
  }
}

TEST_F(Cli, UsageErrorsExitTwo) {
  const std::string q0 = "0,0,0,0,0,0";
  Result run = scanplan({"bogus"});
  EXPECT_EQ(run.exit_code, 2) << describe(run);
  run = scanplan({"fk", "--robot", kViper});
  EXPECT_EQ(run.exit_code, 2) << describe(run);
  EXPECT_TRUE(contains(run.err, "--joints")) << run.err;
  run = scanplan({"fk", "--joints", q0});
  EXPECT_EQ(run.exit_code, 2) << describe(run);
  EXPECT_TRUE(contains(run.err, "--robot")) << run.err;
  run = scanplan({"fk", "--robot", kViper, "--job", kDemoJob, "--joints", q0});
  EXPECT_EQ(run.exit_code, 2) << describe(run);
  run = scanplan({"ik", "--robot", kViper});
  EXPECT_EQ(run.exit_code, 2) << describe(run);
  EXPECT_TRUE(contains(run.err, "scanplan: error:") && contains(run.err, "--trans") &&
              contains(run.err, "--matrix"))
      << run.err;
}

// A device or a pipe as the trajectory was read without end (/dev/zero filled the memory):
// refused as not a regular file, exit 4, naming it.
TEST_F(Cli, ADeviceAsTheTrajectoryIsBadInput) {
  const Result run = scanplan({"validate", kDemoJob, "-t", "/dev/zero"});
  EXPECT_EQ(run.exit_code, 4) << describe(run);
  EXPECT_TRUE(contains(run.err, "/dev/zero: is not a regular file")) << run.err;
}

// docs/design.md §3.1 (standard DH, zero offsets). q = 0: the α's of J1/J3 cancel, so the flange
// sits at x = a1 + a2 + a3 = 75 + 270 − 90 = 255, z = d1 + d4 + d6 = 335 + 295 + 80 = 710 mm.
// q2 = −90 stands the upper arm up (J3 at z = 335 + 270) and q3 = 180 points the forearm along
// +x: wrist centre (75 + 295, 0, 605 + 90) = (370, 0, 695). q5 = 0 keeps the flange pointing
// along +x → (450, 0, 695) = TRANS(…, 0, 90, 0); q5 = 90 turns it down → (370, 0, 615) with
// z_F = −z_W.
TEST_F(Cli, FkReproducesTheDesignGoldenPoses) {
  Result run = scanplan({"fk", "--robot", kViper, "--joints", "0,0,0,0,0,0", "--json"});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_TRUE(near(array(run.out, "position_mm"), {255, 0, 710}, kPositionTolMm));

  run = scanplan({"fk", "--robot", kViper, "--joints", "0,-90,180,0,90,0", "--json"});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_TRUE(near(array(run.out, "position_mm"), {370, 0, 615}, kPositionTolMm));
  EXPECT_TRUE(near(column(array(run.out, "rotation_matrix"), 2), {0, 0, -1}, kRotationTol));

  run = scanplan({"fk", "--robot", kViper, "--joints", "0,-90,180,0,0,0", "--json"});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_TRUE(near(array(run.out, "position_mm"), {450, 0, 695}, kPositionTolMm));
  EXPECT_TRUE(near(array(run.out, "trans_zyz_deg"), {0, 90, 0}, kAngleTolDeg));
}

TEST_F(Cli, FkJsonMatchesGoldenFile) {
  const Result run =
      scanplan({"fk", "--robot", kViper, "--joints", "10,-60,150,20,45,30", "--json"});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_TRUE(matchesGolden(run.out, "fk_viper_10_-60_150_20_45_30.json"));
}

TEST_F(Cli, IkJsonMatchesGoldenFile) {
  const Result run = scanplan({"ik", "--robot", kViper, "--trans", "450,0,695,0,90,0", "--json"});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_TRUE(matchesGolden(run.out, "ik_viper_450_0_695_0_90_0.json"));
}

// FK(IK(X)) = X through the command line: every listed solution reaches the target pose.
TEST_F(Cli, EveryIkSolutionFedBackToFkReachesTheTarget) {
  for (const std::string trans : {"450,0,695,0,90,0", "-300,100,500,30,120,45"}) {
    const Result ik = scanplan({"ik", "--robot", kViper, "--trans", trans, "--json"});
    ASSERT_EQ(ik.exit_code, 0) << describe(ik);
    const auto target_p = array(ik.out, "position_mm");
    const auto target_R = array(ik.out, "rotation_matrix");
    const auto solutions_at = ik.out.find("\"solutions\"");
    ASSERT_NE(solutions_at, std::string::npos) << ik.out;
    const auto solutions = allArrays(ik.out.substr(solutions_at), "joints_deg");
    ASSERT_GE(solutions.size(), 2u) << trans;
    for (const auto& q : solutions) {
      ASSERT_EQ(q.size(), 6u);
      const Result fk = scanplan({"fk", "--robot", kViper, "--joints=" + joinedDeg(q), "--json"});
      ASSERT_EQ(fk.exit_code, 0) << describe(fk);
      EXPECT_TRUE(near(array(fk.out, "position_mm"), target_p, kPositionTolMm))
          << trans << " q " << join(q);
      EXPECT_TRUE(near(array(fk.out, "rotation_matrix"), target_R, kRotationTol))
          << trans << " q " << join(q);
    }
  }
}

TEST_F(Cli, IkOfAnUnreachablePoseExitsThreeAndSaysNoSolution) {
  Result run = scanplan({"ik", "--robot", kViper, "--trans", "2000,0,0,0,0,0"});
  EXPECT_EQ(run.exit_code, 3) << describe(run);
  EXPECT_TRUE(contains(run.out + run.err, "no solution")) << describe(run);
  run = scanplan({"ik", "--robot", kViper, "--trans", "2000,0,0,0,0,0", "--json"});
  EXPECT_EQ(run.exit_code, 3) << describe(run);
  EXPECT_TRUE(contains(run.out, "\"reachable\": false")) << run.out;
  EXPECT_TRUE(contains(run.out, "\"solutions\": []")) << run.out;
}

TEST_F(Cli, IkWithinLimitsListsOnlyTheInLimitSolutions) {
  // Joint limits of docs/design.md §3.1, an independent copy of the robot file's numbers.
  constexpr std::array<std::array<double, 2>, 6> kLimitsDeg = {
      {{-170, 170}, {-190, 45}, {-29, 256}, {-190, 190}, {-120, 120}, {-360, 360}}};
  for (const std::string trans : {"450,0,695,0,90,0", "-300,100,500,30,120,45"}) {
    const Result all = scanplan({"ik", "--robot", kViper, "--trans", trans, "--json"});
    const Result in =
        scanplan({"ik", "--robot", kViper, "--trans", trans, "--json", "--within-limits"});
    ASSERT_EQ(all.exit_code, 0) << describe(all);
    ASSERT_EQ(in.exit_code, 0) << describe(in);
    const auto all_flags = allBools(all.out, "within_limits");
    const auto in_flags = allBools(in.out, "within_limits");
    const auto in_count =
        static_cast<std::size_t>(std::count(all_flags.begin(), all_flags.end(), true));
    ASSERT_LT(in_count, all_flags.size()) << trans << ": the case should have some out of limits";
    EXPECT_EQ(in_flags, std::vector<bool>(in_count, true)) << in.out;
    for (const auto& q : allArrays(in.out, "joints_deg")) {
      for (std::size_t j = 0; j < q.size() && j < 6; ++j) {
        EXPECT_TRUE(q[j] >= kLimitsDeg[j][0] && q[j] <= kLimitsDeg[j][1])
            << "j" << j + 1 << " in " << join(q);
      }
    }
  }
}

TEST_F(Cli, IkRejectsANonRigidMatrix) {
  for (const std::string m : {"2,0,0,450,0,1,0,0,0,0,1,695,0,0,0,1",     // scaled x axis
                              "1,0,0,450,0,1,0,0,0,0,-1,695,0,0,0,1",    // a mirror, det −1
                              "1,0,0,450,0,1,0,0,0,0,1,695,0,0,1,1"}) {  // projective last row
    const Result run = scanplan({"ik", "--robot", kViper, "--matrix", m});
    EXPECT_EQ(run.exit_code, 4) << m << "\n" << describe(run);
    EXPECT_TRUE(contains(run.err, "scanplan: error:") && contains(run.err, "--matrix")) << run.err;
  }
}

TEST_F(Cli, FkRejectsBadJointNumbers) {
  for (const std::string joints :
       {"1,2,x,4,5,6", "1,2,3,4,5", "1,2,3,4,5,6,7", "nan,0,0,0,0,0", "0,0,0,inf,0,0", "1,,3,4,5,6",
        "1,2,3deg,4,5,6", "1,2,3,4,5,6,"}) {
    const Result run = scanplan({"fk", "--robot", kViper, "--joints", joints});
    EXPECT_EQ(run.exit_code, 4) << joints << "\n" << describe(run);
    EXPECT_TRUE(contains(run.err, "scanplan: error:") && contains(run.err, "--joints")) << run.err;
  }
}

// demo.yaml mounts the laser frame at X_FS = T(0, 0, 110 mm): the sensor sits 110 mm along the
// flange z axis and keeps the flange orientation.
TEST_F(Cli, FkWithAJobAlsoPrintsTheSensorPoseOffsetByTheMount) {
  const Result text = scanplan({"fk", "--job", kDemoJob, "--joints", "10,-60,150,20,45,30"});
  ASSERT_EQ(text.exit_code, 0) << describe(text);
  EXPECT_TRUE(contains(text.out, "flange") && contains(text.out, "sensor")) << text.out;

  const Result run =
      scanplan({"fk", "--job", kDemoJob, "--joints", "10,-60,150,20,45,30", "--json"});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  const auto sensor_at = run.out.find("\"sensor\"");
  ASSERT_NE(sensor_at, std::string::npos) << run.out;
  const std::string flange = run.out.substr(0, sensor_at);
  const std::string sensor = run.out.substr(sensor_at);
  const auto p_F = array(flange, "position_mm");
  const auto R_F = array(flange, "rotation_matrix");
  const auto z_F = column(R_F, 2);
  ASSERT_EQ(p_F.size(), 3u);
  ASSERT_EQ(z_F.size(), 3u);
  const std::vector<double> p_S = {p_F[0] + 110 * z_F[0], p_F[1] + 110 * z_F[1],
                                   p_F[2] + 110 * z_F[2]};
  EXPECT_TRUE(near(array(sensor, "position_mm"), p_S, kPositionTolMm));
  EXPECT_TRUE(near(array(sensor, "rotation_matrix"), R_F, kRotationTol));
}

TEST_F(Cli, JobShowPrintsEverySection) {
  const Result run = scanplan({"job", "show", kDemoJob});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  for (const std::string line :
       {"\nrobot:\n", "\n  dh:\n", "\ntable:\n", "\n  max_accel_deg_s2: 60\n", "\npart:\n",
        "\n  mesh: ", "\nscanner:\n", "\n  mount:\n"}) {
    EXPECT_TRUE(contains(run.out, line)) << "lacks '" << line << "'\n" << run.out;
  }
}

// A copy of the demo job with absolute paths, so it can live in the scratch folder.
std::string demoJobText(const std::string& mesh) {
  std::string text = readFile(kDemoJob);
  const auto replace = [&text](const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    if (at != std::string::npos) text.replace(at, from.size(), to);
    return at != std::string::npos;
  };
  EXPECT_TRUE(replace("../robots/viper_s650.yaml", kViper));
  EXPECT_TRUE(replace("../parts/demo_housing.stl", mesh));
  return text;
}

TEST_F(Cli, JobWithAnUnknownKeyIsAnInputErrorNamingFileAndLine) {
  std::string text = demoJobText((kSourceDir / "data/parts/demo_housing.stl").string());
  const auto at = text.find("  radius_mm: 200\n");
  ASSERT_NE(at, std::string::npos);
  text.insert(at, "  colour: red\n");
  const auto line =
      1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n');
  const fs::path job = dir_ / "unknown_key.yaml";
  writeFile(job, text);
  const Result run = scanplan({"job", "show", job.string()});
  EXPECT_EQ(run.exit_code, 4) << describe(run);
  EXPECT_TRUE(contains(run.err, "scanplan: error:")) << run.err;
  EXPECT_TRUE(contains(run.err, job.string() + ":" + std::to_string(line))) << run.err;
  EXPECT_TRUE(contains(run.err, "colour")) << run.err;
}

TEST_F(Cli, PlanWritesTheResolvedJob) {
  const fs::path out = dir_ / "out";
  std::vector<std::string> light;
  for (const std::string& o : scanplan::test::kLightDemo) {
    light.push_back("--set");
    light.push_back(o);
  }
  std::vector<std::string> args{"plan", kDemoJob, "-o", out.string()};
  args.insert(args.end(), light.begin(), light.end());
  const Result run = scanplan(args);
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  ASSERT_TRUE(fs::exists(out / "job.yaml")) << describe(run);
  EXPECT_TRUE(tmpFiles(out).empty());
  // The written job is `job show`'s resolved YAML (with the same --set overrides), and it loads
  // again to the same job (only the "fully resolved from <file>" comment on the first line
  // differs).
  args = {"job", "show", kDemoJob};
  args.insert(args.end(), light.begin(), light.end());
  const Result shown = scanplan(args);
  EXPECT_EQ(readFile(out / "job.yaml"), shown.out);
  const Result again = scanplan({"job", "show", (out / "job.yaml").string()});
  EXPECT_EQ(again.exit_code, 0) << describe(again);
  const auto body = [](const std::string& yaml) { return yaml.substr(yaml.find('\n') + 1); };
  EXPECT_EQ(body(again.out), body(shown.out));
}

// The demo's programs, in every language, switch the trigger at each
// scan pass's first and last sample, set the tool (the mount, T(0, 0, 110 mm)) and the payload
// (0.9 kg at the housing's centre: its box centre (50, 0, -25) mm in the laser frame, 110 mm up
// the flange), and last the plan's time within 1 % in their own timing model (read back).
TEST_F(Cli, PlanDemoWritesControllerReadyProgramsInEveryLanguage) {
  const fs::path out = dir_ / "demo";
  const Result run = scanplan(
      {"plan", (kSourceDir / "data/jobs/demo.yaml").string(), "-o", out.string(), "--set",
       "outputs.programs=[vplus, krl, rapid, urscript, csv]", "--set", "simulation.enabled=false"});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  const scanplan::kinematics::Trajectory plan =
      scanplan::kinematics::parseTrajectoryCsv(readFile(out / "trajectory.csv"), "trajectory.csv");
  std::size_t passes = 0;
  for (std::size_t k = 0; k < plan.samples.size(); ++k) {
    passes += plan.samples[k].scanning && (k == 0 || !plan.samples[k - 1].scanning);
  }
  ASSERT_GE(passes, 3u);
  for (const char* file : {"scan.v2", "scan.src", "scan.mod", "scan.script"}) {
    const auto format = scanplan::programs::programFormatOfFile(file);
    ASSERT_TRUE(format) << file;
    const scanplan::programs::ProgramReading back =
        scanplan::programs::readProgram(readFile(out / "programs" / file), *format, file);
    ASSERT_TRUE(back.tool) << file;
    EXPECT_LT((back.tool->translation() - Eigen::Vector3d(0, 0, 0.110)).norm(), 1e-6) << file;
    EXPECT_LT((back.tool->linear() - Eigen::Matrix3d::Identity()).norm(), 1e-7) << file;
    if (*format != scanplan::programs::ProgramFormat::kVplus) {  // V+ states it in a comment only
      EXPECT_NEAR(back.payload_kg, 0.9, 1e-9) << file;
      EXPECT_LT((back.payload_cog - Eigen::Vector3d(0.050, 0.0, 0.085)).norm(), 1e-6) << file;
    }
    std::size_t on = 0, off = 0;
    for (const scanplan::programs::TriggerSwitch& s : back.triggers) {
      EXPECT_EQ(s.output, 1) << file;
      (s.on ? on : off) += 1;
    }
    EXPECT_EQ(on, passes) << file;
    // Idle before; each pass's end (the last pass's, when it runs to the end, after the motion).
    EXPECT_EQ(off, passes + 1) << file;
    ASSERT_FALSE(back.triggers.empty()) << file;
    EXPECT_FALSE(back.triggers.back().on) << file;
    for (std::size_t i = 1; i < back.triggers.size(); ++i)
      EXPECT_NE(back.triggers[i].on, back.triggers[i - 1].on) << file << ", switch " << i;
    const double planned = plan.duration() - plan.samples.front().t;
    const double timed = back.trajectory.duration() - back.trajectory.samples.front().t;
    EXPECT_LT(std::abs(timed - planned) / planned, 0.01) << file << ": " << timed << " s";
  }
}

// An existing file where the output folder should go is the user's mistake, not a crash.
TEST_F(Cli, PlanIntoAnExistingFileIsAnInputError) {
  const fs::path not_a_dir = dir_ / "a_file";
  writeFile(not_a_dir, "x");
  const Result run = scanplan({"plan", kDemoJob, "-o", not_a_dir.string()});
  EXPECT_EQ(run.exit_code, 4) << describe(run);
  EXPECT_TRUE(contains(run.err, "scanplan: error:") && contains(run.err, not_a_dir.string()));
}

TEST_F(Cli, PlanWithAMissingMeshIsAnInputErrorAndLeavesNoTmpFiles) {
  const fs::path mesh = dir_ / "no_such_part.stl";
  const fs::path job = dir_ / "missing_mesh.yaml";
  writeFile(job, demoJobText(mesh.string()));
  const fs::path out = dir_ / "out";
  fs::create_directories(out);
  const Result run = scanplan({"plan", job.string(), "-o", out.string()});
  EXPECT_EQ(run.exit_code, 4) << describe(run);
  EXPECT_TRUE(contains(run.err, "scanplan: error:") && contains(run.err, mesh.string())) << run.err;
  EXPECT_TRUE(tmpFiles(out).empty());
  EXPECT_FALSE(fs::exists(out / "job.yaml"));
}

TEST_F(Cli, CheckScoresAPoseAndListsEveryPair) {
  const Result run =
      scanplan({"check", kDemoJob, "--table", "30", "--joints=-20,-40,120,0,40,0", "--json"});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_EQ(array(run.out, "joint_factors").size(), 6u);
  const auto factors = allArrays(run.out, "witness_a_mm");  // only pairs closer than d_high
  const auto beyond = allBools(run.out, "beyond_d_high");
  EXPECT_GT(beyond.size(), 20u);
  EXPECT_EQ(factors.size(),
            static_cast<std::size_t>(std::count(beyond.begin(), beyond.end(), false)));
  EXPECT_TRUE(contains(run.out, "\"collision\": false")) << run.out;
  EXPECT_TRUE(contains(run.out, "\"limiting\": ")) << run.out;
  const Result text = scanplan({"check", kDemoJob, "--table", "30", "--joints=-20,-40,120,0,40,0"});
  ASSERT_EQ(text.exit_code, 0) << describe(text);
  EXPECT_TRUE(contains(text.out, "scanner - part")) << text.out;
  EXPECT_TRUE(contains(text.out, "collision    no")) << text.out;
  // --set as on the other job commands: the job-wide d_high moves every pair without a rule.
  const Result wider = scanplan({"check", kDemoJob, "--table", "30", "--joints=-20,-40,120,0,40,0",
                                 "--json", "--set", "constraints.clearance.d_high_mm=60"});
  ASSERT_EQ(wider.exit_code, 0) << describe(wider);
  EXPECT_TRUE(contains(wider.out, "\"d_high_mm\": 60")) << wider.out;
  EXPECT_FALSE(contains(run.out, "\"d_high_mm\": 60")) << run.out;
  const Result bad = scanplan({"check", kDemoJob, "--table", "30", "--joints=-20,-40,120,0,40,0",
                               "--set", "constraints.clearance.d_high_mm=-1"});
  EXPECT_EQ(bad.exit_code, 4) << describe(bad);
  EXPECT_TRUE(contains(bad.err, "constraints.clearance.d_high_mm")) << bad.err;
}

TEST_F(Cli, CheckReportsASelfCollisionAsAForbiddenPose) {
  // The scanner folded back into link 1 (joints 2 and 3 near their limits).
  const Result run = scanplan({"check", kDemoJob, "--table", "0", "--joints", "0,-150,250,0,90,0"});
  EXPECT_EQ(run.exit_code, 3) << describe(run);
  EXPECT_TRUE(contains(run.out, "collision    YES")) << run.out;
  EXPECT_TRUE(contains(run.out, "link1 - scanner")) << run.out;
  EXPECT_TRUE(contains(run.out, "CONTACT")) << run.out;
}

// --time picks the scan-path sample at that time and solves it: the joints it reports put the
// flange where the chain of docs/design.md §2 says the scan pose needs it at that table angle.
TEST_F(Cli, CheckAtATimeSolvesTheScanPathSample) {
  const Result run = scanplan({"check", kDemoJob, "--table", "40", "--time", "5", "--json"});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  const std::vector<double> joints = array(run.out, "joints_deg");
  ASSERT_EQ(joints.size(), 6u) << run.out;
  using namespace scanplan;
  const config::JobSpec job = config::loadJob(kDemoJob);
  const kinematics::CellModel cell = config::buildCell(job);
  const kinematics::ScanPath path = cli::generateScanPath(job, cell).path;
  const auto k = static_cast<std::size_t>(std::llround(5.0 / path.dt));
  ASSERT_LT(k, path.samples.size());
  const Eigen::Isometry3d X_BF_wanted = cell.flangeTarget(deg(40.0), path.samples[k].X_PS);
  kinematics::JointVector q;
  for (int i = 0; i < 6; ++i) q(i) = deg(joints[static_cast<std::size_t>(i)]);
  const Eigen::Isometry3d X_BF = cell.robot.fk(q);
  // The JSON prints the joints to 17 digits: the flange agrees to far below a micrometre.
  EXPECT_LT((X_BF.translation() - X_BF_wanted.translation()).norm(), 1e-9);
  EXPECT_LT((X_BF.linear() - X_BF_wanted.linear()).norm(), 1e-9);
  // A time outside the scan path is bad input.
  const Result late = scanplan({"check", kDemoJob, "--table", "40", "--time", "1e6"});
  EXPECT_EQ(late.exit_code, 4) << describe(late);
  EXPECT_TRUE(contains(late.err, "--time")) << late.err;
}

TEST_F(Cli, CheckRejectsBadJointsAndBadPairRules) {
  const Result joints = scanplan({"check", kDemoJob, "--table", "0", "--joints", "0,0,0"});
  EXPECT_EQ(joints.exit_code, 4) << describe(joints);
  EXPECT_TRUE(contains(joints.err, "--joints")) << joints.err;
  // A NaN table angle once reached FCL and aborted the process.
  for (const char* table : {"nan", "inf", "-inf"}) {
    const Result bad = scanplan({"check", kDemoJob, "--table", table, "--joints", "0,0,0,0,0,0"});
    EXPECT_EQ(bad.exit_code, 4) << table << ": " << describe(bad);
    EXPECT_TRUE(contains(bad.err, "--table")) << bad.err;
  }
  const fs::path job = dir_ / "rule.yaml";
  writeFile(job, "robot: " + (kSourceDir / "data/robots/viper_s650.yaml").string() +
                     "\npart: {mesh: " + (kSourceDir / "data/parts/demo_housing.stl").string() +
                     "}\nconstraints:\n  clearance:\n    pairs:\n      - {a: scaner, b: part, "
                     "exclude: true}\n");
  const Result rule =
      scanplan({"check", job.string(), "--table", "0", "--joints", "0,-60,150,0,60,0"});
  EXPECT_EQ(rule.exit_code, 4) << describe(rule);
  EXPECT_TRUE(contains(rule.err, "constraints.clearance.pairs")) << rule.err;
  EXPECT_TRUE(contains(rule.err, "scaner")) << rule.err;
}

// Help says what each command does and what it accepts.
TEST_F(Cli, HelpTextsSayWhatTheCommandsAccept) {
  Result run = scanplan({"plan", "--help"});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  for (const std::string m : {"scan path", "maps", "validation", "robot programs", "simulation",
                              "planner.refine.enabled"})
    EXPECT_TRUE(contains(run.out, m)) << "plan --help lacks " << m << "\n" << run.out;
  for (const std::string command : {"validate", "simulate", "export"}) {
    run = scanplan({command, "--help"});
    ASSERT_EQ(run.exit_code, 0) << describe(run);
    EXPECT_TRUE(contains(run.out, "trajectory CSV") &&
                contains(run.out, "scan.v2, .src, .mod, .script"))
        << command << " --help\n"
        << run.out;
  }
}

// Missing input files are bad input (exit 4) naming the file, for every command; CLI11's
// usage error (exit 2) is only for the command line itself.
TEST_F(Cli, MissingInputFilesAreInputErrorsNamingTheFile) {
  const std::string gone = (dir_ / "nonexist.yaml").string();
  const std::string gone_csv = (dir_ / "nonexist.csv").string();
  const std::string gone_dir = (dir_ / "no_such_run").string();
  const std::string out = (dir_ / "out").string();
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"plan", gone, "-o", out}, gone},
      {{"path", gone, "-o", out}, gone},
      {{"map", gone, "-o", out}, gone},
      {{"check", gone, "--table", "0", "--joints", "0,0,0,0,0,0"}, gone},
      {{"job", "show", gone}, gone},
      {{"validate", gone, "-t", gone_csv}, gone},
      {{"validate", kDemoJob, "-t", gone_csv}, gone_csv},
      {{"simulate", kDemoJob, "-t", gone_csv, "-o", out}, gone_csv},
      {{"export", kDemoJob, "-t", gone_csv, "-o", out}, gone_csv},
      {{"fk", "--robot", gone, "--joints", "0,0,0,0,0,0"}, gone},
      {{"fk", "--job", gone, "--joints", "0,0,0,0,0,0"}, gone},
      {{"ik", "--job", gone, "--trans", "450,0,695,0,90,0"}, gone},
      {{"batch", gone, "-o", out}, gone},
      {{"batch", "report", gone_dir}, gone_dir},
      {{"batch", "merge", gone_dir, "-o", out}, gone_dir},
  };
  for (const auto& [args, file] : cases) {
    SCOPED_TRACE(args.front() + " " + args[1]);
    const Result run = scanplan(args);
    EXPECT_EQ(run.exit_code, 4) << describe(run);
    EXPECT_TRUE(contains(run.err, "scanplan: error: " + file + ": ") &&
                contains(run.err, "does not exist"))
        << run.err;
  }
  EXPECT_FALSE(fs::exists(out));
  // A folder where a file belongs, and the other way round.
  Result run = scanplan({"job", "show", dir_.string()});
  EXPECT_EQ(run.exit_code, 4) << describe(run);
  EXPECT_TRUE(contains(run.err, dir_.string() + ": is a folder")) << run.err;
  run = scanplan({"batch", "report", kDemoJob});
  EXPECT_EQ(run.exit_code, 4) << describe(run);
  EXPECT_TRUE(contains(run.err, kDemoJob + ": is not a folder")) << run.err;
}

// -q: errors only, before or after the subcommand; -v: what was read and how long it took.
TEST_F(Cli, QuietDropsTheSummaryAndGlobalOptionsWorkAfterTheCommand) {
  const fs::path out = dir_ / "out";
  std::vector<std::string> args{
      "plan", kDemoJob, "-o", out.string(), "-q", "--set", "simulation.enabled=false"};
  for (const std::string& o : scanplan::test::kLightDemo) {
    args.push_back("--set");
    args.push_back(o);
  }
  Result run = scanplan(args);
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_EQ(run.out, "");
  EXPECT_EQ(run.err, "");
  EXPECT_TRUE(fs::exists(out / "trajectory.csv"));

  run = scanplan({"-q", "path", (dir_ / "nonexist.yaml").string(), "-o", out.string()});
  EXPECT_EQ(run.exit_code, 4) << describe(run);
  EXPECT_EQ(run.out, "");
  EXPECT_TRUE(contains(run.err, "scanplan: error: ")) << run.err;

  // What job show, fk, check print is their result: -q keeps it.
  run = scanplan({"job", "show", kDemoJob, "--quiet"});
  EXPECT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_TRUE(contains(run.out, "\ntable:\n")) << run.out;

  run = scanplan({"fk", "--robot", kViper, "--joints", "0,0,0,0,0,0", "--json", "-v"});
  EXPECT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_TRUE(contains(run.out, "position_mm")) << run.out;
  EXPECT_TRUE(contains(run.err, "scanplan: debug: done in ")) << run.err;
  run = scanplan({"-v", "job", "show", kDemoJob, "--set", "table.radius_mm=250"});
  EXPECT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_TRUE(contains(run.err, "job demo_rings (" + kDemoJob + "): robot Adept Viper s650") &&
              contains(run.err, "--set table.radius_mm=250"))
      << run.err;
  EXPECT_FALSE(contains(run.out, "debug")) << run.out;
}

// A --set value is blamed on the override, not on a place in the job file.
TEST_F(Cli, SetErrorsNameTheOverride) {
  const Result run =
      scanplan({"plan", kDemoJob, "-o", (dir_ / "out").string(), "--set", "table.radius_mm=abc"});
  EXPECT_EQ(run.exit_code, 4) << describe(run);
  EXPECT_TRUE(contains(run.err,
                       "scanplan: error: --set table.radius_mm=abc: table.radius_mm: "
                       "'abc' is not a number"))
      << run.err;
  EXPECT_FALSE(contains(run.err, "demo.yaml")) << run.err;
}

// A broken part mesh names the job as the user gave it, like every other job error.
TEST_F(Cli, MeshErrorsNameTheJobAsGiven) {
  const fs::path mesh = dir_ / "broken.stl";
  writeFile(mesh, "solid broken\n  facet normal 0 0 1\n    outer loop\n      vertex 0 0\n");
  const fs::path job = dir_ / "broken_mesh.yaml";
  writeFile(job, demoJobText(mesh.string()));
  const fs::path relative = fs::relative(job);
  ASSERT_TRUE(relative.is_relative()) << relative;
  const Result run = scanplan({"plan", relative.string(), "-o", (dir_ / "out").string()});
  EXPECT_EQ(run.exit_code, 4) << describe(run);
  EXPECT_TRUE(contains(run.err, "scanplan: error: " + relative.string() + ": part.mesh: "))
      << run.err;
  EXPECT_FALSE(contains(run.err, "error: " + job.string())) << run.err;
}

// Robustness catalogue: fk and check took --joints=1e300,… (fk printed a pose).
TEST(CliArguments, NumberListsRefuseNumbersBeyondTheLimit) {
  EXPECT_TRUE(throwsInputError(
      [] { scanplan::cli::parseNumberList("1e300,0,0,0,0,0", 6, "--joints", "joints"); },
      {"--joints", "1e300", "within ±1e9"}));
  EXPECT_EQ(scanplan::cli::parseNumberList("1e9,0,0,0,0,-1e9", 6, "--joints", "joints").size(), 6u);
}

}  // namespace

// ---- OutputStage: publishing a folder in one step --------------------------------------------

namespace {

using scanplan::cli::OutputStage;

void write(const fs::path& file, const std::string& text) {
  fs::create_directories(file.parent_path());
  std::ofstream(file, std::ios::binary) << text;
}

std::string read(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Every name in `dir` and beside it that only a run in progress should leave.
std::vector<std::string> leftovers(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir.parent_path())) {
    const std::string n = e.path().filename().string();
    if (n.find(".scanplan-") != std::string::npos) out.push_back(n);
  }
  return out;
}

// An earlier run's OUT: an owned file this run writes again, one it does not, the user's file
// and folder; and in a folder this run writes into, the same three and another run's folder.
void earlierRun(const fs::path& out) {
  write(out / "report.json", "old report");
  write(out / "trajectory.csv", "old trajectory");
  write(out / "notes.txt", "mine");
  write(out / "mine" / "a.txt", "mine too");
  write(out / "programs" / "scan.v2", "old program");
  write(out / "programs" / "scan.src", "old krl");
  write(out / "programs" / "note.txt", "my note");
  write(out / "programs" / "other_run" / "x.v2", "another run's");
  write(out / "profiles" / "profile_000001.png", "old image");  // replaced by another
  write(out / "setup2" / "job.yaml", "old second setup");       // a folder only of old outputs
}

const std::vector<std::string> kOwned = {"report.json",        "trajectory.csv",
                                         "programs/scan.v2",   "programs/scan.src",
                                         "profiles/profile_*", "setup2/job.yaml"};

// This run: a report and a program.
void stageRun(const fs::path& stage) {
  write(stage / "report.json", "new report");
  write(stage / "programs" / "scan.v2", "new program");
  write(stage / "profiles" / "profile_000002.png", "new image");
}

void expectPublished(const fs::path& out) {
  EXPECT_EQ(read(out / "report.json"), "new report");
  EXPECT_FALSE(fs::exists(out / "trajectory.csv")) << "owned, not written again: dropped";
  EXPECT_EQ(read(out / "notes.txt"), "mine");
  EXPECT_EQ(read(out / "mine" / "a.txt"), "mine too");
  EXPECT_EQ(read(out / "programs" / "scan.v2"), "new program");
  EXPECT_FALSE(fs::exists(out / "programs" / "scan.src")) << "owned, not written again: dropped";
  EXPECT_EQ(read(out / "programs" / "note.txt"), "my note") << "a folder is not replaced whole";
  EXPECT_EQ(read(out / "programs" / "other_run" / "x.v2"), "another run's");
  EXPECT_FALSE(fs::exists(out / "profiles" / "profile_000001.png"));
  EXPECT_EQ(read(out / "profiles" / "profile_000002.png"), "new image");
  EXPECT_FALSE(fs::exists(out / "setup2")) << "held only earlier outputs";
  EXPECT_TRUE(leftovers(out).empty());
}

}  // namespace

TEST_F(Cli, AStagedOutputReplacesTheOwnedFilesAndKeepsTheUsersOwn) {
  const fs::path out = dir_ / "out";
  earlierRun(out);
  struct stat before {
  }, after{};
  ASSERT_EQ(::stat((out / "notes.txt").c_str(), &before), 0);
  {
    OutputStage stage(out, kOwned);
    stageRun(stage.dir());
    EXPECT_EQ(read(out / "report.json"), "old report") << "nothing changes before commit";
    stage.commit();
  }
  expectPublished(out);
  ASSERT_EQ(::stat((out / "notes.txt").c_str(), &after), 0);
  EXPECT_EQ(after.st_ino, before.st_ino) << "the user's file itself, not a copy";
}

// With the working folder inside OUT the folders are not exchanged: entries move one by one,
// with the same result.
TEST_F(Cli, AStagedOutputFallsBackToMovingEntriesWhenOutIsTheWorkingFolder) {
  const fs::path out = dir_ / "out";
  earlierRun(out);
  const fs::path cwd = fs::current_path();
  fs::current_path(out);
  {
    OutputStage stage(".", kOwned);
    stageRun(stage.dir());
    stage.commit();
  }
  fs::current_path(cwd);
  expectPublished(out);
}

TEST_F(Cli, AnAbandonedStageLeavesNoFolderAndALockedFolderIsRefused) {
  const fs::path out = dir_ / "new" / "deeper" / "out";
  {
    OutputStage stage(out, {"report.json"});
    write(stage.dir() / "report.json", "never published");
    try {
      OutputStage second(out, {"report.json"});
      ADD_FAILURE() << "a second stage into a locked folder";
    } catch (const scanplan::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("is in use by pid"), std::string::npos) << e.what();
    }
  }  // destroyed without commit: an error or an interrupt
  EXPECT_FALSE(fs::exists(dir_ / "new")) << "the folders made for OUT are removed again";
}

// A full disk names the file as the user asked for it (under OUT, not the staging folder) and
// the system's reason, exits 4 and leaves no OUT. Needs a small tmpfs: skipped where this
// process may not mount one.
TEST_F(Cli, AFullDiskNamesTheFileAndTheReason) {
  const fs::path disk = dir_ / "disk";
  fs::create_directories(disk);
  if (::mount("tmpfs", disk.c_str(), "tmpfs", 0, "size=256k") != 0)
    GTEST_SKIP() << "cannot mount a tmpfs here";
  const fs::path job = fs::path(SCANPLAN_SOURCE_DIR) / "data/jobs/demo_rings.yaml";
  std::vector<std::string> args{"plan", job.string(), "-o", (disk / "out").string()};
  for (const std::string& o : scanplan::test::kLightDemo) args.insert(args.end(), {"--set", o});
  const Result run = scanplan(args);
  const bool out_left = fs::exists(disk / "out");
  ::umount(disk.c_str());
  EXPECT_EQ(run.exit_code, 4) << describe(run);
  EXPECT_TRUE(contains(run.err, (disk / "out").string() + "/")) << run.err;
  EXPECT_TRUE(contains(run.err, "No space left on device")) << run.err;
  EXPECT_FALSE(contains(run.err, "staging")) << run.err;
  EXPECT_FALSE(out_left);
}
