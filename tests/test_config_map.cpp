// Configuration maps (seed §7.2, docs/design.md §4): cells recomputed independently from IK and the
// Eq. 6–8 formulas, an analytic clearance band, the wrap-around of a continuous table,
// determinism across thread counts, the memory limit, branch words, and `scanplan map`.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <tbb/global_control.h>

#include <scanplan/collision/chain_levers.h>
#include <scanplan/collision/clearance.h>
#include <scanplan/collision/map_clearance.h>
#include <scanplan/collision/scene.h>
#include <scanplan/collision/self_pair_grid.h>
#include <scanplan/config/job.h>
#include <scanplan/config/spec.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/shape.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/planner/config_map.h>
#include <scanplan/planner/constraints.h>
#include <scanplan/scanner/path_generators.h>
#include <scanplan/scanner/raycaster.h>
#include "cli/plot/image_io.h"
#include "cli/report/plan_summary.h"
#include "tests/image_support.h"
#include "tests/io_support.h"
#include "tests/test_support.h"

extern char** environ;

namespace {

namespace fs = std::filesystem;
using namespace scanplan;
using planner::ConfigMap;
using planner::Limit;

// Layers are float32 computed from double: 1e-6 relative covers the two roundings.
constexpr double kFloatRel = 1e-6;

::testing::AssertionResult closeRel(double actual, double expected, const char* what) {
  if (std::abs(actual - expected) <= kFloatRel * std::max(std::abs(expected), 1e-6)) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure() << what << ": map " << actual << ", recomputed " << expected;
}

// ---------------------------------------------------------------------------------------------
// The demo cell with a short path: one 90° ring at 40°/s sampled every 0.25 s (10 samples),
// 10° angle steps (36 angles), every branch: 2 880 cells.

config::JobSpec shortDemoJob(const std::vector<std::string>& overrides = {}) {
  config::JobSpec job = config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml", overrides);
  config::PathElementSpec ring;
  ring.type = "ring";
  ring.height_mm = 50.0;
  ring.tilt_deg = 20.0;
  ring.start_deg = 0.0;
  ring.extent_deg = 90.0;
  ring.speed_deg_s = 40.0;
  job.scan.paths = {ring};
  job.scan.dt_s = 0.25;
  job.map.angle_step_deg = 10.0;
  return job;
}

kinematics::ScanPath jobPath(const config::JobSpec& job, const kinematics::CellModel& cell) {
  const auto part = kinematics::loadMesh(cell.part.mesh.path, cell.part.mesh.options);
  const scanner::Raycaster raycaster(part.mesh);
  return scanner::generatePath(config::pathRequest(job), part.mesh, raycaster,
                               scanner::laserWindow(config::laserOptics(job)))
      .path;
}

std::vector<kinematics::IkBranch> allBranches() {
  std::vector<kinematics::IkBranch> all;
  for (int i = 0; i < 8; ++i) all.push_back(kinematics::IkBranch::fromIndex(i));
  return all;
}

struct DemoMap {
  config::JobSpec job = shortDemoJob();
  kinematics::CellModel cell = config::buildCell(job);
  kinematics::ScanPath path = jobPath(job, cell);
  std::unique_ptr<collision::Scene> scene =
      std::make_unique<collision::Scene>(cell, config::clearanceConfig(job));
  planner::ConstraintSettings settings = config::constraintSettings(job);
  planner::MapRequest request = [] {
    planner::MapRequest r;
    r.angle_step = deg(10.0);
    r.branches = allBranches();
    return r;
  }();
  ConfigMap map = planner::buildConfigMap(*scene, settings, path, request);
};

const DemoMap& demoMap() {
  static const DemoMap demo;
  return demo;
}

// ---------------------------------------------------------------------------------------------
// Independent formulas.

// Eq. 7: sin(π (q − min) / (max − min))^γ, 0 outside.
double jointFactor(double q, double min, double max, double gamma) {
  if (q <= min || q >= max) return 0.0;
  return std::pow(std::sin(std::numbers::pi * (q - min) / (max - min)), gamma);
}

// The monotone Eq. 8 ramp of docs/design.md §4: sin(π/2 · x)^γ on [low, high].
double ramp(double x, double low, double high, double gamma) {
  if (x < low) return 0.0;
  if (x >= high) return 1.0;
  return std::pow(std::sin(0.5 * std::numbers::pi * (x - low) / (high - low)), gamma);
}

struct Expected {
  bool reachable = false;
  double joint = 0.0, singularity = 0.0, clearance = 1.0, f = 0.0;
  Limit limit = Limit::kUnreachable;
  kinematics::JointVector q = kinematics::JointVector::Zero();
};

// One cell from scratch: IK of the chain, the branch's solution farthest from the limits,
// Eq. 7, the singularity ramps on measures computed from the DH frames, and the clearance of a
// PoseEvaluator (bounded exact distances).
Expected recompute(const collision::Scene& scene,
                   const planner::ConstraintSettings& settings,
                   double theta,
                   const Eigen::Isometry3d& X_PS,
                   const kinematics::IkBranch& branch) {
  const kinematics::CellModel& cell = scene.cell();
  const kinematics::RobotModel& robot = cell.robot;
  // X_BF = X_WB⁻¹ · X_WA · Rz(θ) · X_RP · X_PS · X_FS⁻¹ (no eccentricity or tilt in these cells).
  const Eigen::Isometry3d X_BF =
      cell.X_WB.inverse() * cell.table.X_WA *
      Eigen::Isometry3d(Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ())) * cell.part.X_RP *
      X_PS * cell.scanner.X_FS.inverse();
  Expected e;
  for (const kinematics::IkSolution& s : robot.ik(X_BF)) {
    if (!(s.branch == branch)) continue;
    EXPECT_TRUE(robot.fk(s.q).isApprox(X_BF, 1e-9));
    double joint = 1.0;
    for (int j = 0; j < kinematics::kNumJoints; ++j) {
      joint *= jointFactor(s.q(j), robot.joint(j).min, robot.joint(j).max,
                           settings.joint_gamma[static_cast<std::size_t>(j)]);
    }
    if (!e.reachable || joint > e.joint) {
      e.joint = joint;
      e.q = s.q;
    }
    e.reachable = true;
  }
  if (!e.reachable) return e;
  if (e.joint <= 0.0) {
    e.limit = Limit::kJointLimit;
    return e;
  }
  const auto frames = robot.linkFrames(e.q);
  const Eigen::Vector3d shoulder = frames[1].translation(), elbow = frames[2].translation(),
                        wrist = frames[4].translation();
  const Eigen::Vector3d upper = (elbow - shoulder).normalized(), fore = wrist - elbow;
  const double wrist_measure = std::abs(std::sin(e.q(4)));
  const double elbow_measure = upper.cross(fore).norm() / fore.norm();
  const double shoulder_measure = wrist.head<2>().norm();
  const kinematics::SingularityMeasures m = robot.singularity(e.q, false);
  EXPECT_NEAR(m.wrist, wrist_measure, 1e-12);
  EXPECT_NEAR(m.elbow, elbow_measure, 1e-9);
  EXPECT_NEAR(m.shoulder, shoulder_measure, 1e-9);
  e.singularity =
      ramp(wrist_measure, settings.wrist.low, settings.wrist.high, settings.wrist.gamma) *
      ramp(elbow_measure, settings.elbow.low, settings.elbow.high, settings.elbow.gamma) *
      ramp(shoulder_measure, settings.shoulder.low, settings.shoulder.high,
           settings.shoulder.gamma);
  if (e.singularity > 0.0) {
    planner::PoseEvaluator evaluator(scene, settings);
    e.clearance = evaluator.score(theta, e.q).clearance.factor;
  }
  e.f = e.joint * e.singularity * e.clearance;
  const float lowest = std::min({static_cast<float>(e.joint), static_cast<float>(e.singularity),
                                 static_cast<float>(e.clearance)});
  e.limit = lowest >= 1.0f                                ? Limit::kNone
            : static_cast<float>(e.joint) == lowest       ? Limit::kJointLimit
            : static_cast<float>(e.singularity) == lowest ? Limit::kSingularity
                                                          : Limit::kClearance;
  return e;
}

