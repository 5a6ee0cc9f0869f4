// The automatic scan is valid on every part and setting: map time step, point spacing, frame
// rate, robot and the part's pose, one at a time around a base setting, on synthetic parts with
// hard spots (many cavities, thin walls, a deep pocket). Each plan must come out planned with a
// validated program (limits, speeds, the table's acceleration, collisions over the whole motion),
// or with a named reason and no program; the same job twice gives the same bytes.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <scanplan/config/job.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/trajectory.h>
#include <scanplan/pipeline/plan_scan.h>
#include "test_support.h"
#include "tests/part_support.h"

namespace {

using namespace scanplan;
namespace fs = std::filesystem;

struct Part {
  std::string name;
  std::vector<test::Quad> quads;
};

std::vector<Part> parts() {
  return {{"cavities", test::blockWithCavities(70, 70, 40, 2, 14, 15)},
          {"thin_walls", test::thinWalls()},
          {"deep_pocket", test::blockWithHole(70, 70, 50, 16, 40)}};
}

// The demo cell scanning `mesh` automatically at a coarse base setting (a unit test's budget),
// with `extra` overrides on top.
pipeline::ScanProblem problem(const fs::path& mesh, const std::vector<std::string>& extra) {
  std::vector<std::string> set{"part.mesh=" + mesh.string(),
                               "part.units=mm",
                               "part.place=table",
                               "scan.paths=[]",
                               "scan.auto={point_spacing_mm: 1.0, sample_spacing_mm: 5}",
                               "scan.dt_s=0.2",
                               "map.angle_step_deg=5",
                               "scanner.rays_per_profile=60"};
  set.insert(set.end(), extra.begin(), extra.end());
  return config::toProblem(config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml", set));
}

std::string robot(const std::string& file) {
  return "robot=" + (test::sourceDir() / "data/robots" / file).string();
}

// One setting changed at a time from the base.
const std::vector<std::vector<std::string>> kSettings{
    {},
    {"scan.dt_s=0.05"},
    {"scan.dt_s=0.1"},
    {"scan.auto.point_spacing_mm=0.5"},
    {"scan.auto.point_spacing_mm=0"},  // the line's own pitch
    {"scanner.frame_rate_hz=50"},
    {"scanner.frame_rate_hz=400"},
    {"scanner.frame_rate_hz=1000"},
    {robot("kuka_kr6_r900_sixx.yaml")},
    {"part.pose={xyz_mm: [0, 0, 0], rpy_deg: [90, 0, 0]}"},  // on its side
};

std::string describe(const std::vector<std::string>& s) {
  std::string out;
  for (const auto& x : s) out += x + " ";
  return out.empty() ? "base" : out;
}

class AutoScanMatrix : public ::testing::TestWithParam<std::size_t> {};

TEST_P(AutoScanMatrix, EverySettingPlansAValidProgramOrSaysWhy) {
  const Part part = parts()[GetParam()];
  const fs::path dir = fs::temp_directory_path() / ("scanplan_test_matrix_" + part.name);
  fs::create_directories(dir);
  const fs::path mesh = dir / (part.name + ".stl");
  test::writeStl(mesh, part.quads);
  for (const auto& setting : kSettings) {
    SCOPED_TRACE(part.name + ": " + describe(setting));
    const pipeline::ScanProblem p = problem(mesh, setting);
    const pipeline::ScanPlan plan = pipeline::planScan(p);
    // Never an invalid trajectory as the answer.
    EXPECT_NE(plan.status, pipeline::ScanStatus::kInvalidTrajectory) << plan.reason;
    ASSERT_TRUE(plan.planned()) << plan.reason;
    ASSERT_TRUE(plan.validation);
    EXPECT_TRUE(plan.validation->valid);
    // A program that scans: most of what was planned runs.
    EXPECT_GE(plan.order.size(), 1u);
    EXPECT_LE(plan.dropped.size(), plan.order.size() / 10 + 1);
    EXPECT_GT(plan.program.scanning, 0.0);
    EXPECT_NEAR(plan.program.scanning + plan.program.moving, plan.program.total, 1e-9);
    // The passes measure the target, or every larger margin was tried and none measured it
    // (then the first cover stands); and the cloud covers what was measured, but for a sliver.
    const pipeline::AutoScanReport& r = *plan.prepared->auto_scan;
    if (r.measured_fraction < p.auto_scan->target_coverage) {
      EXPECT_EQ(r.rechosen, 2u);
      EXPECT_FALSE(r.rechosen_kept);
    }
    if (r.rechosen_kept) {
      EXPECT_GE(r.measured_fraction, p.auto_scan->target_coverage);
    }
    ASSERT_TRUE(plan.certificate);
    EXPECT_GE(plan.certificate->covered_of_scannable, r.measured_fraction - 0.003);
  }
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Parts,
                         AutoScanMatrix,
                         ::testing::Values(0, 1, 2),
                         [](const auto& param_info) { return parts()[param_info.param].name; });

TEST(AutoScanMatrix, TheSameJobGivesTheSameProgramBytes) {
  const fs::path dir = fs::temp_directory_path() / "scanplan_test_matrix_same";
  fs::create_directories(dir);
  const fs::path mesh = dir / "cavities.stl";
  test::writeStl(mesh, parts()[0].quads);
  const pipeline::ScanProblem p = problem(mesh, {});
  const pipeline::ScanPlan a = pipeline::planScan(p);
  const pipeline::ScanPlan b = pipeline::planScan(p);
  ASSERT_TRUE(a.trajectory && b.trajectory);
  EXPECT_EQ(kinematics::trajectoryToCsv(a.trajectory->trajectory),
            kinematics::trajectoryToCsv(b.trajectory->trajectory));
  fs::remove_all(dir);
}

}  // namespace
