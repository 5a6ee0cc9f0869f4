#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <thread>

#include <gtest/gtest.h>
#include <unistd.h>

#include <scanplan/collision/chain_levers.h>
#include <scanplan/collision/clearance.h>
#include <scanplan/collision/fcl_geometry.h>
#include <scanplan/collision/scene.h>
#include <scanplan/collision/self_collision.h>
#include <scanplan/collision/self_pair_grid.h>
#include <scanplan/config/job.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/ramp.h>
#include <scanplan/kinematics/units.h>
#include "tests/test_support.h"

namespace scanplan::collision {
namespace {

namespace fs = std::filesystem;
using kinematics::JointVector;

// FCL's GJK (libccd) stops at distance_tolerance = 1e-6 m; analytic cases allow that much.
constexpr double kGjkTol = 2e-6;
// On curved support functions (cylinders) libccd's GJK converges more loosely: ~1e-5 m seen.
constexpr double kGjkCurvedTol = 2e-5;
// Spheres are zero-length capsules (fcl_geometry.cpp): looser again, 3.3e-5 m seen at 58 mm.
constexpr double kGjkSphereTol = 5e-5;
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

TEST_P(AnalyticPrimitives, BoxBoxAcrossEveryFaceEdgeAndCorner) {
  // Box A (half-sides 0.10, 0.15, 0.20) at the origin; box B (0.05, 0.08, 0.06) beside it in
  // each of the 26 directions s ∈ {−1, 0, 1}³ \ 0: 6 faces, 12 edges, 8 corners. Along an axis
  // with s_i ≠ 0 the boxes are apart by gap g_i; along s_i = 0 they overlap (B's centre offset
  // o_i lies within A's extent). Distance = √(Σ over s_i ≠ 0 of g_i²).
  const Eigen::Vector3d ha(0.10, 0.15, 0.20), hb(0.05, 0.08, 0.06), g(0.03, 0.04, 0.012),
      o(0.02, -0.05, 0.07);
  const auto a = primitive(kinematics::Box{2 * ha});
  const auto b = primitive(kinematics::Box{2 * hb});
  int faces = 0, edges = 0, corners = 0;
  for (int sx = -1; sx <= 1; ++sx) {
    for (int sy = -1; sy <= 1; ++sy) {
      for (int sz = -1; sz <= 1; ++sz) {
        const Eigen::Vector3i s(sx, sy, sz);
        const int apart = s.cwiseAbs().sum();
        if (apart == 0) continue;
        Eigen::Vector3d c, gaps = Eigen::Vector3d::Zero();
        for (int i = 0; i < 3; ++i) {
          c(i) = s(i) == 0 ? o(i) : s(i) * (ha(i) + hb(i) + g(i));
          if (s(i) != 0) gaps(i) = g(i);
        }
        EXPECT_NEAR(distance(a, Eigen::Isometry3d::Identity(), b, at(c.x(), c.y(), c.z())),
                    gaps.norm(), kGjkTol)
            << "direction " << s.transpose();
        (apart == 1 ? faces : apart == 2 ? edges : corners)++;
      }
    }
  }
  EXPECT_EQ(faces, 6);
  EXPECT_EQ(edges, 12);
  EXPECT_EQ(corners, 8);
}

TEST_P(AnalyticPrimitives, CylinderAgainstABoxFaceEdgeAndCorner) {
  // The box: half-sides 0.1 at the origin. The cylinder: axis along z, radius r, length 0.3.
  const double r = 0.05, half_length = 0.15;
  const auto box = primitive(kinematics::Box{Eigen::Vector3d(0.2, 0.2, 0.2)});
  const auto cylinder = primitive(kinematics::Cylinder{r, 2 * half_length});
  // Side against a face: axis 0.2 from the face at x = 0.1 → 0.2 − r = 0.15.
  EXPECT_NEAR(distance(cylinder, at(0.3, 0, 0), box, at(0, 0, 0)), 0.15, kGjkCurvedTol);
  // Cap against a face: the cap 0.04 above the top face, over it.
  EXPECT_NEAR(distance(cylinder, at(0.02, -0.03, 0.1 + 0.04 + half_length), box, at(0, 0, 0)), 0.04,
              kGjkCurvedTol);
  // Cap rim against the top edge along y (x = z = 0.1): the axis r + 0.03 beyond the edge in
  // x, the cap 0.04 above → nearest rim point (0.13, 0, 0.14): √(0.03² + 0.04²) = 0.05.
  EXPECT_NEAR(distance(cylinder, at(0.1 + r + 0.03, 0, 0.1 + 0.04 + half_length), box, at(0, 0, 0)),
              0.05, kGjkCurvedTol);
  // Cap rim against the corner (0.1, 0.1, 0.1): the axis at horizontal distance ρ = 0.06·√2
  // from the corner's vertical, the cap 0.02 above → √((ρ − r)² + 0.02²).
  const double rho = 0.06 * std::sqrt(2.0);
  EXPECT_NEAR(distance(cylinder, at(0.16, 0.16, 0.1 + 0.02 + half_length), box, at(0, 0, 0)),
              std::hypot(rho - r, 0.02), kGjkCurvedTol);
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
  config::JobSpec job = config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml");
  Scene scene{config::buildCell(job), config::clearanceConfig(job)};
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
  ClearanceConfig config = config::clearanceConfig(demo.job);
  config.rules.push_back({"scanner", "*", PairRule::Action::kSet, 0.001, 0.040, 2.0});
  config.rules.push_back({"link3", "robot", PairRule::Action::kExclude});
  config.rules.push_back({"link5", "link6", PairRule::Action::kInclude});  // consecutive: off
  const Scene scene(demo.scene.cell(), config);
  bool link5_link6 = false;
  for (const auto& p : scene.pairs()) {
    const auto& na = scene.bodies()[static_cast<std::size_t>(p.a)].name;
    const auto& nb = scene.bodies()[static_cast<std::size_t>(p.b)].name;
    EXPECT_FALSE(na == "link3" && nb.rfind("link", 0) == 0) << na << " - " << nb;
    EXPECT_FALSE(nb == "link3" && (na.rfind("link", 0) == 0 || na == "base")) << na << " - " << nb;
    if (na == "scanner" || nb == "scanner") {
      EXPECT_DOUBLE_EQ(p.thresholds.d_high, 0.040);
      EXPECT_DOUBLE_EQ(p.thresholds.gamma, 2.0);
    }
    link5_link6 = link5_link6 || (na == "link5" && nb == "link6");
  }
  EXPECT_TRUE(link5_link6);
  ClearanceConfig bad = config;
  bad.rules.push_back({"scaner", "*", PairRule::Action::kExclude});
  EXPECT_THROW(Scene(demo.scene.cell(), bad), InputError);
  // The table and the part it carries never move apart: no pair to include, said so.
  ClearanceConfig still = config;
  still.rules.push_back({"table", "part", PairRule::Action::kInclude});
  try {
    const Scene s(demo.scene.cell(), still);
    ADD_FAILURE() << "a rule over bodies that never move apart was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("can move relative to one another"), std::string::npos)
        << e.what();
  }
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

// A non-finite pose must never reach FCL: libccd's GJK asserts on it and aborts the process
// (seen with `check --table nan` before the CLI checked its input).
TEST(Clearance, NonFinitePosesAreRefusedNotPassedToFcl) {
  DemoCell demo;
  ClearanceEvaluator evaluator(demo.scene);
  const JointVector q = JointVector::Zero();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_THROW(evaluator.evaluate(nan, q), std::invalid_argument);
  EXPECT_THROW(evaluator.factor(inf, q), std::invalid_argument);
  JointVector bad = q;
  bad(4) = nan;
  EXPECT_THROW(evaluator.evaluate(0.0, bad), std::invalid_argument);
  EXPECT_THROW(evaluator.factor(0.0, bad), std::invalid_argument);
  EXPECT_NO_THROW(evaluator.evaluate(0.0, q));  // and the evaluator is still usable
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

// The table turns into no new space, so nothing measures it against the base or the world's
// obstacles in motion: a cell where it overlaps them where it stands is refused, naming the
// keys; one where it is clear of them (the demo, a post beside the table) is not.
TEST(Scene, ATableOverlappingTheBaseOrAWorldObstacleIsRefused) {
  const auto scene = [](const std::vector<std::string>& set) {
    const config::JobSpec job =
        config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml", set);
    return Scene(config::buildCell(job), config::clearanceConfig(job));
  };
  EXPECT_NO_THROW(scene({}));
  const std::string post =
      "obstacles=[{name: post, type: box, size_mm: [40, 40, 300], pose: "
      "{xyz_mm: [%X, 0, 0]}}]";
  const auto with_post = [&](const std::string& x) {
    std::string s = post;
    s.replace(s.find("%X"), 2, x);
    return s;
  };
  EXPECT_NO_THROW(scene({with_post("760")}));  // 20 mm beyond the table's rim (520 + 200 + 20)
  struct Case {
    std::vector<std::string> set;
    std::string message;
  };
  const std::vector<Case> cases = {
      // The table's rim 35 mm into the base (its disc ends 165 mm from the robot's axis).
      {{"table.axis.xyz_mm=[165, 0, 0]"}, "overlaps the robot's base"},
      {{"table.axis.xyz_mm=[0, 0, 0]"}, "overlaps the robot's base"},
      {{with_post("700")}, "overlaps the obstacle 'post', which stands in the world"},
  };
  for (const Case& c : cases) {
    try {
      scene(c.set);
      ADD_FAILURE() << c.set[0] << ": no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("table.axis"), std::string::npos) << e.what();
    }
  }
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
  const config::JobSpec spec = config::loadJob(job);
  const kinematics::CellModel cell = config::buildCell(spec);
  ASSERT_EQ(cell.obstacles.size(), 2u);
  const auto& box = std::get<kinematics::Box>(cell.obstacles[0].shapes[0].geometry);
  EXPECT_TRUE(box.size.isApprox(Eigen::Vector3d(0.1, 0.05, 0.2), 1e-12));
  EXPECT_TRUE(cell.obstacles[0].shapes[0].X_BG.translation().isApprox(
      Eigen::Vector3d(0.25, 0.275, 0.1), 1e-12));
  EXPECT_EQ(cell.obstacles[1].carrier, kinematics::Carrier::kTable);
  const Scene scene(cell, config::clearanceConfig(spec));
  EXPECT_GE(scene.bodyIndex("post"), 0);
  EXPECT_GE(scene.bodyIndex("jig"), 0);
  fs::remove_all(dir);
}

// Distance from point p to an axis-aligned box centred at the origin with half-sides h.
double pointBoxDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& h) {
  return (p.cwiseAbs() - h).cwiseMax(0.0).norm();
}

// Obstacles: a sphere carried by the table and one standing in the world, placed by hand beside
// the demo scanner housing for one pose; their distances to the housing follow point–box
// geometry, the table's one turning with θ (X_WR = X_WA · Rz(θ), composed here), the world's
// one not. A group rule sets the scanner ↔ obstacles thresholds.
TEST(Clearance, ObstaclesOnTheTableTurnWithItAndWorldOnesStayPut) {
  DemoCell demo;
  kinematics::CellModel cell = demo.scene.cell();
  ASSERT_TRUE(cell.table.eccentricity.isZero());  // X_WR is the plain rotation below
  const double theta0 = 0.3;
  JointVector q;
  q << deg(-20), deg(-40), deg(120), deg(0), deg(40), deg(0);
  // The housing: a 170 × 70 × 90 mm box at (50, 0, −25) mm in the laser frame S (demo.yaml).
  const Eigen::Vector3d half(0.085, 0.035, 0.045), centre_S(0.05, 0.0, -0.025);
  const Eigen::Isometry3d X_WS = cell.X_WB * cell.robot.fk(q) * cell.scanner.X_FS;
  const auto X_WR = [&](double theta) {
    return cell.table.X_WA * Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ());
  };
  // The jig (r 20 mm) 15 mm beyond the housing's +x face at θ0; the pillar (r 25 mm) 20 mm
  // beyond its −y face.
  const double r_jig = 0.020, r_pillar = 0.025;
  const Eigen::Vector3d jig_W = X_WS * (centre_S + Eigen::Vector3d(half.x() + r_jig + 0.015, 0, 0));
  const Eigen::Vector3d pillar_W =
      X_WS * (centre_S + Eigen::Vector3d(0.01, -(half.y() + r_pillar + 0.020), 0.005));
  const auto sphere = [](double r, const Eigen::Vector3d& at) {
    kinematics::Shape shape;
    shape.geometry = kinematics::Sphere{r};
    shape.X_BG.translation() = at;
    return shape;
  };
  cell.obstacles.push_back(
      {"jig", kinematics::Carrier::kTable, {sphere(r_jig, X_WR(theta0).inverse() * jig_W)}});
  cell.obstacles.push_back({"pillar", kinematics::Carrier::kWorld, {sphere(r_pillar, pillar_W)}});
  ClearanceConfig config = config::clearanceConfig(demo.job);
  config.rules.push_back({"scanner", "obstacles", PairRule::Action::kSet, 0.002, 0.080, 1.0});
  const Scene scene(cell, config);

  const auto pairOf = [&](const std::string& a, const std::string& b) -> int {
    for (std::size_t i = 0; i < scene.pairs().size(); ++i) {
      const auto& p = scene.pairs()[i];
      const auto& na = scene.bodies()[static_cast<std::size_t>(p.a)].name;
      const auto& nb = scene.bodies()[static_cast<std::size_t>(p.b)].name;
      if ((na == a && nb == b) || (na == b && nb == a)) return static_cast<int>(i);
    }
    return -1;
  };
  const int scanner_jig = pairOf("scanner", "jig"), scanner_pillar = pairOf("scanner", "pillar");
  ASSERT_GE(scanner_jig, 0);
  ASSERT_GE(scanner_pillar, 0);
  for (const char* link : {"link1", "link3", "link6"}) {
    EXPECT_GE(pairOf(link, "jig"), 0) << link;
    EXPECT_GE(pairOf(link, "pillar"), 0) << link;
  }
  EXPECT_LT(pairOf("base", "pillar"), 0) << "both stand in the world";
  EXPECT_LT(pairOf("table", "jig"), 0) << "both turn with the table";
  EXPECT_LT(pairOf("part", "jig"), 0) << "both turn with the table";
  EXPECT_GE(pairOf("part", "pillar"), 0) << "the part turns past the pillar";
  EXPECT_GE(pairOf("jig", "pillar"), 0) << "the jig turns past the pillar";
  EXPECT_GE(pairOf("part", "base"), 0) << "the part turns past the robot base";
  EXPECT_LT(pairOf("table", "pillar"), 0) << "the table turns into no new space";
  const auto& jig_t = scene.pairs()[static_cast<std::size_t>(scanner_jig)].thresholds;
  EXPECT_DOUBLE_EQ(jig_t.d_low, 0.002);
  EXPECT_DOUBLE_EQ(jig_t.d_high, 0.080);
  EXPECT_DOUBLE_EQ(
      scene.pairs()[static_cast<std::size_t>(pairOf("link3", "jig"))].thresholds.d_high, 0.030);

  ClearanceEvaluator evaluator(scene);
  int near = 0, beyond = 0, inside = 0;
  std::vector<double> jig_distances;
  for (int k = -12; k <= 12; ++k) {
    const double theta = theta0 + 0.08 * k;
    const ClearanceResult bounded = evaluator.evaluate(theta, q);
    const ClearanceResult exact = evaluator.evaluate(theta, q, {.bounded = false});
    const Eigen::Vector3d jig_now = X_WR(theta) * (X_WR(theta0).inverse() * jig_W);
    const double want_jig = pointBoxDistance(X_WS.inverse() * jig_now - centre_S, half) - r_jig;
    const double want_pillar =
        pointBoxDistance(X_WS.inverse() * pillar_W - centre_S, half) - r_pillar;
    EXPECT_NEAR(want_pillar, 0.020, 1e-12);
    for (const auto& [pair, want] :
         {std::pair{scanner_jig, want_jig}, std::pair{scanner_pillar, want_pillar}}) {
      const PairClearance& b = bounded.pairs[static_cast<std::size_t>(pair)];
      const PairClearance& e = exact.pairs[static_cast<std::size_t>(pair)];
      if (want <= 0.0) {  // the jig turned into the housing
        EXPECT_TRUE(b.penetrating && e.penetrating) << "θ " << theta;
        EXPECT_EQ(b.distance, 0.0);
        EXPECT_EQ(b.factor, 0.0);
        EXPECT_TRUE(bounded.collision);
        ++inside;
        continue;
      }
      EXPECT_NEAR(e.distance, want, kGjkSphereTol) << "θ " << theta;
      if (want < 0.080 - kGjkSphereTol) {
        near += pair == scanner_jig ? 1 : 0;
        EXPECT_FALSE(b.beyond_bound) << "θ " << theta;
        EXPECT_NEAR(b.distance, e.distance, kSameTol) << "θ " << theta;
        EXPECT_NEAR(b.factor, rampFactor(b.distance, 0.002, 0.080, 1.0), 1e-12) << "θ " << theta;
      } else if (want > 0.080 + kGjkSphereTol) {
        beyond += pair == scanner_jig ? 1 : 0;
        EXPECT_TRUE(b.beyond_bound) << "θ " << theta;
        EXPECT_EQ(b.factor, 1.0);
      }
    }
    jig_distances.push_back(bounded.pairs[static_cast<std::size_t>(scanner_jig)].distance);
  }
  EXPECT_GT(near, 3);
  EXPECT_GT(beyond, 0) << "the jig turns out of the scanner's d_high";
  EXPECT_GT(inside, 0) << "and into the housing";
  EXPECT_NEAR(jig_distances[12], 0.015, kGjkCurvedTol);  // θ0, as placed
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
  std::vector<JointVector> poses;
  std::vector<double> factors;
  int near = 0;
  for (int k = 0; k < 40; ++k) {
    const JointVector q = test::randomJoints(cell.robot, rng);
    const auto bounded = evaluator.evaluate(0.2 * k, q);
    const auto exact = evaluator.evaluate(0.2 * k, q, {.bounded = false});
    ASSERT_TRUE(boundedMatchesExact(scene, bounded, exact)) << "pose " << k;
    for (std::size_t i = 0; i < exact.pairs.size(); ++i) {
      near += exact.pairs[i].distance < scene.pairs()[i].thresholds.d_high ? 1 : 0;
    }
    poses.push_back(q);
    factors.push_back(bounded.factor);
  }
  EXPECT_GT(near, 10) << "mesh pairs within d_high: the bound was exercised";

  // The scanner folded back into link 1, as with the primitive links: a collision.
  JointVector folded;
  folded << 0, deg(-150), deg(250), 0, deg(90), 0;
  const ClearanceResult fold = evaluator.evaluate(0.0, folded);
  EXPECT_TRUE(fold.collision);
  EXPECT_EQ(fold.factor, 0.0);
  EXPECT_TRUE(
      boundedMatchesExact(scene, fold, evaluator.evaluate(0.0, folded, {.bounded = false})));

  // Threads sharing the mesh scene: each its own evaluator, the same factors.
  std::vector<std::vector<double>> per_thread(3);
  std::vector<std::thread> threads;
  for (auto& out : per_thread) {
    threads.emplace_back([&scene, &poses, &out] {
      ClearanceEvaluator own(scene);
      for (std::size_t k = 0; k < poses.size(); ++k) {
        out.push_back(own.evaluate(0.2 * static_cast<double>(k), poses[k]).factor);
      }
    });
  }
  for (auto& t : threads) t.join();
  for (const auto& out : per_thread) EXPECT_EQ(out, factors);
}

// The exact distance of two bodies, a mesh replaced by its bounding box (a solid the levers
// bound the same way, and cheap to measure).
double boxedDistance(const detail::BodyGeometry& a,
                     const Eigen::Isometry3d& X_a,
                     const detail::BodyGeometry& b,
                     const Eigen::Isometry3d& X_b) {
  const auto boxed = [](detail::BodyGeometry body) {
    for (detail::CollisionShape& s : body.shapes) {
      if (s.primitive || !s.bounding_box) continue;
      s.primitive = s.bounding_box;
      s.geometry = std::make_shared<fcl::Boxd>(2.0 * s.bounding_box->half);
      s.polyhedron.reset();
      s.X_BG = s.X_BG * s.bounding_box->X_W;
      s.primitive->X_W.setIdentity();
      s.centre_G.setZero();
      s.radius = s.bounding_box->half.norm();
      s.bounding_box.reset();
    }
    return body;
  };
  return detail::bodyDistance(boxed(a), X_a, boxed(b), X_b, 1e9, true, false).distance;
}

// A body of many shapes (a link as convex pieces: more shape pairs than the list order is kept
// for) is measured nearest pair first. The bounded distance must still be the least exact
// distance over every shape pair when that is below the bound, and beyond it, its lower bound
// must lie between the bound and the exact distance: checked on random poses, near and far.
TEST(BodyDistance, ManyShapesNearestFirstAgreeWithEveryPairMeasuredExactly) {
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto body = [&](int shapes) {
    detail::BodyGeometry b;
    for (int i = 0; i < shapes; ++i) {
      kinematics::Shape s;
      if (i % 3 == 0) s.geometry = kinematics::Sphere{0.01 + 0.005 * (1.0 + u(rng))};
      if (i % 3 == 1) s.geometry = kinematics::Capsule{0.008, 0.03};
      if (i % 3 == 2) s.geometry = kinematics::Box{Eigen::Vector3d(0.02, 0.015, 0.03)};
      s.X_BG = randomPose(rng, 0.05);
      b.shapes.push_back(detail::makeCollisionShape(s));
    }
    return b;
  };
  const detail::BodyGeometry a = body(7), b = body(5);  // 35 shape pairs
  int near = 0, far = 0;
  for (int k = 0; k < 300; ++k) {
    const Eigen::Isometry3d X_a = randomPose(rng, 0.02), X_b = randomPose(rng, 0.12);
    double exact = std::numeric_limits<double>::infinity();
    for (const auto& sa : a.shapes)
      for (const auto& sb : b.shapes)
        exact = std::min(exact,
                         detail::exactShapeDistance(sa, X_a * sa.X_BG, sb, X_b * sb.X_BG).distance);
    const double bound = 0.03;
    const detail::ShapeDistance d = detail::bodyDistance(a, X_a, b, X_b, bound, false, false);
    if (exact < bound - 1e-5) {
      ASSERT_FALSE(d.beyond) << "pose " << k << ", exact " << exact;
      EXPECT_NEAR(d.distance, exact, 2e-6) << "pose " << k;
      ++near;
    } else if (exact > bound + 1e-5) {
      ASSERT_TRUE(d.beyond) << "pose " << k << ", exact " << exact;
      EXPECT_GE(d.lower, bound) << "pose " << k;
      EXPECT_LE(d.lower, exact + 2e-6) << "pose " << k;
      ++far;
    }
  }
  EXPECT_GT(near, 30);  // both cases were seen
  EXPECT_GT(far, 30);
}

// ChainLevers bounds how far the distance of a pair with a robot link can change when the table
// and the joints turn: checked against the exact distances of every such pair of the demo cell
// (links, scanner, table, base; the part's bounding box stands in for its 31k triangles) before
// and after random moves, small and large, some by whole turns.
TEST(ChainLevers, BoundHowFarTheDistanceOfAPairWithALinkCanChange) {
  DemoCell demo;
  const Scene& scene = demo.scene;
  const ChainLevers levers(scene);
  const auto& bodies = scene.geometry().bodies;
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<Eigen::Isometry3d> X0, X1;
  int together = 0, tight = 0;
  for (int k = 0; k < 400; ++k) {
    const JointVector q0 = test::randomJoints(scene.cell().robot, rng);
    JointVector q1 = q0;
    const double size = k % 2 == 0 ? 0.05 : 1.0;
    for (int j = 0; j < 6; ++j)
      q1(j) += size * unit(rng) + (k % 5 == 0 ? 2.0 * std::numbers::pi : 0.0);
    const double theta0 = 3.0 * unit(rng), theta1 = theta0 + (k % 3 == 0 ? 0.0 : size * unit(rng));
    scene.bodyPoses(theta0, q0, X0);
    scene.bodyPoses(theta1, q1, X1);
    for (std::size_t p = 0; p < scene.pairs().size(); ++p) {
      if (!levers.covers(p)) continue;
      const auto a = static_cast<std::size_t>(scene.pairs()[p].a),
                 b = static_cast<std::size_t>(scene.pairs()[p].b);
      const double d0 = boxedDistance(bodies[a], X0[a], bodies[b], X0[b]);
      const double d1 = boxedDistance(bodies[a], X1[a], bodies[b], X1[b]);
      const double bound = levers.motion(p, levers.weights(p), theta0, q0, theta1, q1);
      ASSERT_LE(std::abs(d1 - d0), bound + 1e-9)
          << scene.bodies()[a].name << " - " << scene.bodies()[b].name << ", move " << k;
      ++together;
      tight += std::abs(d1 - d0) > 0.2 * bound ? 1 : 0;
    }
  }
  EXPECT_GE(together, 400 * 20);    // 20 such pairs in the demo cell
  EXPECT_GT(tight, together / 20);  // not a bound so loose that it says nothing
}

// SelfPairGrid: a bin's bound holds at every configuration in it, and lies within twice the
// erosion of the distance there when that is below d_high (the bin's centre was then measured
// exactly): checked on the demo cell's arm pairs at random configurations, and at their
// neighbours a hair away (mostly in the same bins). The distances here are placed by the
// scene's full FK, the grid's by the chain between the two links.
TEST(SelfPairGrid, ABinsBoundHoldsAtEveryConfigurationInIt) {
  DemoCell demo;
  const Scene& scene = demo.scene;
  const ChainLevers levers(scene);
  constexpr double kErosion = 0.004;
  SelfPairGrid grid(scene, levers, kErosion);
  std::size_t covered = 0;
  for (std::size_t p = 0; p < scene.pairs().size(); ++p) {
    if (!grid.covers(p)) continue;
    ++covered;
    const BodyInfo& a = scene.bodies()[static_cast<std::size_t>(scene.pairs()[p].a)];
    const BodyInfo& b = scene.bodies()[static_cast<std::size_t>(scene.pairs()[p].b)];
    EXPECT_GE(std::min(a.link, b.link), 0) << a.name << " - " << b.name;  // both on the arm
  }
  EXPECT_GE(covered, 8u);  // base-link2, link2-link4, link4-link6 (one joint), base-link3 …
  const auto& bodies = scene.geometry().map_bodies;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> hair(-1e-3, 1e-3);
  std::vector<Eigen::Isometry3d> X;
  std::size_t checked = 0, near = 0;
  for (int k = 0; k < 1000; ++k) {
    JointVector q = test::randomJoints(scene.cell().robot, rng);
    if (k % 2 == 1) q = q.unaryExpr([&](double v) { return v + hair(rng); });
    scene.bodyPoses(0.3 * k, q, X);
    for (std::size_t p = 0; p < scene.pairs().size(); ++p) {
      if (!grid.covers(p)) continue;
      const auto a = static_cast<std::size_t>(scene.pairs()[p].a),
                 b = static_cast<std::size_t>(scene.pairs()[p].b);
      const double d = detail::bodyDistance(bodies[a], X[a], bodies[b], X[b],
                                            std::numeric_limits<double>::infinity(), false, false)
                           .distance;
      const double lower = grid.lower(p, q);
      if (!std::isfinite(lower)) continue;  // a joint a hair outside its limits
      ASSERT_LE(lower, d + 1e-9) << scene.bodies()[a].name << " - " << scene.bodies()[b].name;
      ++checked;
      if (d >= scene.pairs()[p].thresholds.d_high) continue;
      ASSERT_GE(lower, d - 2.0 * kErosion * 1.001)
          << scene.bodies()[a].name << " - " << scene.bodies()[b].name;
      ++near;
    }
  }
  EXPECT_GT(checked, 1000u * covered * 9 / 10);
  EXPECT_GT(near, 200u);                // the second check is not vacuous
  EXPECT_LT(grid.measured(), checked);  // neighbours share bins
}

// A cylinder turning about its own axis does not move: link 6's flange cylinder lies on the J6
// axis, so J6 does not change its distance from link 4, and its weight is 0.
TEST(ChainLevers, ABodyTurningAboutItsOwnAxisDoesNotMove) {
  DemoCell demo;
  const Scene& scene = demo.scene;
  const ChainLevers levers(scene);
  bool found = false;
  for (std::size_t p = 0; p < scene.pairs().size(); ++p) {
    const std::string a = scene.bodies()[static_cast<std::size_t>(scene.pairs()[p].a)].name;
    const std::string b = scene.bodies()[static_cast<std::size_t>(scene.pairs()[p].b)].name;
    if (a != "link4" || b != "link6") continue;
    found = true;
    EXPECT_EQ(levers.weights(p)[5], 0.0);
    EXPECT_GT(levers.weights(p)[4], 0.0);
    EXPECT_EQ(levers.weights(p)[0], 0.0);  // joints before link 4 do not move them apart
  }
  EXPECT_TRUE(found);
}

// The robot file's allowed_collisions: the pair is not checked; a job's include rule checks it
// again; a name the robot does not have is an input error naming the key.
TEST(AllowedCollisions, ARobotsAllowedPairIsNotCheckedUnlessAJobIncludesIt) {
  const auto hasPair = [](const Scene& scene, const std::string& a, const std::string& b) {
    for (const PairInfo& p : scene.pairs()) {
      const std::string& na = scene.bodies()[static_cast<std::size_t>(p.a)].name;
      const std::string& nb = scene.bodies()[static_cast<std::size_t>(p.b)].name;
      if ((na == a && nb == b) || (na == b && nb == a)) return true;
    }
    return false;
  };
  config::JobSpec job = config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml");
  ASSERT_TRUE(
      hasPair(Scene(config::buildCell(job), config::clearanceConfig(job)), "link4", "link6"));
  job.robot.allowed_collisions = {{"link6", "link4"}};
  const Scene allowed(config::buildCell(job), config::clearanceConfig(job));
  EXPECT_FALSE(hasPair(allowed, "link4", "link6"));
  EXPECT_TRUE(hasPair(allowed, "link3", "link6"));
  config::PairRuleSpec include;
  include.a = "link4";
  include.b = "link6";
  include.include = true;
  job.constraints.clearance.pairs.push_back(include);
  EXPECT_TRUE(
      hasPair(Scene(config::buildCell(job), config::clearanceConfig(job)), "link4", "link6"));

  const fs::path dir = fs::temp_directory_path() / ("scanplan_allowed_" + std::to_string(getpid()));
  fs::create_directories(dir);
  {
    std::ifstream in(test::sourceDir() / "data/robots/viper_s650.yaml");
    std::ofstream out(dir / "robot.yaml");
    out << in.rdbuf() << "allowed_collisions: [[link4, link9]]\n";
  }
  try {
    config::loadRobotFile(dir / "robot.yaml");
    FAIL() << "an unknown link was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("allowed_collisions"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("link9"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("robot.yaml"), std::string::npos) << e.what();
  }
  // Not a pair, a link with itself, a pair twice (either order): errors naming the key.
  for (const char* bad :
       {"[[link4]]", "[[link4, link4]]", "[[link4, link6], [link6, link4]]", "[link4, link6]"}) {
    {
      std::ifstream in(test::sourceDir() / "data/robots/viper_s650.yaml");
      std::ofstream out(dir / "robot.yaml");
      out << in.rdbuf() << "allowed_collisions: " << bad << "\n";
    }
    try {
      config::loadRobotFile(dir / "robot.yaml");
      ADD_FAILURE() << bad << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("allowed_collisions"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("robot.yaml"), std::string::npos) << e.what();
    }
  }
  fs::remove_all(dir);
}

// `robot check`'s survey: the bundled Viper has no pair that overlaps by design; give its flange
// a 150 mm sphere around the wrist centre and link 4, which ends there, meets it in every
// configuration; allowed in the robot, the pair is reported as allowed.
TEST(SelfCollisionSurvey, APairThatOverlapsByDesignCollidesInEverySample) {
  config::JobSpec job = config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml");
  const auto survey = [&] {
    return surveySelfCollisions(config::buildRobotModel(job.robot, "test"), 2000, 5);
  };
  const auto find = [](const SelfSurvey& s, const std::string& a, const std::string& b) {
    for (const SelfPairSurvey& p : s.pairs) {
      if (p.a == a && p.b == b) return p;
    }
    ADD_FAILURE() << a << " - " << b << " not surveyed";
    return SelfPairSurvey{};
  };
  const SelfSurvey plain = survey();
  EXPECT_EQ(plain.samples, 2000u);
  for (const SelfPairSurvey& p : plain.pairs) {
    EXPECT_EQ(p.adjacent, p.link_b - p.link_a == 1);
    if (!p.adjacent) {
      EXPECT_LT(p.colliding, 2000u * 19 / 20) << p.a << " - " << p.b;
    }
    EXPECT_EQ(p.colliding > 0, p.min_distance == 0.0) << p.a << " - " << p.b;
  }
  config::ShapeSpec sphere;
  sphere.type = "sphere";
  sphere.radius_mm = 150;
  sphere.pose.xyz_mm = {0, 0, -80};  // the wrist centre, 80 mm behind the flange
  job.robot.links[6].shapes.push_back(sphere);
  const SelfPairSurvey overlapping = find(survey(), "link4", "link6");
  EXPECT_EQ(overlapping.colliding, 2000u);
  EXPECT_FALSE(overlapping.allowed);
  job.robot.allowed_collisions = {{"link4", "link6"}};
  EXPECT_TRUE(find(survey(), "link4", "link6").allowed);
}

}  // namespace
}  // namespace scanplan::collision
