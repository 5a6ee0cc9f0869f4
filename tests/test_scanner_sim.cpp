// The scanner simulation (docs/design.md §6): a plane at a known distance against the fan geometry
// and the depth window, a wall and a robot link that shadow known rays, Embree against a
// brute-force loop over whole simulations, points on the demo part and the bunny, the noise
// model, table calibration errors, coverage statistics, the PLY writers and the tessellated
// primitives.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/config/job.h>
#include <scanplan/kinematics/cell.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/shape.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/scanner/cloud_io.h>
#include <scanplan/scanner/coverage.h>
#include <scanplan/scanner/laser_model.h>
#include <scanplan/scanner/path_generators.h>
#include <scanplan/scanner/raycaster.h>
#include <scanplan/scanner/simulator.h>
#include <nlohmann/json.hpp>
#include "tests/geometry_support.h"

#include "tests/io_support.h"
#include "tests/test_support.h"

namespace {

namespace fs = std::filesystem;
using namespace scanplan;
using kinematics::CellModel;
using kinematics::TriangleMesh;
using scanner::CameraRule;
using scanner::CloudPoint;
using scanner::ScanFrame;
using scanner::SimulatedCloud;
using scanner::SimulationSettings;
using test::pointTriangleDistance;

// The hit point is refined in double on the hit triangle's plane, then carried through a few
// rigid transforms of O(1 m): ~1e-15 m of rounding. The target is 1e-6 mm.
constexpr double kOnPlaneTol = 1e-9;  // m
// Points on a part: within 1e-4 mm. A hit may sit a float ulp outside its triangle's edge
// (Embree's test), ~1e-8 of the edge length.
constexpr double kOnPartTol = 1e-7;  // m
// Embree and the brute-force loop give the same triangle; both points come from its plane.
constexpr double kBackendTol = 1e-9;  // m

// ---------------------------------------------------------------------------------------------
// Cells and frames.

// The demo cell with the head these tests were written for (depth window 136 … 184 mm, the
// camera 100 mm out along the beam), whatever the bundled demo uses today.
config::JobSpec demoJob() {
  return config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml",
                         {"scanner.optics={a_mm: 100, b_mm: 100, phi_deg: 60, gamma_deg: 10}",
                          "scanner.body=[{type: box, size_mm: [60, 90, 110], pose: {xyz_mm: [0, "
                          "0, -55]}}]"});
}

CellModel demoCell() {
  static const CellModel cell = config::buildCell(demoJob());
  return cell;
}

const scanner::LaserOptics& demoOptics() {
  static const scanner::LaserOptics optics = config::laserOptics(demoJob());
  return optics;
}

// The frame that puts the scanner at X_PS with the table at θ: the in-limit IK solution
// nearest to `near` (any when absent); nothing when unreachable.
std::optional<ScanFrame> frameFor(const CellModel& cell,
                                  double t,
                                  double theta,
                                  const Eigen::Isometry3d& X_PS,
                                  const std::optional<kinematics::JointVector>& near = {}) {
  kinematics::IkRequest request;
  request.within_limits_only = true;
  const auto solutions = cell.robot.ik(cell.flangeTarget(theta, X_PS), request);
  if (solutions.empty()) return std::nullopt;
  const kinematics::IkSolution* best = &solutions.front();
  if (near) {
    for (const auto& s : solutions) {
      if ((s.q - *near).norm() < (best->q - *near).norm()) best = &s;
    }
  }
  return ScanFrame{t, theta, best->q};
}

// The scanner frame in the part frame that the frame really gives (FK), nominal table.
Eigen::Isometry3d realisedX_PS(const CellModel& cell, const ScanFrame& f) {
  return (cell.table.X_WR(f.theta) * cell.part.X_RP).inverse() * cell.X_WB * cell.robot.fk(f.q) *
         cell.scanner.X_FS;
}

// A square plane z = 0 (part frame) of side `side`, split into n × n cells of two triangles.
TriangleMesh planeMesh(double side, int n) {
  TriangleMesh mesh;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      mesh.vertices.emplace_back(side * (static_cast<double>(i) / n - 0.5),
                                 side * (static_cast<double>(j) / n - 0.5), 0.0);
    }
  }
  const auto at = [n](int i, int j) { return j * (n + 1) + i; };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      mesh.triangles.emplace_back(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      mesh.triangles.emplace_back(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
  }
  return mesh;
}

// The demo cell with a plane as the part, 80 mm above the table top.
CellModel planeCell() {
  CellModel cell = demoCell();
  cell.part.X_RP = Eigen::Isometry3d::Identity();
  cell.part.X_RP.translation() << 0.0, 0.0, 0.08;
  return cell;
}

// The scanner looking straight down at the plane from height d, its line turned by `yaw`
// about the plane normal, its origin at (x, y) over the plane.
Eigen::Isometry3d lookingDown(double d, double yaw = 0.3, double x = 0.004, double y = -0.003) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = kinematics::rotZ(yaw) * kinematics::rotX(std::numbers::pi);
  X.translation() << x, y, d;
  return X;
}

// The plane cell's frame for a scanner at height d over the plane; the table turned so the
// scanner is on the robot's side.
ScanFrame planeFrame(const CellModel& cell, double d, double t = 0.0, double yaw = 0.3) {
  const auto f = frameFor(cell, t, std::numbers::pi, lookingDown(d, yaw));
  EXPECT_TRUE(f) << "scanner pose at " << d << " m unreachable";
  return f.value_or(ScanFrame{});
}

SimulatedCloud run(const scanner::ScanSimulator& sim,
                   const std::vector<ScanFrame>& frames,
                   const SimulationSettings& settings = {},
                   const scanner::LaserOptics& optics = demoOptics()) {
  return sim.simulate(frames, optics, settings);
}

// ---------------------------------------------------------------------------------------------
// Geometry helpers.

double triangleDistance(const TriangleMesh& mesh, std::size_t t, const Eigen::Vector3d& p) {
  const Eigen::Vector3i& f = mesh.triangles[t];
  return pointTriangleDistance(p, mesh.vertices[static_cast<std::size_t>(f(0))],
                               mesh.vertices[static_cast<std::size_t>(f(1))],
                               mesh.vertices[static_cast<std::size_t>(f(2))]);
}

double meshDistance(const TriangleMesh& mesh, const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    best = std::min(best, triangleDistance(mesh, t, p));
  }
  return best;
}

// Where ray k of the fan meets the plane through p0 with normal n (scanner frame).
Eigen::Vector3d fanHit(double alpha, const Eigen::Vector3d& p0, const Eigen::Vector3d& n) {
  const Eigen::Vector3d d(0.0, std::sin(alpha), std::cos(alpha));
  return n.dot(p0) / n.dot(d) * d;
}

// Does the segment a → b cross the box [lo, hi]? The entry parameter's distance to the
// box's boundary planes, for telling ambiguous cases apart, goes to `margin`.
bool segmentCrossesBox(const Eigen::Vector3d& a,
                       const Eigen::Vector3d& b,
                       const Eigen::Vector3d& lo,
                       const Eigen::Vector3d& hi,
                       double& margin) {
  double s0 = 0.0, s1 = 1.0;
  const Eigen::Vector3d d = b - a;
  for (int k = 0; k < 3; ++k) {
    const double u = (lo(k) - a(k)) / d(k), v = (hi(k) - a(k)) / d(k);
    s0 = std::max(s0, std::min(u, v));
    s1 = std::min(s1, std::max(u, v));
  }
  margin = std::abs(s1 - s0) * d.norm();
  return s0 <= s1;
}

// ---------------------------------------------------------------------------------------------
// Camera geometry and the fan.

// Eq. 5 from the chosen camera position: the camera centre C+ = (a, 0, b) sees the near edge
// (0, 0, z_min) under φ + γ from the laser's +Z and the far edge under φ − γ, the edges of its
// view: tan ψ = a / (z − b) for a point (0, 0, z) of the line.
TEST(ScannerGeometry, CameraCentreSeesTheDepthWindowUnderItsViewAngle) {
  const scanner::LaserOptics& o = demoOptics();
  const scanner::LaserWindow w = scanner::laserWindow(o);
  const auto cams = scanner::cameraCentres(o, CameraRule::kEither);
  ASSERT_EQ(cams.size(), 2u);
  for (const Eigen::Vector3d& c : cams) {
    EXPECT_NEAR(std::atan2(std::abs(c.x()), w.z_min - c.z()), o.phi + o.gamma, 1e-12);
    EXPECT_NEAR(std::atan2(std::abs(c.x()), w.z_max - c.z()), o.phi - o.gamma, 1e-12);
  }
  EXPECT_GT(cams[0].x(), 0.0);
  EXPECT_LT(cams[1].x(), 0.0);
  EXPECT_EQ(scanner::cameraCentres(o, CameraRule::kPositive).front(), cams[0]);
  EXPECT_EQ(scanner::cameraCentres(o, CameraRule::kNegative).front(), cams[1]);
}

