// planScan() and the planner interface, through the C++ API (no files written, no CLI): the
// pipeline's trajectory follows the scan path through the 7-DOF chain, is what the planners and
// evaluate() say it is, and bad problems are refused with the field named.
#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <numbers>
#include <random>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include <gtest/gtest.h>

#include <scanplan/config/job.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/placement.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/pipeline/plan_scan.h>
#include <scanplan/planner/dp_planner.h>
#include <scanplan/planner/registry.h>
#include "map_support.h"
#include "test_support.h"

namespace {

using namespace scanplan;
using planner::PlannerStatus;

// The light demo (two rings every 0.2 s) on one branch and a 2° grid, no simulation: ~1 s.
pipeline::ScanProblem lightDemo(std::vector<std::string> extra = {}) {
  std::vector<std::string> overrides = test::kLightDemo;
  overrides.push_back("map.branch=RIGHTY ABOVE NOFLIP");
  overrides.push_back("map.angle_step_deg=2");
  overrides.push_back("simulation.enabled=false");
  for (auto& e : extra) overrides.push_back(std::move(e));
  return config::toProblem(
      config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml", overrides));
}

// Positions agree to 1 µm and orientations to 1 µrad: IK solutions reproduce FK to ~1e-12 m,
// so anything looser than this is a wrong chain, not rounding.
constexpr double kPoseTol = 1e-6;

TEST(PlanScan, TrajectoryPutsTheScannerOnThePathThroughTheWholeChain) {
  const pipeline::ScanProblem problem = lightDemo();
  const pipeline::ScanPlan plan = pipeline::planScan(problem);
  ASSERT_TRUE(plan.planned()) << plan.reason;
  ASSERT_TRUE(plan.trajectory && plan.validation);
  EXPECT_TRUE(plan.validation->valid);
  const auto& samples = plan.trajectory->trajectory.samples;
  const auto& path = plan.prepared->path.path.samples;
  ASSERT_EQ(samples.size(), path.size());
  for (std::size_t k = 0; k < samples.size(); ++k) {
    // FK of the arm joints must land the flange where the table angle and the path ask.
    const Eigen::Isometry3d X_BF = problem.cell.robot.fk(samples[k].q);
    const Eigen::Isometry3d want = problem.cell.flangeTarget(samples[k].theta, path[k].X_PS);
    ASSERT_LT((X_BF.translation() - want.translation()).norm(), kPoseTol) << "sample " << k;
    ASSERT_LT((X_BF.linear() - want.linear()).norm(), kPoseTol) << "sample " << k;
    ASSERT_DOUBLE_EQ(samples[k].theta, plan.choice.theta[k]);
  }
}

TEST(PlanScan, ReportedTermsAreEvaluateOfThePathAndTheDpYardstickIsTheDpPlanner) {
  const pipeline::ScanProblem problem = lightDemo();
  const pipeline::ScanPlan plan = pipeline::planScan(problem);
  ASSERT_TRUE(plan.planned()) << plan.reason;
  const planner::ConfigMap& map = plan.prepared->map;
  const std::size_t b = plan.choice.chosen.result.branch;
  const planner::ObjectiveTerms e =
      planner::evaluate(map, b, plan.choice.theta, problem.planning.objective, true);
  EXPECT_TRUE(e.feasible);
  EXPECT_NEAR(e.total, plan.choice.terms.total, test::kSumTol * std::max(1.0, e.total));
  // The yardstick is DP through the registry on the same branch: the same path.
  ASSERT_TRUE(plan.choice.dp && plan.choice.dp->solved());
  const planner::PlanResult dp =
      planner::planDpRefined(map, b, problem.planning.objective, true, plan.choice.dp_subdivisions);
  EXPECT_EQ(dp.theta, plan.choice.dp->theta);
  EXPECT_TRUE(plan.choice.dpGap().has_value());
}

TEST(PlanScan, PreparedMapsAreReusedAcrossPlannerSettings) {
  const pipeline::ScanProblem problem = lightDemo();
  const auto prepared = pipeline::prepareScan(problem);
  pipeline::ScanProblem dp_problem = lightDemo({"planner.method=dp"});
  const pipeline::ScanPlan a = pipeline::planPrepared(dp_problem, prepared);
  const pipeline::ScanPlan b = pipeline::planScan(dp_problem);
  ASSERT_TRUE(a.planned() && b.planned()) << a.reason << b.reason;
  EXPECT_EQ(a.prepared.get(), prepared.get());
  EXPECT_EQ(a.choice.chosen.method, "dp");
  EXPECT_EQ(a.choice.theta, b.choice.theta);  // deterministic, same map either way
}

TEST(PlanScan, BadProblemsAreInputErrorsNamingTheField) {
  pipeline::ScanProblem p = lightDemo();
  p.planning.method = "astar";
  EXPECT_TRUE(test::throwsInputError([&] { pipeline::planScan(p); },
                                     {"planning.method", "astar", "ray, dp or ompl"}));
  p = lightDemo();
  p.path.elements.clear();
  EXPECT_TRUE(test::throwsInputError([&] { pipeline::planScan(p); }, {"path.elements"}));
  p = lightDemo();
  p.map.angle_step = std::nan("");
  EXPECT_TRUE(test::throwsInputError([&] { pipeline::planScan(p); }, {"map.angle_step"}));
}

// `part.place: table`: the part's lowest point on the table top and its box centred on the axis,
// whatever the mesh's own origin (here the housing turned y-up and yawed 30°).
TEST(PartPlacement, TableRestsTheLowestPointOnTheTopCentredOnTheAxis) {
  const config::JobSpec job = config::loadJob(
      test::sourceDir() / "data/jobs/demo_rings.yaml",
      {"part.up_axis=y", "part.place=table", "part.pose={xyz_mm: [0, 0, 0], rpy_deg: [0, 0, 30]}"});
  const kinematics::CellModel cell = config::buildCell(job);
  const kinematics::LoadedMesh part = config::loadPart(job, cell);
  Eigen::AlignedBox3d box_R;
  for (const Eigen::Vector3d& v : part.mesh.vertices) box_R.extend(cell.part.X_RP * v);
  EXPECT_NEAR(box_R.min().z(), 0.0, 1e-12);
  EXPECT_NEAR(box_R.center().x(), 0.0, 1e-12);
  EXPECT_NEAR(box_R.center().y(), 0.0, 1e-12);
  // The yaw is kept: the part frame's x axis is turned 30° about the table's z.
  EXPECT_NEAR(std::atan2(cell.part.X_RP(1, 0), cell.part.X_RP(0, 0)), 30.0 * kDegToRad, 1e-12);
}

TEST(PartPlacement, APartBelowTheTableTopIsAnErrorNamingThePose) {
  const config::JobSpec job = config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml",
                                              {"part.pose.xyz_mm=[0, 0, -5]"});
  const kinematics::CellModel cell = config::buildCell(job);
  EXPECT_TRUE(test::throwsInputError(
      [&] { config::loadPart(job, cell); },
      {"demo_rings.yaml", "part.pose", "5.00 mm below the table top", "part.place: table"}));
}

TEST(PartPlacement, APartBeyondTheArmsReachIsAnErrorNamingTheTable) {
  const config::JobSpec job = config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml",
                                              {"table.axis.xyz_mm=[3000, 0, 0]"});
  const kinematics::CellModel cell = config::buildCell(job);
  EXPECT_TRUE(test::throwsInputError([&] { config::loadPart(job, cell); },
                                     {"demo_rings.yaml", "within the arm's reach", "table.axis"}));
}

