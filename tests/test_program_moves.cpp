// The automatic scan's program: each pass a segment planned on its own, joined by point-to-point
// moves at the robot's limits (pipeline/program_moves.h). Checked on a synthetic part by the
// validation of the whole program and by recomputing its time split and moves from the samples.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/parallel_invoke.h>

#include <scanplan/collision/clearance.h>
#include <scanplan/config/job.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/ptp_move.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/pipeline/plan_scan.h>
#include <scanplan/pipeline/program_moves.h>
#include <scanplan/planner/validation.h>
#include "test_support.h"
#include "tests/part_support.h"

namespace {

using namespace scanplan;

// A box x × y × z (mm) as an STL file.
std::filesystem::path writeBox(const std::filesystem::path& file, double x, double y, double z) {
  std::vector<test::Quad> quads;
  test::addBox(quads, Eigen::Vector3d::Zero(), Eigen::Vector3d(x, y, z));
  test::writeStl(file, quads);
  return file;
}

pipeline::ScanProblem boxProblem(const std::filesystem::path& mesh,
                                 std::vector<std::string> extra = {}) {
  std::vector<std::string> set{"part.mesh=" + mesh.string(),
                               "part.place=table",
                               "scan.paths=[]",
                               "scan.auto={point_spacing_mm: 1.0, sample_spacing_mm: 4}",
                               "scan.dt_s=0.2",
                               "map.angle_step_deg=4",
                               "scanner.rays_per_profile=80"};
  set.insert(set.end(), extra.begin(), extra.end());
  return config::toProblem(config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml", set));
}

class ProgramMoves : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // One folder per process: ctest runs each test of the suite in a process of its own, in
    // parallel, and one's teardown must not remove another's part.
    dir_ = std::filesystem::temp_directory_path() /
           ("scanplan_test_program_moves_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
    problem_ = std::make_unique<pipeline::ScanProblem>(
        boxProblem(writeBox(dir_ / "box.stl", 100, 80, 70)));
    plan_ = std::make_unique<pipeline::ScanPlan>(pipeline::planScan(*problem_));
  }
  static void TearDownTestSuite() {
    plan_.reset();
    problem_.reset();
    std::filesystem::remove_all(dir_);
  }
  static std::filesystem::path dir_;
  static std::unique_ptr<pipeline::ScanProblem> problem_;
  static std::unique_ptr<pipeline::ScanPlan> plan_;
};
std::filesystem::path ProgramMoves::dir_;
std::unique_ptr<pipeline::ScanProblem> ProgramMoves::problem_;
std::unique_ptr<pipeline::ScanPlan> ProgramMoves::plan_;

TEST_F(ProgramMoves, EveryPassIsASegmentAndTheJoinedProgramIsValid) {
  const pipeline::ScanPlan& plan = *plan_;
  ASSERT_TRUE(plan.planned()) << plan.reason;
  ASSERT_TRUE(plan.prepared->auto_scan);
  const auto& path = plan.prepared->path.path;
  EXPECT_EQ(path.breaks.size() + 1, plan.prepared->auto_scan->passes.size());
  ASSERT_TRUE(plan.validation);
  // The validation proves the whole program: limits, joint and table speeds, the table's
  // acceleration at every knot (the seams between passes and moves included), collisions.
  EXPECT_TRUE(plan.validation->valid);
  // Every pass runs once, each in the program; no pass dropped on a box.
  EXPECT_TRUE(plan.dropped.empty());
  EXPECT_EQ(plan.order.size(), path.breaks.size() + 1);
  EXPECT_EQ(plan.program.moves + 1, plan.order.size());
}

TEST_F(ProgramMoves, TheTimeSplitAddsUpFromTheSamples) {
  const pipeline::ScanPlan& plan = *plan_;
  ASSERT_TRUE(plan.trajectory);
  const auto& s = plan.trajectory->trajectory.samples;
  double scanning = 0.0;
  std::size_t runs = 0;
  for (std::size_t k = 1; k < s.size(); ++k) {
    ASSERT_GT(s[k].t, s[k - 1].t) << k;
    if (s[k].scanning && s[k - 1].scanning) scanning += s[k].t - s[k - 1].t;
    if (s[k].scanning && !s[k - 1].scanning) ++runs;
  }
  EXPECT_EQ(runs + (s.front().scanning ? 1 : 0), plan.order.size());
  EXPECT_NEAR(plan.program.scanning, scanning, 1e-9);
  EXPECT_NEAR(plan.program.total, s.back().t - s.front().t, 1e-9);
  EXPECT_NEAR(plan.program.scanning + plan.program.moving, plan.program.total, 1e-9);
  // Each pass is sampled on whole map steps: its scanning time is at least what it was planned
  // to take (never faster), and the sum matches within a step per pass.
  const auto& report = *plan.prepared->auto_scan;
  const double dt = plan.prepared->path.path.dt;
  EXPECT_GE(plan.program.scanning, report.scan_time - 1e-9);
  EXPECT_LE(plan.program.scanning,
            report.scan_time + dt * static_cast<double>(report.passes.size()) + 1e-9);
}

TEST_F(ProgramMoves, MovesBetweenPassesBeatTheOldDetourAroundTheSafeSphere) {
  // The tour's estimate is the old program's moves: back off, around the sphere at 100 mm/s,
  // in again. The point-to-point moves at the robot's limits must be shorter.
  const pipeline::ScanPlan& plan = *plan_;
  ASSERT_TRUE(plan.planned());
  EXPECT_LT(plan.program.moving, plan.prepared->auto_scan->transfer_time);
}

TEST_F(ProgramMoves, AMoveIsNoSlowerThanItsSlowestAxisNeeds) {
  // Between two runs the move's time is bounded below by each axis's own trapezoid at the
  // limits the moves use (the brake and launch only add to it).
  const pipeline::ScanPlan& plan = *plan_;
  ASSERT_TRUE(plan.trajectory);
  const auto& cell = problem_->cell;
  const pipeline::MoveSettings ms;
  const auto lim = kinematics::axisLimits(cell.robot, cell.table, ms.speed_scale, ms.accel_time);
  const auto& s = plan.trajectory->trajectory.samples;
  for (std::size_t k = 1; k < s.size(); ++k) {
    if (!(s[k - 1].scanning && !s[k].scanning)) continue;
    std::size_t m = k;
    while (m < s.size() && !s[m].scanning) ++m;
    if (m == s.size()) break;
    const double d_table = std::abs(s[m].theta - s[k - 1].theta);
    const double need = d_table >= lim.speed(0) * lim.speed(0) / lim.accel(0)
                            ? d_table / lim.speed(0) + lim.speed(0) / lim.accel(0)
                            : 2.0 * std::sqrt(d_table / lim.accel(0));
    // Brakes and launches can reduce how far the middle part has to go by at most v²/(2a) at
    // each end; allow that much.
    const double slack = 2.0 * lim.speed(0) / lim.accel(0);
    EXPECT_GE(s[m].t - s[k - 1].t, need - slack) << "move at t = " << s[k - 1].t;
  }
}

// The program's scanning runs, each as a segment of its own (times as in the program).
std::vector<kinematics::Trajectory> scanningRuns(const kinematics::Trajectory& program) {
  std::vector<kinematics::Trajectory> runs;
  const auto& s = program.samples;
  for (std::size_t k = 0; k < s.size(); ++k) {
    if (!s[k].scanning) continue;
    if (k == 0 || !s[k - 1].scanning) runs.emplace_back();
    runs.back().samples.push_back(s[k]);
  }
  return runs;
}

// Joint 2 turned from the sample's until the arm meets something (f = 0), never past its limits.
std::optional<kinematics::JointVector> blocked(const pipeline::ScanPlan& plan,
                                               const kinematics::TrajectorySample& at) {
  collision::ClearanceEvaluator clearance(*plan.prepared->scene);
  const auto& robot = plan.prepared->scene->cell().robot;
  for (const double sign : {1.0, -1.0})
    for (double d = 0.05; d < 3.0; d += 0.05) {
      kinematics::JointVector q = at.q;
      q(1) += sign * d;
      if (!robot.withinLimits(q)) break;
      if (!(clearance.factor(at.theta, q) > 0.0)) return q;
    }
  return std::nullopt;
}

TEST_F(ProgramMoves, APassNoMoveEntersIsRunLastAndBackwardsWhereItsOtherEndIsClear) {
  const pipeline::ScanPlan& plan = *plan_;
  ASSERT_TRUE(plan.trajectory);
  std::vector<kinematics::Trajectory> runs = scanningRuns(plan.trajectory->trajectory);
  ASSERT_GE(runs.size(), 3u);
  runs.resize(3);
  // The middle pass starts where the arm is in a collision: no move can end there.
  auto& b = runs[1].samples;
  ASSERT_GE(b.size(), 3u);
  const auto q = blocked(plan, b.front());
  ASSERT_TRUE(q) << "no colliding joint 2 found";
  b[0].q = b[1].q = *q;
  const collision::Scene& scene = *plan.prepared->scene;
  const pipeline::JoinedProgram joined = pipeline::joinSegments(scene, runs, {});
  EXPECT_TRUE(joined.dropped.empty());
  ASSERT_EQ(joined.start_times.size(), 3u);
  EXPECT_LT(joined.start_times[0], joined.start_times[2]);
  EXPECT_LT(joined.start_times[2], joined.start_times[1]);
  EXPECT_EQ(joined.flipped, (std::vector<std::uint8_t>{0, 1, 0}));
  // It runs last and backwards: the program ends on the pass's first (blocked) pose.
  EXPECT_EQ(joined.trajectory.samples.back().q, *q);
  EXPECT_EQ(joined.times.moves, 2u);

  // Blocked at both ends: dropped, and the reason says what was tried.
  b.back().q = b[b.size() - 2].q = *q;
  const pipeline::JoinedProgram dropped = pipeline::joinSegments(scene, runs, {});
  ASSERT_EQ(dropped.dropped.size(), 1u);
  EXPECT_EQ(dropped.dropped[0].first, 1u);
  EXPECT_NE(dropped.dropped[0].second.find("either way round"), std::string::npos);
  EXPECT_TRUE(std::isnan(dropped.start_times[1]));
  EXPECT_EQ(dropped.times.moves, 1u);
}

// A blocked move backs off at one end alone where that clears it: the program's moves are never
// slower than backing off at both ends, and the program stays valid.
TEST_F(ProgramMoves, BackingOffAtOneEndIsNeverSlowerThanAtBoth) {
  const pipeline::ScanPlan& plan = *plan_;
  ASSERT_TRUE(plan.trajectory);
  const std::vector<kinematics::Trajectory> runs = scanningRuns(plan.trajectory->trajectory);
  const collision::Scene& scene = *plan.prepared->scene;
  pipeline::MoveSettings both;
  both.one_sided = false;
  const pipeline::JoinedProgram one = pipeline::joinSegments(scene, runs, {});
  const pipeline::JoinedProgram two = pipeline::joinSegments(scene, runs, both);
  ASSERT_TRUE(one.dropped.empty() && two.dropped.empty());
  ASSERT_GT(two.times.detours, 0u) << "no move of this program backs off: nothing to compare";
  EXPECT_EQ(one.times.moves, two.times.moves);
  EXPECT_LE(one.times.moving, two.times.moving + 1e-9);
  planner::ValidationSettings settings;
  const planner::ValidationReport report =
      planner::validateTrajectory(scene, one.trajectory, settings);
  EXPECT_TRUE(report.valid) << (report.violations.empty() ? "" : report.violations[0].what);
}

// Move settings with a cache of their own.
struct WithCache {
  pipeline::MoveCache cache;
  pipeline::MoveSettings settings;
  WithCache() { settings.cache = &cache; }
};

// The same program, sample for sample, with the same moves backed off.
void expectSameJoin(const pipeline::JoinedProgram& a, const pipeline::JoinedProgram& b) {
  ASSERT_EQ(a.trajectory.samples.size(), b.trajectory.samples.size());
  for (std::size_t k = 0; k < a.trajectory.samples.size(); ++k) {
    const auto &x = a.trajectory.samples[k], &y = b.trajectory.samples[k];
    ASSERT_EQ(x.t, y.t) << k;
    ASSERT_EQ(x.theta, y.theta) << k;
    ASSERT_EQ(x.q, y.q) << k;
  }
  EXPECT_EQ(a.times.detours, b.times.detours);
}

// Moves taken from the cache are the moves planned afresh: joined in another order with a
// cache filled by the first order, the program is the same, sample for sample, as without it;
// joined again in the first order, nothing new is planned.
TEST_F(ProgramMoves, CachedMovesAreTheMovesPlannedAfresh) {
  const pipeline::ScanPlan& plan = *plan_;
  ASSERT_TRUE(plan.trajectory);
  std::vector<kinematics::Trajectory> runs = scanningRuns(plan.trajectory->trajectory);
  ASSERT_GE(runs.size(), 4u);
  const collision::Scene& scene = *plan.prepared->scene;
  WithCache c;
  const pipeline::JoinedProgram first = pipeline::joinSegments(scene, runs, c.settings);
  const std::size_t planned = c.cache.size();
  EXPECT_EQ(planned, first.times.moves);
  const pipeline::JoinedProgram again = pipeline::joinSegments(scene, runs, c.settings);
  EXPECT_EQ(c.cache.size(), planned);
  ASSERT_EQ(again.trajectory.samples.size(), first.trajectory.samples.size());
  // Another order: the two middle passes swapped, the others' moves still in the cache.
  std::swap(runs[1], runs[2]);
  const pipeline::JoinedProgram with = pipeline::joinSegments(scene, runs, c.settings);
  const pipeline::JoinedProgram without = pipeline::joinSegments(scene, runs, {});
  EXPECT_GT(c.cache.size(), planned);
  expectSameJoin(with, without);
  // The moves made, listed as they run, take the program's time beside the passes.
  ASSERT_TRUE(without.dropped.empty());
  ASSERT_EQ(without.made.size(), without.times.moves);
  double moved = 0.0;
  for (const auto& m : without.made) moved += m.duration;
  EXPECT_NEAR(
      moved,
      without.times.total -
          [&] {
            double scanning = 0.0;
            for (const auto& r : runs) scanning += r.samples.back().t - r.samples.front().t;
            return scanning;
          }(),
      1e-6);
}

// With a table that turns without end, a move met again whole turns on is the same move turned:
// the passes joined once more two turns further plan nothing new, and every sample is the first
// join's with the table two turns on and the same joints.
TEST_F(ProgramMoves, AMoveWholeTableTurnsOnIsPlannedOnceAndTheSame) {
  const pipeline::ScanPlan& plan = *plan_;
  ASSERT_TRUE(plan.trajectory);
  ASSERT_TRUE(plan.prepared->scene->cell().table.continuous);
  std::vector<kinematics::Trajectory> runs = scanningRuns(plan.trajectory->trajectory);
  const collision::Scene& scene = *plan.prepared->scene;
  WithCache c;
  const pipeline::JoinedProgram first = pipeline::joinSegments(scene, runs, c.settings);
  const std::size_t planned = c.cache.size();
  ASSERT_GT(planned, 0u);
  constexpr double kTurns = 2.0 * 6.283185307179586;
  for (auto& run : runs)
    for (auto& s : run.samples) s.theta += kTurns;
  const pipeline::JoinedProgram turned = pipeline::joinSegments(scene, runs, c.settings);
  EXPECT_EQ(c.cache.size(), planned);
  ASSERT_EQ(turned.trajectory.samples.size(), first.trajectory.samples.size());
  for (std::size_t k = 0; k < first.trajectory.samples.size(); ++k) {
    const auto &a = first.trajectory.samples[k], &b = turned.trajectory.samples[k];
    ASSERT_NEAR(b.theta - a.theta, kTurns, 1e-9) << k;
    ASSERT_EQ(a.q, b.q) << k;
    ASSERT_NEAR(a.t, b.t, 1e-9) << k;
  }
}

// The moves do not depend on the threads: the passes joined on one thread, on all of them, and
// in two orders at once sharing one cache give the same samples as each order joined alone.
TEST_F(ProgramMoves, TheMovesAreTheSameOnOneThreadAndOnMany) {
  const pipeline::ScanPlan& plan = *plan_;
  ASSERT_TRUE(plan.trajectory);
  const std::vector<kinematics::Trajectory> runs = scanningRuns(plan.trajectory->trajectory);
  ASSERT_GE(runs.size(), 4u);
  std::vector<kinematics::Trajectory> swapped = runs;
  std::swap(swapped[1], swapped[2]);
  const collision::Scene& scene = *plan.prepared->scene;
  pipeline::JoinedProgram one, one_swapped;
  {
    const tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = pipeline::joinSegments(scene, runs, {});
    one_swapped = pipeline::joinSegments(scene, swapped, {});
  }
  expectSameJoin(pipeline::joinSegments(scene, runs, {}), one);
  pipeline::MoveCache cache;
  pipeline::MoveSettings shared;
  shared.cache = &cache;
  pipeline::JoinedProgram a, b;
  tbb::parallel_invoke([&] { a = pipeline::joinSegments(scene, runs, shared); },
                       [&] { b = pipeline::joinSegments(scene, swapped, shared); });
  expectSameJoin(a, one);
  expectSameJoin(b, one_swapped);
}

// Joining the passes polls the cancel flag at every leg of every move: set, it ends the join
// with Cancelled; clear, the join is the same as without a flag.
TEST_F(ProgramMoves, ACancelFlagEndsTheJoinWithCancelled) {
  const pipeline::ScanPlan& plan = *plan_;
  ASSERT_TRUE(plan.trajectory);
  const std::vector<kinematics::Trajectory> runs = scanningRuns(plan.trajectory->trajectory);
  ASSERT_GE(runs.size(), 2u);
  const collision::Scene& scene = *plan.prepared->scene;
  std::atomic<bool> cancel{true};
  pipeline::MoveSettings settings;
  settings.cancel = &cancel;
  EXPECT_THROW(pipeline::joinSegments(scene, runs, settings), pipeline::Cancelled);
  cancel = false;
  const pipeline::JoinedProgram flagged = pipeline::joinSegments(scene, runs, settings);
  const pipeline::JoinedProgram plain = pipeline::joinSegments(scene, runs, {});
  EXPECT_EQ(flagged.times.moves, plain.times.moves);
  EXPECT_EQ(flagged.trajectory.samples.size(), plain.trajectory.samples.size());
  EXPECT_EQ(flagged.times.total, plain.times.total);
}

// The automatic scan reports its progress through all its steps (the candidates, the aimed
// passes, the reach checks, the set cover and the tour): its last report says all is done and
// comes before the map's first. It polls the cancel flag at every report: set at the first
// report past 90 %, the plan ends with Cancelled before the map starts.
TEST_F(ProgramMoves, TheAutomaticScanReportsAndPollsThroughItsSteps) {
  pipeline::ScanProblem problem = *problem_;
  std::atomic<bool> cancel{false};
  problem.planning.termination.cancel = &cancel;
  std::mutex mutex;  // reports come from worker threads
  std::vector<std::pair<std::string, double>> seen;
  const auto record = [&](std::string_view stage, std::size_t done, std::size_t total) {
    const std::lock_guard<std::mutex> lock(mutex);
    seen.emplace_back(std::string(stage), static_cast<double>(done) / static_cast<double>(total));
  };
  pipeline::prepareScan(problem, record);
  const auto first_map =
      std::find_if(seen.begin(), seen.end(), [](const auto& r) { return r.first == "map"; });
  ASSERT_NE(first_map, seen.begin());
  ASSERT_NE(first_map, seen.end());
  EXPECT_EQ(std::prev(first_map)->first, "auto");
  EXPECT_EQ(std::prev(first_map)->second, 1.0);
  for (auto r = seen.begin(); r != first_map; ++r) EXPECT_EQ(r->first, "auto");
  EXPECT_GE(std::count_if(seen.begin(), first_map, [](const auto& r) { return r.second > 0.5; }),
            10);  // the steps after the candidates report too

  seen.clear();
  std::size_t after = 0;
  EXPECT_THROW(
      pipeline::prepareScan(problem,
                            [&](std::string_view stage, std::size_t done, std::size_t total) {
                              const std::lock_guard<std::mutex> lock(mutex);
                              if (cancel) ++after;
                              EXPECT_EQ(stage, "auto");
                              if (10 * done > 9 * total) cancel = true;
                            }),
      pipeline::Cancelled);
  EXPECT_TRUE(cancel);
  // At most the reports already past their poll on the other threads.
  EXPECT_LT(after, std::max(1u, std::thread::hardware_concurrency()));
}

TEST_F(ProgramMoves, AProgramTimeLimitKeepsTheBestCoverageThatFitsIt) {
  const pipeline::ScanPlan& full = *plan_;
  ASSERT_TRUE(full.planned());
  const double limit = 0.5 * full.program.total;
  const pipeline::ScanProblem problem =
      boxProblem(dir_ / "box.stl", {"scan.auto.max_program_s=" + std::to_string(limit)});
  const pipeline::ScanPlan plan = pipeline::planScan(problem);
  ASSERT_TRUE(plan.planned()) << plan.reason;
  ASSERT_TRUE(plan.validation);
  EXPECT_TRUE(plan.validation->valid);
  EXPECT_LE(plan.program.total, limit + 1e-9);
  EXPECT_GT(plan.program.total, 0.0);
  // Every pass left out says why, naming the key.
  for (const auto& [segment, why] : plan.dropped)
    EXPECT_NE(why.find("max_program_s"), std::string::npos) << segment << ": " << why;
  // Fewer passes run than in the unlimited program, covering less of the part.
  EXPECT_LT(plan.order.size() - plan.dropped.size(), full.order.size());
  // The simulated clouds (on by default) tell.
  ASSERT_FALSE(plan.coverage_curve.fraction.empty());
  ASSERT_FALSE(full.coverage_curve.fraction.empty());
  EXPECT_LT(plan.coverage_curve.fraction.back(), full.coverage_curve.fraction.back());
  EXPECT_LE(plan.coverage_curve.t.back(), limit + 1e-9);
}

}  // namespace

