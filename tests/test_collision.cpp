#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <thread>

#include <gtest/gtest.h>
#include <unistd.h>

#include "cli/job.h"
#include "collision/clearance.h"
#include "collision/fcl_geometry.h"
#include "collision/scene.h"
#include "kinematics/error.h"
#include "kinematics/pose.h"
#include "kinematics/ramp.h"
#include "kinematics/units.h"
#include "tests/test_support.h"

namespace scanplan::collision {
namespace {

namespace fs = std::filesystem;
using kinematics::JointVector;

// FCL's GJK (libccd) stops at distance_tolerance = 1e-6 m; analytic cases allow that much.
constexpr double kGjkTol = 2e-6;
// On curved support functions (cylinders) libccd's GJK converges more loosely: ~1e-5 m seen.
constexpr double kGjkCurvedTol = 2e-5;
// Its witness points converge more loosely still: up to ~0.3 mm off a cylinder's surface seen,
// while the distance itself is within kGjkCurvedTol.
constexpr double kWitnessTol = 5e-4;
// The bounded query must reproduce the plain query's number, not just approximately.
constexpr double kSameTol = 1e-9;

Eigen::Isometry3d randomPose(std::mt19937& rng, double extent) {
  std::uniform_real_distribution<double> d(-extent, extent);
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = kinematics::rotationFromRpy({d(rng) * 3, d(rng) * 3, d(rng) * 3});
  X.translation() << d(rng), d(rng), d(rng);
  return X;
}

detail::CollisionShape primitive(kinematics::ShapeGeometry g) {
  kinematics::Shape s;
  s.geometry = std::move(g);
  return detail::makeCollisionShape(s);
}

Eigen::Isometry3d at(double x, double y, double z) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() << x, y, z;
  return X;
}

TEST(Ramp, Eq8IsZeroBelowLowOneAtHighAndMonotoneBetween) {
  EXPECT_EQ(rampFactor(0.0049, 0.005, 0.03, 1.0), 0.0);
  EXPECT_EQ(rampFactor(0.005, 0.005, 0.03, 1.0), 0.0);  // sin(0)
  EXPECT_EQ(rampFactor(0.03, 0.005, 0.03, 1.0), 1.0);
  EXPECT_EQ(rampFactor(0.5, 0.005, 0.03, 1.0), 1.0);
  EXPECT_EQ(rampFactor(std::nan(""), 0.005, 0.03, 1.0), 0.0);
  // Midway: sin(π/4); γ = 2 squares it (stricter), γ = 0.5 takes the root (more permissive).
  EXPECT_NEAR(rampFactor(0.0175, 0.005, 0.03, 1.0), std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(rampFactor(0.0175, 0.005, 0.03, 2.0), 0.5, 1e-15);
  EXPECT_GT(rampFactor(0.0175, 0.005, 0.03, 0.5), rampFactor(0.0175, 0.005, 0.03, 1.0));
  double last = 0.0;
  for (double d = 0.0; d < 0.04; d += 1e-4) {
    const double f = rampFactor(d, 0.005, 0.03, 1.5);
    ASSERT_GE(f, last) << "not monotone at d = " << d;
    last = f;
  }
}

TEST(Ramp, Eq7JointFactorPeaksMidRangeAndVanishesAtTheLimits) {
  EXPECT_EQ(jointLimitFactor(-1.0, -1.0, 2.0, 0.2), 0.0);
  EXPECT_EQ(jointLimitFactor(2.0, -1.0, 2.0, 0.2), 0.0);
  EXPECT_EQ(jointLimitFactor(3.0, -1.0, 2.0, 0.2), 0.0);
  EXPECT_NEAR(jointLimitFactor(0.5, -1.0, 2.0, 0.2), 1.0, 1e-15);
  EXPECT_NEAR(jointLimitFactor(-0.25, -1.0, 2.0, 1.0), std::sin(std::numbers::pi / 4), 1e-15);
}

// Analytic distances, each rerun with both bodies moved by several world transforms G.
class AnalyticPrimitives : public ::testing::TestWithParam<int> {
 protected:
  Eigen::Isometry3d G() const {
    std::mt19937 rng(static_cast<unsigned>(GetParam()));
    return GetParam() == 0 ? Eigen::Isometry3d::Identity() : randomPose(rng, 2.0);
  }
  double distance(const detail::CollisionShape& a,
                  const Eigen::Isometry3d& X_a,
                  const detail::CollisionShape& b,
                  const Eigen::Isometry3d& X_b) const {
    const auto bounded = detail::shapeDistance(a, G() * X_a, b, G() * X_b, 1.0, true);
    const auto exact = detail::exactShapeDistance(a, G() * X_a, b, G() * X_b);
    EXPECT_NEAR(bounded.distance, exact.distance, kSameTol);
    EXPECT_NEAR((bounded.p_a - bounded.p_b).norm(), bounded.distance, kGjkCurvedTol);
    return bounded.distance;
  }
};

TEST_P(AnalyticPrimitives, SphereSphere) {
  // |c1 − c2| − r1 − r2 = √(0.3² + 0.4²) − 0.1 − 0.15 = 0.25.
  EXPECT_NEAR(distance(primitive(kinematics::Sphere{0.1}), at(0, 0, 0),
                       primitive(kinematics::Sphere{0.15}), at(0.3, 0.4, 0)),
              0.25, kGjkTol);
}

TEST_P(AnalyticPrimitives, BoxBoxAcrossAFaceAnEdgeAndACorner) {
  const auto box = primitive(kinematics::Box{Eigen::Vector3d(0.2, 0.2, 0.2)});
  // Faces 0.05 apart along x: centres 0.25 apart minus two half-sides of 0.1.
  EXPECT_NEAR(distance(box, at(0, 0, 0), box, at(0.25, 0.05, -0.03)), 0.05, kGjkTol);
  // Edges: gaps 0.03 in x and 0.04 in y → 0.05.
  EXPECT_NEAR(distance(box, at(0, 0, 0), box, at(0.23, 0.24, 0.0)), 0.05, kGjkTol);
  // Corners: gaps 0.02, 0.03, 0.06 → 0.07.
  EXPECT_NEAR(distance(box, at(0, 0, 0), box, at(0.22, 0.23, 0.26)), 0.07, kGjkTol);
}

TEST_P(AnalyticPrimitives, CylinderBesideABoxFace) {
  // Cylinder axis along z, 0.2 from the box face at x = 0.1, radius 0.05 → 0.15.
  EXPECT_NEAR(distance(primitive(kinematics::Cylinder{0.05, 0.3}), at(0.3, 0, 0),
                       primitive(kinematics::Box{Eigen::Vector3d(0.2, 0.2, 0.2)}), at(0, 0, 0)),
              0.15, kGjkCurvedTol);
}

TEST_P(AnalyticPrimitives, CapsuleEndAboveASphere) {
  // Capsule along z centred at 0, half-length 0.1 + radius 0.02: its tip is at z = 0.12.
  EXPECT_NEAR(distance(primitive(kinematics::Capsule{0.02, 0.2}), at(0, 0, 0),
                       primitive(kinematics::Sphere{0.03}), at(0, 0, 0.2)),
              0.2 - 0.12 - 0.03, kGjkTol);
}

TEST_P(AnalyticPrimitives, OverlapIsContactAtZero) {
  const auto bounded =
      detail::shapeDistance(primitive(kinematics::Sphere{0.1}), G() * at(0, 0, 0),
                            primitive(kinematics::Sphere{0.1}), G() * at(0.15, 0, 0), 0.03, false);
  EXPECT_TRUE(bounded.penetrating);
  EXPECT_EQ(bounded.distance, 0.0);
}

TEST_P(AnalyticPrimitives, FarPairsAreOnlyReportedBeyondTheBound) {
  const auto bounded =
      detail::shapeDistance(primitive(kinematics::Sphere{0.1}), G() * at(0, 0, 0),
                            primitive(kinematics::Sphere{0.1}), G() * at(0.5, 0, 0), 0.03, false);
  EXPECT_TRUE(bounded.beyond);
  EXPECT_EQ(bounded.distance, 0.03);
}

INSTANTIATE_TEST_SUITE_P(WorldFrames, AnalyticPrimitives, ::testing::Values(0, 1, 2, 3));

// The bundled demo cell, built through the job file as a user would.
struct DemoCell {
  cli::JobSpec job = cli::loadJob(test::sourceDir() / "data/jobs/demo.yaml");
  Scene scene{cli::buildCell(job), cli::clearanceConfig(job)};
};

// How far a factor may move when its distance moves by kSameTol (the ramp's slope there),
// plus rounding.
double factorTolerance(const PairThresholds& t, double d) {
  return std::abs(rampFactor(d + kSameTol, t.d_low, t.d_high, t.gamma) -
                  rampFactor(std::max(0.0, d - kSameTol), t.d_low, t.d_high, t.gamma)) +
         1e-12;
}

// The product of the pairs' factors within the sum of their tolerances.
double productTolerance(const Scene& scene, const ClearanceResult& exact) {
  double tol = 0.0;
  for (std::size_t i = 0; i < scene.pairs().size(); ++i) {
    if (exact.pairs[i].distance < scene.pairs()[i].thresholds.d_high)
      tol += factorTolerance(scene.pairs()[i].thresholds, exact.pairs[i].distance);
  }
  return tol + 1e-12;
}

::testing::AssertionResult boundedMatchesExact(const Scene& scene,
                                               const ClearanceResult& bounded,
                                               const ClearanceResult& exact) {
  for (std::size_t i = 0; i < scene.pairs().size(); ++i) {
    const auto& b = bounded.pairs[i];
    const auto& e = exact.pairs[i];
    const double d_high = scene.pairs()[i].thresholds.d_high;
    const std::string name = scene.bodies()[static_cast<std::size_t>(scene.pairs()[i].a)].name +
                             " - " +
                             scene.bodies()[static_cast<std::size_t>(scene.pairs()[i].b)].name;
    if (e.distance < d_high) {
      if (b.beyond_bound || std::abs(b.distance - e.distance) > kSameTol ||
          std::abs(b.factor - e.factor) >
              factorTolerance(scene.pairs()[i].thresholds, e.distance)) {
        return ::testing::AssertionFailure()
               << name << ": exact " << e.distance << " (f " << e.factor << "), bounded "
               << b.distance << " (f " << b.factor << (b.beyond_bound ? ", beyond" : "") << ")";
      }
    } else if (!b.beyond_bound || b.factor != 1.0) {
      return ::testing::AssertionFailure() << name << ": exact " << e.distance << " ≥ d_high "
                                           << d_high << " but bounded says " << b.distance;
    }
  }
  return ::testing::AssertionSuccess();
}

TEST(Clearance, BoundedEqualsExactOnTheDemoCellAlongRandomPaths) {
  DemoCell demo;
  ClearanceEvaluator evaluator(demo.scene);
  std::mt19937 rng(17);
  const auto& robot = demo.scene.cell().robot;
  int near = 0;
  // The exact reference costs ~35 ms a pose on the 31k-triangle demo part: 10 paths x 12 steps.
  for (int path = 0; path < 10; ++path) {
    JointVector q = test::randomJoints(robot, rng);
    const JointVector step = (test::randomJoints(robot, rng) - q) / 12.0;
    const double theta = std::uniform_real_distribution<double>(-3, 3)(rng);
    for (int k = 0; k < 12; ++k, q += step) {
      const ClearanceResult bounded = evaluator.evaluate(theta, q, {.bounded = true});
      const ClearanceResult exact = evaluator.evaluate(theta, q, {.bounded = false});
      ASSERT_TRUE(boundedMatchesExact(demo.scene, bounded, exact))
          << "path " << path << " step " << k;
      ASSERT_NEAR(bounded.factor, exact.factor, productTolerance(demo.scene, exact));
      ASSERT_EQ(evaluator.factor(theta, q), bounded.factor);
      for (const auto& p : exact.pairs) near += p.distance < 0.03 ? 1 : 0;
    }
  }
  EXPECT_GT(near, 10);  // the bound was actually exercised
}

TEST(Clearance, BoundedEqualsExactWithTheScannerJustAboveThePart) {
  // The scanner housing 0–30 mm above the housing's hub, looking down: the costly case, where
  // thousands of part triangles lie within d_high of the scanner.
  DemoCell demo;
  ClearanceEvaluator evaluator(demo.scene);
  const auto& cell = demo.scene.cell();
  int scanner_near = 0;
  for (int k = 0; k < 24; ++k) {
    Eigen::Isometry3d X_PS = Eigen::Isometry3d::Identity();
    X_PS.linear() = Eigen::Vector3d(1, -1, -1).asDiagonal();
    X_PS.translation() << 0.03 * std::sin(k), 0.03 * std::cos(0.7 * k), 0.110 + 0.00125 * k;
    const double theta = 0.3 * k;
    const auto solutions =
        cell.robot.ik(cell.flangeTarget(theta, X_PS), {.within_limits_only = true});
    if (solutions.empty()) continue;
    const ClearanceResult bounded = evaluator.evaluate(theta, solutions[0].q);
    const ClearanceResult exact = evaluator.evaluate(theta, solutions[0].q, {.bounded = false});
    ASSERT_TRUE(boundedMatchesExact(demo.scene, bounded, exact)) << "pose " << k;
    ASSERT_NEAR(bounded.factor, exact.factor, productTolerance(demo.scene, exact));
    ASSERT_EQ(evaluator.factor(theta, solutions[0].q), bounded.factor);
    for (std::size_t i = 0; i < exact.pairs.size(); ++i) {
      const auto& p = demo.scene.pairs()[i];
      if (demo.scene.bodies()[static_cast<std::size_t>(p.b)].name == "part" &&
          demo.scene.bodies()[static_cast<std::size_t>(p.a)].name == "scanner") {
        scanner_near += exact.pairs[i].distance < p.thresholds.d_high ? 1 : 0;
      }
    }
  }
  EXPECT_GT(scanner_near, 15);
}

TEST(Clearance, DefaultPairsSkipRigidAndConsecutiveBodies) {
  DemoCell demo;
  const auto& bodies = demo.scene.bodies();
  const auto has = [&](const std::string& a, const std::string& b) {
    for (const auto& p : demo.scene.pairs()) {
      const auto& na = bodies[static_cast<std::size_t>(p.a)].name;
      const auto& nb = bodies[static_cast<std::size_t>(p.b)].name;
      if ((na == a && nb == b) || (na == b && nb == a)) return true;
    }
    return false;
  };
  for (int i = 0; i < 6; ++i) {
    const std::string li = i == 0 ? "base" : "link" + std::to_string(i);
    EXPECT_FALSE(has(li, "link" + std::to_string(i + 1)))
        << "consecutive links are always in contact";
  }
  EXPECT_FALSE(has("scanner", "link6"));  // rigidly mounted
  EXPECT_FALSE(has("scanner", "link5"));  // consecutive with its carrier link
  EXPECT_FALSE(has("table", "part"));     // both turn with the table
  EXPECT_FALSE(has("base", "table"));     // neither moves with the arm
  EXPECT_TRUE(has("scanner", "part"));
  EXPECT_TRUE(has("scanner", "link1"));
  EXPECT_TRUE(has("link3", "table"));
  // The demo's rules: scanner ↔ link4 fully clear at 10 mm, scanner ↔ table 20 / 50 mm.
  for (const auto& p : demo.scene.pairs()) {
    const auto& na = bodies[static_cast<std::size_t>(p.a)].name;
    const auto& nb = bodies[static_cast<std::size_t>(p.b)].name;
    if (na == "link4" && nb == "scanner") {
      EXPECT_DOUBLE_EQ(p.thresholds.d_high, 0.010);
    }
    if (na == "scanner" && nb == "table") {
      EXPECT_DOUBLE_EQ(p.thresholds.d_low, 0.020);
      EXPECT_DOUBLE_EQ(p.thresholds.d_high, 0.050);
    }
  }
}

TEST(Clearance, RulesExcludeIncludeAndSetThresholdsByGroup) {
  DemoCell demo;
  ClearanceConfig config = cli::clearanceConfig(demo.job);
  config.rules.push_back({"scanner", "*", PairRule::Action::kSet, 0.001, 0.040, 2.0});
  config.rules.push_back({"link3", "robot", PairRule::Action::kExclude});
  config.rules.push_back({"table", "part", PairRule::Action::kInclude});
  const Scene scene(demo.scene.cell(), config);
  bool table_part = false;
  for (const auto& p : scene.pairs()) {
    const auto& na = scene.bodies()[static_cast<std::size_t>(p.a)].name;
    const auto& nb = scene.bodies()[static_cast<std::size_t>(p.b)].name;
    EXPECT_FALSE(na == "link3" && nb.rfind("link", 0) == 0) << na << " - " << nb;
    EXPECT_FALSE(nb == "link3" && (na.rfind("link", 0) == 0 || na == "base")) << na << " - " << nb;
    if (na == "scanner" || nb == "scanner") {
      EXPECT_DOUBLE_EQ(p.thresholds.d_high, 0.040);
      EXPECT_DOUBLE_EQ(p.thresholds.gamma, 2.0);
    }
    table_part = table_part || (na == "table" && nb == "part");
  }
  EXPECT_TRUE(table_part);
  ClearanceConfig bad = config;
  bad.rules.push_back({"scaner", "*", PairRule::Action::kExclude});
  EXPECT_THROW(Scene(demo.scene.cell(), bad), InputError);
}

TEST(Clearance, ScannerFoldedIntoLinkOneIsACollision) {
  DemoCell demo;
  ClearanceEvaluator evaluator(demo.scene);
  JointVector q;
  q << 0, -150, 250, 0, 90, 0;
  q *= kDegToRad;
  const ClearanceResult r = evaluator.evaluate(0.0, q, {.witness_points = true});
  EXPECT_TRUE(r.collision);
  EXPECT_EQ(r.factor, 0.0);
  bool link1_scanner = false;
  for (std::size_t i = 0; i < r.pairs.size(); ++i) {
    const auto& p = demo.scene.pairs()[i];
    if (demo.scene.bodies()[static_cast<std::size_t>(p.a)].name == "link1" &&
        demo.scene.bodies()[static_cast<std::size_t>(p.b)].name == "scanner") {
      link1_scanner = r.pairs[i].penetrating;
    }
  }
  EXPECT_TRUE(link1_scanner);
  EXPECT_EQ(evaluator.factor(0.0, q), 0.0);
}

// Distance from a world point to a body of the scene (a small probe sphere against each shape).
double pointToBody(const Scene& scene,
                   int body,
                   const std::vector<Eigen::Isometry3d>& X_W,
                   const Eigen::Vector3d& p) {
  constexpr double kProbe = 1e-4;
  const auto probe = primitive(kinematics::Sphere{kProbe});
  double best = 1e9;
  for (const auto& shape : scene.geometry().bodies[static_cast<std::size_t>(body)].shapes) {
    const auto d = detail::exactShapeDistance(probe, at(p.x(), p.y(), p.z()), shape,
                                              X_W[static_cast<std::size_t>(body)] * shape.X_BG);
    best = std::min(best, d.penetrating ? 0.0 : d.distance + kProbe);
  }
  return best;
}

TEST(Clearance, WitnessPointsLieOnTheirBodiesAndAreTheReportedDistanceApart) {
  DemoCell demo;
  ClearanceEvaluator evaluator(demo.scene);
  std::mt19937 rng(23);
  int checked = 0;
  std::vector<Eigen::Isometry3d> X_W;
  for (int k = 0; k < 300; ++k) {
    const JointVector q = test::randomJoints(demo.scene.cell().robot, rng);
    const ClearanceResult r = evaluator.evaluate(0.3 * k, q, {.witness_points = true});
    demo.scene.bodyPoses(0.3 * k, q, X_W);
    for (std::size_t i = 0; i < r.pairs.size(); ++i) {
      const auto& p = r.pairs[i];
      if (p.beyond_bound || p.penetrating) continue;
      EXPECT_LT(pointToBody(demo.scene, demo.scene.pairs()[i].a, X_W, p.p_a), kWitnessTol);
      EXPECT_LT(pointToBody(demo.scene, demo.scene.pairs()[i].b, X_W, p.p_b), kWitnessTol)
          << demo.scene.bodies()[static_cast<std::size_t>(demo.scene.pairs()[i].a)].name << " - "
          << demo.scene.bodies()[static_cast<std::size_t>(demo.scene.pairs()[i].b)].name << " d "
          << p.distance << " pb " << p.p_b.transpose();
    }
    for (std::size_t i = 0; i < r.pairs.size(); ++i) {
      const auto& p = r.pairs[i];
      if (p.beyond_bound || p.penetrating) continue;
      EXPECT_NEAR((p.p_a - p.p_b).norm(), p.distance, kGjkCurvedTol)
          << demo.scene.bodies()[static_cast<std::size_t>(demo.scene.pairs()[i].a)].name << " - "
          << demo.scene.bodies()[static_cast<std::size_t>(demo.scene.pairs()[i].b)].name;
      ++checked;
    }
  }
  EXPECT_GT(checked, 20);
}

TEST(Clearance, ThreadsSharingOneSceneGetIdenticalResults) {
  DemoCell demo;
  std::mt19937 rng(31);
  std::vector<std::pair<double, JointVector>> poses;
  for (int k = 0; k < 300; ++k)
    poses.emplace_back(0.1 * k, test::randomJoints(demo.scene.cell().robot, rng));
  const auto run = [&](std::vector<double>& out) {
    ClearanceEvaluator evaluator(demo.scene);
    for (const auto& [theta, q] : poses) {
      const ClearanceResult r = evaluator.evaluate(theta, q);
      out.push_back(r.factor);
      for (const auto& p : r.pairs) out.push_back(p.distance);
    }
  };
  std::vector<double> reference;
  run(reference);
  std::vector<std::vector<double>> results(4);
  std::vector<std::thread> threads;
  for (auto& r : results) threads.emplace_back([&run, &r] { run(r); });
  for (auto& t : threads) t.join();
  for (const auto& r : results) EXPECT_EQ(r, reference);
}

TEST(Scene, CornerBoxesWithNegativeSizesAreNormalised) {
  const fs::path dir =
      fs::temp_directory_path() / ("scanplan_test_scene_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path job = dir / "job.yaml";
  std::ofstream(job)
      << "robot: " << (test::sourceDir() / "data/robots/viper_s650.yaml").string()
      << "\npart: {mesh: " << (test::sourceDir() / "data/parts/demo_housing.stl").string()
      << "}\nobstacles:\n"
         "  - {name: post, type: box, corner_mm: [300, 300, 0], size_mm: [-100, -50, 200]}\n"
         "  - {name: jig, carrier: table, type: sphere, radius_mm: 20, pose: {xyz_mm: [0, 150, "
         "0]}}\n";
  const cli::JobSpec spec = cli::loadJob(job);
  const kinematics::CellModel cell = cli::buildCell(spec);
  ASSERT_EQ(cell.obstacles.size(), 2u);
  const auto& box = std::get<kinematics::Box>(cell.obstacles[0].shapes[0].geometry);
  EXPECT_TRUE(box.size.isApprox(Eigen::Vector3d(0.1, 0.05, 0.2), 1e-12));
  EXPECT_TRUE(cell.obstacles[0].shapes[0].X_BG.translation().isApprox(
      Eigen::Vector3d(0.25, 0.275, 0.1), 1e-12));
  EXPECT_EQ(cell.obstacles[1].carrier, kinematics::Carrier::kTable);
  const Scene scene(cell, cli::clearanceConfig(spec));
  EXPECT_GE(scene.bodyIndex("post"), 0);
  EXPECT_GE(scene.bodyIndex("jig"), 0);
  fs::remove_all(dir);
}

TEST(Scene, SharedViperLinkMeshesAndTheBunnyKeepBoundedEqualToExact) {
  const fs::path data = test::sharedDataDir();
  if (!fs::exists(data / "robots/viper_s650/link0.stl") ||
      !fs::exists(data / "meshes/stlmodels_bunny.bin.stl")) {
    GTEST_SKIP() << "shared test data not present";
  }
  kinematics::RobotDefinition def = test::bundledRobot("viper_s650").definition();
  for (int k = 0; k <= 6; ++k) {
    kinematics::Shape mesh;
    mesh.geometry =
        kinematics::MeshFile{data / "robots/viper_s650" / ("link" + std::to_string(k) + ".stl"),
                             {kinematics::LengthUnit::kMetre, 1.0}};
    // SOURCES.md: meshes 3, 4, 5 are Rz(180°) from their DH frames.
    if (k >= 3 && k <= 5) mesh.X_BG.linear() = kinematics::rotZ(std::numbers::pi);
    def.links[static_cast<std::size_t>(k)].shapes = {mesh};
  }
  kinematics::CellModel cell("shared", kinematics::RobotModel(def));
  cell.table.X_WA.translation() << 0.5, 0.0, 0.0;
  cell.part.mesh = {data / "meshes/stlmodels_bunny.bin.stl", {kinematics::LengthUnit::kMetre, 1.0}};
  kinematics::Shape scanner;
  scanner.geometry = kinematics::Box{Eigen::Vector3d(0.06, 0.09, 0.11)};
  scanner.X_BG.translation() << 0, 0, -0.055;
  cell.scanner.body = {scanner};
  cell.scanner.X_FS.translation() << 0, 0, 0.11;
  const Scene scene(cell, {});
  ClearanceEvaluator evaluator(scene);
  std::mt19937 rng(41);
  for (int k = 0; k < 40; ++k) {
    const JointVector q = test::randomJoints(cell.robot, rng);
    const auto bounded = evaluator.evaluate(0.2 * k, q);
    const auto exact = evaluator.evaluate(0.2 * k, q, {.bounded = false});
    ASSERT_TRUE(boundedMatchesExact(scene, bounded, exact)) << "pose " << k;
  }
}

}  // namespace
}  // namespace scanplan::collision