void expectCell(
    const ConfigMap& map, std::size_t b, std::size_t a, std::size_t t, const Expected& e) {
  const std::size_t i = map.index(b, a, t);
  SCOPED_TRACE(fmt::format("branch {}, angle {} deg, t = {} s", map.branches[b].words(),
                           toDeg(map.angles[a]), map.times[t]));
  EXPECT_EQ(static_cast<int>(map.limit[i]), static_cast<int>(e.limit))
      << "map says " << planner::limitName(static_cast<Limit>(map.limit[i])) << ", recomputed "
      << planner::limitName(e.limit);
  EXPECT_TRUE(closeRel(map.joint[i], e.joint, "joint"));
  EXPECT_TRUE(closeRel(map.singularity[i], e.singularity, "singularity"));
  EXPECT_TRUE(closeRel(map.clearance[i], e.clearance, "clearance"));
  EXPECT_TRUE(closeRel(map.f[i], e.f, "f"));
}

// Recomputes `random` random cells with an IK solution within the limits (most of a map can
// be unreachable), a fifth as many anywhere, and the first three of every limit code the map
// holds; returns how many cells of each code the map has.
std::vector<int> checkCells(const ConfigMap& map,
                            const collision::Scene& scene,
                            const planner::ConstraintSettings& settings,
                            const kinematics::ScanPath& path,
                            int random,
                            std::uint32_t seed) {
  const std::size_t n = map.branches.size() * map.cellsPerBranch();
  EXPECT_EQ(map.f.size(), n);
  EXPECT_EQ(map.limit.size(), n);
  std::mt19937 rng(seed);
  std::vector<std::size_t> cells, reachable;
  for (std::size_t i = 0; i < n; ++i) {
    if (map.joint[i] > 0.0f) reachable.push_back(i);
  }
  EXPECT_FALSE(reachable.empty());
  for (int k = 0; k < random && !reachable.empty(); ++k) {
    cells.push_back(
        reachable[std::uniform_int_distribution<std::size_t>(0, reachable.size() - 1)(rng)]);
  }
  for (int k = 0; k < random / 5; ++k)
    cells.push_back(std::uniform_int_distribution<std::size_t>(0, n - 1)(rng));
  std::vector<int> per_code(planner::kLimitCount, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (per_code[map.limit[i]]++ < 3) cells.push_back(i);
  }
  for (std::size_t i : cells) {
    const std::size_t t = i % map.times.size(), a = (i / map.times.size()) % map.angles.size(),
                      b = i / map.cellsPerBranch();
    expectCell(map, b, a, t,
               recompute(scene, settings, map.angles[a], path.samples[t].X_PS, map.branches[b]));
  }
  return per_code;
}

TEST(ConfigMap, RandomCellsMatchAnIndependentRecomputation) {
  const DemoMap& demo = demoMap();
  const ConfigMap& map = demo.map;
  ASSERT_EQ(map.angles.size(), 36u);
  ASSERT_EQ(map.times.size(), 10u);
  ASSERT_EQ(map.branches.size(), 8u);
  for (std::size_t t = 0; t < map.times.size(); ++t)
    EXPECT_DOUBLE_EQ(map.times[t], demo.path.samples[t].t);
  const std::vector<int> codes = checkCells(map, *demo.scene, demo.settings, demo.path, 50, 31);
  EXPECT_GT(codes[static_cast<std::size_t>(Limit::kUnreachable)], 0);
  EXPECT_GT(codes[static_cast<std::size_t>(Limit::kJointLimit)], 0);
  EXPECT_GT(codes[static_cast<std::size_t>(Limit::kClearance)], 0);
}

// The demo ring never comes near a singularity. These sensor poses put the arm at
// q = (0, −90°, 180°, 0, q5, 0) at table angle 0 with q5 = 2° … 20°: near the wrist
// singularity (|sin q5| below the 0.25 ramp end), where the singularity group is the lowest.
TEST(ConfigMap, CellsNearTheWristSingularityMatchAnIndependentRecomputation) {
  const DemoMap& demo = demoMap();
  const kinematics::CellModel& cell = demo.cell;
  kinematics::ScanPath path;
  path.dt = 1.0;
  int k = 0;
  for (double q5 : {2.0, 5.0, 10.0, 20.0}) {
    kinematics::JointVector q;
    q << 0.0, deg(-90.0), deg(180.0), 0.0, deg(q5), 0.0;
    kinematics::ScanSample s;
    s.t = k++;
    s.X_PS = (cell.X_WB.inverse() * cell.table.X_WR(0.0) * cell.part.X_RP).inverse() *
             cell.robot.fk(q) * cell.scanner.X_FS;
    path.samples.push_back(s);
  }
  const ConfigMap map = planner::buildConfigMap(*demo.scene, demo.settings, path, demo.request);
  const std::vector<int> codes = checkCells(map, *demo.scene, demo.settings, path, 20, 32);
  EXPECT_GT(codes[static_cast<std::size_t>(Limit::kSingularity)], 0);
}