TEST(ScannerGeometry, FanSpansTheWidestCornerOfTheTrapezoid) {
  const scanner::LaserWindow w = scanner::laserWindow(demoOptics());
  const auto angles = scanner::fanAngles(w, 201);
  ASSERT_EQ(angles.size(), 201u);
  // Demo optics: the near corners are the widest (18.8 / 136.4 > 23.0 / 183.9).
  const double alpha_max = std::atan2(w.y_near, w.z_min);
  EXPECT_NEAR(angles.front(), -alpha_max, 1e-15);
  EXPECT_NEAR(angles.back(), alpha_max, 1e-15);
  EXPECT_NEAR(angles[100], 0.0, 1e-15);
  for (std::size_t k = 1; k < angles.size(); ++k) {
    EXPECT_NEAR(angles[k] - angles[k - 1], alpha_max / 100.0, 1e-15);
  }
  EXPECT_EQ(scanner::fanAngles(w, 1), std::vector<double>{0.0});
}

// ---------------------------------------------------------------------------------------------
// A plane at a known distance.

// Scanner at height d over the plane, looking straight down: ray k meets it at
// (0, d·tan α_k, d) in the scanner frame, range d / cos α_k, incidence α_k; it is measured when
// that point lies in the trapezoid, i.e. |d·tan α_k| ≤ halfWidth(d) and d in [z_min, z_max].
TEST(ScannerSimulation, PlaneAtAKnownDistanceMatchesTheFanGeometry) {
  const CellModel cell = planeCell();
  const TriangleMesh plane = planeMesh(0.3, 4);
  const scanner::ScanSimulator sim(cell, plane);
  const scanner::LaserWindow w = scanner::laserWindow(demoOptics());
  SimulationSettings settings;
  settings.rays_per_profile = 181;
  const auto angles = scanner::fanAngles(w, settings.rays_per_profile);
  const std::vector<double> depths = {w.z_min + 1e-4, 0.150, 0.16, 0.175, w.z_max - 1e-4,
                                      0.120,          0.130, 0.19, 0.25};
  for (const double d : depths) {
    SCOPED_TRACE("plane at " + std::to_string(toMm(d)) + " mm");
    const ScanFrame frame = planeFrame(cell, d);
    const SimulatedCloud cloud = run(sim, {frame}, settings);
    const Eigen::Isometry3d X_SP = realisedX_PS(cell, frame).inverse();
    // The realised pose differs from the requested one by the IK round trip (~1e-13 m): take
    // the plane's depth in the realised scanner frame.
    const Eigen::Vector3d n_S = X_SP.linear() * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d p0_S = X_SP.translation();
    std::vector<std::uint32_t> expected;
    for (std::size_t k = 0; k < angles.size(); ++k) {
      const Eigen::Vector3d p = fanHit(angles[k], p0_S, n_S);
      if (w.contains(p.y(), p.z())) expected.push_back(static_cast<std::uint32_t>(k));
    }
    ASSERT_EQ(cloud.points.size(), expected.size());
    EXPECT_EQ(cloud.stats.laser_rays, angles.size());
    if (d < w.z_min || d > w.z_max) {
      EXPECT_TRUE(cloud.points.empty());
    }
    for (std::size_t i = 0; i < cloud.points.size(); ++i) {
      const CloudPoint& p = cloud.points[i];
      ASSERT_EQ(p.ray, expected[i]);
      const double alpha = angles[p.ray];
      const Eigen::Vector3d want = fanHit(alpha, p0_S, n_S);
      EXPECT_NEAR(p.p_P.z(), 0.0, kOnPlaneTol);
      EXPECT_LT((X_SP * p.p_P - want).norm(), kOnPlaneTol);
      EXPECT_NEAR(p.range, want.norm(), kOnPlaneTol);
      EXPECT_NEAR(p.incidence, std::acos(std::abs(n_S.dot(want.normalized()))), 1e-9);
      EXPECT_EQ(p.profile, 0u);
      EXPECT_GE(p.part_triangle, 0);
      // Spacing: consecutive points d·(tan α_{k+1} − tan α_k) apart along the line.
      if (i > 0) {
        const double spacing = (p.p_P - cloud.points[i - 1].p_P).norm();
        EXPECT_NEAR(spacing, (want - fanHit(angles[p.ray - 1], p0_S, n_S)).norm(), kOnPlaneTol);
      }
    }
    if (d > w.z_min && d < w.z_max) {
      // Line length: 2·halfWidth(d), sampled at the fan's spacing.
      const double span = (cloud.points.back().p_P - cloud.points.front().p_P).norm();
      EXPECT_LE(span, 2.0 * w.halfWidth(d) + 1e-12);
      // At most one spacing (d·Δα / cos² α_max) short at either end.
      const double alpha_max = angles.back(), step = angles[1] - angles[0];
      const double spacing = d * step / (std::cos(alpha_max) * std::cos(alpha_max));
      EXPECT_GT(span, 2.0 * w.halfWidth(d) - 2.0 * spacing);
    }
  }
}

// A plane tilted about the scanner's X by 25°: the depth along the line runs from below z_min
// to beyond z_max, and exactly the rays whose hit is inside the trapezoid give points.
TEST(ScannerSimulation, PointsOutsideTheDepthWindowAreAbsent) {
  CellModel cell = planeCell();
  const TriangleMesh plane = planeMesh(0.4, 3);
  const scanner::ScanSimulator sim(cell, plane);
  const scanner::LaserWindow w = scanner::laserWindow(demoOptics());
  SimulationSettings settings;
  settings.rays_per_profile = 301;
  const auto angles = scanner::fanAngles(w, settings.rays_per_profile);
  // Scanner 80 mm over the plane, its Z tilted by 60° from the plane normal about its X (the
  // central ray meets the plane 160 mm away), so along the line the depth runs from 129 mm
  // to 210 mm, across the whole window [136, 184] mm.
  Eigen::Isometry3d X_PS = lookingDown(0.08, 0.3);
  X_PS.linear() = X_PS.linear() * kinematics::rotX(deg(60.0));
  const auto frame = frameFor(cell, 0.0, std::numbers::pi, X_PS);
  ASSERT_TRUE(frame);
  const Eigen::Isometry3d X_SP = realisedX_PS(cell, *frame).inverse();
  const Eigen::Vector3d n_S = X_SP.linear() * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d p0_S = X_SP.translation();
  std::vector<std::uint32_t> expected;
  int too_near = 0, too_far = 0, beside = 0;
  for (std::size_t k = 0; k < angles.size(); ++k) {
    const Eigen::Vector3d p = fanHit(angles[k], p0_S, n_S);
    if (w.contains(p.y(), p.z())) {
      expected.push_back(static_cast<std::uint32_t>(k));
    } else if (p.z() < w.z_min) {
      ++too_near;
    } else if (p.z() > w.z_max) {
      ++too_far;
    } else {
      ++beside;
    }
  }
  ASSERT_GT(too_near, 10);
  ASSERT_GT(too_far, 10);
  ASSERT_GT(expected.size(), 50u);
  const SimulatedCloud cloud = run(sim, {*frame}, settings);
  ASSERT_EQ(cloud.points.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(cloud.points[i].ray, expected[i]);
    const Eigen::Vector3d p_S = X_SP * cloud.points[i].p_P;
    EXPECT_TRUE(w.contains(p_S.y(), p_S.z()));
    EXPECT_NEAR(cloud.points[i].p_P.z(), 0.0, kOnPlaneTol);
  }
  // Rays end at the far edge: hits beyond z_max are not hits; nearer ones outside count.
  EXPECT_EQ(cloud.stats.outside_window, static_cast<std::size_t>(too_near + beside));
  EXPECT_EQ(cloud.stats.hits, expected.size() + static_cast<std::size_t>(too_near + beside));
  EXPECT_EQ(cloud.stats.points, expected.size());
}

TEST(ScannerSimulation, RejectsSettingsTheJobWouldNotAllow) {
  const CellModel cell = planeCell();
  const scanner::ScanSimulator sim(cell, planeMesh(0.3, 1));
  const ScanFrame frame = planeFrame(cell, 0.16);
  SimulationSettings settings;
  settings.rays_per_profile = 0;
  EXPECT_THROW(run(sim, {frame}, settings), std::invalid_argument);
  settings.rays_per_profile = 10;
  settings.sigma_orthogonal = -1e-6;
  EXPECT_THROW(run(sim, {frame}, settings), std::invalid_argument);
  settings.sigma_orthogonal = 0.0;
  EXPECT_EQ(run(sim, {}, settings).points.size(), 0u);
  settings.rays_per_profile = 1;  // the central ray only
  const SimulatedCloud one = run(sim, {frame}, settings);
  ASSERT_EQ(one.points.size(), 1u);
  EXPECT_NEAR(one.points[0].range, 0.16, 1e-9);
}