// partReach is a necessary condition: points the scanner can reach are never called beyond. Each
// vertex here lies within `lever` of the wrist centre of an in-limit pose with the table at 0,
// since the flange is c4 from the wrist centre; so none may be reported beyond reach.
TEST(PartPlacement, PartReachNeverCallsAReachablePointBeyond) {
  const config::JobSpec job = config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml");
  kinematics::CellModel cell = config::buildCell(job);
  cell.part.X_RP = Eigen::Isometry3d::Identity();
  const double c4 = cell.robot.definition().opw.c4, lever = 0.2;
  const Eigen::Isometry3d X_RB = cell.table.X_WR(0.0).inverse() * cell.X_WB;
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  kinematics::TriangleMesh mesh;
  for (int k = 0; k < 3000; ++k) {
    const Eigen::Vector3d flange = cell.robot.fk(test::randomJoints(cell.robot, rng)).translation();
    Eigen::Vector3d dir(unit(rng), unit(rng), unit(rng));
    dir.normalize();
    mesh.vertices.push_back(X_RB * (flange + (lever - c4) * std::abs(unit(rng)) * dir));
  }
  const kinematics::PartReach reach = kinematics::partReach(cell, mesh, lever);
  EXPECT_EQ(reach.beyond_fraction, 0.0);
  EXPECT_LE(reach.nearest_excess, 0.0);
  // The same cloud 3 m further along the world x axis: all of it beyond, by over a metre.
  for (Eigen::Vector3d& v : mesh.vertices)
    v = X_RB * (X_RB.inverse() * v + Eigen::Vector3d(3, 0, 0));
  const kinematics::PartReach far = kinematics::partReach(cell, mesh, lever);
  EXPECT_EQ(far.beyond_fraction, 1.0);
  EXPECT_GT(far.nearest_excess, 0.0);
}