namespace {

// A segment of `n` steps `dt` apart: joint 1 and the table turn evenly at `speed` (a share of
// each one's limit), the table's rate changing by `accel` (a share of its limit) over the middle.
kinematics::Trajectory evenSegment(
    const kinematics::CellModel& cell, int n, double dt, double speed, double accel) {
  kinematics::Trajectory seg;
  const double w1 = speed * cell.robot.joint(0).max_speed, w0 = speed * cell.table.max_speed;
  const double a0 = accel * cell.table.max_accel;
  for (int k = 0; k <= n; ++k) {
    kinematics::TrajectorySample s;
    s.t = 1.0 + dt * k;
    s.q(0) = w1 * dt * k;
    const double t = dt * k, mid = 0.5 * dt * n;
    s.theta = w0 * t + (t > mid ? 0.5 * a0 * (t - mid) * (t - mid) : 0.0);
    s.scanning = true;
    seg.samples.push_back(s);
  }
  return seg;
}

double largestSpeed(const kinematics::Trajectory& seg, int axis) {
  double v = 0.0;
  for (std::size_t k = 1; k < seg.samples.size(); ++k) {
    const auto &a = seg.samples[k - 1], &b = seg.samples[k];
    const double d = axis < 0 ? b.theta - a.theta : b.q(axis) - a.q(axis);
    v = std::max(v, std::abs(d) / (b.t - a.t));
  }
  return v;
}

}  // namespace