// ---------------------------------------------------------------------------------------------
// Occlusion.

// A thin wall between the plane and the +X camera: the hit → C+ segments that cross it are
// exactly the points lost with the +X camera; the −X camera sees all of them.
TEST(ScannerSimulation, WallBetweenHitAndCameraRemovesExactlyTheShadowedPoints) {
  CellModel cell = planeCell();
  const scanner::LaserOptics& optics = demoOptics();
  const double d = 0.16;
  const ScanFrame frame = planeFrame(cell, d);
  const Eigen::Isometry3d X_PS = realisedX_PS(cell, frame);
  const Eigen::Isometry3d X_WS = cell.X_WB * cell.robot.fk(frame.q) * cell.scanner.X_FS;
  // The wall, in the scanner frame: halfway to C+ = (a, 0, b), covering y in [4, 30] mm.
  const Eigen::Vector3d lo(0.045, 0.004, 0.11), hi(0.055, 0.030, 0.15);
  kinematics::Obstacle wall;
  wall.name = "wall";
  wall.carrier = kinematics::Carrier::kWorld;
  kinematics::Shape box;
  box.geometry = kinematics::Box{hi - lo};
  box.X_BG = X_WS * Eigen::Translation3d(0.5 * (lo + hi));
  wall.shapes.push_back(box);
  cell.obstacles.push_back(wall);

  const TriangleMesh plane = planeMesh(0.3, 4);
  const scanner::ScanSimulator open_sim(planeCell(), plane);
  const scanner::ScanSimulator walled_sim(cell, plane);
  SimulationSettings settings;
  settings.rays_per_profile = 241;
  const SimulatedCloud open = run(open_sim, {frame}, settings);
  ASSERT_GT(open.points.size(), 200u);

  const Eigen::Vector3d c_plus = scanner::cameraCentres(optics, CameraRule::kPositive).front();
  std::set<std::uint32_t> shadowed;
  for (const CloudPoint& p : open.points) {
    const Eigen::Vector3d p_S = X_PS.inverse() * p.p_P;
    double margin = 0.0;
    const bool crosses = segmentCrossesBox(p_S, c_plus, lo, hi, margin);
    ASSERT_TRUE(!crosses || margin > 1e-6) << "ray " << p.ray << " grazes the wall";
    if (crosses) shadowed.insert(p.ray);
  }
  ASSERT_GT(shadowed.size(), 20u);
  ASSERT_LT(shadowed.size(), open.points.size() - 20);

  for (const CameraRule rule :
       {CameraRule::kPositive, CameraRule::kBoth, CameraRule::kNegative, CameraRule::kEither}) {
    SCOPED_TRACE("rule " + std::to_string(static_cast<int>(rule)));
    settings.cameras = rule;
    const SimulatedCloud walled = run(walled_sim, {frame}, settings);
    const bool plus_needed = rule == CameraRule::kPositive || rule == CameraRule::kBoth;
    std::vector<std::uint32_t> expected;
    for (const CloudPoint& p : open.points) {
      if (!(plus_needed && shadowed.count(p.ray))) expected.push_back(p.ray);
    }
    std::vector<std::uint32_t> got;
    for (const CloudPoint& p : walled.points) got.push_back(p.ray);
    EXPECT_EQ(got, expected);
    EXPECT_EQ(walled.stats.occluded, open.points.size() - expected.size());
  }
}

// A plate on the flange 100 mm in front of the laser origin (closer than z_min): the rays that
// hit it end there, outside the window, and leave a gap in the line on the plane. The fan lies in
// the link's x = 0 plane, its rays' x components ±1e-19 of rounding noise: before
// embreeDirection() Embree lost their sign and let a packet of 4 rays through the plate (which
// packet depended on the last bit of the joint angles).
TEST(ScannerSimulation, RobotLinkInTheFanShadowsThePart) {
  CellModel cell = planeCell();
  kinematics::RobotDefinition def = cell.robot.definition();
  kinematics::Shape plate;
  plate.geometry = kinematics::Box{Eigen::Vector3d(0.04, 0.02, 0.005)};
  plate.X_BG = cell.scanner.X_FS * Eigen::Translation3d(0.0, 0.0, 0.1);  // S: z = 100 mm
  def.links[6].shapes.push_back(plate);
  cell.robot = kinematics::RobotModel(def);
  const TriangleMesh plane = planeMesh(0.3, 4);
  const scanner::ScanSimulator sim(cell, plane);
  const scanner::ScanSimulator open_sim(planeCell(), plane);
  SimulationSettings settings;
  settings.rays_per_profile = 199;
  const auto angles = scanner::fanAngles(scanner::laserWindow(demoOptics()), 199);
  const ScanFrame frame = planeFrame(cell, 0.16);
  const SimulatedCloud open = run(open_sim, {frame}, settings);
  const SimulatedCloud shadowed = run(sim, {frame}, settings);
  // The plate's near face is at z = 97.5 mm, |y| ≤ 10 mm: ray k hits it iff
  // |tan α_k| ≤ 10 / 97.5.
  std::vector<std::uint32_t> expected;
  for (const CloudPoint& p : open.points) {
    if (std::abs(std::tan(angles[p.ray])) > 0.01 / 0.0975) expected.push_back(p.ray);
  }
  ASSERT_LT(expected.size(), open.points.size() - 20);
  std::vector<std::uint32_t> got;
  for (const CloudPoint& p : shadowed.points) got.push_back(p.ray);
  EXPECT_EQ(got, expected);
  EXPECT_EQ(shadowed.stats.outside_window - open.stats.outside_window,
            open.points.size() - expected.size());
}

// ---------------------------------------------------------------------------------------------
// Embree against brute force.

TriangleMesh sphereMesh(const Eigen::Vector3d& centre, double radius, int rings, int segments) {
  TriangleMesh mesh;
  for (int r = 0; r <= rings; ++r) {
    const double polar = std::numbers::pi * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double azimuth = 2.0 * std::numbers::pi * s / segments;
      mesh.vertices.push_back(centre + radius * Eigen::Vector3d(std::sin(polar) * std::cos(azimuth),
                                                                std::sin(polar) * std::sin(azimuth),
                                                                std::cos(polar)));
    }
  }
  const auto at = [&](int r, int s) { return r * segments + (s % segments); };
  for (int r = 0; r < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      if (r > 0) mesh.triangles.emplace_back(at(r, s), at(r + 1, s), at(r, s + 1));
      if (r + 1 < rings) mesh.triangles.emplace_back(at(r, s + 1), at(r + 1, s), at(r + 1, s + 1));
    }
  }
  return mesh;
}

// Frames on a ring around the part: the scanner at `distance` from the point `aim` (part
// frame), looking at it tilted down by `tilt`, its line vertical (turned by `roll` about the
// view direction), the table turned as close as the arm allows
// to putting the scanner between part and robot (for an aim point near the table axis);
// poses unreachable at every table angle tried are skipped.
std::vector<ScanFrame> ringFrames(const CellModel& cell,
                                  const Eigen::Vector3d& aim,
                                  double distance,
                                  double tilt,
                                  int count,
                                  double roll = 0.0) {
  std::vector<ScanFrame> frames;
  std::optional<kinematics::JointVector> last;
  for (int i = 0; i < count; ++i) {
    const double beta = 2.0 * std::numbers::pi * i / count;
    // Z_S towards the axis and down by the tilt; X_S horizontal (tangent): the line vertical.
    const Eigen::Vector3d radial(std::cos(beta), std::sin(beta), 0.0);
    const Eigen::Vector3d z =
        (-std::cos(tilt) * radial - std::sin(tilt) * Eigen::Vector3d::UnitZ());
    const Eigen::Vector3d x(-std::sin(beta), std::cos(beta), 0.0);
    Eigen::Isometry3d X_PS = Eigen::Isometry3d::Identity();
    X_PS.linear().col(0) = x;
    X_PS.linear().col(1) = z.cross(x);
    X_PS.linear().col(2) = z;
    X_PS.translation() = aim - distance * z;
    X_PS.linear() = X_PS.linear() * kinematics::rotZ(roll);
    // The table angle nearest to "scanner between part and robot" that the arm reaches.
    for (int step = 0; step <= 36; ++step) {
      const double turn = deg(5.0) * ((step + 1) / 2) * (step % 2 ? 1.0 : -1.0);
      const double theta = kinematics::wrapToPi(std::numbers::pi - beta + turn);
      if (auto f = frameFor(cell, 0.05 * i, theta, X_PS, last)) {
        frames.push_back(*f);
        last = f->q;
        break;
      }
    }
  }
  return frames;
}

