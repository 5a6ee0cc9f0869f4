// The automatic scan (scan.auto): the set cover, the transfers and the tour on small known
// instances, and whole automatic plans of synthetic parts with known answers, checked by the
// simulated cloud (not by the planner's own prediction).
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <scanplan/collision/scene.h>
#include <scanplan/config/job.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/placement.h>
#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/pipeline/plan_scan.h>
#include <scanplan/pipeline/setups.h>
#include <scanplan/scanner/area_coverage.h>
#include <scanplan/scanner/pass_selection.h>
#include <scanplan/scanner/scan_passes.h>
#include "test_support.h"

namespace {

using namespace scanplan;
using scanner::ScanPass;

ScanPass coverPass(std::vector<std::uint32_t> covers, double duration) {
  ScanPass p;
  p.covers = std::move(covers);
  p.t = {0.0, duration};
  p.X_RS = {Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity()};
  return p;
}

TEST(GreedyCover, TakesTheBestAreaPerSecondFirstAndStopsAtTheTarget) {
  // 10 samples; pass 0 covers 6 slowly, pass 1 covers 4 fast, pass 2 covers the rest.
  const std::vector<ScanPass> passes{coverPass({0, 1, 2, 3, 4, 5}, 20.0),
                                     coverPass({0, 1, 2, 3}, 1.0), coverPass({6, 7, 8, 9}, 2.0)};
  scanner::CoverSettings s;
  s.pass_overhead = 0.0;
  s.target = 1.0;
  const std::vector<std::uint8_t> counts(10, 1);
  const auto r = scanner::greedyCover(passes, counts, {}, s);
  EXPECT_EQ(r.chosen, (std::vector<std::size_t>{1, 2, 0}));
  EXPECT_EQ(r.covered_counted, 10u);
  EXPECT_EQ(r.stop, "target reached");

  s.target = 0.8;  // 8 of 10 after passes 1 and 2
  EXPECT_EQ(scanner::greedyCover(passes, counts, {}, s).chosen, (std::vector<std::size_t>{1, 2}));
}

TEST(GreedyCover, SkipsRefusedPassesAndSamplesThatDoNotCount) {
  const std::vector<ScanPass> passes{coverPass({0, 1, 2, 3}, 1.0), coverPass({0, 1}, 1.0),
                                     coverPass({4, 5}, 1.0)};
  std::vector<std::uint8_t> counts{1, 1, 1, 1, 1, 1};
  scanner::CoverSettings s;
  s.target = 1.0;
  std::vector<std::size_t> asked;
  const auto r = scanner::greedyCover(passes, counts, {}, s, [&](std::size_t p) {
    asked.push_back(p);
    return p != 0;
  });
  EXPECT_EQ(r.rejected, (std::vector<std::size_t>{0}));
  EXPECT_EQ(r.chosen, (std::vector<std::size_t>{1, 2}));
  EXPECT_EQ(r.covered_counted, 4u);  // 2 and 3 only pass 0 covers
  EXPECT_EQ(r.stop, "no gain");
  EXPECT_EQ(std::count(asked.begin(), asked.end(), 0u), 1);  // never asked twice

  counts = {1, 1, 0, 0, 0, 0};  // only 0 and 1 count; pass 1 is as good as pass 0 there
  const auto only = scanner::greedyCover(passes, counts, {}, s);
  EXPECT_EQ(only.counted, 2u);
  EXPECT_EQ(only.chosen.size(), 1u);
  EXPECT_EQ(only.stop, "target reached");
}

Eigen::Isometry3d poseAt(const Eigen::Vector3d& p) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = p;
  return X;
}

// The head at p looking at c (its laser, z_S, towards it), its x axis as level as can be.
Eigen::Isometry3d lookingAt(const Eigen::Vector3d& p, const Eigen::Vector3d& c) {
  return kinematics::frameFromAxes(p, c - p, Eigen::Vector3d::UnitZ().cross(c - p));
}