TEST_F(ProgramMoves, ARetimedSegmentRunsInItsOwnTimeWhereTheAxesAllowIt) {
  const kinematics::CellModel& cell = problem_->cell;
  // 5 steps of 0.2 s, the axes at 40 % of their speed: the segment's own 0.5 s doubles the
  // speeds to 80 %, within the limits: it runs in 0.5 s, evenly, starting where it did.
  kinematics::Trajectory seg = evenSegment(cell, 5, 0.2, 0.4, 0.0);
  EXPECT_NEAR(pipeline::retimeSegment(cell, seg, 0.5), 0.5, 1e-12);
  EXPECT_NEAR(seg.samples.front().t, 1.0, 1e-12);
  EXPECT_NEAR(seg.samples.back().t - seg.samples.front().t, 0.5, 1e-12);
  for (std::size_t k = 1; k < seg.samples.size(); ++k)
    EXPECT_NEAR(seg.samples[k].t - seg.samples[k - 1].t, 0.1, 1e-12);
  // Its own 0.3 s would take joint 1 past its limit: it runs as fast as 98 % of the limit allows.
  seg = evenSegment(cell, 5, 0.2, 0.4, 0.0);
  const double f = pipeline::retimeSegment(cell, seg, 0.3);
  EXPECT_GT(f, 0.3);
  EXPECT_NEAR(largestSpeed(seg, 0), 0.98 * cell.robot.joint(0).max_speed, 1e-9);
  EXPECT_LE(largestSpeed(seg, -1), 0.98 * cell.table.max_speed * (1.0 + 1e-9));
  // Already too fast: slowed as slowToLimits() does, never sped up.
  seg = evenSegment(cell, 5, 0.2, 1.5, 0.0);
  EXPECT_GT(pipeline::retimeSegment(cell, seg, 0.5), 1.0);
  EXPECT_NEAR(largestSpeed(seg, 0), 0.98 * cell.robot.joint(0).max_speed, 1e-9);
}

