// `scanplan plan` end to end on the demo job (coarsened with --set so each run takes about a
// second): the trajectory, report and figure it writes, every planner, --compare, --refine, the
// no-path exit code, and --set errors.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <scanplan/config/job.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/trajectory.h>
#include <scanplan/kinematics/units.h>
#include "cli/plot/image_io.h"
#include "cli_support.h"
#include "test_support.h"
#include "tests/io_support.h"

namespace {

using namespace scanplan;
using namespace scanplan::test;

const fs::path kSourceDir = SCANPLAN_SOURCE_DIR;
const std::string kDemoJob = (kSourceDir / "data/jobs/demo_rings.yaml").string();
// The demo, lightened (test::kLightDemo) so a plan takes about a second.
std::vector<std::string> lightDemo() {
  std::vector<std::string> args;
  for (const std::string& o : kLightDemo) {
    args.push_back("--set");
    args.push_back(o);
  }
  return args;
}

class CliPlan : public Cli {
 protected:
  Result plan(std::vector<std::string> extra) const {
    std::vector<std::string> args{"plan", kDemoJob, "-o", out().string()};
    const std::vector<std::string> light = lightDemo();
    args.insert(args.end(), light.begin(), light.end());
    args.insert(args.end(), extra.begin(), extra.end());
    return scanplan(args);
  }
  fs::path out() const { return dir_ / "out"; }
  // The lock and staging folders live beside OUT: `.out.scanplan-lock`, `.out.scanplan-staging-N`.
  fs::path beside(const std::string& what) const { return dir_ / (".out.scanplan-" + what); }
  // JSON is YAML: yaml-cpp reads the report.
  YAML::Node report() const { return YAML::LoadFile((out() / "report.json").string()); }
};

// Every sample's joints put the scanner where the path wants it: base ← flange ← sensor equals
// table ← part ← sensor, within 1e-6 mm (the CSV carries 12 significant digits).
void expectReachesTargets(const kinematics::Trajectory& trajectory) {
  const config::JobSpec job = config::loadJob(kDemoJob);
  const kinematics::CellModel cell = config::buildCell(job);
  double worst_mm = 0.0, worst_rot = 0.0;
  for (const auto& s : trajectory.samples) {
    const Eigen::Isometry3d a = cell.X_WB * cell.robot.fk(s.q) * cell.scanner.X_FS;
    const Eigen::Isometry3d b = cell.table.X_WR(s.theta) * cell.part.X_RP * s.X_PS;
    worst_mm = std::max(worst_mm, toMm((a.translation() - b.translation()).norm()));
    worst_rot = std::max(worst_rot, (a.linear() - b.linear()).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst_mm, 1e-6);
  EXPECT_LT(worst_rot, 1e-9);
}

// A second run into a folder another run is writing is refused, naming the holder's pid; the
// lock of a run that was killed is stale and taken over.
// An output folder that is, holds or lies inside an input is refused before anything is written,
// naming the input: the job (plan into the job's own folder), the part mesh, the trajectory
// (simulate), the URDF (robot import onto itself). The inputs are untouched.
TEST_F(CliPlan, AnOutputThatCouldReplaceAnInputIsRefusedNamingIt) {
  const fs::path data = dir_ / "data";
  for (const char* f : {"jobs/demo_rings.yaml", "robots/viper_s650.yaml", "parts/demo_housing.stl",
                        "robots/urdf/viper_s650.urdf"}) {
    fs::create_directories((data / f).parent_path());
    fs::copy_file(kSourceDir / "data" / f, data / f);
  }
  const fs::path job = data / "jobs/demo_rings.yaml";
  const std::string job_text = readFile(job);
  struct Case {
    std::vector<std::string> args;
    std::string input;  // the input the error names
  };
  const std::vector<Case> cases = {
      {{"plan", job.string(), "-o", (data / "jobs").string()}, job.string()},
      {{"plan", job.string(), "-o", data.string()}, job.string()},
      {{"plan", job.string(), "-o", (data / "parts").string()},
       (data / "parts/demo_housing.stl").string()},
      {{"path", job.string(), "-o", (data / "robots").string()},
       (data / "robots/viper_s650.yaml").string()},
      {{"simulate", job.string(), "-t", job.string(), "-o", (data / "jobs").string()},
       job.string()},
      {{"robot", "import", (data / "robots/urdf/viper_s650.urdf").string(), "-o",
        (data / "robots/urdf/viper_s650.urdf").string()},
       (data / "robots/urdf/viper_s650.urdf").string()},
  };
  for (const Case& c : cases) {
    const Result r = scanplan(c.args);
    EXPECT_EQ(r.exit_code, 4) << describe(r);
    EXPECT_TRUE(contains(r.err, "the input " + c.input + ": writing there could replace it"))
        << r.err;
  }
  EXPECT_EQ(readFile(job), job_text);
  EXPECT_FALSE(fs::exists(data / "jobs/report.json"));
  EXPECT_FALSE(fs::exists(data / "report.json"));
  EXPECT_EQ(readFile(data / "robots/urdf/viper_s650.urdf"),
            readFile(kSourceDir / "data/robots/urdf/viper_s650.urdf"));
}

// A second plan into the same OUT replaces its own files one by one: a user's note and another
// run's folder inside programs/ stay; a program of a language no longer asked for goes.
TEST_F(CliPlan, ASecondPlanKeepsTheUsersFilesInItsFolders) {
  ASSERT_EQ(plan({"--set", "outputs.programs=[vplus, krl, csv]"}).exit_code, 0);
  ASSERT_TRUE(fs::exists(out() / "programs/scan.src"));
  writeFile(out() / "programs/note.txt", "checked on the cell, 2026-11-28");
  fs::create_directories(out() / "programs/cell_b");
  writeFile(out() / "programs/cell_b/scan.v2", "another cell's program");
  const Result again = plan({"--set", "outputs.programs=[vplus, csv]"});
  ASSERT_EQ(again.exit_code, 0) << describe(again);
  EXPECT_EQ(readFile(out() / "programs/note.txt"), "checked on the cell, 2026-11-28");
  EXPECT_EQ(readFile(out() / "programs/cell_b/scan.v2"), "another cell's program");
  EXPECT_TRUE(fs::exists(out() / "programs/scan.v2"));
  EXPECT_FALSE(fs::exists(out() / "programs/scan.src")) << "an earlier output not written again";
}

// This process's start time (/proc/self/stat field 22), as a run writes it into its lock.
long long ownStartTime() {
  std::ifstream in("/proc/self/stat");
  std::string stat;
  std::getline(in, stat);
  std::istringstream fields(stat.substr(stat.rfind(')') + 1));
  std::string field;
  for (int i = 3; i <= 22; ++i) fields >> field;
  return std::stoll(field);
}

TEST_F(CliPlan, AFolderInUseIsRefusedAndAStaleLockTakenOver) {
  fs::create_directories(out());
  // This test process stands for a run holding the lock: its pid and its start time.
  std::ofstream(beside("lock")) << ::getpid() << " " << ownStartTime() << "\n";
  const Result busy = plan({"--set", "simulation.enabled=false"});
  EXPECT_EQ(busy.exit_code, 4) << describe(busy);
  EXPECT_TRUE(contains(busy.err, "is in use by pid " + std::to_string(::getpid()))) << busy.err;
  EXPECT_FALSE(fs::exists(out() / "report.json")) << "nothing written";
  // The same live pid with another start time, or alone while its process is not scanplan: a
  // later process reusing a dead run's pid. The lock is stale.
  for (const std::string& holder :
       {fmt::format("{} {}", ::getpid(), ownStartTime() + 1), std::to_string(::getpid())}) {
    std::ofstream(beside("lock")) << holder << "\n";
    const Result taken = plan({"--set", "simulation.enabled=false"});
    EXPECT_EQ(taken.exit_code, 0) << holder << ": " << describe(taken);
    EXPECT_FALSE(fs::exists(beside("lock"))) << "released when done";
  }
  // A FIFO where the lock goes is no lock: refused at once (a read would block), and kept.
  ASSERT_EQ(::mkfifo(beside("lock").c_str(), 0644), 0);
  const Result fifo = plan({"--set", "simulation.enabled=false"});
  EXPECT_EQ(fifo.exit_code, 4) << describe(fifo);
  EXPECT_TRUE(contains(fifo.err, "is not a lock file scanplan wrote")) << fifo.err;
  EXPECT_TRUE(fs::is_fifo(beside("lock")));
  fs::remove(beside("lock"));
  // A pid that has exited: a child that ends at once.
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ::waitpid(child, nullptr, 0);
  std::ofstream(beside("lock")) << child << "\n";
  const Result run = plan({"--set", "simulation.enabled=false"});
  EXPECT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_TRUE(fs::exists(out() / "report.json"));
  EXPECT_FALSE(fs::exists(beside("lock"))) << "released when done";
}

TEST_F(CliPlan, WritesTrajectoryReportAndPathFigure) {
  const Result run = plan({});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  for (const char* f : {"trajectory.csv", "report.json", "configmap_path.png", "configmap_path.svg",
                        "configmap.npy", "path.csv", "job.yaml"}) {
    EXPECT_TRUE(fs::exists(out() / f)) << f;
  }
  EXPECT_TRUE(tmpFiles(out()).empty());
  EXPECT_TRUE(contains(run.out, "plan       ray on ")) << run.out;
  EXPECT_TRUE(contains(run.out, "baseline   DP optimum")) << run.out;

  const kinematics::Trajectory trajectory = kinematics::parseTrajectoryCsv(
      readFile(out() / "trajectory.csv"), (out() / "trajectory.csv").string());
  const YAML::Node r = report();
  EXPECT_EQ(r["status"].as<std::string>(), "planned");
  EXPECT_EQ(r["planner"]["method"].as<std::string>(), "ray");
  EXPECT_EQ(r["path"]["samples"].as<std::size_t>(), trajectory.samples.size());
  const YAML::Node j = r["objective"];
  EXPECT_NEAR(
      j["J_s"].as<double>(),
      j["cost_f_s"].as<double>() + j["cost_omega_s"].as<double>() + j["cost_alpha_s"].as<double>(),
      1e-9);
  EXPECT_LE(r["path"]["max_abs_omega_deg_s"].as<double>(), 30.0 * (1 + 1e-9));
  EXPECT_LE(r["path"]["max_abs_alpha_deg_s2"].as<double>(), 60.0 * (1 + 1e-9));
  EXPECT_GT(r["path"]["min_f"].as<double>(), 0.0);
  EXPECT_TRUE(r["dp_baseline"]["gap_percent"].IsDefined());
  EXPECT_EQ(r["job_hash"].as<std::string>().size(), 16u);
  // The cell transforms, mm: the demo's table axis sits at x = 520 mm.
  EXPECT_DOUBLE_EQ(r["cell"]["X_WA"][0][3].as<double>(), 520.0);
  EXPECT_DOUBLE_EQ(r["cell"]["X_WA"][3][3].as<double>(), 1.0);

  // The trajectory: the table speed and acceleration bounds hold on the written samples, and
  // the scan pose is reached at every sample.
  const auto& s = trajectory.samples;
  for (std::size_t k = 1; k < s.size(); ++k) {
    const double dt = s[k].t - s[k - 1].t;
    EXPECT_LE(std::abs(s[k].theta - s[k - 1].theta) / dt, deg(30.0) * (1 + 1e-6)) << k;
    EXPECT_GT(s[k].f, 0.0) << k;
  }
  expectReachesTargets(trajectory);

  const cli::RgbImage figure = test::decodePng(readFile(out() / "configmap_path.png"));
  EXPECT_GE(figure.width, 180);
  EXPECT_TRUE(contains(readFile(out() / "configmap_path.svg"), "ray + refine J "));
}

TEST_F(CliPlan, EveryPlannerFindsAnExecutablePathOnTheDemo) {
  for (const std::string method : {"ray", "dp", "ompl"}) {
    SCOPED_TRACE(method);
    fs::remove_all(out());
    const Result run = plan({"--planner", method, "--set", "planner.ompl.max_iterations=3000"});
    ASSERT_EQ(run.exit_code, 0) << describe(run);
    EXPECT_EQ(report()["planner"]["method"].as<std::string>(), method);
    expectReachesTargets(
        kinematics::parseTrajectoryCsv(readFile(out() / "trajectory.csv"), "trajectory.csv"));
  }
}

TEST_F(CliPlan, CompareRunsTheOtherPlannersOnTheChosenBranch) {
  const Result run = plan({"--compare", "--set", "planner.ompl.max_iterations=3000"});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  const YAML::Node compare = report()["compare"];
  ASSERT_TRUE(compare.IsSequence());
  ASSERT_EQ(compare.size(), 2u);
  EXPECT_EQ(compare[0]["method"].as<std::string>(), "dp");
  EXPECT_EQ(compare[1]["method"].as<std::string>(), "ompl");
  const std::string svg = readFile(out() / "configmap_path.svg");
  EXPECT_TRUE(contains(svg, "ray + refine J ") && contains(svg, "dp J ")) << svg;
}

TEST_F(CliPlan, RefineNeverRaisesTheObjective) {
  const Result run = plan({"--set", "planner.refine.enabled=false", "--refine"});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  const YAML::Node r = report();
  ASSERT_TRUE(r["refine"].IsDefined()) << readFile(out() / "report.json");
  EXPECT_LE(r["refine"]["J_after_s"].as<double>(), r["refine"]["J_before_s"].as<double>());
  EXPECT_DOUBLE_EQ(r["objective"]["J_s"].as<double>(), r["refine"]["J_after_s"].as<double>());
  EXPECT_TRUE(contains(run.out, "refine     J ")) << run.out;
}

TEST_F(CliPlan, SameJobSameBytes) {
  ASSERT_EQ(plan({"--set", "planner.refine.enabled=false"}).exit_code, 0);
  const std::string trajectory = readFile(out() / "trajectory.csv");
  const std::string map = readFile(out() / "configmap.npy");
  const std::string figure = readFile(out() / "configmap_path.png");
  fs::remove_all(out());
  ASSERT_EQ(plan({"--set", "planner.refine.enabled=false"}).exit_code, 0);
  EXPECT_EQ(readFile(out() / "trajectory.csv"), trajectory);
  EXPECT_EQ(readFile(out() / "configmap.npy"), map);
  EXPECT_EQ(readFile(out() / "configmap_path.png"), figure);
  EXPECT_FALSE(report()["refine"].IsDefined());
}

TEST_F(CliPlan, UnreachableCellExitsThreeWithAReportThatSaysWhy) {
  // The table 1 m from the robot: the part is within the arm's stretch (the placement check
  // passes) but no scan pose is reachable. (3 m away is refused at placement: test_pipeline.)
  const Result run = plan({"--set", "table.axis.xyz_mm=[1000, 0, 0]"});
  EXPECT_EQ(run.exit_code, 3) << describe(run);
  EXPECT_TRUE(contains(run.out, "NO PATH")) << run.out;
  EXPECT_FALSE(fs::exists(out() / "trajectory.csv"));
  const YAML::Node r = report();
  EXPECT_EQ(r["status"].as<std::string>(), "no_path");
  EXPECT_TRUE(contains(r["reason"].as<std::string>(),
                       "(scan.paths[0], ring): the sensor poses are out of the arm's reach at "
                       "every table angle: move table.axis"))
      << r["reason"].as<std::string>();
  EXPECT_TRUE(tmpFiles(out()).empty());
}

// Staging folders (or old outputs set aside) left in `dir` or beside it, if any.
std::vector<fs::path> stagingFolders(const fs::path& dir) {
  std::vector<fs::path> out;
  for (const fs::path& d : {dir, dir.parent_path()}) {
    std::error_code ec;  // `dir` may not exist
    for (const auto& e : fs::directory_iterator(d, ec)) {
      const std::string name = e.path().filename().string();
      if (name.find(".scanplan-staging") != std::string::npos ||
          name.find(".scanplan-old") != std::string::npos)
        out.push_back(e.path());
    }
  }
  return out;
}

TEST_F(CliPlan, ReplanningIntoTheSameFolderLeavesNothingOfTheEarlierPlan) {
  ASSERT_EQ(plan({}).exit_code, 0);
  ASSERT_TRUE(fs::exists(out() / "trajectory.csv"));
  ASSERT_TRUE(fs::exists(out() / "programs"));
  writeFile(out() / "notes.txt", "the user's own file");
  fs::create_directories(out() / "mine" / "deeper");
  writeFile(out() / "mine" / "deeper" / "a.txt", "the user's own folder");
  // Same folder, nothing reachable: the earlier trajectory and programs must not survive beside
  // the new report (a robot-side tool would pick them up as the plan).
  const Result run = plan({"--set", "table.axis.xyz_mm=[1000, 0, 0]"});
  EXPECT_EQ(run.exit_code, 3) << describe(run);
  EXPECT_EQ(report()["status"].as<std::string>(), "no_path");
  for (const char* stale : {"trajectory.csv", "programs", "cloud.ply", "coverage.ply", "cloud.png",
                            "configmap_path.png", "configmap_path.svg"}) {
    EXPECT_FALSE(fs::exists(out() / stale)) << stale;
  }
  EXPECT_TRUE(fs::exists(out() / "configmap.npy"));  // this run's maps
  EXPECT_EQ(readFile(out() / "notes.txt"), "the user's own file");
  EXPECT_EQ(readFile(out() / "mine" / "deeper" / "a.txt"), "the user's own folder");
  EXPECT_TRUE(stagingFolders(out()).empty());
}

TEST_F(CliPlan, ALateErrorLeavesTheEarlierOutputsAsTheyWere) {
  ASSERT_EQ(plan({}).exit_code, 0);
  const std::string job = readFile(out() / "job.yaml");
  const std::string trajectory = readFile(out() / "trajectory.csv");
  // Bad input found only when the map is sized, after the job was read and checked.
  const Result run = plan({"--set", "map.memory_limit_mb=1"});
  EXPECT_EQ(run.exit_code, 4) << describe(run);
  EXPECT_TRUE(contains(run.err, "memory_limit_mb")) << run.err;
  EXPECT_EQ(readFile(out() / "job.yaml"), job);
  EXPECT_EQ(readFile(out() / "trajectory.csv"), trajectory);
  EXPECT_TRUE(stagingFolders(out()).empty());
  EXPECT_TRUE(tmpFiles(out()).empty());
}

// A run that was killed leaves its staging folder; the next run into the folder removes it
// once its process is gone, and leaves a running one's alone.
TEST_F(CliPlan, StagingFoldersOfKilledRunsAreCleanedUp) {
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) ::_exit(0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);  // `child` is now a pid of no process
  const fs::path dead = beside("staging-" + std::to_string(child));
  const fs::path alive = beside("staging-" + std::to_string(::getpid()));
  fs::create_directories(out());
  fs::create_directories(dead);
  fs::create_directories(alive);
  writeFile(dead / "report.json", "{}");
  writeFile(alive / "report.json", "{}");
  const Result run = plan({});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_FALSE(fs::exists(dead));
  EXPECT_TRUE(fs::exists(alive / "report.json")) << "another run's folder, still in use";
  EXPECT_EQ(stagingFolders(out()), std::vector<fs::path>{alive});
}

// Starts `scanplan plan` (the light demo) into `out`, stdout and stderr into `log`; its pid.
pid_t startPlan(const fs::path& out, const fs::path& log) {
  std::vector<std::string> args{SCANPLAN_BINARY, "plan", kDemoJob, "-o", out.string()};
  for (const std::string& a : lightDemo()) args.push_back(a);
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_CREAT | O_WRONLY | O_TRUNC, 0644);
    ::dup2(fd, 1);
    ::dup2(fd, 2);
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  return pid;
}