// Placed, ring heights count from the table top: a part lifted 40 mm (a riser) with rings at
// 75 and 145 mm scans exactly where the part on the table with rings at 35 and 105 mm does.
TEST(PartPlacement, PlacedRingHeightsCountFromTheTableTop) {
  const auto path = [](std::vector<std::string> overrides) {
    overrides.insert(overrides.begin(), test::kLightDemo.begin(), test::kLightDemo.end());
    const config::JobSpec job =
        config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml", overrides);
    return config::toProblem(job).path;
  };
  const scanplan::scanner::PathRequest on_table = path({});
  const scanplan::scanner::PathRequest lifted =
      path({"part.place=table", "part.pose.xyz_mm=[0, 0, 40]",
            "scan.paths=[{type: ring, height_mm: 75, tilt_deg: 25}, {type: ring, height_mm: 145, "
            "tilt_deg: 60}]"});
  ASSERT_EQ(on_table.elements.size(), 2u);
  ASSERT_EQ(lifted.elements.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_NEAR(std::get<scanplan::scanner::RingSpec>(lifted.elements[i]).height,
                std::get<scanplan::scanner::RingSpec>(on_table.elements[i]).height, 1e-12);
  }
}

// The geometry on its own: a unit cube at (10, 20, 30) yawed 45° rests with its lowest point at
// 0 and its centre on the axis; its corners then reach √2/2 from the axis.
TEST(PartPlacement, PlacedOnTableAndPartExtentOnAKnownCube) {
  kinematics::TriangleMesh cube;
  for (int i = 0; i < 8; ++i) {
    cube.vertices.emplace_back(10.0 + (i & 1), 20.0 + ((i >> 1) & 1), 30.0 + ((i >> 2) & 1));
  }
  const Eigen::Isometry3d yaw(Eigen::AngleAxisd(std::numbers::pi / 4, Eigen::Vector3d::UnitZ()));
  const Eigen::Isometry3d X_RP = kinematics::placedOnTable(cube, yaw);
  const kinematics::PartExtent e = kinematics::partExtent(cube, X_RP);
  EXPECT_NEAR(e.lowest, 0.0, 1e-12);
  EXPECT_NEAR(e.widest, std::sqrt(0.5), 1e-12);
  // Lifted 5 below the top by the pose: reaches 5 into the table.
  Eigen::Isometry3d sunk = X_RP;
  sunk.translation().z() -= 5.0;
  EXPECT_NEAR(kinematics::partExtent(cube, sunk).lowest, -5.0, 1e-12);
}

TEST(PartPlacement, AnUnknownPlacementNamesTheKeyAndTheChoices) {
  EXPECT_TRUE(test::throwsInputError(
      [] {
        config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml", {"part.place=floor"});
      },
      {"part.place", "floor", "none", "table"}));
}

TEST(PlannerRegistry, NamesMakeEveryPlannerAndUnknownNamesNone) {
  const planner::PlannerConfig config;
  for (const std::string& name : planner::plannerNames()) {
    const auto p = planner::makePlanner(name, config);
    ASSERT_TRUE(p) << name;
    EXPECT_EQ(p->name(), name);
  }
  EXPECT_EQ(planner::makePlanner("rrt", config), nullptr);
}

TEST(PlannerInterface, MalformedProblemsAreInvalidInputNotExceptions) {
  std::mt19937 rng(7);
  const planner::ConfigMap map = test::randomMap(rng, 72, 40, true);
  for (const std::string& name : planner::plannerNames()) {
    const auto p = planner::makePlanner(name, {});
    planner::PlanningProblem bad{&map, 3, {}, true, {}};  // the map has one branch
    const planner::PlanResult r = p->solve(bad, {});
    EXPECT_EQ(r.status, PlannerStatus::kInvalidInput) << name;
    EXPECT_NE(r.reason.find("branch 3"), std::string::npos) << r.reason;
    bad.branch = 0;
    bad.settings.omega_max = -1.0;
    EXPECT_EQ(p->solve(bad, {}).status, PlannerStatus::kInvalidInput) << name;
    bad.settings = {};
    EXPECT_EQ(p->solve(bad, {0, -1.0}).status, PlannerStatus::kTimeout) << name;
    const planner::PlanResult ok = p->solve(bad, {2000, 10.0});
    EXPECT_EQ(ok.status, PlannerStatus::kExact) << name << ": " << ok.reason;
    EXPECT_EQ(planner::statusName(ok.status), "exact");
  }
}

TEST(PlannerInterface, OmplTerminationIsPassedInAndAnIterationCapRepeats) {
  std::mt19937 rng(11);
  const planner::ConfigMap map = test::randomMap(rng, 72, 60, true);
  const auto ompl = planner::makePlanner("ompl", {});
  const planner::PlanningProblem problem{&map, 0, {}, true, {}};
  const planner::PlanResult a = ompl->solve(problem, {3000, 30.0});
  const planner::PlanResult b = ompl->solve(problem, {3000, 30.0});
  ASSERT_TRUE(a.solved()) << a.reason << " " << a.detail;
  EXPECT_EQ(a.theta, b.theta);
  EXPECT_NE(a.detail.find("3000 iterations"), std::string::npos) << a.detail;
  const planner::PlanResult c = ompl->solve(problem, {500, 30.0});
  EXPECT_NE(c.detail.find("500 iterations"), std::string::npos) << c.detail;
}