TEST_F(ProgramMoves, ARetimedSegmentKeepsTheTableWithinItsAcceleration) {
  // The table speeds up at 60 % of its acceleration limit: halving the time would quadruple it,
  // so the segment shortens only to sqrt(0.6 / 0.98) of its span, where it reaches 98 %.
  const kinematics::CellModel& cell = problem_->cell;
  ASSERT_GT(cell.table.max_accel, 0.0);
  kinematics::Trajectory seg = evenSegment(cell, 10, 0.05, 0.05, 0.6);
  const kinematics::Trajectory before = seg;
  const double f = pipeline::retimeSegment(cell, seg, 0.25);
  EXPECT_NEAR(f, std::sqrt(0.6 / 0.98), 1e-9);
  EXPECT_GT(f, 0.5);
  EXPECT_LT(f, 1.0);
  // The table's rate changes by the most at the knot where the acceleration starts: measured
  // as validation does, on the retimed samples.
  double a = 0.0;
  const auto& s = seg.samples;
  for (std::size_t k = 2; k < s.size(); ++k) {
    const double w1 = (s[k].theta - s[k - 1].theta) / (s[k].t - s[k - 1].t);
    const double w0 = (s[k - 1].theta - s[k - 2].theta) / (s[k - 1].t - s[k - 2].t);
    a = std::max(a, std::abs(w1 - w0) / (0.5 * (s[k].t - s[k - 2].t)));
  }
  EXPECT_NEAR(a, 0.98 * cell.table.max_accel, 1e-9);
  EXPECT_NEAR(s.back().t - s.front().t, f * (before.samples.back().t - before.samples.front().t),
              1e-12);
}