// f and every layer stay in [0, 1]; f is the product of the three layers (Eq. 6).
TEST(ConfigMap, LayersAreFactorsOfF) {
  const ConfigMap& map = demoMap().map;
  for (std::size_t i = 0; i < map.f.size(); ++i) {
    for (float v : {map.f[i], map.joint[i], map.singularity[i], map.clearance[i]}) {
      ASSERT_GE(v, 0.0f);
      ASSERT_LE(v, 1.0f);
    }
    ASSERT_NEAR(map.f[i], static_cast<double>(map.joint[i]) * map.singularity[i] * map.clearance[i],
                1e-6)
        << i;
    if (map.limit[i] == static_cast<std::uint8_t>(Limit::kUnreachable)) {
      ASSERT_EQ(map.f[i], 0.0f);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Known answers.

// A pose 3 m from the robot: no IK anywhere, so every cell of every branch is unreachable.
TEST(ConfigMap, AnOutOfReachPathIsUnreachableEverywhere) {
  const DemoMap& demo = demoMap();
  kinematics::ScanPath path;
  path.dt = 0.5;
  for (int i = 0; i < 3; ++i) {
    kinematics::ScanSample s;
    s.t = 0.5 * i;
    s.X_PS.translation() = Eigen::Vector3d(3.0, 0.1 * i, 0.2);
    path.samples.push_back(s);
  }
  const ConfigMap map = planner::buildConfigMap(*demo.scene, demo.settings, path, demo.request);
  ASSERT_EQ(map.f.size(), 8u * 36u * 3u);
  for (std::size_t i = 0; i < map.f.size(); ++i) {
    ASSERT_EQ(map.f[i], 0.0f) << i;
    ASSERT_EQ(map.joint[i], 0.0f) << i;
    ASSERT_EQ(map.clearance[i], 1.0f) << i;
    ASSERT_EQ(map.limit[i], static_cast<std::uint8_t>(Limit::kUnreachable)) << i;
  }
}

// A scratch folder per test (ctest runs tests as separate processes, possibly in parallel).
class MapJob : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("scanplan_test_config_map_" + std::to_string(::getpid()) +
                                        "_" + info->test_suite_name() + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name, std::ios::binary | std::ios::trunc) << text;
    return dir_ / name;
  }

  fs::path dir_;
};

std::string yamlList(const Eigen::Vector3d& v) {
  return fmt::format("[{:.17g}, {:.17g}, {:.17g}]", v.x(), v.y(), v.z());
}

std::string yamlPose(const Eigen::Isometry3d& X) {
  const config::PoseSpec p = config::toPoseSpec(X);
  return fmt::format(
      "{{xyz_mm: [{:.17g}, {:.17g}, {:.17g}], rpy_deg: [{:.17g}, {:.17g}, {:.17g}]}}", p.xyz_mm[0],
      p.xyz_mm[1], p.xyz_mm[2], p.rpy_deg[0], p.rpy_deg[1], p.rpy_deg[2]);
}

// A sphere of radius 30 mm around the laser origin is the scanner body; the only pairs checked
// are scanner ↔ post (a sphere r = 20 mm fixed in the world) and scanner ↔ lid (a sphere
// r = 20 mm carried by the table), d_low = 5 mm, d_high = 30 mm.
//
// The sensor pose in the part frame (= table frame, X_RP = I) is p_PS = (200, 0, 120) mm, z_S
// inward and 20° down, then 20 mm along x_S = ŷ. The table axis is at (520, 0, 0) mm, so at
// table angle θ the laser origin is c(θ) = (520, 0, 0) + Rz(θ) · p_PS: a horizontal circle of
// radius ρ = 200 mm (at t = 0). The post sits at c(150°) (t = 0), so
//   |c(θ) − post| = 2ρ · sin(|θ − 150°| / 2),  d_post = that − 50 mm,
//   f_post = 0 where d_post < 5 mm   ⇔ |θ − 150°| < 2·asin(55/400) = 15.81°,
//   f_post = 1 where d_post ≥ 30 mm  ⇔ |θ − 150°| ≥ 2·asin(80/400) = 23.07°.
// The lid sits 60 mm above p_PS in the table frame: it turns with the sensor, d_lid = 10 mm at
// t = 0 whatever θ, f_lid = sin(π/2 · 5/25) = 0.309017.
TEST_F(MapJob, ClearanceBandOfAWorldPostAndTheConstantOfATableLidAreAnalytic) {
  const fs::path src = test::sourceDir();
  const double tilt = deg(20.0);
  const Eigen::Vector3d p_PS(0.2, 0.0, 0.12);
  Eigen::Isometry3d X_PS = Eigen::Isometry3d::Identity();
  X_PS.linear().col(0) = Eigen::Vector3d::UnitY();
  X_PS.linear().col(2) = Eigen::Vector3d(-std::cos(tilt), 0.0, -std::sin(tilt));
  X_PS.linear().col(1) = X_PS.linear().col(2).cross(X_PS.linear().col(0));
  X_PS.translation() = p_PS;
  Eigen::Isometry3d X_PS2 = X_PS;
  X_PS2.translation() += 0.02 * Eigen::Vector3d::UnitY();
  const Eigen::Vector3d axis(0.52, 0.0, 0.0);
  const double theta0 = deg(150.0);
  const Eigen::Vector3d post = axis + Eigen::AngleAxisd(theta0, Eigen::Vector3d::UnitZ()) * p_PS;
  const Eigen::Vector3d lid = p_PS + Eigen::Vector3d(0.0, 0.0, 0.06);

  const fs::path file =
      write("job.yaml",
            "name: synthetic\n"
            "robot: " +
                (src / "data/robots/viper_s650.yaml").string() +
                "\n"
                "table: {axis: {xyz_mm: [520, 0, 0], rpy_deg: [0, 0, 0]}, radius_mm: 200, "
                "height_mm: 150}\n"
                "part: {mesh: " +
                (src / "data/parts/demo_housing.stl").string() +
                "}\n"
                "scanner:\n"
                "  mount: {xyz_mm: [0, 0, 110], rpy_deg: [0, 0, 0]}\n"
                "  body: [{type: sphere, radius_mm: 30}]\n"
                "obstacles:\n"
                "  - {name: post, carrier: world, type: sphere, radius_mm: 20, pose: {xyz_mm: " +
                yamlList(post * 1e3) +
                "}}\n"
                "  - {name: lid, carrier: table, type: sphere, radius_mm: 20, pose: {xyz_mm: " +
                yamlList(lid * 1e3) +
                "}}\n"
                "constraints:\n"
                "  clearance:\n"
                "    d_low_mm: 5\n"
                "    d_high_mm: 30\n"
                "    pairs:\n"
                "      - {a: '*', b: '*', exclude: true}\n"
                "      - {a: scanner, b: post, include: true}\n"
                "      - {a: scanner, b: lid, include: true}\n"
                "scan:\n"
                "  dt_s: 0.1\n"
                "  paths:\n"
                "    - type: waypoints\n"
                "      points:\n"
                "        - " +
                yamlPose(X_PS) +
                "\n"
                "        - {xyz_mm: " +
                yamlList(X_PS2.translation() * 1e3) +
                ", rpy_deg: " + yamlList(Eigen::Vector3d(config::toPoseSpec(X_PS).rpy_deg.data())) +
                ", speed_mm_s: 50}\n"
                "map: {angle_step_deg: 1}\n");
  const config::JobSpec job = config::loadJob(file);
  const kinematics::CellModel cell = config::buildCell(job);
  const kinematics::ScanPath path = jobPath(job, cell);
  ASSERT_EQ(path.samples.size(), 5u);  // 20 mm at 50 mm/s = 0.4 s
  ASSERT_TRUE(path.samples.front().X_PS.isApprox(X_PS, 1e-9));
  const collision::Scene scene(cell, config::clearanceConfig(job));
  ASSERT_EQ(scene.pairs().size(), 2u);
  planner::MapRequest request;
  request.angle_step = deg(1.0);
  request.branches = allBranches();
  const ConfigMap map =
      planner::buildConfigMap(scene, config::constraintSettings(job), path, request);
  ASSERT_EQ(map.angles.size(), 360u);

  // FCL's sphere–sphere distance is exact; float storage and the ramp's slope (π/2 / 25 mm)
  // keep the factor within 1e-6.
  constexpr double kTol = 1e-6;
  int in_band = 0, on_ramp = 0, clear = 0;
  for (std::size_t b = 0; b < map.branches.size(); ++b) {
    for (std::size_t a = 0; a < map.angles.size(); ++a) {
      const double theta = map.angles[a];
      for (std::size_t t = 0; t < map.times.size(); ++t) {
        const std::size_t i = map.index(b, a, t);
        if (map.joint[i] <= 0.0f || map.singularity[i] <= 0.0f) {
          EXPECT_EQ(map.clearance[i], 1.0f) << "not evaluated where f is already 0";
          continue;
        }
        const Eigen::Isometry3d& X = path.samples[t].X_PS;
        const Eigen::Vector3d c =
            axis + Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()) * X.translation();
        const double d_post = (c - post).norm() - 0.05;
        const double d_lid = (X.translation() - lid).norm() - 0.05;
        const double expected = ramp(d_post, 0.005, 0.03, 1.0) * ramp(d_lid, 0.005, 0.03, 1.0);
        EXPECT_NEAR(map.clearance[i], expected, kTol)
            << map.branches[b].words() << ", θ = " << toDeg(theta) << "°, t = " << map.times[t];
        if (t != 0) continue;
        const double off = std::abs(std::remainder(theta - theta0, 2.0 * std::numbers::pi));
        const double f_lid = std::sin(0.5 * std::numbers::pi * 5.0 / 25.0);
        if (off < 2.0 * std::asin(55.0 / 400.0) - 1e-9) {
          ++in_band;
          EXPECT_EQ(map.clearance[i], 0.0f)
              << "θ = " << toDeg(theta) << "°: inside the post's band";
          EXPECT_EQ(map.limit[i], static_cast<std::uint8_t>(Limit::kClearance));
        } else if (off >= 2.0 * std::asin(80.0 / 400.0) + 1e-9) {
          ++clear;
          EXPECT_NEAR(map.clearance[i], f_lid, kTol)
              << "θ = " << toDeg(theta) << "°: only the lid counts";
        } else {
          ++on_ramp;
          EXPECT_GT(map.clearance[i], 0.0f);
          EXPECT_LT(map.clearance[i], f_lid);
        }
      }
    }
  }
  // The check means something only if the robot reaches poses in all three regions.
  EXPECT_GT(in_band, 10);
  EXPECT_GT(on_ramp, 5);
  EXPECT_GT(clear, 50);
}

// ---------------------------------------------------------------------------------------------
// The angle grid and its wrap-around.

TEST(ConfigMap, ContinuousTableAnglesCoverAFullTurnWithoutRepeating360) {
  kinematics::RotaryTableModel table;
  table.continuous = true;
  for (double step_deg : {1.0, 10.0, 0.5, 7.5, 45.0}) {
    SCOPED_TRACE(step_deg);
    const auto angles = planner::mapAngles(table, deg(step_deg));
    ASSERT_EQ(angles.size(), static_cast<std::size_t>(std::llround(360.0 / step_deg)));
    EXPECT_EQ(angles.front(), 0.0);
    for (std::size_t i = 1; i < angles.size(); ++i)
      EXPECT_NEAR(angles[i] - angles[i - 1], deg(step_deg), 1e-12);
    EXPECT_NEAR(angles.back() + deg(step_deg), 2.0 * std::numbers::pi, 1e-12)
        << "the last angle's neighbour is 360° = 0°";
    EXPECT_LT(angles.back(), 2.0 * std::numbers::pi - 0.5 * deg(step_deg));
  }
}