::testing::AssertionResult sameClouds(const SimulatedCloud& a, const SimulatedCloud& b) {
  if (a.points.size() != b.points.size()) {
    return ::testing::AssertionFailure()
           << "sizes " << a.points.size() << " vs " << b.points.size();
  }
  for (std::size_t i = 0; i < a.points.size(); ++i) {
    const CloudPoint &p = a.points[i], &q = b.points[i];
    if (p.profile != q.profile || p.ray != q.ray || p.part_triangle != q.part_triangle ||
        (p.p_P - q.p_P).norm() > kBackendTol || std::abs(p.range - q.range) > kBackendTol) {
      return ::testing::AssertionFailure()
             << "point " << i << ": profile " << p.profile << "/" << q.profile << ", ray " << p.ray
             << "/" << q.ray << ", triangle " << p.part_triangle << "/" << q.part_triangle
             << ", at " << p.p_P.transpose() << " vs " << q.p_P.transpose();
    }
  }
  return ::testing::AssertionSuccess();
}

// A faceted sphere on the table with a box fixture beside it and a pillar in the world, seen
// from a ring with both cameras: the Embree simulation and the brute-force one give the same
// points, rays and triangles (the scene has no ray grazing an edge within float precision).
TEST(ScannerSimulation, EmbreeMatchesBruteForceOnSmallMeshes) {
  CellModel cell = demoCell();
  cell.part.X_RP = Eigen::Isometry3d::Identity();
  const TriangleMesh ball = sphereMesh(Eigen::Vector3d(0.0, 0.0, 0.06), 0.05, 12, 20);
  kinematics::Obstacle fixture;
  fixture.name = "fixture";
  fixture.carrier = kinematics::Carrier::kTable;
  kinematics::Shape block;
  block.geometry = kinematics::Box{Eigen::Vector3d(0.03, 0.04, 0.05)};
  block.X_BG.translation() << 0.06, 0.03, 0.025;
  fixture.shapes.push_back(block);
  kinematics::Shape post;
  post.geometry = kinematics::Cylinder{0.012, 0.08};
  post.X_BG.translation() << -0.05, -0.06, 0.04;
  fixture.shapes.push_back(post);
  cell.obstacles.push_back(fixture);

  const scanner::ScanSimulator embree(cell, ball);
  scanner::SimulatorOptions brute_options;
  brute_options.backend = scanner::RayBackend::kBruteForce;
  const scanner::ScanSimulator brute(cell, ball, brute_options);
  EXPECT_EQ(embree.triangleCount(), brute.triangleCount());

  // Aimed where ball and table meet, the line vertical and then horizontal (the +X camera
  // above the laser).
  std::vector<ScanFrame> frames =
      ringFrames(cell, Eigen::Vector3d(0.0, 0.0, 0.0), 0.22, deg(40.0), 24);
  const auto turned =
      ringFrames(cell, Eigen::Vector3d(0.0, 0.0, 0.0), 0.22, deg(40.0), 24, -std::numbers::pi / 2);
  frames.insert(frames.end(), turned.begin(), turned.end());
  ASSERT_GT(frames.size(), 40u);
  for (const CameraRule rule : {CameraRule::kPositive, CameraRule::kBoth, CameraRule::kEither}) {
    SCOPED_TRACE("rule " + std::to_string(static_cast<int>(rule)));
    SimulationSettings settings;
    settings.cameras = rule;
    settings.rays_per_profile = 120;
    const SimulatedCloud a = run(embree, frames, settings);
    const SimulatedCloud b = run(brute, frames, settings);
    EXPECT_TRUE(sameClouds(a, b));
    EXPECT_EQ(a.stats.occlusion_rays, b.stats.occlusion_rays);
    EXPECT_EQ(a.stats.occluded, b.stats.occluded);
    EXPECT_EQ(a.stats.outside_window, b.stats.outside_window);
    // Not a trivial scene: ball and table and fixture points, and shadowed ones.
    std::size_t on_ball = 0;
    for (const CloudPoint& p : a.points) on_ball += p.part_triangle >= 0 ? 1 : 0;
    EXPECT_GT(on_ball, 500u);
    EXPECT_GT(a.points.size() - on_ball, 50u);
    EXPECT_GT(a.stats.occluded, 20u);
  }
}

// ---------------------------------------------------------------------------------------------
// Points land on the part.

// Every part point lies on the triangle it names (within 1e-4 mm); a sample of
// them is also checked against the whole mesh.
void expectPointsOnPart(const TriangleMesh& part,
                        const SimulatedCloud& cloud,
                        std::size_t at_least) {
  std::size_t on_part = 0;
  double worst = 0.0, worst_normal = 0.0;
  for (const CloudPoint& p : cloud.points) {
    if (p.part_triangle < 0) continue;
    ++on_part;
    const auto t = static_cast<std::size_t>(p.part_triangle);
    worst = std::max(worst, triangleDistance(part, t, p.p_P));
    // The point's normal is its triangle's face normal (either side), of unit length.
    const Eigen::Vector3i& f = part.triangles[t];
    const Eigen::Vector3d face = (part.vertices[static_cast<std::size_t>(f[1])] -
                                  part.vertices[static_cast<std::size_t>(f[0])])
                                     .cross(part.vertices[static_cast<std::size_t>(f[2])] -
                                            part.vertices[static_cast<std::size_t>(f[0])])
                                     .normalized();
    worst_normal = std::max(
        {worst_normal, std::abs(std::abs(p.n_P.dot(face)) - 1.0), std::abs(p.n_P.norm() - 1.0)});
  }
  EXPECT_GE(on_part, at_least);
  EXPECT_LE(worst, kOnPartTol) << "worst distance to the hit triangle";
  EXPECT_LE(worst_normal, 1e-9) << "normals against the hit triangles' face normals";
  const std::size_t step = std::max<std::size_t>(1, cloud.points.size() / 150);
  for (std::size_t i = 0; i < cloud.points.size(); i += step) {
    if (cloud.points[i].part_triangle < 0) continue;
    EXPECT_LE(meshDistance(part, cloud.points[i].p_P), kOnPartTol);
  }
}

TEST(ScannerSimulation, NoiselessPointsLandOnTheDemoPart) {
  const CellModel cell = demoCell();
  const kinematics::LoadedMesh part =
      kinematics::loadMesh(cell.part.mesh.path, cell.part.mesh.options);
  const scanner::ScanSimulator sim(cell, part.mesh);
  std::vector<ScanFrame> frames =
      ringFrames(cell, Eigen::Vector3d(0.0, 0.0, 0.05), 0.23, deg(20.0), 90);
  const auto upper = ringFrames(cell, Eigen::Vector3d(0.0, 0.0, 0.10), 0.20, deg(50.0), 60);
  frames.insert(frames.end(), upper.begin(), upper.end());
  ASSERT_GT(frames.size(), 120u);
  SimulationSettings settings;
  settings.cameras = CameraRule::kEither;
  const SimulatedCloud cloud = run(sim, frames, settings);
  expectPointsOnPart(part.mesh, cloud, 5000);
}