TEST_F(ProgramMoves, EachPassRunsNoFasterThanPlannedAndMostInTheirOwnTime) {
  // The passes' own durations are what their point spacing needs; the path's samples stand
  // whole steps apart and span more. In the program each run lasts its own time (or longer
  // where an axis needs it), never less.
  const pipeline::ScanPlan& plan = *plan_;
  ASSERT_TRUE(plan.planned());
  ASSERT_TRUE(plan.prepared && plan.prepared->auto_scan);
  const auto& passes = plan.prepared->auto_scan->passes;
  const auto runs = scanningRuns(plan.trajectory->trajectory);
  ASSERT_EQ(runs.size(), plan.order.size() - plan.dropped.size());
  std::size_t own = 0;
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const auto& run = plan.order[k];
    ASSERT_LT(run.segment, passes.size());
    const double wanted = passes[run.segment].duration;
    EXPECT_NEAR(runs[k].samples.front().t, run.start, 1e-9);
    EXPECT_GE(runs[k].duration() - runs[k].samples.front().t, wanted - 1e-9);
    if (runs[k].duration() - runs[k].samples.front().t < wanted + 1e-6) ++own;
  }
  EXPECT_GE(own, runs.size() / 2) << "most passes run in their own time";
  // Altogether: no less than the passes' own time, and less than whole steps would take.
  const double planned = plan.prepared->auto_scan->scan_time;
  EXPECT_GE(plan.program.scanning, planned - 1e-6);
  EXPECT_LT(plan.program.scanning, planned + 0.2 * static_cast<double>(runs.size()));
}