TEST(ConfigMap, LimitedTableAnglesSpanMinToMax) {
  kinematics::RotaryTableModel table;
  table.continuous = false;
  table.min = deg(-90.0);
  table.max = deg(90.0);
  auto angles = planner::mapAngles(table, deg(10.0));
  ASSERT_EQ(angles.size(), 19u);
  EXPECT_NEAR(angles.front(), deg(-90.0), 1e-12);
  EXPECT_NEAR(angles.back(), deg(90.0), 1e-12);
  angles = planner::mapAngles(table, deg(7.0));  // 180 / 7 = 25.7: the last angle stays inside
  ASSERT_EQ(angles.size(), 26u);
  EXPECT_NEAR(angles.back(), deg(85.0), 1e-12);
}

// Turning the table's axis frame by one step about its own axis shifts the map by one row: the
// shifted map's last row (350° + 10°) must be the original's row 0. The table is a cylinder on
// its axis and the demo has no table-carried obstacles, so nothing else changes.
TEST(ConfigMap, RowZeroAndTheRowAfterTheLastAreTheSameTableAngle) {
  const DemoMap& demo = demoMap();
  const ConfigMap& map = demo.map;
  const double step = map.angles[1] - map.angles[0];
  kinematics::CellModel turned = demo.cell;
  turned.table.X_WA = turned.table.X_WA * Eigen::AngleAxisd(step, Eigen::Vector3d::UnitZ());
  const collision::Scene scene(turned, config::clearanceConfig(demo.job));
  const ConfigMap shifted = planner::buildConfigMap(scene, demo.settings, demo.path, demo.request);
  const std::size_t na = map.angles.size();
  // Rounding of the composed transforms (~1e-16 m) can only move a bounded distance query by
  // as much; at the ramp's slope that is far below this.
  constexpr double kTol = 1e-5;
  for (std::size_t b = 0; b < map.branches.size(); ++b) {
    for (std::size_t a = 0; a < na; ++a) {
      for (std::size_t t = 0; t < map.times.size(); ++t) {
        const std::size_t i = shifted.index(b, a, t), j = map.index(b, (a + 1) % na, t);
        ASSERT_NEAR(shifted.f[i], map.f[j], kTol)
            << "row " << a << ", t " << t << ", " << map.branches[b].words();
        ASSERT_EQ(shifted.limit[i], map.limit[j]) << "row " << a << ", t " << t;
      }
    }
  }
  // And the cell at 360° scores like the cell at 0°.
  collision::MapClearance evaluator(*demo.scene, map.branches.size());
  for (std::size_t t = 0; t < map.times.size(); ++t) {
    const Eigen::Isometry3d X_BF =
        demo.cell.flangeTarget(2.0 * std::numbers::pi, demo.path.samples[t].X_PS);
    const auto solutions = demo.cell.robot.ik(X_BF);
    evaluator.beginCell(2.0 * std::numbers::pi, X_BF);
    for (std::size_t b = 0; b < map.branches.size(); ++b) {
      const planner::CellScore s =
          planner::scoreCell(*demo.scene, demo.settings, evaluator, b, solutions, map.branches[b]);
      EXPECT_NEAR(s.f, map.f[map.index(b, 0, t)], kTol);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Determinism and the memory limit.

template <class T>
bool sameBytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

// Motion-bound skipping and the per-cell sharing leave every value as the plain
// query gives it, byte for byte: on the demo and on random variants of it (other rings and
// angle steps), one and two threads.
bool sameMap(const ConfigMap& a, const ConfigMap& b) {
  return sameBytes(a.f, b.f) && sameBytes(a.joint, b.joint) &&
         sameBytes(a.singularity, b.singularity) && sameBytes(a.clearance, b.clearance) &&
         sameBytes(a.limit, b.limit);
}

// MapClearance alone, along sweeps that move only J1–J3 (then only J4–J6) at one table angle:
// the factor with every skip (travel marks per side of the arm, bounds, nearest points) equals
// the plain query's, call for call. A sweep of one side is where a pair reading the wrong
// side's travel would keep a stale mark.
TEST(ConfigMap, ClearanceFactorWithSkippingEqualsThePlainOneAlongSweepsOfEachSide) {
  const DemoMap& demo = demoMap();
  const kinematics::RobotModel& robot = demo.cell.robot;
  std::mt19937 rng(7);
  int near = 0;
  for (int sweep = 0; sweep < 60; ++sweep) {
    collision::MapClearance fast(*demo.scene, 1);
    collision::MapClearance plain(*demo.scene, 1, {.skip = false});
    kinematics::JointVector a = kinematics::JointVector::Zero(), b = a;
    for (int k = 0; k < kinematics::kNumJoints; ++k) {
      const auto& j = robot.joint(k);
      std::uniform_real_distribution<double> in(std::max(j.min, -3.0), std::min(j.max, 3.0));
      a(k) = in(rng);
      b(k) = (k < 3) == (sweep % 2 == 0) ? in(rng) : a(k);  // even: J1–J3 move; odd: J4–J6
    }
    const double theta = deg(10.0 * sweep);
    for (int i = 0; i <= 120; ++i) {
      const kinematics::JointVector q = a + (b - a) * (i / 120.0);
      const Eigen::Isometry3d X_BF = robot.fk(q);
      fast.beginCell(theta, X_BF);
      plain.beginCell(theta, X_BF);
      const double f = plain.factor(0, q);
      ASSERT_EQ(fast.factor(0, q), f) << "sweep " << sweep << ", step " << i;
      near += f < 1.0 ? 1 : 0;
    }
  }
  EXPECT_GT(near, 500) << "premise: the sweeps bring pairs within d_high";
}

// The sharing between branches (a pair's factor taken from a branch scored before at the same
// cell with the same joints up to the pair's last link placed per branch; link 6, the scanner,
// the base, the table and the world placed once per cell) leaves every value as each branch
// alone gives it: the demo map against one MapClearance per branch, each seeing only its own
// branch and querying every pair, byte for byte.
TEST(ConfigMap, SharingBetweenBranchesChangesNoValue) {
  const DemoMap& demo = demoMap();
  const ConfigMap& map = demo.map;
  std::vector<std::unique_ptr<collision::MapClearance>> alone;
  for (std::size_t b = 0; b < map.branches.size(); ++b) {
    alone.push_back(std::make_unique<collision::MapClearance>(
        *demo.scene, 1, collision::MapClearanceOptions{.skip = false}));
  }
  int clearance_limited = 0;
  for (std::size_t a = 0; a < map.angles.size(); ++a) {
    const Eigen::Isometry3d X_BP = demo.cell.partIn(map.angles[a]);
    for (std::size_t t = 0; t < map.times.size(); ++t) {
      const Eigen::Isometry3d X_BF = demo.cell.flangeTarget(X_BP, demo.path.samples[t].X_PS);
      const auto solutions = demo.cell.robot.ik(X_BF);
      for (std::size_t b = 0; b < map.branches.size(); ++b) {
        alone[b]->beginCell(map.angles[a], X_BF);
        const planner::CellScore s = planner::scoreCell(*demo.scene, demo.settings, *alone[b], 0,
                                                        solutions, map.branches[b]);
        const std::size_t i = map.index(b, a, t);
        ASSERT_EQ(s.clearance, map.clearance[i])
            << "angle " << a << ", t " << t << ", " << map.branches[b].words();
        ASSERT_EQ(s.f, map.f[i]) << "angle " << a << ", t " << t;
        clearance_limited += s.limit == Limit::kClearance ? 1 : 0;
      }
    }
  }
  EXPECT_GT(clearance_limited, 50) << "premise: pairs come within d_high";
}

TEST(ConfigMap, MotionBoundSkippingChangesNoValue) {
  const DemoMap& demo = demoMap();
  planner::MapRequest plain = demo.request;
  plain.motion_bounds = false;
  EXPECT_TRUE(
      sameMap(demo.map, planner::buildConfigMap(*demo.scene, demo.settings, demo.path, plain)));
  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> height(20.0, 110.0), tilt(-10.0, 70.0), step(3.0, 12.0);
  int clearance_limited = 0;
  for (int job_index = 0; job_index < 4; ++job_index) {
    config::JobSpec job = shortDemoJob();
    job.scan.paths[0].height_mm = height(rng);
    job.scan.paths[0].tilt_deg = tilt(rng);
    job.scan.paths[0].extent_deg = 360.0;
    job.scan.dt_s = 0.1;
    const kinematics::CellModel cell = config::buildCell(job);
    const kinematics::ScanPath path = jobPath(job, cell);
    const collision::Scene scene(cell, config::clearanceConfig(job));
    planner::MapRequest request = demo.request;
    request.angle_step = deg(step(rng));
    const ConfigMap skipped = planner::buildConfigMap(scene, demo.settings, path, request);
    request.motion_bounds = false;
    ConfigMap plain_map;
    {
      const tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
      plain_map = planner::buildConfigMap(scene, demo.settings, path, request);
    }
    EXPECT_TRUE(sameMap(skipped, plain_map)) << "job " << job_index;
    clearance_limited += static_cast<int>(std::count(skipped.limit.begin(), skipped.limit.end(),
                                                     static_cast<std::uint8_t>(Limit::kClearance)));
  }
  EXPECT_GT(clearance_limited, 100);  // the clearance layer is exercised, not all 1
}

// The demo robot with its links as meshes (each the union of its shapes of that link,
// tessellated: link1 and link2 are non-convex), written into dir; returns the robot file.
fs::path writeMeshRobot(const fs::path& dir) {
  const config::JobSpec primitive = shortDemoJob();
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name, std::ios::binary | std::ios::trunc) << text;
    return dir / name;
  };
  std::ifstream viper(test::sourceDir() / "data/robots/viper_s650.yaml");
  std::string robot((std::istreambuf_iterator<char>(viper)), std::istreambuf_iterator<char>());
  robot = robot.substr(0, robot.find("\nlinks:") + 1);  // the kinematics, then mesh links
  robot += "links:\n";
  const kinematics::CellModel primitive_cell = config::buildCell(primitive);
  for (const kinematics::Link& link : primitive_cell.robot.definition().links) {
    kinematics::TriangleMesh mesh;
    for (const kinematics::Shape& shape : link.shapes) {
      const kinematics::TriangleMesh part = kinematics::shapeSurface(shape);
      const int n = static_cast<int>(mesh.vertices.size());
      mesh.vertices.insert(mesh.vertices.end(), part.vertices.begin(), part.vertices.end());
      for (const Eigen::Vector3i& t : part.triangles) {
        mesh.triangles.push_back(t + Eigen::Vector3i::Constant(n));
      }
    }
    std::string off = fmt::format("OFF\n{} {} 0\n", mesh.vertices.size(), mesh.triangles.size());
    for (const Eigen::Vector3d& v : mesh.vertices)
      off += fmt::format("{:.17g} {:.17g} {:.17g}\n", v.x(), v.y(), v.z());
    for (const Eigen::Vector3i& t : mesh.triangles)
      off += fmt::format("3 {} {} {}\n", t[0], t[1], t[2]);
    const fs::path file = write(link.name + ".off", off);
    robot += fmt::format("  - {{name: {}, shapes: [{{type: mesh, file: {}, units: m}}]}}\n",
                         link.name, file.string());
  }
  return write("mesh_robot.yaml", robot);
}

// Every threshold of the config `by` farther (m): with it a plain map is one of distances `by`
// nearer.
collision::ClearanceConfig raised(collision::ClearanceConfig config, double by) {
  config.defaults.d_low += by;
  config.defaults.d_high += by;
  for (collision::PairRule& rule : config.rules) {
    if (rule.d_low >= 0.0) rule.d_low += by;
    if (rule.d_high >= 0.0) rule.d_high += by;
  }
  return config;
}

// A robot whose links are meshes (writeMeshRobot) maps with the hulls no higher than with the
// exact meshes, cell by cell, and lower somewhere; motion-bound skipping changes no value but
// the fine self pairs' (SelfPairGrid), which lie between the plain map's and that of distances
// 1 mm nearer.
TEST_F(MapJob, MeshLinksMapAsHullsConservativelyAndSkippingStaysExact) {
  const fs::path robot_file = writeMeshRobot(dir_);
  const config::JobSpec job = shortDemoJob({"robot=" + robot_file.string()});
  const kinematics::CellModel cell = config::buildCell(job);
  const kinematics::ScanPath path = jobPath(job, cell);
  collision::ClearanceConfig config = config::clearanceConfig(job);
  EXPECT_EQ(config.link_meshes, collision::LinkMeshes::kAuto);  // the default
  EXPECT_EQ(config.max_hull_margin, 0.002);
  EXPECT_EQ(config.piece_margin, 0.002);
  config.piece_margin = 0.008;  // fits these tessellated links in seconds
  const collision::Scene automatic(cell, config);
  config.link_meshes = collision::LinkMeshes::kHull;
  const collision::Scene hulls(cell, config);
  config.link_meshes = collision::LinkMeshes::kExact;
  const collision::Scene exact(cell, config);
  ASSERT_EQ(hulls.mapHulls().size(), 7u);
  ASSERT_EQ(automatic.mapHulls().size(), 7u);
  EXPECT_TRUE(exact.mapHulls().empty());
  double widest = 0.0, narrowest = 1.0;
  std::size_t with_pieces = 0;
  for (std::size_t k = 0; k < 7; ++k) {
    const collision::MapHull& h = hulls.mapHulls()[k];
    EXPECT_LE(h.hull_vertices, 32u);
    EXPECT_GE(h.margin, 0.0);
    EXPECT_TRUE(h.used);
    // auto: the hull where its margin is within hull_margin_mm (2 mm), else the convex pieces
    // where they fit piece_margin_mm and max_pieces, else the mesh
    const collision::MapHull& a = automatic.mapHulls()[k];
    EXPECT_EQ(a.hull_margin, h.margin) << "link " << k;
    EXPECT_EQ(a.used, h.margin <= 0.002 || a.pieces_fit) << "link " << k;
    if (a.pieces > 0 && a.used) {
      EXPECT_LE(a.margin, config.piece_margin) << "link " << k;
    }
    with_pieces += a.pieces > 0 && a.used ? 1u : 0u;
    widest = std::max(widest, h.margin);
    narrowest = std::min(narrowest, h.margin);
  }
  EXPECT_GT(widest, 0.01) << "premise: a link with two shapes has a hull well outside them";
  EXPECT_LT(narrowest, 0.01) << "premise: a one-shape link's hull is close to it";
  EXPECT_GT(with_pieces, 0u) << "premise: convex pieces stand in for a non-convex link";
  {
    // Pieces over the limit: the maps measure the mesh, and the summary says which link and
    // what to change.
    collision::ClearanceConfig tight = config::clearanceConfig(job);
    tight.piece_margin = 0.008;
    tight.max_pieces = 1;
    tight.piece_cache.clear();
    const collision::Scene over(cell, tight);
    const std::string text = cli::linkMeshSummary(over);
    EXPECT_NE(text.find("max_pieces"), std::string::npos) << text;
    EXPECT_NE(text.find("the maps measure the mesh"), std::string::npos) << text;
    EXPECT_NE(text.find("link2 "), std::string::npos) << text;
  }
  // The pieces were kept beside the robot file: a second scene reads them.
  collision::ClearanceConfig same = config::clearanceConfig(job);
  same.piece_margin = config.piece_margin;
  const collision::Scene again(cell, same);
  for (std::size_t k = 0; k < 7; ++k) {
    EXPECT_EQ(again.mapHulls()[k].from_cache, automatic.mapHulls()[k].pieces > 0) << "link " << k;
    EXPECT_EQ(again.mapHulls()[k].pieces, automatic.mapHulls()[k].pieces) << "link " << k;
  }

  const planner::ConstraintSettings settings = config::constraintSettings(job);
  planner::MapRequest request;
  request.angle_step = deg(10.0);
  request.branches = allBranches();
  const ConfigMap hull_map = planner::buildConfigMap(hulls, settings, path, request);
  const ConfigMap exact_map = planner::buildConfigMap(exact, settings, path, request);
  std::size_t lower = 0;
  for (std::size_t i = 0; i < hull_map.f.size(); ++i) {
    ASSERT_LE(hull_map.clearance[i], exact_map.clearance[i] + 1e-6) << "cell " << i;
    ASSERT_LE(hull_map.f[i], exact_map.f[i] + 1e-6) << "cell " << i;
    lower += hull_map.clearance[i] < exact_map.clearance[i] - 1e-3f ? 1u : 0u;
  }
  EXPECT_GT(lower, 0u) << "premise: the hulls are conservative somewhere";
  EXPECT_LT(lower, hull_map.f.size());
  request.motion_bounds = false;
  const ConfigMap plain = planner::buildConfigMap(hulls, settings, path, request);
  collision::ClearanceConfig hull_config = config;
  hull_config.link_meshes = collision::LinkMeshes::kHull;
  const collision::Scene nearer(cell, raised(hull_config, 0.00101));
  const ConfigMap plain_nearer = planner::buildConfigMap(nearer, settings, path, request);
  std::size_t binned = 0;
  for (std::size_t i = 0; i < hull_map.f.size(); ++i) {
    ASSERT_LE(hull_map.clearance[i], plain.clearance[i] + 1e-6) << "cell " << i;
    ASSERT_GE(hull_map.clearance[i], plain_nearer.clearance[i] - 1e-6) << "cell " << i;
    binned += hull_map.clearance[i] < plain.clearance[i] - 1e-6f ? 1u : 0u;
  }
  EXPECT_GT(binned, 0u) << "premise: a fine pair's bins take something off";
  EXPECT_TRUE(sameBytes(hull_map.joint, plain.joint));

  // The default map (a cylinder for a round link, convex pieces where the hull is loose) is no
  // higher than the exact one anywhere, and no lower than the exact map of distances nearer by
  // the largest margin and the fine pairs' 1 mm.
  request.motion_bounds = true;
  const ConfigMap auto_map = planner::buildConfigMap(automatic, settings, path, request);
  double margin = 0.0;
  for (const collision::MapHull& h : automatic.mapHulls()) margin = std::max(margin, h.margin);
  collision::ClearanceConfig exact_config = config;
  exact_config.link_meshes = collision::LinkMeshes::kExact;
  const collision::Scene exact_nearer(cell, raised(exact_config, margin + 0.00101));
  const ConfigMap exact_nearer_map = planner::buildConfigMap(exact_nearer, settings, path, request);
  std::size_t above_hull = 0;
  for (std::size_t i = 0; i < auto_map.f.size(); ++i) {
    ASSERT_LE(auto_map.clearance[i], exact_map.clearance[i] + 1e-6) << "cell " << i;
    ASSERT_LE(auto_map.f[i], exact_map.f[i] + 1e-6) << "cell " << i;
    ASSERT_GE(auto_map.clearance[i], exact_nearer_map.clearance[i] - 1e-6) << "cell " << i;
    above_hull += auto_map.clearance[i] > hull_map.clearance[i] + 1e-3f ? 1u : 0u;
  }
  EXPECT_GT(above_hull, 0u) << "premise: the pieces are tighter than the hulls somewhere";
}

// A link round about its own joint's axis (the mesh robot's link 6, its flange cylinder on the
// J6 axis, tessellated) stands in as a cylinder about that axis within the margin: the maps see
// it never farther than the mesh and at most its margin nearer, and turning J6 does not move it.
TEST_F(MapJob, ARoundLinkStandsInAsACylinderThatItsJointDoesNotMove) {
  const config::JobSpec job = shortDemoJob({"robot=" + writeMeshRobot(dir_).string()});
  const kinematics::CellModel cell = config::buildCell(job);
  collision::ClearanceConfig config = config::clearanceConfig(job);
  // The other links as their meshes, measured alike by both evaluators (and without the minutes
  // of fitting pieces).
  config.max_pieces = 1;
  const collision::Scene scene(cell, config);
  const int link6 = scene.bodyIndex("link6");
  const collision::MapHull* round = nullptr;
  for (const collision::MapHull& h : scene.mapHulls()) round = h.body == link6 ? &h : round;
  ASSERT_NE(round, nullptr);
  EXPECT_TRUE(round->cylinder && round->used);
  EXPECT_LE(round->margin, 0.002);
  ASSERT_EQ(round->standin.size(), 1u);  // its prism, for the pictures
  const collision::ChainLevers levers(scene);
  collision::ClearanceEvaluator map(scene, true, collision::Geometry::kMap);
  collision::ClearanceEvaluator exact(scene, true, collision::Geometry::kExact);
  std::mt19937 rng(3);
  std::size_t pairs = 0, near = 0;
  for (std::size_t p = 0; p < scene.pairs().size(); ++p) {
    const collision::PairInfo& pair = scene.pairs()[p];
    if (pair.a != link6 && pair.b != link6) continue;
    ++pairs;
    if (pair.a == scene.bodyIndex("link4") || pair.b == scene.bodyIndex("link4")) {
      EXPECT_EQ(levers.weights(p)[5], 0.0);  // J6 turns link 6 about itself
      EXPECT_GT(levers.weights(p)[4], 0.0);
    }
  }
  ASSERT_GT(pairs, 0u);
  for (int k = 0; k < 150; ++k) {
    const kinematics::JointVector q = test::randomJoints(cell.robot, rng);
    // Distances below 5 cm, each to GJK's tolerance (1e-6 m).
    const collision::ClearanceResult m = map.evaluate(0.2 * k, q, {.bound = 0.05});
    const collision::ClearanceResult e = exact.evaluate(0.2 * k, q, {.bound = 0.05});
    for (std::size_t p = 0; p < scene.pairs().size(); ++p) {
      const collision::PairInfo& pair = scene.pairs()[p];
      if ((pair.a != link6 && pair.b != link6) || e.pairs[p].beyond_bound) continue;
      ASSERT_FALSE(m.pairs[p].beyond_bound) << "pair " << p;
      ASSERT_LE(m.pairs[p].distance, e.pairs[p].distance + 2e-6) << "pair " << p;
      ASSERT_GE(m.pairs[p].distance, e.pairs[p].distance - round->margin - 2e-6)
          << scene.bodies()[static_cast<std::size_t>(pair.a)].name << "-"
          << scene.bodies()[static_cast<std::size_t>(pair.b)].name << " r "
          << round->cylinder_radius << " L " << round->cylinder_length;
      ++near;
    }
  }
  EXPECT_GT(near, 10u);  // pairs near enough for the margin to matter
}

// SelfPairGrid's fine pairs: the arm's own pairs with one or two joints between them measured as
// stand-ins (here the links' hulls). A bin's bound holds at every configuration in it and lies
// within twice the fine erosion of the distance there, below d_high; with the meshes measured
// exactly no pair is fine.
TEST_F(MapJob, AFinePairsBoundLiesWithinTwiceTheFineErosionOfItsDistance) {
  const config::JobSpec job = shortDemoJob({"robot=" + writeMeshRobot(dir_).string()});
  const kinematics::CellModel cell = config::buildCell(job);
  collision::ClearanceConfig config = config::clearanceConfig(job);
  config.link_meshes = collision::LinkMeshes::kExact;
  const collision::Scene exact(cell, config);
  const collision::ChainLevers exact_levers(exact);
  const collision::SelfPairGrid exact_grid(exact, exact_levers, 0.004, 0.0005);
  config.link_meshes = collision::LinkMeshes::kHull;
  const collision::Scene scene(cell, config);
  const collision::ChainLevers levers(scene);
  constexpr double kFine = 0.0005;
  collision::SelfPairGrid grid(scene, levers, 0.004, kFine);
  std::size_t fine = 0;
  for (std::size_t p = 0; p < scene.pairs().size(); ++p) {
    fine += grid.fine(p) ? 1u : 0u;
    EXPECT_FALSE(exact_grid.fine(p)) << "pair " << p;
    if (grid.fine(p)) {
      EXPECT_TRUE(grid.covers(p) && scene.armPair(p)) << "pair " << p;
    }
  }
  ASSERT_GE(fine, 4u);  // link2-link4, link4-link6, link4-scanner, …
  collision::ClearanceEvaluator evaluator(scene, true, collision::Geometry::kMap);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> hair(-2e-3, 2e-3);
  std::size_t checked = 0, near = 0;
  for (int k = 0; k < 400; ++k) {
    kinematics::JointVector q = test::randomJoints(cell.robot, rng);
    if (k % 2 == 1) q = q.unaryExpr([&](double v) { return v + hair(rng); });
    const collision::ClearanceResult r = evaluator.evaluate(0.1 * k, q, {.bounded = false});
    for (std::size_t p = 0; p < scene.pairs().size(); ++p) {
      const double lower =
          grid.fine(p) ? grid.lower(p, q) : -std::numeric_limits<double>::infinity();
      if (!std::isfinite(lower)) continue;  // not fine, or a joint a hair outside its limits
      const double d = r.pairs[p].distance;
      ASSERT_LE(lower, d + 1e-9) << "pair " << p << " at sample " << k;
      ++checked;
      if (d >= scene.pairs()[p].thresholds.d_high) continue;
      ASSERT_GE(lower, d - 2.0 * kFine * 1.001) << "pair " << p << " at sample " << k;
      ++near;
    }
  }
  EXPECT_GT(checked, 400u * fine * 9 / 10);
  EXPECT_GT(near, 100u);  // the second check is not vacuous
}

// A map whose fine pairs read bins (the mesh robot's links as hulls) is the same to the byte on
// one thread and on two: a bin's bound depends on its joints alone, not on which cells a thread
// saw before.
TEST_F(MapJob, AMapWithFinePairsIsByteIdenticalForOneAndTwoThreads) {
  const config::JobSpec job = shortDemoJob({"robot=" + writeMeshRobot(dir_).string()});
  const kinematics::CellModel cell = config::buildCell(job);
  collision::ClearanceConfig config = config::clearanceConfig(job);
  config.link_meshes = collision::LinkMeshes::kHull;
  const collision::Scene scene(cell, config);
  const planner::ConstraintSettings settings = config::constraintSettings(job);
  const kinematics::ScanPath path = jobPath(job, cell);
  planner::MapRequest request;
  request.angle_step = deg(10.0);
  request.branches = allBranches();
  ConfigMap one, two;
  {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = planner::buildConfigMap(scene, settings, path, request);
  }
  {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = planner::buildConfigMap(scene, settings, path, request);
  }
  EXPECT_TRUE(sameMap(one, two));
  request.motion_bounds = false;
  std::size_t binned = 0;  // premise: the fine pairs' bins decide some cells
  const ConfigMap plain = planner::buildConfigMap(scene, settings, path, request);
  for (std::size_t i = 0; i < one.f.size(); ++i)
    binned += one.clearance[i] < plain.clearance[i] - 1e-6f ? 1u : 0u;
  EXPECT_GT(binned, 0u);
}

TEST(ConfigMap, LayersAreByteIdenticalForOneAndTwoThreads) {
  const DemoMap& demo = demoMap();
  ConfigMap one, two;
  {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = planner::buildConfigMap(*demo.scene, demo.settings, demo.path, demo.request);
  }
  {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = planner::buildConfigMap(*demo.scene, demo.settings, demo.path, demo.request);
  }
  EXPECT_TRUE(sameBytes(one.f, two.f));
  EXPECT_TRUE(sameBytes(one.joint, two.joint));
  EXPECT_TRUE(sameBytes(one.singularity, two.singularity));
  EXPECT_TRUE(sameBytes(one.clearance, two.clearance));
  EXPECT_TRUE(sameBytes(one.limit, two.limit));
  EXPECT_TRUE(sameBytes(one.f, demo.map.f)) << "and equal to the default-parallelism map";
}

TEST(ConfigMap, AMapOverTheMemoryLimitIsRefusedBeforeComputing) {
  const DemoMap& demo = demoMap();
  // Four float layers and one byte layer per cell.
  EXPECT_EQ(planner::mapBytes(8, 36, 10), 8u * 36u * 10u * 17u);
  planner::MapRequest request = demo.request;
  request.memory_limit_bytes = planner::mapBytes(8, 36, 10) - 1;
  int progress_calls = 0;
  try {
    planner::buildConfigMap(*demo.scene, demo.settings, demo.path, request,
                            [&](std::size_t, std::size_t) { ++progress_calls; });
    ADD_FAILURE() << "no exception";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("memory_limit_mb"), std::string::npos) << message;
    EXPECT_NE(message.find("36 angles"), std::string::npos) << message;
  }
  EXPECT_EQ(progress_calls, 0) << "nothing computed";
  // At the limit exactly it goes ahead and reports progress up to every cell.
  request.memory_limit_bytes = planner::mapBytes(8, 36, 10);
  std::size_t last = 0, total = 0;
  planner::buildConfigMap(*demo.scene, demo.settings, demo.path, request,
                          [&](std::size_t d, std::size_t n) {
                            last = std::max(last, d);
                            total = n;
                          });
  EXPECT_EQ(total, 360u);
  EXPECT_EQ(last, 360u);
}

