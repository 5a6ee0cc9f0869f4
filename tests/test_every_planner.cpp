// Every planner (ray, dp, ompl), with and without refinement, plans every bundled job
// (data/jobs/*.yaml) into a valid program: the validation proves each one. The automatic demo is
// shortened to its first passes (same time step, so the same samples per pass), which keeps the
// suite's time; the hand-written jobs run whole. bunny_shared.yaml needs the shared test data
// beside the repository and is skipped without it.
#include <algorithm>
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <scanplan/config/job.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/pipeline/plan_scan.h>
#include "test_support.h"

namespace {

using namespace scanplan;

struct Case {
  std::string job;
  std::vector<std::string> set;
};

std::vector<Case> bundledJobs() {
  return {
      {"demo", {"simulation.enabled=false", "scan.auto.max_passes=8"}},
      {"demo_rings", {"simulation.enabled=false"}},
      {"demo_sensors", {"simulation.enabled=false"}},
      {"kuka_demo", {"simulation.enabled=false"}},
      {"bunny_shared", {"simulation.enabled=false"}},
  };
}

// The case's name in ctest's listing, not its bytes.
void PrintTo(const Case& c, std::ostream* os) { *os << c.job; }

class EveryPlanner : public ::testing::TestWithParam<Case> {};

TEST_P(EveryPlanner, PlansTheBundledJobValidlyWithAndWithoutRefinement) {
  const Case& c = GetParam();
  const auto file = test::sourceDir() / "data" / "jobs" / (c.job + ".yaml");
  if (c.job == "bunny_shared" &&
      !std::filesystem::exists(test::sourceDir() / "../shared/data/meshes/stlmodels_bunny.bin.stl"))
    GTEST_SKIP() << "the shared test data is not beside the repository";
  const pipeline::ScanProblem base = config::toProblem(config::loadJob(file, c.set));
  const auto prepared = pipeline::prepareScan(base);
  for (const std::string method : {"ray", "dp", "ompl"}) {
    for (const bool refine : {false, true}) {
      SCOPED_TRACE(c.job + ", " + method + (refine ? ", refined" : ""));
      pipeline::ScanProblem problem = base;
      problem.planning.method = method;
      problem.planning.refine = refine;
      const pipeline::ScanPlan plan = pipeline::planPrepared(problem, prepared);
      ASSERT_TRUE(plan.planned()) << plan.reason;
      EXPECT_TRUE(plan.dropped.empty()) << plan.dropped.front().second;
      ASSERT_TRUE(plan.validation);
      EXPECT_TRUE(plan.validation->valid);
      EXPECT_EQ(plan.choice.chosen.method, method);
      // Refinement ran where asked, on the path or on each of its passes.
      if (plan.choice.segments.empty()) {
        EXPECT_EQ(plan.choice.refine.has_value(), refine);
      } else {
        for (const auto& segment : plan.choice.segments)
          EXPECT_EQ(segment.refine.has_value(), refine);
      }
      // The DP optimum on the same branches bounds every path from below, within the grid: a
      // continuous path may beat DP's grid by a little, never by much.
      if (const auto gap = plan.choice.dpGap()) {
        EXPECT_GT(*gap, -0.02);
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Jobs,
                         EveryPlanner,
                         ::testing::ValuesIn(bundledJobs()),
                         [](const auto& param) { return param.param.job; });

TEST(EveryPlannerCompare, TheAutomaticDemoShowsAllThreePlanners) {
  const auto file = test::sourceDir() / "data" / "jobs" / "demo.yaml";
  const pipeline::ScanProblem problem = config::toProblem(
      config::loadJob(file, {"simulation.enabled=false", "scan.auto.max_passes=8"}));
  pipeline::PlanOptions options;
  options.compare = true;
  const pipeline::ScanPlan plan = pipeline::planScan(problem, options);
  ASSERT_TRUE(plan.planned()) << plan.reason;
  std::vector<std::string> methods{plan.choice.chosen.method};
  for (const auto& other : plan.choice.others) {
    methods.push_back(other.method);
    EXPECT_TRUE(other.result.solved()) << other.method << ": " << other.result.reason;
  }
  std::sort(methods.begin(), methods.end());
  EXPECT_EQ(methods, (std::vector<std::string>{"dp", "ompl", "ray"}));
}

}  // namespace