// A poll runs at least every 100 000 rays without changing the cloud; what it throws leaves
// simulate() and stops the run there.
TEST(ScannerSimulation, APollRunsBetweenBatchesAndItsExceptionEndsTheRun) {
  const CellModel cell = demoCell();
  const kinematics::LoadedMesh part =
      kinematics::loadMesh(cell.part.mesh.path, cell.part.mesh.options);
  const scanner::ScanSimulator sim(cell, part.mesh);
  const std::vector<ScanFrame> frames =
      ringFrames(cell, Eigen::Vector3d(0.0, 0.0, 0.05), 0.23, deg(20.0), 300);
  SimulationSettings settings;
  settings.rays_per_profile = 1000;
  const SimulatedCloud plain = run(sim, frames, settings);
  std::size_t calls = 0;
  const SimulatedCloud polled = sim.simulate(frames, demoOptics(), settings, [&] { ++calls; });
  EXPECT_GE(calls, frames.size() * 1000 / 100'000);
  ASSERT_EQ(polled.points.size(), plain.points.size());
  ASSERT_FALSE(plain.points.empty());
  EXPECT_EQ(polled.points.back().p_P, plain.points.back().p_P);
  struct Stop {};
  std::size_t k = 0;
  EXPECT_THROW(sim.simulate(frames, demoOptics(), settings,
                            [&] {
                              if (++k == 2) throw Stop{};
                            }),
               Stop);
  EXPECT_EQ(k, 2u);
}

TEST(ScannerSimulation, NoiselessPointsLandOnTheBunny) {
  const fs::path file = test::sharedDataDir() / "meshes/stlmodels_bunny.bin.stl";
  if (!fs::exists(file)) GTEST_SKIP() << file << " absent (shared test data)";
  kinematics::MeshLoadOptions options;
  options.units = kinematics::LengthUnit::kMetre;
  const TriangleMesh bunny = kinematics::loadMesh(file, options).mesh;
  ASSERT_EQ(bunny.triangles.size(), 69451u);
  CellModel cell = demoCell();
  const Eigen::AlignedBox3d box = bunny.bounds();
  cell.part.X_RP = Eigen::Isometry3d::Identity();
  cell.part.X_RP.translation() << -box.center().x(), -box.center().y(), -box.min().z();
  const scanner::ScanSimulator sim(cell, bunny);
  // Around the bunny's box centre (on the table axis), twice: low and from above.
  std::vector<ScanFrame> frames = ringFrames(cell, box.center(), 0.19, deg(20.0), 60);
  const auto upper = ringFrames(cell, box.center(), 0.18, deg(55.0), 40);
  frames.insert(frames.end(), upper.begin(), upper.end());
  ASSERT_GT(frames.size(), 80u);
  const SimulatedCloud cloud = run(sim, frames);
  expectPointsOnPart(bunny, cloud, 2000);
}

// ---------------------------------------------------------------------------------------------
// Image mode (seed §5.3: render the camera image, detect the stripe, triangulate with Eq. 4).

SimulationSettings imageSettings(int columns = 200) {
  SimulationSettings settings;
  settings.mode = scanner::SimulationMode::kImage;
  settings.rays_per_profile = columns;
  settings.image.rows = 256;
  settings.image.columns = columns;
  settings.image.thickness = 1e-3;
  return settings;
}

// The plane cell at several depths and yaws: image-mode points lie on the plane (part frame
// z = 0) within a quarter of a row's depth footprint at that depth (see test_camera_image),
// and span the same line as the geometric mode's points, to a column and a ray pitch.
TEST(ScannerSimulationImage, PlanePointsLieOnThePlaneAndAgreeWithTheGeometricMode) {
  const CellModel cell = planeCell();
  const TriangleMesh plane = planeMesh(0.4, 2);
  const scanner::ScanSimulator sim(cell, plane);
  const scanner::LaserOptics& optics = demoOptics();
  std::vector<ScanFrame> frames;
  const std::vector<double> depths = {0.145, 0.155, 0.165, 0.175};
  for (std::size_t i = 0; i < depths.size(); ++i)
    frames.push_back(planeFrame(cell, depths[i], 0.01 * static_cast<double>(i),
                                0.3 + 0.2 * static_cast<double>(i)));
  const SimulationSettings image_settings = imageSettings();
  const SimulatedCloud image = run(sim, frames, image_settings);
  SimulationSettings geometric_settings;
  geometric_settings.rays_per_profile = 200;
  const SimulatedCloud geometric = run(sim, frames, geometric_settings);
  scanner::CameraModel camera;
  camera.optics = optics;
  camera.rows = image_settings.image.rows;
  camera.columns = image_settings.image.columns;
  for (std::uint32_t f = 0; f < frames.size(); ++f) {
    SCOPED_TRACE("depth " + std::to_string(depths[f]));
    const double d = depths[f];
    const Eigen::Vector2d at = *camera.project({0.0, 0.0, d});
    const double footprint = std::abs(camera.triangulate(0.0, at.y() + 0.5).z() -
                                      camera.triangulate(0.0, at.y() - 0.5).z());
    const Eigen::Isometry3d X_SP = realisedX_PS(cell, frames[f]).inverse();
    double lo_i = 1.0, hi_i = -1.0, lo_g = 1.0, hi_g = -1.0;
    std::size_t count = 0;
    for (const CloudPoint& p : image.points) {
      if (p.profile != f) continue;
      ++count;
      EXPECT_LT(std::abs(p.p_P.z()), 0.25 * footprint);
      EXPECT_EQ(p.part_triangle >= 0, true);
      const Eigen::Vector3d p_S = X_SP * p.p_P;
      EXPECT_LT(std::abs(p_S.x()), 1e-12);  // in the laser plane
      lo_i = std::min(lo_i, p_S.y());
      hi_i = std::max(hi_i, p_S.y());
    }
    EXPECT_EQ(count, 200u);
    for (const CloudPoint& p : geometric.points) {
      if (p.profile != f) continue;
      const Eigen::Vector3d p_S = X_SP * p.p_P;
      lo_g = std::min(lo_g, p_S.y());
      hi_g = std::max(hi_g, p_S.y());
    }
    // The camera's field at depth d is |y| ≤ tan γ·|C − (0, 0, d)| (the Eq. 4 camera); the
    // geometric window interpolates Eq. 5's corners linearly: at most slightly wider.
    const double half = std::tan(optics.gamma) * std::hypot(optics.a, d - optics.b);
    const double column_pitch = 2.0 * half / 200.0;
    const double ray_pitch = 2.0 * d *
                             std::tan(std::atan2(scanner::laserWindow(optics).y_near,
                                                 scanner::laserWindow(optics).z_min)) /
                             199.0;
    EXPECT_NEAR(hi_i - lo_i, 2.0 * half - column_pitch, column_pitch);
    EXPECT_LT(std::abs((hi_i - lo_i) - (hi_g - lo_g)),
              2.0 * (column_pitch + ray_pitch) +
                  2.0 * (scanner::laserWindow(optics).halfWidth(d) - half));
  }
  EXPECT_EQ(image.stats.pixel_rays, frames.size() * 256u * 200u);
  EXPECT_GT(image.stats.lit_pixels, frames.size() * 200u);
}

// With sensor noise on, the same seed gives the same cloud.ply bytes, whatever the thread
// count; another seed gives another cloud.
TEST(ScannerSimulationImage, NoisyImagesAreDeterministicPerSeed) {
  const CellModel cell = planeCell();
  const TriangleMesh plane = planeMesh(0.4, 2);
  const scanner::ScanSimulator sim(cell, plane);
  std::vector<ScanFrame> frames;
  for (int i = 0; i < 12; ++i)
    frames.push_back(planeFrame(cell, 0.15 + 0.002 * i, 0.01 * i, 0.1 * i));
  SimulationSettings settings = imageSettings(64);
  settings.image.rows = 96;
  settings.image.noise = 6.0;
  settings.seed = 11;
  const SimulatedCloud a = run(sim, frames, settings);
  SimulatedCloud b;
  {
    tbb::task_arena one(1);
    one.execute([&] { b = run(sim, frames, settings); });
  }
  ASSERT_EQ(a.points.size(), b.points.size());
  ASSERT_GT(a.points.size(), 0u);
  std::ostringstream ply_a(std::ios::binary), ply_b(std::ios::binary);
  scanner::writeCloudPly(ply_a, a.points);
  scanner::writeCloudPly(ply_b, b.points);
  EXPECT_TRUE(ply_a.str() == ply_b.str());
  settings.seed = 12;
  const SimulatedCloud c = run(sim, frames, settings);
  bool differ = c.points.size() != a.points.size();
  for (std::size_t i = 0; !differ && i < a.points.size(); ++i)
    differ = a.points[i].p_P != c.points[i].p_P;
  EXPECT_TRUE(differ);
}

// renderImage() is the image simulate() measured: its stripe triangulates to the same points.
TEST(ScannerSimulationImage, RenderImageIsTheImageTheProfileWasMeasuredFrom) {
  const CellModel cell = planeCell();
  const TriangleMesh plane = planeMesh(0.4, 2);
  const scanner::ScanSimulator sim(cell, plane);
  const std::vector<ScanFrame> frames = {planeFrame(cell, 0.16)};
  SimulationSettings settings = imageSettings(100);
  // With noise, each column's sub-pixel peak depends on the noise drawn: the same columns and
  // the same ranges (Eq. 4 of the detected rows) show the same image, seed and profile stream.
  settings.image.noise = 10.0;
  settings.seed = 7;
  const SimulatedCloud cloud = run(sim, frames, settings);
  const scanner::ProfileImage image = sim.renderImage(frames[0], 0, demoOptics(), settings);
  const auto rows = scanner::detectStripe(image, settings.image.threshold, settings.image.method);
  std::vector<std::uint32_t> detected, measured;
  for (std::size_t c = 0; c < rows.size(); ++c) {
    if (rows[c]) detected.push_back(static_cast<std::uint32_t>(c));
  }
  for (const auto& p : cloud.points) measured.push_back(p.ray);
  ASSERT_EQ(detected, measured);
  scanner::CameraModel camera;
  camera.optics = demoOptics();
  camera.rows = settings.image.rows;
  camera.columns = settings.image.columns;
  for (std::size_t i = 0; i < detected.size(); ++i) {
    const Eigen::Vector2d p = camera.imagePlane(detected[i], *rows[detected[i]]);
    EXPECT_NEAR(cloud.points[i].range, camera.triangulate(p.x(), p.y()).norm(), 1e-12) << i;
  }
  // Another seed draws other noise: other spurious columns.
  settings.seed = 8;
  const scanner::ProfileImage other = sim.renderImage(frames[0], 0, demoOptics(), settings);
  EXPECT_NE(other.grey, image.grey);
}

TEST(ScannerSimulationImage, UnsupportedSettingsAreRefused) {
  const CellModel cell = planeCell();
  const scanner::ScanSimulator sim(cell, planeMesh(0.4, 2));
  const std::vector<ScanFrame> frames = {planeFrame(cell, 0.16)};
  SimulationSettings settings = imageSettings();
  settings.cameras = CameraRule::kBoth;
  EXPECT_THROW(run(sim, frames, settings), std::invalid_argument);
  settings = imageSettings();
  settings.image.thickness = 0.0;
  EXPECT_THROW(run(sim, frames, settings), std::invalid_argument);
  settings = imageSettings();
  settings.image.rows = 1;
  EXPECT_THROW(run(sim, frames, settings), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// Noise.

TEST(ScannerSimulation, NoiseMatchesSigmasAndIsSeeded) {
  const CellModel cell = planeCell();
  const TriangleMesh plane = planeMesh(0.4, 2);
  const scanner::ScanSimulator sim(cell, plane);
  std::vector<ScanFrame> frames;
  for (int i = 0; i < 30; ++i)
    frames.push_back(planeFrame(cell, 0.15 + 0.001 * i, 0.01 * i, 0.1 * i));
  SimulationSettings clean_settings;
  const SimulatedCloud clean = run(sim, frames, clean_settings);
  SimulationSettings noisy_settings;
  noisy_settings.sigma_longitudinal = 0.00005;  // 50 µm
  noisy_settings.sigma_orthogonal = 0.00002;    // 20 µm
  noisy_settings.seed = 7;
  const SimulatedCloud noisy = run(sim, frames, noisy_settings);
  ASSERT_EQ(noisy.points.size(), clean.points.size());
  ASSERT_GT(clean.points.size(), 4000u);
  const auto angles = scanner::fanAngles(scanner::laserWindow(demoOptics()), 200);
  double sum_l = 0, sum_o = 0, sum_ll = 0, sum_oo = 0, sum_lo = 0, worst_x = 0;
  for (std::size_t i = 0; i < clean.points.size(); ++i) {
    const CloudPoint &c = clean.points[i], &p = noisy.points[i];
    ASSERT_EQ(c.ray, p.ray);
    ASSERT_EQ(c.profile, p.profile);
    const Eigen::Isometry3d X_SP = realisedX_PS(cell, frames[c.profile]).inverse();
    const Eigen::Vector3d r = X_SP.linear() * (p.p_P - c.p_P);
    const double alpha = angles[c.ray];
    const Eigen::Vector3d d(0.0, std::sin(alpha), std::cos(alpha)),
        u(0.0, std::cos(alpha), -std::sin(alpha));
    const double e_l = r.dot(d), e_o = r.dot(u);
    EXPECT_NEAR(p.range - c.range, e_l, 1e-12);
    worst_x = std::max(worst_x, std::abs(r.x()));
    sum_l += e_l;
    sum_o += e_o;
    sum_ll += e_l * e_l;
    sum_oo += e_o * e_o;
    sum_lo += e_l * e_o;
  }
  const double n = static_cast<double>(clean.points.size());
  const double sd_l = std::sqrt(sum_ll / n), sd_o = std::sqrt(sum_oo / n);
  // Sampling error: the mean ~ σ/√n, the standard deviation ~ σ/√(2n); 5 of those each.
  EXPECT_NEAR(sum_l / n, 0.0, 5.0 * 5e-5 / std::sqrt(n));
  EXPECT_NEAR(sum_o / n, 0.0, 5.0 * 2e-5 / std::sqrt(n));
  EXPECT_NEAR(sd_l, 5e-5, 5.0 * 5e-5 / std::sqrt(2.0 * n));
  EXPECT_NEAR(sd_o, 2e-5, 5.0 * 2e-5 / std::sqrt(2.0 * n));
  EXPECT_NEAR(sum_lo / n / (sd_l * sd_o), 0.0, 5.0 / std::sqrt(n));
  EXPECT_LT(worst_x, 1e-12) << "noise must stay in the laser plane";

  // Same seed, same cloud, whatever the thread count; another seed, another cloud.
  SimulatedCloud again;
  tbb::task_arena one(1);
  one.execute([&] { again = run(sim, frames, noisy_settings); });
  ASSERT_EQ(again.points.size(), noisy.points.size());
  for (std::size_t i = 0; i < noisy.points.size(); ++i) {
    ASSERT_EQ(again.points[i].p_P, noisy.points[i].p_P) << i;
    ASSERT_EQ(again.points[i].range, noisy.points[i].range) << i;
  }
  noisy_settings.seed = 8;
  const SimulatedCloud other = run(sim, frames, noisy_settings);
  std::size_t differing = 0;
  for (std::size_t i = 0; i < noisy.points.size(); ++i) {
    if (other.points[i].p_P != noisy.points[i].p_P) ++differing;
  }
  EXPECT_EQ(differing, noisy.points.size());
}

// ---------------------------------------------------------------------------------------------
// Table calibration errors.

// The simulated table is tilted by 2 mrad and off its axis by 0.5 mm; the planner's model is
// ideal. The points, mapped with the ideal model, leave the plane by up to tilt × their
// distance from the tilt axis; mapped with the true table they are back on it.
TEST(ScannerSimulation, TableCalibrationErrorsShowInTheCloud) {
  const CellModel cell = planeCell();
  const TriangleMesh plane = planeMesh(0.3, 2);
  const scanner::ScanSimulator sim(cell, plane);
  std::vector<ScanFrame> frames;
  for (int i = 0; i < 8; ++i) frames.push_back(planeFrame(cell, 0.16, 0.1 * i, 0.4 * i));
  SimulationSettings settings;
  kinematics::RotaryTableModel truth = cell.table;
  truth.tilt = Eigen::Vector2d(0.002, 0.0);
  truth.eccentricity = Eigen::Vector2d(0.0005, 0.0);
  settings.simulated_table = truth;
  const SimulatedCloud cloud = run(sim, frames, settings);
  ASSERT_GT(cloud.points.size(), 1000u);
  double worst_nominal = 0.0, worst_true = 0.0, expected = 0.0;
  for (const CloudPoint& p : cloud.points) {
    const ScanFrame& f = frames[p.profile];
    const Eigen::Isometry3d X_WP_nominal = cell.table.X_WR(f.theta) * cell.part.X_RP;
    const Eigen::Isometry3d X_WP_true = truth.X_WR(f.theta) * cell.part.X_RP;
    const Eigen::Vector3d p_true = X_WP_true.inverse() * X_WP_nominal * p.p_P;
    worst_nominal = std::max(worst_nominal, std::abs(p.p_P.z()));
    worst_true = std::max(worst_true, std::abs(p_true.z()));
    // Tilt about R's x by 2 mrad: a point at height 80 mm and y in R moves by ~2e-3·y in z.
    expected = std::max(expected, 0.002 * std::abs((cell.part.X_RP * p_true).y()));
  }
  EXPECT_LT(worst_true, kOnPlaneTol);
  EXPECT_GT(worst_nominal, 0.5 * expected);
  EXPECT_GT(worst_nominal, 1e-5);
}

// ---------------------------------------------------------------------------------------------
// Coverage.

// Two triangles of 2 mm² and one of 8 mm² (a right triangle 4 × 4 mm): 5 points on the first,
// 1 on the second, none on the third.
TEST(Coverage, StatisticsOnAHandMadeMesh) {
  TriangleMesh mesh;
  mesh.vertices = {{0, 0, 0},    {0.002, 0, 0}, {0, 0.002, 0},   {0.002, 0.002, 0},
                   {0.01, 0, 0}, {0.014, 0, 0}, {0.01, 0.004, 0}};
  mesh.triangles = {{0, 1, 2}, {1, 3, 2}, {4, 5, 6}};
  std::vector<CloudPoint> points(7);
  for (int i = 0; i < 5; ++i) points[static_cast<std::size_t>(i)].part_triangle = 0;
  points[5].part_triangle = 1;
  points[6].part_triangle = -1;  // the table
  const scanner::PartCoverage c = scanner::computeCoverage(mesh, points);
  EXPECT_EQ(c.hits, (std::vector<std::uint32_t>{5, 1, 0}));
  EXPECT_EQ(c.part_points, 6u);
  EXPECT_EQ(c.covered_triangles, 2u);
  EXPECT_NEAR(c.total_area, 12e-6, 1e-18);
  EXPECT_NEAR(c.covered_area, 4e-6, 1e-18);
  EXPECT_NEAR(c.covered_fraction, 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(c.density_mean_per_mm2, 6.0 / 4.0, 1e-12);
  // Densities 2.5 and 0.5 /mm², each over half the covered area.
  EXPECT_NEAR(c.density_p5_per_mm2, 0.5, 1e-12);
  EXPECT_NEAR(c.density_median_per_mm2, 0.5, 1e-12);
  EXPECT_NEAR(c.density_p95_per_mm2, 2.5, 1e-12);
  scanner::CoverageSettings strict;
  strict.min_points = 2;
  const scanner::PartCoverage s = scanner::computeCoverage(mesh, points, strict);
  EXPECT_EQ(s.covered_triangles, 1u);
  EXPECT_NEAR(s.covered_fraction, 1.0 / 6.0, 1e-12);
  EXPECT_NEAR(s.density_mean_per_mm2, 2.5, 1e-12);
}

TEST(Coverage, DensityColourScale) {
  using C = std::array<std::uint8_t, 3>;
  EXPECT_EQ(scanner::densityColour(3.0, 4.0, false), (C{220, 70, 40}));
  EXPECT_EQ(scanner::densityColour(0.0, 4.0, true), (C{68, 1, 84}));
  EXPECT_EQ(scanner::densityColour(2.0, 4.0, true), (C{33, 145, 140}));
  EXPECT_EQ(scanner::densityColour(4.0, 4.0, true), (C{253, 231, 37}));
  EXPECT_EQ(scanner::densityColour(40.0, 4.0, true), (C{253, 231, 37}));
}

// The plane scanned in parallel lines: every triangle under the lines is covered, and the
// density matches the line spacing × point spacing.
TEST(Coverage, ParallelLinesOnAPlaneGiveTheExpectedDensity) {
  const CellModel cell = planeCell();
  const TriangleMesh plane = planeMesh(0.2, 40);  // 5 mm cells
  const scanner::ScanSimulator sim(cell, plane);
  std::vector<ScanFrame> frames;
  // Lines along the part's y (yaw π/2 turns the scanner's Y onto the part's −x … keep yaw 0:
  // the line runs along the part's ∓y), 0.5 mm apart in x, over x in [−10, 10) mm.
  for (int i = 0; i < 40; ++i) {
    const auto f = frameFor(cell, 0.01 * i, std::numbers::pi,
                            lookingDown(0.16, 0.0, -0.01 + 0.0005 * i, 0.0013));
    ASSERT_TRUE(f);
    frames.push_back(*f);
  }
  SimulationSettings settings;
  settings.rays_per_profile = 400;
  const SimulatedCloud cloud = run(sim, frames, settings);
  const scanner::PartCoverage c = scanner::computeCoverage(plane, cloud.points);
  EXPECT_EQ(c.part_points, cloud.points.size());
  // Lines 0.5 mm apart; along a line the points are 160·Δ(tan α) ≈ 0.11 mm apart near α = 0.
  const auto angles = scanner::fanAngles(scanner::laserWindow(demoOptics()), 400);
  const double along = 0.16 * (std::tan(angles[200]) - std::tan(angles[199]));
  const double expected = 1.0 / (0.5 * toMm(along));
  EXPECT_NEAR(c.density_median_per_mm2, expected, 0.15 * expected);
  // Covered: x in [−10, 10) mm over the line length ~2·halfWidth(160 mm): whole 5 mm cells
  // touched by it.
  EXPECT_GT(c.covered_fraction, 0.01);
  EXPECT_LT(c.covered_fraction, 0.05);
}

// ---------------------------------------------------------------------------------------------
// PLY.

TEST(CloudPly, HeaderIsStandardAndValuesRoundTrip) {
  std::vector<CloudPoint> points(3);
  points[0].p_P = Eigen::Vector3d(0.001, -0.002, 0.0305);
  points[0].n_P = Eigen::Vector3d(0.6, 0.0, 0.8);
  points[0].t = 1.25;
  points[0].profile = 7;
  points[0].ray = 199;
  points[0].range = 0.16;
  points[0].incidence = deg(30.0);
  points[0].part_triangle = 31243;
  points[1].p_P = Eigen::Vector3d(-0.1, 0.2, 0.3);
  points[1].profile = 2000000000u;
  points[1].part_triangle = -1;  // on the table
  points[2].t = 1234.5;
  std::ostringstream out(std::ios::binary);
  scanner::writeCloudPly(out, points);
  const std::string bytes = out.str();
  const std::string header =
      "ply\r\n"
      "format binary_little_endian 1.0\r\n"
      "comment scanplan simulated cloud: part frame, mm; normals unit, towards the laser; time "
      "s; range mm; incidence deg; part_triangle -1 = on another body; quality = incidence deg "
      "(for MeshLab)\r\n"
      "element vertex 3\r\n"
      "property float x\r\n"
      "property float y\r\n"
      "property float z\r\n"
      "property float nx\r\n"
      "property float ny\r\n"
      "property float nz\r\n"
      "property float scalar_time\r\n"
      "property int scalar_profile\r\n"
      "property int scalar_ray\r\n"
      "property float scalar_range_mm\r\n"
      "property float scalar_incidence_deg\r\n"
      "property int scalar_part_triangle\r\n"
      "property float quality\r\n"
      "end_header\r\n";
  ASSERT_EQ(bytes.substr(0, header.size()), header);
  EXPECT_EQ(bytes.size(), header.size() + 3 * 13 * 4);
  // The first float after the header: x = 1 mm, little-endian IEEE 754 (0x3F800000).
  EXPECT_EQ(bytes.substr(header.size(), 4), std::string("\x00\x00\x80\x3F", 4));
  // Only float and int properties: no uint, which Open3D drops.
  EXPECT_EQ(header.find("uint"), std::string::npos);

  std::istringstream in(bytes, std::ios::binary);
  const test::PlyVertices v = test::readPlyVertices(in, "memory");
  EXPECT_EQ(v.format, "binary_little_endian");
  ASSERT_EQ(v.count, 3u);
  EXPECT_EQ(v.names,
            (std::vector<std::string>{"x", "y", "z", "nx", "ny", "nz", "scalar_time",
                                      "scalar_profile", "scalar_ray", "scalar_range_mm",
                                      "scalar_incidence_deg", "scalar_part_triangle", "quality"}));
  for (std::size_t i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_FLOAT_EQ(static_cast<float>(v.column(std::string(1, "xyz"[k]))[i]),
                      static_cast<float>(toMm(points[i].p_P[k])));
      EXPECT_FLOAT_EQ(static_cast<float>(v.column("n" + std::string(1, "xyz"[k]))[i]),
                      static_cast<float>(points[i].n_P[k]));
    }
    EXPECT_FLOAT_EQ(static_cast<float>(v.column("scalar_time")[i]),
                    static_cast<float>(points[i].t));
    EXPECT_EQ(v.column("scalar_profile")[i], points[i].profile);
    EXPECT_EQ(v.column("scalar_ray")[i], points[i].ray);
    EXPECT_EQ(v.column("scalar_part_triangle")[i], points[i].part_triangle);
    EXPECT_FLOAT_EQ(static_cast<float>(v.column("scalar_range_mm")[i]),
                    static_cast<float>(toMm(points[i].range)));
    EXPECT_FLOAT_EQ(static_cast<float>(v.column("scalar_incidence_deg")[i]),
                    static_cast<float>(toDeg(points[i].incidence)));
    EXPECT_EQ(v.column("quality")[i], v.column("scalar_incidence_deg")[i]);
  }
}

// x = 1.0000012 mm is the float 0x3F80000A, written little-endian: its first byte is 0x0A, the
// byte assimp drops after a header ending in a bare '\n' (and loadMesh refuses there). The
// writers end header lines with "\r\n", after which it is read as data.
const double kLineFeedFirstMm = static_cast<double>(std::bit_cast<float>(0x3F80000Au));

// The byte after a written PLY header.
char firstDataByte(const std::string& bytes) {
  const std::size_t end = bytes.find("end_header\r\n");
  return end == std::string::npos ? '?' : bytes[end + 12];
}

TEST(CloudPly, DataStartingWithALineFeedByteRoundTrips) {
  std::vector<CloudPoint> points(2);
  points[0].p_P = Eigen::Vector3d(mm(kLineFeedFirstMm), mm(-2.5), mm(30.5));
  points[1].p_P = Eigen::Vector3d(mm(-100), mm(200), mm(kLineFeedFirstMm));
  std::ostringstream out(std::ios::binary);
  scanner::writeCloudPly(out, points);
  ASSERT_EQ(firstDataByte(out.str()), '\x0A');
  std::istringstream in(out.str(), std::ios::binary);
  const test::PlyVertices v = test::readPlyVertices(in, "memory");
  ASSERT_EQ(v.count, 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    for (const auto& [axis, k] : {std::pair{"x", 0}, std::pair{"y", 1}, std::pair{"z", 2}}) {
      EXPECT_EQ(static_cast<float>(v.column(axis)[i]), static_cast<float>(toMm(points[i].p_P[k])))
          << "point " << i << " " << axis;
    }
  }
}

TEST(CloudPly, ReaderReadsAsciiAndRejectsTruncatedFiles) {
  std::istringstream ascii(
      "ply\r\nformat ascii 1.0\r\ncomment x\r\nelement face 1\r\nproperty list uchar int "
      "vertex_indices\r\nelement vertex 2\r\nproperty float x\r\nproperty uchar red\r\n"
      "end_header\r\n3 0 1 1\r\n1.5 7\r\n-2 255\r\n");
  const test::PlyVertices v = test::readPlyVertices(ascii, "ascii");
  ASSERT_EQ(v.count, 2u);
  EXPECT_EQ(v.column("x"), (std::vector<double>{1.5, -2.0}));
  EXPECT_EQ(v.column("red"), (std::vector<double>{7.0, 255.0}));

  std::ostringstream out(std::ios::binary);
  scanner::writeCloudPly(out, std::vector<CloudPoint>(5));
  std::string bytes = out.str();
  bytes.resize(bytes.size() - 3);
  std::istringstream truncated(bytes, std::ios::binary);
  EXPECT_THROW(test::readPlyVertices(truncated, "t.ply"), InputError);
  std::istringstream not_ply("solid x\n");
  EXPECT_THROW(test::readPlyVertices(not_ply, "x.stl"), InputError);
}

// coverage.ply loads in assimp (what loadMesh uses) as the part, and carries the colours.
TEST(CoveragePly, LoadsAsThePartMeshWithDensityColours) {
  TriangleMesh mesh;
  mesh.vertices = {{0, 0, 0}, {0.002, 0, 0}, {0, 0.002, 0}, {0.002, 0.002, 0.001}};
  mesh.triangles = {{0, 1, 2}, {1, 3, 2}};
  std::vector<CloudPoint> points(4);
  for (auto& p : points) p.part_triangle = 0;
  const scanner::PartCoverage c = scanner::computeCoverage(mesh, points);
  const fs::path dir = fs::temp_directory_path() / ("scanplan_cov_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path file = dir / "coverage.ply";
  {
    std::ofstream out(file, std::ios::binary);
    scanner::writeCoveragePly(out, mesh, c);
  }
  const TriangleMesh loaded = kinematics::loadMesh(file).mesh;  // mm
  EXPECT_EQ(loaded.triangles.size(), 2u);
  EXPECT_EQ(loaded.vertices.size(), 4u);  // welded again
  EXPECT_LT((loaded.bounds().max() - mesh.bounds().max()).norm(), 1e-9);
  std::ifstream in(file, std::ios::binary);
  const test::PlyVertices v = test::readPlyVertices(in, file.string());
  ASSERT_EQ(v.count, 6u);
  // Triangle 0 has 4 points on 2 mm² (the scale's top: p95 = 2 /mm²), triangle 1 none.
  EXPECT_EQ(v.column("red")[0], 253);
  EXPECT_EQ(v.column("green")[2], 231);
  EXPECT_EQ(v.column("red")[3], 220);  // not covered: red-orange (220, 70, 40)
  EXPECT_EQ(v.column("blue")[5], 40);
  EXPECT_EQ(v.column("scalar_points")[0], 4.0);
  EXPECT_EQ(v.column("scalar_points")[3], 0.0);
  // The header says what the colours are, and the point count is a signed int (Open3D's tensor
  // reader refuses unsigned ones).
  std::ifstream again(file, std::ios::binary);
  std::string header, line;
  while (std::getline(again, line) && line.rfind("end_header", 0) != 0) {
    if (!line.empty() && line.back() == '\r') line.pop_back();  // the header's lines end CR LF
    header += line + "\n";
  }
  EXPECT_NE(header.find("red-orange (220, 70, 40) = not covered"), std::string::npos) << header;
  EXPECT_NE(header.find("property int scalar_points\n"), std::string::npos) << header;
  EXPECT_EQ(header.find("grey"), std::string::npos) << header;
  fs::remove_all(dir);
}

// coverage.ply (a mesh: loadMesh reads it) whose data starts with 0x0A loads through loadMesh's
// checks and assimp with its coordinates, and through the test reader.
TEST(CoveragePly, DataStartingWithALineFeedByteLoadsThroughLoadMesh) {
  TriangleMesh mesh;
  mesh.vertices = {{mm(kLineFeedFirstMm), 0, 0}, {0.003, 0, 0}, {0, 0.002, 0.001}};
  mesh.triangles = {{0, 1, 2}};
  const scanner::PartCoverage c = scanner::computeCoverage(mesh, {});
  std::ostringstream bytes(std::ios::binary);
  scanner::writeCoveragePly(bytes, mesh, c);
  ASSERT_EQ(firstDataByte(bytes.str()), '\x0A');
  const fs::path dir = fs::temp_directory_path() / ("scanplan_lf_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path file = dir / "coverage.ply";
  std::ofstream(file, std::ios::binary) << bytes.str();
  const TriangleMesh loaded = kinematics::loadMesh(file).mesh;  // mm
  ASSERT_EQ(loaded.triangles.size(), 1u);
  ASSERT_EQ(loaded.vertices.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    // float32 in the file: the loaded vertex is the written one rounded to a float.
    EXPECT_LT((loaded.vertices[i] - mesh.vertices[i]).norm(), 1e-9) << "vertex " << i;
  }
  std::ifstream in(file, std::ios::binary);
  const test::PlyVertices v = test::readPlyVertices(in, file.string());
  ASSERT_EQ(v.count, 3u);
  EXPECT_EQ(static_cast<float>(v.column("x")[0]), static_cast<float>(kLineFeedFirstMm));
  fs::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------
// Tessellated primitives.

TEST(ShapeSurface, PrimitivesAreClosedAndWithinTheChordTolerance) {
  kinematics::TessellationOptions options;
  options.chord_tolerance = 1e-4;
  struct Case {
    kinematics::ShapeGeometry geometry;
    double area;
    std::function<double(const Eigen::Vector3d&)> distance;  // signed, to the true surface
  };
  const double r = 0.03, l = 0.08;
  const std::vector<Case> cases = {
      {kinematics::Box{Eigen::Vector3d(0.1, 0.2, 0.3)}, 2 * (0.02 + 0.03 + 0.06),
       [](const Eigen::Vector3d& p) {
         return (p.cwiseAbs() - Eigen::Vector3d(0.05, 0.1, 0.15)).maxCoeff();
       }},
      {kinematics::Sphere{r}, 4 * std::numbers::pi * r * r,
       [r](const Eigen::Vector3d& p) { return p.norm() - r; }},
      {kinematics::Cylinder{r, l}, 2 * std::numbers::pi * r * (r + l),
       [r, l](const Eigen::Vector3d& p) {
         return std::max(p.head<2>().norm() - r, std::abs(p.z()) - 0.5 * l);
       }},
      {kinematics::Capsule{r, l}, 2 * std::numbers::pi * r * (2 * r + l),
       [r, l](const Eigen::Vector3d& p) {
         const double z = std::clamp(p.z(), -0.5 * l, 0.5 * l);
         return (p - Eigen::Vector3d(0, 0, z)).norm() - r;
       }},
  };
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = kinematics::rotationFromRpy(Eigen::Vector3d(0.3, -0.2, 1.1));
  X.translation() << 0.1, -0.2, 0.3;
  for (const Case& c : cases) {
    SCOPED_TRACE(kinematics::shapeKindName(c.geometry));
    kinematics::Shape shape;
    shape.geometry = c.geometry;
    shape.X_BG = X;
    const TriangleMesh mesh = kinematics::shapeSurface(shape, options);
    EXPECT_TRUE(mesh.isClosed());
    EXPECT_NEAR(mesh.area(), c.area, 0.01 * c.area);
    EXPECT_LE(mesh.area(), c.area * (1.0 + 1e-12));  // inscribed
    for (const Eigen::Vector3d& v : mesh.vertices) {
      EXPECT_NEAR(c.distance(X.inverse() * v), 0.0, 1e-12);
    }
    for (const Eigen::Vector3i& f : mesh.triangles) {
      const Eigen::Vector3d centroid = (mesh.vertices[static_cast<std::size_t>(f(0))] +
                                        mesh.vertices[static_cast<std::size_t>(f(1))] +
                                        mesh.vertices[static_cast<std::size_t>(f(2))]) /
                                       3.0;
      const double gap = c.distance(X.inverse() * centroid);
      EXPECT_LE(gap, 1e-12);
      EXPECT_GE(gap, -3.0 * options.chord_tolerance);
      // Outward: the normal points away from the shape's centre line.
      const Eigen::Vector3d n = (mesh.vertices[static_cast<std::size_t>(f(1))] -
                                 mesh.vertices[static_cast<std::size_t>(f(0))])
                                    .cross(mesh.vertices[static_cast<std::size_t>(f(2))] -
                                           mesh.vertices[static_cast<std::size_t>(f(0))]);
      EXPECT_GT(n.dot(centroid - X.translation()), 0.0);
    }
  }
}

}  // namespace