// ---------------------------------------------------------------------------------------------
// Branch words.

TEST(ConfigMap, BranchWordsParseInAnyOrderAndBadWordsAreRejected) {
  const auto parsed = config::parseBranch("RIGHTY ABOVE NOFLIP");
  ASSERT_TRUE(parsed);
  EXPECT_EQ(*parsed, (kinematics::IkBranch{false, false, false}));
  EXPECT_EQ(parsed->words(), "RIGHTY ABOVE NOFLIP");
  EXPECT_EQ(config::parseBranch("FLIP  LEFTY\tBELOW"), (kinematics::IkBranch{true, true, true}));
  for (int i = 0; i < 8; ++i) {
    const kinematics::IkBranch b = kinematics::IkBranch::fromIndex(i);
    EXPECT_EQ(config::parseBranch(b.words()), b) << b.words();
  }
  for (const char* bad :
       {"", "RIGHTY ABOVE", "RIGHTY ABOVE NOFLIP EXTRA", "FOO", "RIGHTY ABOVE NOFLIP,",
        "righty above noflip", "RIGHTY-ABOVE-NOFLIP", "auto"}) {
    EXPECT_FALSE(config::parseBranch(bad)) << "'" << bad << "'";
  }
}

// Exactly one word of each pair: "RIGHTY LEFTY ABOVE NOFLIP" is ambiguous and must be refused.
TEST(ConfigMap, BranchWordsGivingBothWordsOfAPairAreRejected) {
  for (const char* bad : {"RIGHTY LEFTY ABOVE NOFLIP", "RIGHTY ABOVE BELOW NOFLIP",
                          "RIGHTY ABOVE FLIP NOFLIP", "RIGHTY RIGHTY ABOVE NOFLIP"}) {
    EXPECT_FALSE(config::parseBranch(bad)) << "'" << bad << "'";
  }
}