// A cancel flag ends a running OMPL search at its next iteration: with a minute of budget and no
// iteration cap, a flag set after 0.2 s from another thread ends the solve within seconds; a flag
// set before any solve refuses every planner at once.
TEST(PlannerInterface, ACancelFlagEndsARunningSearch) {
  std::mt19937 rng(11);
  const planner::ConfigMap map = test::randomMap(rng, 72, 60, true);
  const planner::PlanningProblem problem{&map, 0, {}, true, {}};
  std::atomic<bool> cancel{false};
  planner::Termination t{0, 60.0};
  t.cancel = &cancel;
  std::thread stopper([&cancel] {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    cancel = true;
  });
  const planner::PlanResult r = planner::makePlanner("ompl", {})->solve(problem, t);
  stopper.join();
  EXPECT_LT(r.seconds, 20.0) << r.reason << " " << r.detail;  // not the minute of budget
  for (const std::string& name : planner::plannerNames()) {
    const planner::PlanResult refused = planner::makePlanner(name, {})->solve(problem, t);
    EXPECT_EQ(refused.status, PlannerStatus::kTimeout) << name;
    EXPECT_NE(refused.reason.find("cancelled"), std::string::npos) << refused.reason;
  }
}

// The pipeline polls the flag in every progress report and between stages: set before the call
// it throws Cancelled before any work; set from the map's progress it throws during the map.
TEST(PlanScan, ACancelFlagEndsThePipelineWithCancelled) {
  std::atomic<bool> cancel{true};
  pipeline::ScanProblem problem = lightDemo();
  problem.planning.termination.cancel = &cancel;
  EXPECT_THROW(pipeline::planScan(problem), pipeline::Cancelled);
  cancel = false;
  std::mutex mutex;  // the map reports from its worker threads
  std::size_t reports = 0, after = 0;
  EXPECT_THROW(pipeline::planScan(problem, {},
                                  [&](std::string_view stage, std::size_t, std::size_t) {
                                    const std::lock_guard<std::mutex> lock(mutex);
                                    if (cancel) ++after;
                                    if (stage == "map" && ++reports == 3) cancel = true;
                                  }),
               pipeline::Cancelled);
  EXPECT_EQ(reports, 3u);
  EXPECT_LE(after, 2u);  // at most the reports already past the poll on the other threads
}

// A plan with no path says, per branch, when (the time span and the pass), what (the
// constraint) and which (the body pair, or the joint and the value it would need), and what to
// change. Three ways to close the light demo's map: the scanner kept 150 mm off the table, the
// table 1 m from the robot, J5 held within ±10°.
TEST(NoPath, TheReasonNamesTheTimeTheConstraintAndTheBodiesOrJoint) {
  const auto reason = [](std::vector<std::string> set, double j5_limit_deg = 120.0) {
    set.insert(set.end(), test::kLightDemo.begin(), test::kLightDemo.end());
    set.push_back("simulation.enabled=false");
    config::JobSpec job = config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml", set);
    job.robot.dh[4].min_deg = -j5_limit_deg;
    job.robot.dh[4].max_deg = j5_limit_deg;
    const pipeline::ScanPlan plan = pipeline::planScan(config::toProblem(job));
    EXPECT_EQ(plan.status, pipeline::ScanStatus::kNoPath);
    return plan.reason;
  };
  const std::string clearance = reason(
      {"constraints.clearance.pairs=[{a: scanner, b: table, d_low_mm: 150, d_high_mm: 200}]"});
  EXPECT_NE(clearance.find("RIGHTY ABOVE NOFLIP: t = 0.0–"), std::string::npos) << clearance;
  EXPECT_NE(clearance.find("(scan.paths[0], ring): clearance scanner – table below d_low"),
            std::string::npos)
      << clearance;
  EXPECT_NE(clearance.find("d_low 150.0 mm): raise the pass"), std::string::npos) << clearance;

  const std::string reach = reason({"table.axis.xyz_mm=[1000, 0, 0]"});
  EXPECT_NE(reach.find("t = 0.0–"), std::string::npos) << reach;
  EXPECT_NE(reach.find("out of the arm's reach at every table angle: move table.axis"),
            std::string::npos)
      << reach;

  const std::string joint = reason({}, 10.0);
  EXPECT_NE(joint.find("joint limits: J5 would need"), std::string::npos) << joint;
  EXPECT_NE(joint.find("(limits -10.0 … 10.0°)"), std::string::npos) << joint;
}

}  // namespace