TEST_F(ProgramMoves, AHeldPassStartsWhereTheTableStoodAfterThePassBefore) {
  // A pass whose table path was shifted (table_shift ≠ 0) starts, in the program, at the table
  // angle the run before it ended at (a continuous table: up to whole turns). As many passes
  // were shifted as the program says.
  const pipeline::ScanPlan& plan = *plan_;
  ASSERT_TRUE(plan.planned());
  const auto& segments = plan.choice.segments;
  ASSERT_EQ(segments.size(), plan.order.size());
  std::size_t shifted = 0;
  for (const auto& c : segments) shifted += c.table_shift != 0.0 ? 1u : 0u;
  EXPECT_EQ(shifted, plan.program.held);
  // Held only where the map says f > 0 all along the shifted path: J stays finite.
  EXPECT_TRUE(std::isfinite(plan.program.held_cost));
  EXPECT_TRUE(std::isfinite(plan.choice.terms.total));
  for (const auto& c : segments) EXPECT_GT(c.terms.min_f, 0.0);
  EXPECT_GT(plan.program.held, 0u) << "the box's passes: some moves would turn the table";
  const auto runs = scanningRuns(plan.trajectory->trajectory);
  ASSERT_EQ(runs.size(), plan.order.size() - plan.dropped.size());
  std::size_t checked = 0;
  for (std::size_t k = 1; k < runs.size(); ++k) {
    if (segments[plan.order[k].segment].table_shift == 0.0) continue;
    const double gap = runs[k].samples.front().theta - runs[k - 1].samples.back().theta;
    EXPECT_NEAR(std::remainder(gap, 2.0 * 3.141592653589793), 0.0, 1e-9)
        << "run " << k << " (pass " << plan.order[k].segment + 1 << ")";
    ++checked;
  }
  EXPECT_GT(checked, 0u);
}