std::string demoJobText() {
  std::ifstream in(test::sourceDir() / "data/jobs/demo_rings.yaml");
  std::stringstream s;
  s << in.rdbuf();
  std::string text = s.str();
  const auto replace = [&](const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    if (at != std::string::npos) text.replace(at, from.size(), to);
  };
  replace("../robots/viper_s650.yaml",
          (test::sourceDir() / "data/robots/viper_s650.yaml").string());
  replace("../parts/demo_housing.stl",
          (test::sourceDir() / "data/parts/demo_housing.stl").string());
  return text.substr(0, text.find("\nscan:")) + "\n";  // the cell, without scan and map
}

const char* kShortScan =
    "scan:\n"
    "  dt_s: 0.25\n"
    "  paths:\n"
    "    - {type: ring, height_mm: 50, tilt_deg: 20, start_deg: 0, extent_deg: 90, speed_deg_s: "
    "40}\n";

TEST_F(MapJob, MapBranchMustBeAutoOrThreeWords) {
  const fs::path job = write("job.yaml", demoJobText() + kShortScan + "map: {branch: FOO}\n");
  try {
    config::loadJob(job);
    ADD_FAILURE() << "no exception";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(job.string() + ":"), std::string::npos) << message;
    EXPECT_NE(message.find("map.branch: 'FOO'"), std::string::npos) << message;
    EXPECT_NE(message.find("RIGHTY ABOVE NOFLIP"), std::string::npos) << message;
  }
  const config::JobSpec ok = config::loadJob(
      write("ok.yaml", demoJobText() + kShortScan + "map: {branch: LEFTY BELOW FLIP}\n"));
  EXPECT_EQ(ok.map.branch, "LEFTY BELOW FLIP");
}