// The exit code of `pid` once it ends.
int exitCode(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// SIGINT and SIGTERM in the middle of a run: exit 130 / 143, OUT as it was (the earlier run's
// files byte for byte, or no OUT at all), no staging folder or lock left. The signal comes once
// the run has started writing (its staging folder exists) or, on a fast machine, after it ended
// (then OUT is the new complete output, exit 0).
TEST_F(CliPlan, AnInterruptedRunLeavesTheOutputAsItWasAndSaysSo) {
  for (const auto& [sig, code] : {std::pair{SIGINT, 130}, std::pair{SIGTERM, 143}}) {
    ASSERT_EQ(plan({}).exit_code, 0);
    const std::string report_before = readFile(out() / "report.json");
    for (const bool existing : {true, false}) {
      if (!existing) fs::remove_all(out());
      const pid_t pid = startPlan(out(), dir_ / "log.txt");
      const fs::path stage = beside("staging-" + std::to_string(pid));
      for (int k = 0; k < 2000 && !fs::exists(stage) && ::waitpid(pid, nullptr, WNOHANG) == 0; ++k)
        ::usleep(5000);
      ::kill(pid, sig);
      const int got = exitCode(pid);
      const std::string log = readFile(dir_ / "log.txt");
      EXPECT_TRUE(stagingFolders(out()).empty()) << log;
      EXPECT_FALSE(fs::exists(beside("lock"))) << log;
      if (got == 0) continue;  // it had finished
      EXPECT_EQ(got, code) << log;
      EXPECT_TRUE(contains(log, sig == SIGINT ? "stopped by SIGINT" : "stopped by SIGTERM")) << log;
      if (existing)
        EXPECT_EQ(readFile(out() / "report.json"), report_before) << log;
      else
        EXPECT_FALSE(fs::exists(out())) << log;
    }
  }
}

TEST_F(CliPlan, ALateErrorIntoANewFolderLeavesNoFolder) {
  const Result run = plan({"--set", "map.memory_limit_mb=1"});
  EXPECT_EQ(run.exit_code, 4) << describe(run);
  EXPECT_FALSE(fs::exists(out())) << "a failed run left " << out();
}

TEST_F(CliPlan, SetOverridesAreValidatedLikeTheFile) {
  struct Case {
    std::vector<std::string> args;
    int code;
    std::vector<std::string> says;
  };
  const std::vector<Case> cases{
      {{"--set", "planner.ray.horizont=5"}, 4, {"planner.ray", "horizont", "horizon"}},
      {{"--set", "planner.ray.horizon=abc"}, 4, {"planner.ray.horizon", "abc"}},
      {{"--set", "planner.method=astar"}, 4, {"planner.method", "astar", "ray"}},
      {{"--set", "planner"}, 4, {"--set 'planner'", "key.path=value"}},
      {{"--set", "scan.paths[7].height_mm=5"}, 4, {"scan.paths has no item [7]"}},
      {{"--planner", "astar"}, 2, {"astar"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.args.back());
    const Result run = plan(c.args);
    EXPECT_EQ(run.exit_code, c.code) << describe(run);
    for (const std::string& s : c.says) EXPECT_TRUE(contains(run.err, s)) << run.err;
  }
}

}  // namespace

namespace {

// Coverage is claimed only at a resolution the simulated scanner has: one ray per profile is
// refused naming the key; rays farther apart than the coverage spacing are a warning that gives
// the real pitch (the line's width at mid depth over the gaps between rays) and the rays needed.
TEST(ScannerResolution, OneRayIsRefusedAndSparseRaysAreWarnedWithTheRealPitch) {
  config::JobSpec job = config::loadJob(kDemoJob, {"scanner.rays_per_profile=1"});
  try {
    (void)config::toProblem(job);
    ADD_FAILURE() << "one ray per profile was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("scanner.rays_per_profile: 1"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("demo_rings.yaml"), std::string::npos) << e.what();
  }
  job = config::loadJob(kDemoJob, {"scanner.rays_per_profile=11"});
  const kinematics::CellModel cell = config::buildCell(job);
  pipeline::ScanProblem problem = config::toProblem(job, cell, kinematics::TriangleMesh{});
  ASSERT_TRUE(problem.simulation);
  const scanner::LaserWindow w = scanner::laserWindow(problem.optics);
  const double pitch = 2.0 * w.halfWidth(0.5 * (w.z_min + w.z_max)) / 10.0;
  problem.simulation->point_spacing = 0.0;  // measured at the rays' own pitch: no warning
  EXPECT_EQ(config::checkScannerResolution(job, problem), "");
  problem.simulation->point_spacing = 1.01 * pitch;
  EXPECT_EQ(config::checkScannerResolution(job, problem), "");
  problem.simulation->point_spacing = 0.5 * pitch;
  const std::string warning = config::checkScannerResolution(job, problem);
  EXPECT_NE(warning.find(fmt::format("{:.2f} mm apart", toMm(pitch))), std::string::npos)
      << warning;
  EXPECT_NE(warning.find(" 21 rays match"), std::string::npos) << warning;
}

}  // namespace

// Output that cannot reach standard output (/dev/full: every write fails with ENOSPC) is an
// error, exit 4, never a silent success: a job shown, a schema, a plan's JSON document.
TEST_F(CliPlan, StandardOutputThatCannotBeWrittenIsAnError) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const fs::path err = dir_ / "err.txt";
  const auto run = [&](const std::string& args) {
    const std::string command =
        std::string(SCANPLAN_BINARY) + " " + args + " > /dev/full 2> '" + err.string() + "'";
    const int status = std::system(command.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  for (const std::string& args :
       {"job show '" + kDemoJob + "'", std::string("job schema"),
        "plan '" + kDemoJob + "' -o '" + out().string() +
            "' --json --set scan.dt_s=0.2 --set simulation.enabled=false"}) {
    EXPECT_EQ(run(args), 4) << args;
    EXPECT_NE(readFile(err).find("standard output: cannot be written"), std::string::npos)
        << args << ": " << readFile(err);
  }
  // --quiet: the summary goes nowhere, so nothing is lost.
  EXPECT_EQ(run("plan '" + kDemoJob + "' -o '" + out().string() +
                "' --quiet --set scan.dt_s=0.2 --set simulation.enabled=false"),
            0)
      << readFile(err);
}