namespace {

// A segment standing still at table angle `theta` with joints `q` for a second.
kinematics::Trajectory standingSegment(double theta, const kinematics::JointVector& q) {
  kinematics::Trajectory t;
  for (const double time : {0.0, 1.0}) {
    kinematics::TrajectorySample s;
    s.t = time;
    s.theta = theta;
    s.q = q;
    t.samples.push_back(s);
  }
  return t;
}

// The moves' time of running `segments` in `o`, each move costed by moveCost().
double tourTime(const kinematics::CellModel& cell,
                const std::vector<kinematics::Trajectory>& segments,
                const pipeline::SegmentOrder& o) {
  std::vector<kinematics::Trajectory> run;
  for (std::size_t k = 0; k < o.order.size(); ++k)
    run.push_back(o.reversed[k] ? pipeline::reversedSegment(segments[o.order[k]])
                                : segments[o.order[k]]);
  double total = 0.0;
  for (std::size_t k = 1; k < run.size(); ++k)
    total += pipeline::moveCost(cell, run[k - 1], run[k]);
  return total;
}

// `o` with the chain first … first+len−1 put into the gap before position `gap` (reversed as a
// whole when `flip`).
pipeline::SegmentOrder relocated(const pipeline::SegmentOrder& o,
                                 std::size_t first,
                                 std::size_t len,
                                 std::size_t gap,
                                 bool flip) {
  pipeline::SegmentOrder out;
  const std::size_t n = o.order.size();
  for (std::size_t k = 0; k <= n; ++k) {
    if (k == gap)
      for (std::size_t i = 0; i < len; ++i) {
        const std::size_t c = flip ? first + len - 1 - i : first + i;
        out.order.push_back(o.order[c]);
        out.reversed.push_back(static_cast<std::uint8_t>(o.reversed[c] ^ (flip ? 1 : 0)));
      }
    if (k < n && (k < first || k >= first + len)) {
      out.order.push_back(o.order[k]);
      out.reversed.push_back(o.reversed[k]);
    }
  }
  return out;
}

kinematics::CellModel tourCell() {
  const auto dir =
      std::filesystem::temp_directory_path() / ("scanplan_test_tour_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  kinematics::CellModel cell = boxProblem(writeBox(dir / "box.stl", 50, 50, 50)).cell;
  std::filesystem::remove_all(dir);
  return cell;
}

}  // namespace

// Passes standing at table angles 0.3 rad apart, shuffled: no move can be shorter than one step
// of the table, so running them in turn is optimal, and the search finds it.
TEST(SegmentOrder, PassesAlongTheTableRunInTurn) {
  const kinematics::CellModel cell = tourCell();
  std::vector<double> angles;
  for (int k = 0; k < 10; ++k) angles.push_back(0.3 * k);
  std::mt19937 rng(5);
  std::shuffle(angles.begin(), angles.end(), rng);
  std::vector<kinematics::Trajectory> segments;
  for (const double a : angles)
    segments.push_back(standingSegment(a, kinematics::JointVector::Zero()));
  const pipeline::SegmentOrder o = pipeline::orderSegments(cell, segments, 0);
  const double step =
      pipeline::moveCost(cell, standingSegment(0.0, kinematics::JointVector::Zero()),
                         standingSegment(0.3, kinematics::JointVector::Zero()));
  EXPECT_NEAR(tourTime(cell, segments, o), 9.0 * step, 1e-9);
}

// On random passes (table and joints apart, each moving) the order is a local optimum of the
// search's own moves: no pass or chain of two taken out and put in elsewhere, either way round,
// and no stretch reversed gives shorter moves (each tour recosted from scratch).
TEST(SegmentOrder, NoPassMovedElsewhereOrStretchReversedShortensTheMoves) {
  const kinematics::CellModel cell = tourCell();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 3; ++trial) {
    std::vector<kinematics::Trajectory> segments;
    for (int k = 0; k < 30; ++k) {
      kinematics::JointVector q;
      for (int j = 0; j < kinematics::kNumJoints; ++j) q(j) = 0.6 * u(rng);
      kinematics::Trajectory t = standingSegment(2.5 * u(rng), q);
      t.samples.back().theta += 0.5 * u(rng);  // it turns the table
      t.samples.back().q(0) += 0.5 * u(rng);
      t.samples.back().q(4) += 0.5 * u(rng);
      segments.push_back(t);
    }
    const pipeline::SegmentOrder o = pipeline::orderSegments(cell, segments, 0);
    const double found = tourTime(cell, segments, o);
    const std::size_t n = o.order.size();
    for (std::size_t len = 1; len <= 2; ++len)
      for (std::size_t first = 0; first + len <= n; ++first)
        for (std::size_t gap = 0; gap <= n; ++gap) {
          if (gap >= first && gap <= first + len) continue;
          for (const bool flip : {false, true}) {
            const pipeline::SegmentOrder other = relocated(o, first, len, gap, flip);
            EXPECT_GE(tourTime(cell, segments, other), found - 1e-9)
                << "trial " << trial << " chain " << first << "+" << len << " to " << gap;
          }
        }
    for (std::size_t k = 1; k < n; ++k)
      for (std::size_t m = k + 1; m < n; ++m) {
        pipeline::SegmentOrder other = o;
        for (std::size_t i = k; i <= m; ++i) {
          other.order[i] = o.order[k + m - i];
          other.reversed[i] = o.reversed[k + m - i] ^ 1;
        }
        EXPECT_GE(tourTime(cell, segments, other), found - 1e-9) << "reversed " << k << "…" << m;
      }
  }
}