// ---------------------------------------------------------------------------------------------
// `scanplan map`.

struct CliRun {
  int exit_code = -1;
  std::string err;
};

CliRun scanplan(const std::vector<std::string>& args, const fs::path& dir) {
  std::vector<std::string> argv_text{SCANPLAN_BINARY};
  argv_text.insert(argv_text.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_text) argv.push_back(a.data());
  argv.push_back(nullptr);
  const fs::path err = dir / "stderr.txt";
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  CliRun run;
  const int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    ADD_FAILURE() << "cannot start " << argv[0];
    return run;
  }
  int status = 0;
  if (::waitpid(pid, &status, 0) == pid && WIFEXITED(status)) run.exit_code = WEXITSTATUS(status);
  std::ifstream in(err);
  std::stringstream s;
  s << in.rdbuf();
  run.err = s.str();
  return run;
}

std::string readText(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST_F(MapJob, MapCommandWritesLayersJsonAndImages) {
  const fs::path job =
      write("job.yaml", demoJobText() + kShortScan +
                            "map: {angle_step_deg: 10, branch: RIGHTY ABOVE NOFLIP}\n");
  const fs::path out = dir_ / "out";
  const CliRun run = scanplan({"map", job.string(), "-o", out.string()}, dir_);
  ASSERT_EQ(run.exit_code, 0) << run.err;

  const test::NpyArray f = test::readNpy(out / "configmap.npy");
  EXPECT_EQ(f.descr, "<f4");
  EXPECT_EQ(f.shape, (std::vector<std::size_t>{1, 36, 10}));
  ASSERT_EQ(f.raw.size(), 360u * sizeof(float));
  const test::NpyArray limit = test::readNpy(out / "configmap_limit.npy");
  EXPECT_EQ(limit.descr, "|u1");
  EXPECT_EQ(limit.shape, f.shape);
  for (const char* layer :
       {"configmap_joint.npy", "configmap_singularity.npy", "configmap_clearance.npy"}) {
    EXPECT_EQ(test::readNpy(out / layer).shape, f.shape) << layer;
  }
  // The same job in-process, branch RIGHTY ABOVE NOFLIP = index 0 of the 8-branch map: the
  // file holds exactly its f layer.
  const ConfigMap& map = demoMap().map;
  ASSERT_EQ(map.branches[0].words(), "RIGHTY ABOVE NOFLIP");
  EXPECT_EQ(std::memcmp(f.raw.data(), map.f.data(), f.raw.size()), 0)
      << "configmap.npy differs from the library's map";

  const std::string json = readText(out / "configmap.json");
  EXPECT_NE(json.find("RIGHTY ABOVE NOFLIP"), std::string::npos) << json;
  EXPECT_NE(json.find("configmap_limit.npy"), std::string::npos);
  EXPECT_NE(json.find("unreachable"), std::string::npos);

  // configmap.png is the map raster stretched into whole blocks (a cell per block) and framed
  // with axes and legend; its black frame says where the raster sits in the PNG.
  const cli::RgbImage png = test::decodePng(readText(out / "configmap.png"));
  const auto [crop_x, crop_y, crop_w, crop_h] = test::plotArea(png);
  ASSERT_GE(crop_x, 0);
  ASSERT_GE(crop_y, 0);
  ASSERT_LE(crop_x + crop_w, png.width);
  ASSERT_LE(crop_y + crop_h, png.height);
  ASSERT_EQ(crop_w % 10, 0) << crop_w;  // 10 time samples, whole blocks
  ASSERT_EQ(crop_h % 36, 0) << crop_h;  // 36 table angles
  EXPECT_GE(crop_w, 1000) << "stretched to a readable width";
  const int bw = crop_w / 10, bh = crop_h / 36;
  int wrong = 0;
  for (int a = 0; a < 36; ++a) {
    for (int t = 0; t < 10; ++t) {
      // Angle grows upwards; every pixel of the cell's block has the cell's grey.
      const cli::Rgb want =
          cli::grey(map.f[map.index(0, static_cast<std::size_t>(a), static_cast<std::size_t>(t))]);
      for (const auto& [dx, dy] : {std::pair{0, 0}, {bw - 1, bh - 1}, {bw / 2, bh / 2}}) {
        const cli::Rgb got = png.at(crop_x + t * bw + dx, crop_y + (35 - a) * bh + dy);
        if (got.r != want.r || got.g != want.g || got.b != want.b) ++wrong;
      }
    }
  }
  EXPECT_EQ(wrong, 0) << "pixels of the map raster that are not their cell's grey";
  EXPECT_GT(test::decodePng(readText(out / "configmap_cylinder.png")).width, 0);
  EXPECT_GT(test::decodePng(readText(out / "configmap_why.png")).width, 0);
  const std::string why = readText(out / "configmap_why.svg");
  EXPECT_NE(why.find("<svg"), std::string::npos);
  EXPECT_NE(why.find("xlink:href=\"data:image/png;base64,"), std::string::npos) << "the raster";
  EXPECT_NE(why.find("clearance"), std::string::npos) << "the legend names the limits";
  EXPECT_TRUE(fs::exists(out / "configmap.svg"));
  // No temporary files left behind.
  for (const auto& entry : fs::directory_iterator(out)) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
  }
}