// Backs straight off along the laser to the sphere, turns only on it (with the azimuth, so the
// head keeps facing the centre when both ends do), comes straight in; within both speeds.
TEST(Transfer, BacksOffAlongTheLaserTurnsOnTheSphereAndKeepsItsSpeeds) {
  scanner::TransferSphere sphere;
  sphere.centre = Eigen::Vector3d(0, 0, 0.05);
  sphere.radius = 0.3;
  const Eigen::Vector3d c = sphere.centre;
  const Eigen::Isometry3d a = lookingAt({0.2, 0.0, 0.1}, c);
  const Eigen::Isometry3d b = lookingAt({-0.15, 0.1, 0.02}, c);
  const scanner::Move m = scanner::transferMove(a, b, sphere);
  ASSERT_GE(m.X_RS.size(), 5u);
  EXPECT_TRUE(m.X_RS.front().isApprox(a, 1e-12));
  EXPECT_TRUE(m.X_RS.back().isApprox(b, 1e-12));
  EXPECT_NEAR(m.t.back(), scanner::transferTime(a, b, sphere), 1e-9);
  const std::size_t n = m.X_RS.size();
  // The legs: straight back along each end's laser, the head held still, out to the sphere.
  for (const auto& [end, leg] : {std::pair{a, m.X_RS[1]}, std::pair{b, m.X_RS[n - 2]}}) {
    EXPECT_NEAR((leg.translation() - c).norm(), sphere.radius, 1e-9);
    EXPECT_LT((leg.linear() - end.linear()).norm(), 1e-12);
    const Eigen::Vector3d back = end.translation() - leg.translation();
    EXPECT_NEAR(back.normalized().dot(end.linear().col(2)), 1.0, 1e-9);
  }
  for (std::size_t i = 1; i < n; ++i) {
    ASSERT_GT(m.t[i], m.t[i - 1]);
    const double dt = m.t[i] - m.t[i - 1];
    const Eigen::Isometry3d& p = m.X_RS[i - 1];
    const Eigen::Isometry3d& q = m.X_RS[i];
    EXPECT_LE((q.translation() - p.translation()).norm(), sphere.speed * dt * (1 + 1e-9)) << i;
    EXPECT_LE(kinematics::rotationDistance(p.linear(), q.linear()),
              sphere.turn_speed * dt * (1 + 1e-9) + 1e-12)
        << i;
    if (i + 1 < n) {  // on the arc: on the sphere, facing the centre
      EXPECT_NEAR((q.translation() - c).norm(), sphere.radius, 1e-9) << i;
      EXPECT_NEAR(q.linear().col(2).dot((c - q.translation()).normalized()), 1.0, 1e-9) << i;
    }
  }
}

TEST(OrderPasses, TwoOptNeverLosesToTheGivenOrderAndRunsEveryPassOnce) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.2, 0.2);
  std::vector<ScanPass> passes;
  for (int k = 0; k < 14; ++k) {
    ScanPass p;
    p.X_RS = {poseAt({u(rng), u(rng), 0.1 + 0.5 * u(rng)}), poseAt({u(rng), u(rng), 0.1})};
    p.t = {0.0, 5.0};
    passes.push_back(p);
  }
  scanner::TransferSphere sphere;
  sphere.radius = 0.25;
  std::vector<std::size_t> chosen(passes.size());
  std::iota(chosen.begin(), chosen.end(), 0);
  std::vector<scanner::TourStep> given;
  for (std::size_t i : chosen) given.push_back({i, false, 0.0});
  const auto tour = scanner::orderPasses(passes, chosen, std::nullopt, sphere);
  ASSERT_EQ(tour.size(), passes.size());
  std::vector<std::size_t> seen;
  for (const auto& s : tour) seen.push_back(s.pass);
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(seen, chosen);
  const double ordered = scanner::tourTransferTime(passes, tour, std::nullopt, sphere);
  EXPECT_LT(ordered, scanner::tourTransferTime(passes, given, std::nullopt, sphere));
  // A reversed step runs the pass backwards: it starts where the pass ends.
  for (const auto& s : tour) {
    const ScanPass run = scanner::stepPass(passes, s);
    const auto& orig = passes[s.pass];
    EXPECT_TRUE(run.X_RS.front().isApprox(s.reversed ? orig.X_RS.back() : orig.X_RS.front()));
    EXPECT_DOUBLE_EQ(run.t.front(), 0.0);
  }
}

// An ASCII STL of an axis-aligned box, mm.
std::filesystem::path writeBoxStl(const std::filesystem::path& file,
                                  double sx,
                                  double sy,
                                  double sz) {
  const Eigen::Vector3d s(sx, sy, sz);
  std::ofstream out(file);
  out << "solid box\n";
  const auto quad = [&](Eigen::Vector3d a, Eigen::Vector3d b, Eigen::Vector3d c,
                        Eigen::Vector3d d) {
    for (const auto& t :
         {std::array<Eigen::Vector3d, 3>{a, b, c}, std::array<Eigen::Vector3d, 3>{a, c, d}}) {
      const Eigen::Vector3d n = (t[1] - t[0]).cross(t[2] - t[0]).normalized();
      out << "facet normal " << n.x() << ' ' << n.y() << ' ' << n.z() << "\nouter loop\n";
      for (const auto& v : t) out << "vertex " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
      out << "endloop\nendfacet\n";
    }
  };
  const auto P = [&](int x, int y, int z) {
    return Eigen::Vector3d(x * s.x(), y * s.y(), z * s.z());
  };
  quad(P(0, 0, 0), P(0, 1, 0), P(1, 1, 0), P(1, 0, 0));  // bottom, −z
  quad(P(0, 0, 1), P(1, 0, 1), P(1, 1, 1), P(0, 1, 1));  // top
  quad(P(0, 0, 0), P(1, 0, 0), P(1, 0, 1), P(0, 0, 1));  // −y
  quad(P(0, 1, 0), P(0, 1, 1), P(1, 1, 1), P(1, 1, 0));  // +y
  quad(P(0, 0, 0), P(0, 0, 1), P(0, 1, 1), P(0, 1, 0));  // −x
  quad(P(1, 0, 0), P(1, 1, 0), P(1, 1, 1), P(1, 0, 1));  // +x
  out << "endsolid box\n";
  return file;
}