// A move the join measured far slower than its estimate (it had to back off) is left out of the
// order searched again, and the order's own moves are costed as they were measured.
TEST(SegmentOrder, AMoveMeasuredSlowIsLeftOutWhenOrderedAgain) {
  const kinematics::CellModel cell = tourCell();
  std::vector<kinematics::Trajectory> segments;
  for (int k = 0; k < 10; ++k)
    segments.push_back(standingSegment(0.3 * k, kinematics::JointVector::Zero()));
  const pipeline::SegmentOrder in_turn = pipeline::orderSegments(cell, segments, 0);
  ASSERT_EQ(in_turn.order.size(), 10u);
  // Every move of that order as measured: all as estimated, but the one into the sixth pass.
  std::vector<pipeline::KnownMove> known;
  std::size_t slow_from = 0, slow_to = 0;
  for (std::size_t k = 1; k < 10; ++k) {
    pipeline::KnownMove m{in_turn.order[k - 1], in_turn.order[k], in_turn.reversed[k - 1] != 0,
                          in_turn.reversed[k] != 0, 0.0};
    m.duration = pipeline::moveCost(cell, segments[m.from], segments[m.to]);
    if (k == 5) {
      m.duration = 100.0;
      slow_from = m.from;
      slow_to = m.to;
    }
    known.push_back(m);
  }
  const pipeline::SegmentOrder again = pipeline::reorderSegments(cell, segments, 0, in_turn, known);
  EXPECT_FALSE(again == in_turn);
  for (std::size_t k = 1; k < again.order.size(); ++k) {
    const std::size_t a = again.order[k - 1], b = again.order[k];
    EXPECT_FALSE((a == slow_from && b == slow_to) || (a == slow_to && b == slow_from))
        << "the slow move is still made, at " << k;
  }
  // A permutation of the passes.
  std::vector<std::size_t> sorted = again.order;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t k = 0; k < sorted.size(); ++k) EXPECT_EQ(sorted[k], k);
}