// The error names the job file too (`map` left it out, `plan` named it).
TEST_F(MapJob, MapCommandOverTheMemoryLimitIsAnInputError) {
  const fs::path job = write("job.yaml", demoJobText() + kShortScan +
                                             "map: {angle_step_deg: 10, memory_limit_mb: 0.001}\n");
  const CliRun run = scanplan({"map", job.string(), "-o", (dir_ / "out").string()}, dir_);
  EXPECT_EQ(run.exit_code, 4) << run.err;
  EXPECT_NE(run.err.find(job.string() + ": map: "), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("memory_limit_mb"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(dir_ / "out" / "configmap.npy"));
}

}  // namespace

namespace {

// Thousands of obstacles standing in the world: the scene pairs each with the bodies that move
// past it only (the arm's links, the scanner, what the table carries), never with one another;
// a map whose distance checks (branches x angles x samples x pairs) would take hours is refused
// before anything is computed, naming the obstacles among the remedies.
TEST(ConfigMap, ManyObstaclesPairOnlyWithMovingBodiesAndAnOversizedMapIsRefused) {
  const DemoMap& demo = demoMap();
  kinematics::CellModel cell = demo.cell;
  const std::size_t before = cell.obstacles.size();
  constexpr std::size_t kCrates = 10000;
  for (std::size_t i = 0; i < kCrates; ++i) {
    kinematics::Shape crate;
    crate.geometry = kinematics::Sphere{0.01};
    crate.X_BG.translation() << -3.0 - 0.05 * static_cast<double>(i % 100),
        0.05 * static_cast<double>(i / 100), 0.0;
    cell.obstacles.push_back({"crate" + std::to_string(i), kinematics::Carrier::kWorld, {crate}});
  }
  const collision::Scene scene(cell, config::clearanceConfig(demo.job));
  std::size_t moving = 0;  // bodies that pass a world obstacle: arm links 1..6, scanner, cargo
  for (const collision::BodyInfo& b : scene.bodies()) {
    const bool cargo = b.motion == collision::BodyMotion::kTable && b.name != "table";
    if ((b.ridesOnTheArm() && b.link != 0) || cargo) ++moving;
  }
  std::size_t crate_pairs = 0, crate_crate = 0;
  for (const collision::PairInfo& p : scene.pairs()) {
    const bool a = scene.bodies()[static_cast<std::size_t>(p.a)].name.rfind("crate", 0) == 0;
    const bool b = scene.bodies()[static_cast<std::size_t>(p.b)].name.rfind("crate", 0) == 0;
    crate_pairs += a || b;
    crate_crate += a && b;
  }
  EXPECT_EQ(crate_crate, 0u);
  EXPECT_EQ(crate_pairs, kCrates * moving) << moving << " moving bodies, " << before;
  planner::MapRequest request = demo.request;
  request.angle_step = deg(0.1);
  const double checks =
      static_cast<double>(request.branches.size() * 3600 * demo.path.samples.size()) *
      static_cast<double>(scene.pairs().size());
  ASSERT_GT(checks, planner::kMaxMapPairChecks) << "the case must be over the limit";
  int progress_calls = 0;
  try {
    planner::buildConfigMap(scene, demo.settings, demo.path, request,
                            [&](std::size_t, std::size_t) { ++progress_calls; });
    ADD_FAILURE() << "no exception";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("distance checks"), std::string::npos) << message;
    EXPECT_NE(message.find("fewer obstacles"), std::string::npos) << message;
    EXPECT_NE(message.find(fmt::format("{} body pairs", scene.pairs().size())), std::string::npos)
        << message;
  }
  EXPECT_EQ(progress_calls, 0) << "nothing computed";
}

}  // namespace