// The demo cell with `mesh` placed on the table, scanned automatically at a 1 mm point spacing
// on one branch (fast enough for a unit test).
pipeline::ScanProblem autoProblem(const std::filesystem::path& mesh) {
  return config::toProblem(config::loadJob(
      test::sourceDir() / "data/jobs/demo_rings.yaml",
      {"part.mesh=" + mesh.string(), "part.place=table", "scan.paths=[]",
       "scan.auto={point_spacing_mm: 1.0, sample_spacing_mm: 4}", "scan.dt_s=0.2",
       "map.branch=RIGHTY ABOVE NOFLIP", "map.angle_step_deg=4", "scanner.rays_per_profile=80"}));
}

TEST(AutoScan, ACubeOnTheTableIsCoveredExceptItsBottom) {
  const auto dir = std::filesystem::temp_directory_path() / "scanplan_test_autoscan";
  std::filesystem::create_directories(dir);
  const pipeline::ScanProblem problem = autoProblem(writeBoxStl(dir / "cube.stl", 60, 60, 60));
  const pipeline::ScanPlan plan = pipeline::planScan(problem);
  ASSERT_TRUE(plan.planned()) << plan.reason;
  ASSERT_TRUE(plan.prepared->auto_scan && plan.simulation && plan.validation);
  EXPECT_TRUE(plan.validation->valid);
  const auto& report = *plan.prepared->auto_scan;
  EXPECT_GE(report.planned_fraction, 0.98);
  // Exactly the bottom (a sixth of the area) faces the table; the rest is covered.
  const auto& sim = *plan.simulation;
  EXPECT_NEAR(sim.faces_table_fraction, 1.0 / 6.0, 0.01);
  EXPECT_GE(sim.area.covered_fraction, 0.98 * (1.0 - sim.faces_table_fraction));
  // Recomputed from the cloud's points on the part, independently sampled.
  const scanner::AreaSampling sampling = scanner::sampleArea(problem.part, 2e-3, 100000, 99);
  std::vector<Eigen::Vector3d> points;
  for (const auto& p : sim.cloud.points)
    if (p.part_triangle >= 0 && p.incidence <= deg(60.0)) points.push_back(p.p_P);
  const auto again = scanner::areaCoverage(sampling, points, sim.point_spacing);
  EXPECT_NEAR(again.covered_fraction, sim.area.covered_fraction, 0.01);
  // The passes as measured before any motion was planned foretell the cloud's coverage.
  ASSERT_TRUE(plan.certificate);
  EXPECT_GE(report.measured_fraction, 0.98);
  EXPECT_NEAR(report.measured_fraction, plan.certificate->covered_of_scannable, 0.005);
  std::filesystem::remove_all(dir);
}

// Same job, same bytes: on one thread and on all of them, twice. Compares the poses bit for bit
// and the certificate's classes (they once depended on uninitialised memory).
TEST(AutoScan, ThePlanIsTheSameOnOneThreadAndOnAll) {
  const auto dir = std::filesystem::temp_directory_path() / "scanplan_test_autoscan_same";
  std::filesystem::create_directories(dir);
  const pipeline::ScanProblem problem = autoProblem(writeBoxStl(dir / "box.stl", 70, 40, 50));
  const collision::Scene scene(problem.cell, problem.clearance);
  const auto plan = [&] { return pipeline::scanPath(problem, scene); };
  pipeline::ScanPathResult serial;
  tbb::task_arena(1).execute([&] { serial = plan(); });
  for (int run = 0; run < 2; ++run) {
    const pipeline::ScanPathResult again = plan();
    ASSERT_TRUE(serial.auto_scan && again.auto_scan);
    EXPECT_TRUE(serial.auto_scan->classes == again.auto_scan->classes);
    EXPECT_EQ(serial.auto_scan->passes.size(), again.auto_scan->passes.size());
    const auto& a = serial.path.path.samples;
    const auto& b = again.path.path.samples;
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t k = 0; k < a.size(); ++k) {
      ASSERT_EQ(a[k].t, b[k].t) << k;
      ASSERT_TRUE(a[k].X_PS.matrix() == b[k].X_PS.matrix()) << "sample " << k;
      ASSERT_EQ(a[k].scanning, b[k].scanning) << k;
    }
  }
  std::filesystem::remove_all(dir);
}

TEST(Placement, ABoxRestsOnAFaceNotOnAnEdgeAndItsCentroidIsItsCentre) {
  const auto dir = std::filesystem::temp_directory_path() / "scanplan_test_rest";
  std::filesystem::create_directories(dir);
  const auto box = kinematics::loadMesh(writeBoxStl(dir / "box.stl", 80, 40, 20)).mesh;
  EXPECT_LT((kinematics::solidCentroid(box) - Eigen::Vector3d(0.04, 0.02, 0.01)).norm(), 1e-12);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  EXPECT_TRUE(kinematics::restsStably(box, kinematics::placedOnTable(box, pose)));
  pose.linear() = Eigen::AngleAxisd(deg(90.0), Eigen::Vector3d::UnitY()).toRotationMatrix();
  EXPECT_TRUE(kinematics::restsStably(box, kinematics::placedOnTable(box, pose)));  // on its end
  pose.linear() = Eigen::AngleAxisd(deg(45.0), Eigen::Vector3d::UnitX()).toRotationMatrix();
  EXPECT_FALSE(kinematics::restsStably(box, kinematics::placedOnTable(box, pose)));  // an edge
  pose.linear() = Eigen::AngleAxisd(deg(10.0), Eigen::Vector3d::UnitY()).toRotationMatrix();
  EXPECT_FALSE(kinematics::restsStably(box, kinematics::placedOnTable(box, pose)));  // a tilt
  std::filesystem::remove_all(dir);
}

TEST(AutoScan, ASecondSetupTurnsTheCubeOverAndBothCoverItAll) {
  const auto dir = std::filesystem::temp_directory_path() / "scanplan_test_setups";
  std::filesystem::create_directories(dir);
  const pipeline::ScanProblem problem = autoProblem(writeBoxStl(dir / "cube.stl", 60, 60, 60));
  const pipeline::ScanPlan first = pipeline::planScan(problem);
  ASSERT_TRUE(first.planned() && first.certificate) << first.reason;
  const auto setup = pipeline::chooseSecondSetup(problem, first);
  ASSERT_TRUE(setup.has_value());
  // The bottom (a sixth) comes into view; the turned cube still rests on the table top.
  EXPECT_NEAR(setup->gain, first.certificate->fraction[2], 1e-12);
  EXPECT_GT(setup->gain, 0.1);
  EXPECT_NEAR(kinematics::partExtent(problem.part, setup->X_RP).lowest, 0.0, 1e-12);
  const pipeline::ScanProblem turned = pipeline::secondSetupProblem(problem, *setup);
  const pipeline::ScanPlan second = pipeline::planScan(turned);
  ASSERT_TRUE(second.planned() && second.certificate) << second.reason;
  EXPECT_TRUE(second.validation->valid);
  const pipeline::CombinedCoverage both = pipeline::combineSetups(first, second);
  EXPECT_GE(both.area_fraction, 0.98);
  EXPECT_GE(both.area_fraction, first.simulation->area.covered_fraction + 0.1);
  EXPECT_GE(both.covered_of_scannable, 0.98);
  std::filesystem::remove_all(dir);
}

// Work that scales with the input is estimated before it starts: a ring at 1e-6 °/s,
// a raster with a kilometre of lead, a part in mm declared in metres.
TEST(AutoScan, OversizedWorkIsRefusedBeforeItStarts) {
  const auto error = [](const std::string& job, const std::vector<std::string>& set) {
    try {
      pipeline::planScan(config::toProblem(config::loadJob(test::sourceDir() / job, set)));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("data/jobs/demo_rings.yaml", {"scan.paths[0].speed_deg_s=1e-6"})
                .find("expected at most 2000000 samples"),
            std::string::npos);
  EXPECT_NE(error("data/jobs/demo_rings.yaml", {"scan.paths[3].lead_mm=1e6"})
                .find("scan.paths[3]: the raster would probe"),
            std::string::npos);
  // 20× the housing: partly within reach, but 5 m across.
  EXPECT_NE(error("data/jobs/demo.yaml", {"part.scale=20"}).find("too large to scan"),
            std::string::npos);
  // A mesh in mm read as m: nowhere near the arm, and the message says what to check.
  const std::string mm_as_m = error("data/jobs/demo.yaml", {"part.units=m"});
  EXPECT_NE(mm_as_m.find("within the arm's reach"), std::string::npos) << mm_as_m;
  EXPECT_NE(mm_as_m.find("part.units"), std::string::npos) << mm_as_m;
}

}  // namespace
