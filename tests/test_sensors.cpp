// Presence and distance sensors (seed §5.1–5.2): a light curtain fires exactly while the
// scanner's sphere overlaps it (point–box distance worked out by hand), a sensor never sees the
// body carrying it, a beam reads a plane's distance under any tilt (h / cos α), the meshes' ray
// casts agree with Embree's, a receiver behind an occluder gets no reading (the concave-region
// rule), the rules become validation errors over the right span, and bad job keys are refused
// naming the key.
#include <gtest/gtest.h>

#include <unistd.h>
#include <algorithm>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <tbb/global_control.h>

#include <yaml-cpp/yaml.h>

#include <scanplan/collision/scene.h>
#include <scanplan/collision/sensors.h>
#include <scanplan/config/job.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/planner/validation.h>
#include <scanplan/scanner/raycaster.h>
#include "cli/report/sensor_report.h"
#include "cli_support.h"
#include "test_support.h"

namespace {

using namespace scanplan;
using kinematics::JointVector;
using kinematics::Sensor;
using kinematics::SensorExpectation;
using kinematics::TrajectorySample;

// Closed forms and analytic ray casts: exact to rounding on metre-sized numbers.
constexpr double kRangeTol = 1e-9;  // m
// Samples this close to a crossing (in the analytic distance) are not judged: rounding decides.
constexpr double kBoundaryTol = 1e-7;  // m

struct Demo {
  config::JobSpec job;
  kinematics::CellModel cell;
};

Demo demo() {
  config::JobSpec job =
      config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml", test::kLightDemo);
  kinematics::CellModel cell = config::buildCell(job);
  return {std::move(job), std::move(cell)};
}

collision::Scene sceneOf(const Demo& d) {
  return collision::Scene(d.cell, config::clearanceConfig(d.job));
}

JointVector jointsDeg(double q1, double q2, double q3, double q4, double q5, double q6) {
  JointVector q;
  q << deg(q1), deg(q2), deg(q3), deg(q4), deg(q5), deg(q6);
  return q;
}

// The arm folded over itself, the scanner pointing down (as test_validation's home pose).
JointVector home(double q1_deg) { return jointsDeg(q1_deg, -90.0, 180.0, 0.0, 90.0, 0.0); }

Sensor presence(const std::string& name,
                const std::string& carrier,
                const Eigen::Isometry3d& X_CS,
                const kinematics::ShapeGeometry& volume) {
  Sensor s;
  s.name = name;
  s.kind = Sensor::Kind::kPresence;
  s.carrier = carrier;
  s.X_CS = X_CS;
  s.volume.geometry = volume;
  return s;
}

Sensor beam(const std::string& name,
            const Eigen::Isometry3d& X_WS,
            double min_range,
            double max_range) {
  Sensor s;
  s.name = name;
  s.kind = Sensor::Kind::kDistance;
  s.carrier = "world";
  s.X_CS = X_WS;
  s.min_range = min_range;
  s.max_range = max_range;
  return s;
}

kinematics::Obstacle worldBox(const std::string& name,
                              const Eigen::Vector3d& centre,
                              const Eigen::Vector3d& size) {
  kinematics::Shape shape;
  shape.geometry = kinematics::Box{size};
  shape.X_BG.translation() = centre;
  return {name, kinematics::Carrier::kWorld, {shape}};
}

// A pose whose +z looks along `dir` from `origin`.
Eigen::Isometry3d lookingAlong(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), dir.normalized())
                   .toRotationMatrix();
  X.translation() = origin;
  return X;
}

bool hasBody(const collision::Scene& scene, const collision::SensorReading& r, const char* name) {
  const int b = scene.bodyIndex(name);
  return std::find(r.bodies.begin(), r.bodies.end(), b) != r.bodies.end();
}

// The light-curtain case: the scanner housing made a 30 mm sphere at the laser origin, J1
// swept from −40° to 40° in 8 s with the arm folded (scanner down), and a thin world box across
// the sphere's path at J1 = 10°, its top level with the sphere's centre (the links, 110 mm and
// more above, stay out of it).
struct Curtain {
  Demo d;
  double radius = 0.03;
  Eigen::Isometry3d X_WS = Eigen::Isometry3d::Identity();  // the curtain box's frame
  Eigen::Vector3d half{0.15, 0.01, 0.02};
  kinematics::Trajectory trajectory = {};

  Eigen::Vector3d sphereCentre(const JointVector& q) const {
    return (d.cell.X_WB * d.cell.robot.fk(q) * d.cell.scanner.X_FS).translation();
  }
  // Sphere–box overlap by hand: the centre's distance to the solid box against the radius.
  double gap(const JointVector& q) const {
    const Eigen::Vector3d p = X_WS.inverse() * sphereCentre(q);
    return (p.cwiseAbs() - half).cwiseMax(0.0).norm() - radius;
  }
};

// `X_WB`: the robot base in the world; the curtain keeps its place relative to the base.
Curtain curtain(const Eigen::Isometry3d& X_WB = Eigen::Isometry3d::Identity()) {
  Curtain c{demo(), 0.03, Eigen::Isometry3d::Identity(), {0.15, 0.01, 0.02}, {}};
  c.d.cell.X_WB = X_WB;
  kinematics::Shape sphere;
  sphere.geometry = kinematics::Sphere{c.radius};
  c.d.cell.scanner.body = {sphere};
  const Eigen::Vector3d at = c.sphereCentre(home(10.0));
  c.X_WS = Eigen::Isometry3d(X_WB.linear() *
                             Eigen::AngleAxisd(deg(10.0), Eigen::Vector3d::UnitZ()).matrix());
  c.X_WS.translation() = at - X_WB.linear() * Eigen::Vector3d(0, 0, c.half.z());
  c.d.cell.sensors = {presence("light_curtain", "world", c.X_WS, kinematics::Box{2.0 * c.half})};
  c.d.cell.sensors[0].expect.kind = SensorExpectation::Kind::kNever;
  TrajectorySample a, b;
  a.q = home(-40.0);
  b.t = 8.0;
  b.q = home(40.0);
  c.trajectory.samples = {a, b};
  return c;
}

// The curtain fires at exactly the samples where the sphere overlaps it by hand, in one span;
// `first` and `last` get that span's ends.
void expectCurtainFiresExactly(const Curtain& c,
                               const collision::Scene& scene,
                               double& first,
                               double& last) {
  const auto dense = planner::densify(c.trajectory, 0.01);
  const collision::SensorEvaluation e = collision::evaluateSensors(scene, dense.samples);
  ASSERT_EQ(e.t.size(), dense.samples.size());
  first = last = -1.0;
  std::size_t judged = 0;
  for (std::size_t k = 0; k < dense.samples.size(); ++k) {
    const double gap = c.gap(dense.samples[k].q);
    const collision::SensorReading& r = e.readings[0][k];
    if (gap <= 0.0) {
      if (first < 0.0) first = e.t[k];
      last = e.t[k];
    }
    if (std::abs(gap) < kBoundaryTol) continue;
    ++judged;
    EXPECT_EQ(hasBody(scene, r, "scanner"), gap < 0.0) << "t = " << e.t[k] << ", gap " << gap;
    EXPECT_EQ(r.fires, gap < 0.0) << "t = " << e.t[k];  // nothing else reaches the curtain
  }
  EXPECT_GT(judged, dense.samples.size() - 3);
  // The sphere crosses the 20 mm curtain in about 0.3 s of the 8: one span, well inside.
  ASSERT_GT(first, 0.5);
  ASSERT_LT(last, 7.5);
  const auto spans = collision::firingSpans(e, 0);
  ASSERT_EQ(spans.size(), 1u);
  EXPECT_DOUBLE_EQ(spans[0].t_start, first);
  EXPECT_DOUBLE_EQ(spans[0].t_end, last);
  EXPECT_EQ(spans[0].bodies, std::vector<int>{scene.bodyIndex("scanner")});
}

TEST(Sensors, LightCurtainFiresExactlyWhileTheScannerOverlapsIt) {
  const Curtain c = curtain();
  const collision::Scene scene = sceneOf(c.d);
  double first = 0.0, last = 0.0;
  ASSERT_NO_FATAL_FAILURE(expectCurtainFiresExactly(c, scene, first, last));

  // The rule `never` makes it a validation error over exactly that span.
  planner::ValidationSettings settings;
  settings.sample_dt = 0.01;
  const planner::ValidationReport report =
      planner::validateTrajectory(scene, c.trajectory, settings);
  EXPECT_FALSE(report.valid);
  ASSERT_TRUE(report.sensors.has_value());
  std::vector<planner::Violation> sensor_violations;
  for (const auto& v : report.violations) {
    if (v.kind == planner::Violation::Kind::kSensor) sensor_violations.push_back(v);
  }
  ASSERT_EQ(sensor_violations.size(), 1u) << planner::describe(report.violations.front());
  const planner::Violation& v = sensor_violations[0];
  EXPECT_EQ(v.what, "light_curtain");
  EXPECT_DOUBLE_EQ(v.t_start, first);
  EXPECT_DOUBLE_EQ(v.t_end, last);
  EXPECT_NE(v.note.find("expect never: fires (scanner)"), std::string::npos) << v.note;
  EXPECT_NE(planner::describe(v).find("sensor: light_curtain"), std::string::npos);
}

TEST(Sensors, TheCurtainFiresTheSameWhereverTheCellStands) {
  // Frame invariance: the robot base (and the curtain with it) moved and turned in the world.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 3; ++i) {
    Eigen::Isometry3d X_WB(Eigen::AngleAxisd(std::numbers::pi * u(rng), Eigen::Vector3d::UnitZ()) *
                           Eigen::AngleAxisd(deg(5.0) * u(rng), Eigen::Vector3d::UnitX()));
    X_WB.translation() = Eigen::Vector3d(0.1 * u(rng), 0.1 * u(rng), 0.05 * u(rng));
    const Curtain c = curtain(X_WB);
    const collision::Scene scene = sceneOf(c.d);
    double first = 0.0, last = 0.0;
    SCOPED_TRACE(i);
    ASSERT_NO_FATAL_FAILURE(expectCurtainFiresExactly(c, scene, first, last));
  }
}

TEST(Sensors, RulesBreakOverTheRightSpans) {
  // A hand-made series: fires at samples 3…5 of t = 0, 1, …, 9 s.
  collision::SensorEvaluation e;
  e.readings.resize(1);
  for (int k = 0; k < 10; ++k) {
    e.t.push_back(k);
    collision::SensorReading r;
    r.fires = k >= 3 && k <= 5;
    e.readings[0].push_back(r);
  }
  Sensor s;
  const auto check = [&](SensorExpectation x) {
    s.expect = x;
    return collision::checkSensorRules({s}, e);
  };
  using K = SensorExpectation::Kind;
  EXPECT_TRUE(check({K::kAny}).empty());
  EXPECT_TRUE(check({K::kDuring, 3.0, 5.0}).empty());  // exactly within
  EXPECT_TRUE(check({K::kNotDuring, 6.0, 9.0}).empty());
  {
    const auto v = check({K::kNever});
    ASSERT_EQ(v.size(), 1u);
    EXPECT_TRUE(v[0].fired);
    EXPECT_EQ(v[0].span.t_start, 3.0);
    EXPECT_EQ(v[0].span.t_end, 5.0);
  }
  {
    const auto v = check({K::kAlways});
    ASSERT_EQ(v.size(), 2u);
    EXPECT_FALSE(v[0].fired);
    EXPECT_EQ(v[0].span.t_start, 0.0);
    EXPECT_EQ(v[0].span.t_end, 2.0);
    EXPECT_EQ(v[1].span.t_start, 6.0);
    EXPECT_EQ(v[1].span.t_end, 9.0);
  }
  {
    // Expected during [2, 4]: silent at 2, fires (against the rule) at 5.
    const auto v = check({K::kDuring, 2.0, 4.0});
    ASSERT_EQ(v.size(), 2u);
    EXPECT_FALSE(v[0].fired);
    EXPECT_EQ(v[0].span.t_start, 2.0);
    EXPECT_EQ(v[0].span.t_end, 2.0);
    EXPECT_TRUE(v[1].fired);
    EXPECT_EQ(v[1].span.t_start, 5.0);
    EXPECT_EQ(v[1].span.t_end, 5.0);
  }
  {
    const auto v = check({K::kNotDuring, 4.5, 8.0});
    ASSERT_EQ(v.size(), 1u);
    EXPECT_EQ(v[0].span.t_start, 5.0);
    EXPECT_EQ(v[0].span.t_end, 5.0);
  }
  {
    // A `during` window after the motion's end (samples 0…9 s) is never met: nothing shows the
    // sensor firing there. One straddling the end breaks over its unobserved part only.
    const auto after = check({K::kDuring, 20.0, 30.0});
    ASSERT_EQ(after.size(), 2u) << "fired at 3…5 outside it, silent over 20…30 s unseen";
    EXPECT_TRUE(after[0].fired);
    EXPECT_FALSE(after[1].fired);
    EXPECT_EQ(after[1].span.t_start, 20.0);
    EXPECT_EQ(after[1].span.t_end, 30.0);
    e.readings[0][9].fires = true;  // fires at 9 s too: of [9, 12] only 9 s is seen
    const auto straddling = check({K::kDuring, 9.0, 12.0});
    ASSERT_EQ(straddling.size(), 2u) << "fired at 3…5 outside it, silent over 9…12 s unseen";
    EXPECT_FALSE(straddling[1].fired);
    EXPECT_EQ(straddling[1].span.t_start, 9.0);
    EXPECT_EQ(straddling[1].span.t_end, 12.0);
    // `not during` a window after the end: nothing fires there, nothing is asked.
    EXPECT_TRUE(check({K::kNotDuring, 20.0, 30.0}).empty());
  }
}

TEST(Sensors, ASensorNeverSeesTheBodyCarryingIt) {
  Demo d = demo();
  // A 120 mm sphere about the laser origin overlaps the scanner housing and the flange's link.
  const kinematics::Sphere big{0.12};
  d.cell.sensors = {presence("on_scanner", "scanner", Eigen::Isometry3d::Identity(), big),
                    presence("on_link6", "link6", Eigen::Isometry3d::Identity(), big)};
  // link6's frame is the flange: put the second at the laser origin too.
  d.cell.sensors[1].X_CS = d.cell.scanner.X_FS;
  const collision::Scene scene = sceneOf(d);
  ASSERT_GE(scene.bodyIndex("link6"), 0);
  collision::SensorEvaluator evaluator(scene);
  const auto r = evaluator.evaluate(0.0, home(180.0));
  EXPECT_FALSE(hasBody(scene, r[0], "scanner"));
  EXPECT_TRUE(hasBody(scene, r[0], "link6"));
  EXPECT_FALSE(hasBody(scene, r[1], "link6"));
  EXPECT_TRUE(hasBody(scene, r[1], "scanner"));
  // Both frames coincide: the pose each reports is the same.
  EXPECT_TRUE(test::samePose(evaluator.sensorPose(0), evaluator.sensorPose(1), 1e-12));
  EXPECT_EQ(evaluator.carrierBody(0), scene.bodyIndex("scanner"));
}

TEST(Sensors, CarrierFramesAreTheBodyFrames) {
  // World: W; table and part: the table top R at θ; scanner: S; link 6: the flange F.
  Demo d = demo();
  Eigen::Isometry3d X_CS = Eigen::Isometry3d(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()));
  X_CS.translation() << 0.01, 0.02, 0.03;
  const kinematics::Sphere ball{0.001};
  for (const char* carrier : {"world", "table", "part", "scanner", "link6"}) {
    d.cell.sensors.push_back(presence(carrier, carrier, X_CS, ball));
  }
  const collision::Scene scene = sceneOf(d);
  collision::SensorEvaluator evaluator(scene);
  const double theta = 0.7;
  const JointVector q = home(150.0);
  evaluator.evaluate(theta, q);
  const Eigen::Isometry3d X_WF = d.cell.X_WB * d.cell.robot.fk(q);
  const Eigen::Isometry3d X_WR = d.cell.table.X_WR(theta);
  constexpr double kTol = 1e-12;
  EXPECT_TRUE(test::samePose(evaluator.sensorPose(0), X_CS, kTol));
  EXPECT_TRUE(test::samePose(evaluator.sensorPose(1), X_WR * X_CS, kTol));
  EXPECT_TRUE(test::samePose(evaluator.sensorPose(2), X_WR * X_CS, kTol));
  EXPECT_TRUE(test::samePose(evaluator.sensorPose(3), X_WF * d.cell.scanner.X_FS * X_CS, kTol));
  EXPECT_TRUE(test::samePose(evaluator.sensorPose(4), X_WF * X_CS, kTol));
}

// A world box far from the arm and the table: its top face at z = 0.2 m.
Demo withSlab() {
  Demo d = demo();
  d.cell.obstacles.push_back(
      worldBox("slab", Eigen::Vector3d(-0.8, 0.8, 0.1), Eigen::Vector3d(0.4, 0.4, 0.2)));
  return d;
}

TEST(Sensors, ABeamReadsAPlaneAtItsDistanceUnderAnyTilt) {
  Demo d = withSlab();
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Vector3d target(-0.8, 0.8, 0.2);  // the top face's centre
  std::vector<double> expected;
  for (int i = 0; i < 40; ++i) {
    // From a point h above the face, tilted by α from the normal toward a random azimuth; it
    // meets the face plane at h / cos α from the origin (within the face for α ≤ 30°).
    const double h = 0.1 + 0.2 * (0.5 + 0.5 * u(rng));
    const double alpha = deg(30.0) * (0.5 + 0.5 * u(rng));
    const double azimuth = std::numbers::pi * u(rng);
    const Eigen::Vector3d origin = target + Eigen::Vector3d(0, 0, h);
    const Eigen::Vector3d dir(std::sin(alpha) * std::cos(azimuth),
                              std::sin(alpha) * std::sin(azimuth), -std::cos(alpha));
    d.cell.sensors.push_back(
        beam("probe" + std::to_string(i), lookingAlong(origin, dir), 0.0, 1.0));
    expected.push_back(h / std::cos(alpha));
  }
  const collision::Scene scene = sceneOf(d);
  const auto r = collision::SensorEvaluator(scene).evaluate(0.0, home(180.0));
  for (std::size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(r[i].beam, collision::BeamStatus::kReading) << i;
    EXPECT_NEAR(r[i].distance, expected[i], kRangeTol) << i;
    EXPECT_EQ(r[i].body, scene.bodyIndex("slab"));
  }
}

TEST(Sensors, RangeLimitsGiveNoReadingWithTheReason) {
  Demo d = withSlab();
  const Eigen::Isometry3d X = lookingAlong({-0.8, 0.8, 0.5}, -Eigen::Vector3d::UnitZ());
  d.cell.sensors = {beam("in", X, 0.1, 0.4), beam("short", X, 0.0, 0.25),
                    beam("near", X, 0.35, 0.5)};
  const collision::Scene scene = sceneOf(d);
  const auto r = collision::SensorEvaluator(scene).evaluate(0.0, home(180.0));
  EXPECT_EQ(r[0].beam, collision::BeamStatus::kReading);
  EXPECT_NEAR(r[0].distance, 0.3, kRangeTol);
  EXPECT_EQ(r[1].beam, collision::BeamStatus::kNoTarget);
  EXPECT_FALSE(r[1].fires);
  EXPECT_EQ(r[2].beam, collision::BeamStatus::kTooClose);
  EXPECT_FALSE(r[2].fires);
  EXPECT_NEAR(r[2].distance, 0.3, kRangeTol);
}

TEST(Sensors, AReceiverBehindAnOccluderGetsNoReading) {
  // Seed §5.2: the emitter 300 mm above the slab, the receiver 100 mm beside it (+x). A 20 mm
  // cube halfway along the return ray (x = 50 mm, 150 mm up) blocks it but not the beam (x = 0).
  Demo d = withSlab();
  const Eigen::Vector3d hit(-0.8, 0.8, 0.2);
  const Eigen::Isometry3d X =
      lookingAlong(hit + Eigen::Vector3d(0, 0, 0.3), -Eigen::Vector3d::UnitZ());
  const Eigen::Vector3d p_WR = hit + Eigen::Vector3d(0.1, 0, 0.3);
  d.cell.sensors = {beam("triangulation", X, 0.0, 1.0), beam("mirrored", X, 0.0, 1.0),
                    beam("time_of_flight", X, 0.0, 1.0)};
  d.cell.sensors[0].p_SR = X.inverse() * p_WR;
  d.cell.sensors[1].p_SR = X.inverse() * (hit + Eigen::Vector3d(-0.1, 0, 0.3));
  d.cell.obstacles.push_back(
      worldBox("occluder", 0.5 * (hit + p_WR), Eigen::Vector3d(0.02, 0.02, 0.02)));
  const collision::Scene scene = sceneOf(d);
  const auto r = collision::SensorEvaluator(scene).evaluate(0.0, home(180.0));
  EXPECT_EQ(r[0].beam, collision::BeamStatus::kReceiverOccluded);
  EXPECT_FALSE(r[0].fires);
  EXPECT_NEAR(r[0].distance, 0.3, kRangeTol);             // the beam itself hit the slab
  EXPECT_EQ(r[1].beam, collision::BeamStatus::kReading);  // the other side is free
  EXPECT_EQ(r[2].beam, collision::BeamStatus::kReading);  // no receiver: no second ray
  // A receiver below the slab's surface (inside it) cannot see the spot either.
  d.cell.sensors = {beam("buried", X, 0.0, 1.0)};
  d.cell.sensors[0].p_SR = X.inverse() * (hit + Eigen::Vector3d(0.05, 0, -0.05));
  const collision::Scene buried = sceneOf(d);
  EXPECT_EQ(collision::SensorEvaluator(buried).evaluate(0.0, home(180.0))[0].beam,
            collision::BeamStatus::kReceiverOccluded);
}

TEST(Sensors, BeamsOnThePartMeshAgreeWithEmbree) {
  Demo d = demo();
  const kinematics::LoadedMesh part = config::loadPartMesh(d.job, d.cell.part);
  const scanner::Raycaster embree(part.mesh);
  const double theta = deg(30.0);
  const Eigen::Isometry3d X_WP = d.cell.table.X_WR(theta) * d.cell.part.X_RP;
  Eigen::AlignedBox3d box;
  for (const auto& v : part.mesh.vertices) box.extend(X_WP * v);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Sensor> sensors;
  for (int i = 0; i < 60; ++i) {
    // From 100 mm above the part toward a random point of its bounding box.
    const Eigen::Vector3d origin(box.min().x() + u(rng) * box.sizes().x(),
                                 box.min().y() + u(rng) * box.sizes().y(), box.max().z() + 0.1);
    const Eigen::Vector3d aim(box.min().x() + u(rng) * box.sizes().x(),
                              box.min().y() + u(rng) * box.sizes().y(), box.min().z());
    sensors.push_back(beam("b" + std::to_string(i), lookingAlong(origin, aim - origin), 0.0, 2.0));
  }
  d.cell.sensors = sensors;
  const collision::Scene scene = sceneOf(d);
  const auto r = collision::SensorEvaluator(scene).evaluate(theta, home(180.0));
  int compared = 0;
  for (std::size_t i = 0; i < sensors.size(); ++i) {
    const Eigen::Isometry3d& X = sensors[i].X_CS;
    const auto hit = embree.cast(X_WP.inverse() * X.translation(),
                                 X_WP.linear().transpose() * X.linear().col(2));
    if (!hit) {
      EXPECT_NE(r[i].body, scene.bodyIndex("part")) << i;
      continue;
    }
    ASSERT_EQ(r[i].body, scene.bodyIndex("part")) << i;
    // Embree casts in single precision: agreement to its rounding on a ~0.3 m ray.
    EXPECT_NEAR(r[i].distance, hit->distance, 2e-6) << i;
    ++compared;
  }
  EXPECT_GT(compared, 30);
}

TEST(Sensors, ABeamCarriedWithThePartReadsTheSameAtEveryTableAngle) {
  // The demo's part-present sensor: on the table, aimed across the axis along the part mesh's
  // plane of symmetry (through its triangles' shared edges). Sensor and part turn together, so
  // every table angle must give the same reading.
  Demo d = demo();
  Sensor s = beam("part_present", Eigen::Isometry3d::Identity(), 0.02, 0.3);
  s.carrier = "table";
  s.X_CS = config::toIsometry({{190.0, 0.0, 10.0}, {0.0, -90.0, 0.0}});  // as the job writes it
  s.p_SR = Eigen::Vector3d(0.0, 0.03, 0.0);
  d.cell.sensors = {s};
  const collision::Scene scene = sceneOf(d);
  collision::SensorEvaluator evaluator(scene);
  const auto first = evaluator.evaluate(0.0, home(180.0))[0];
  ASSERT_EQ(first.beam, collision::BeamStatus::kReading);
  EXPECT_EQ(first.body, scene.bodyIndex("part"));
  // Every 0.05° of a turn, and every 10⁻⁵° about −360° (the beam along the world's x axis,
  // where a planned demo trajectory once slipped between two triangles).
  std::vector<double> angles;
  for (int i = 1; i < 7200; ++i) angles.push_back(0.05 * i);
  for (int i = -10000; i <= 10000; ++i) angles.push_back(-360.0 + 1e-5 * i);
  for (const double a : angles) {
    const auto r = evaluator.evaluate(deg(a), home(180.0))[0];
    ASSERT_EQ(r.beam, collision::BeamStatus::kReading) << a << " deg";
    ASSERT_NEAR(r.distance, first.distance, kRangeTol) << a << " deg";
  }
}

TEST(Sensors, ReadingsAreBoundedBeforeAllocating) {
  Demo d = demo();
  for (std::size_t i = 0; i < config::kMaxSensors; ++i) {
    d.cell.sensors.push_back(presence("s" + std::to_string(i), "world",
                                      Eigen::Isometry3d::Identity(), kinematics::Sphere{0.01}));
  }
  const collision::Scene scene = sceneOf(d);
  const std::vector<TrajectorySample> samples(collision::kMaxSensorReadings / config::kMaxSensors +
                                              1);
  EXPECT_TRUE(test::throwsInputError(
      [&] { collision::evaluateSensors(scene, samples); },
      {"64 sensors at 156251 poses", "more than 10000000", "scanner.frame_rate_hz"}));
}

TEST(Sensors, EvaluationIsDeterministicWhateverTheThreadCount) {
  Curtain c = curtain();
  // With a triangulation sensor on the scanner too, looking down its laser axis.
  Sensor probe = beam("probe", Eigen::Isometry3d::Identity(), 0.05, 1.0);
  probe.carrier = "scanner";
  probe.p_SR = Eigen::Vector3d(0.1, 0.0, 0.0);
  c.d.cell.sensors.push_back(probe);
  const collision::Scene scene = sceneOf(c.d);
  const auto dense = planner::densify(c.trajectory, 0.05);
  const auto a = collision::evaluateSensors(scene, dense.samples);
  const auto b = collision::evaluateSensors(scene, dense.samples);
  collision::SensorEvaluation one_thread;
  {
    tbb::global_control serial(tbb::global_control::max_allowed_parallelism, 1);
    one_thread = collision::evaluateSensors(scene, dense.samples);
  }
  EXPECT_EQ(cli::sensorsCsv(scene, a), cli::sensorsCsv(scene, one_thread));
  EXPECT_EQ(cli::sensorsCsv(scene, a), cli::sensorsCsv(scene, b));
  EXPECT_EQ(cli::sensorsSummary(scene, a), cli::sensorsSummary(scene, b));
}

TEST(Sensors, CsvAndSummaryCarryTheSpans) {
  const Curtain c = curtain();
  const collision::Scene scene = sceneOf(c.d);
  const auto dense = planner::densify(c.trajectory, 0.01);
  const auto e = collision::evaluateSensors(scene, dense.samples);
  const std::string csv = cli::sensorsCsv(scene, e);
  EXPECT_EQ(csv.substr(0, csv.find('\n')), "t_s,light_curtain,light_curtain_bodies");
  const auto spans = collision::firingSpans(e, 0);
  ASSERT_EQ(spans.size(), 1u);
  EXPECT_NE(csv.find(fmt::format("{:.9f},1,scanner\n", spans[0].t_start)), std::string::npos);
  const std::string summary = cli::sensorsSummary(scene, e);
  EXPECT_NE(summary.find(fmt::format("sensor     light_curtain: fires {:.3f}–{:.3f} s (scanner); "
                                     "expect never: BROKEN",
                                     spans[0].t_start, spans[0].t_end)),
            std::string::npos)
      << summary;
}

// --- job keys -------------------------------------------------------------------------------

std::vector<std::string> withSensors(const std::string& sensors) {
  std::vector<std::string> o = test::kLightDemo;
  o.push_back("sensors=" + sensors);
  return o;
}

::testing::AssertionResult refused(const std::string& sensors,
                                   std::initializer_list<std::string> parts) {
  return test::throwsInputError(
      [&] {
        config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml", withSensors(sensors));
      },
      parts);
}

TEST(SensorJob, KeysBecomeTheCellsSensors) {
  const config::JobSpec job = config::loadJob(
      test::sourceDir() / "data/jobs/demo_rings.yaml",
      withSensors("[{name: curtain, kind: presence, carrier: world, shape: cylinder, "
                  "radius_mm: 20, length_mm: 300, pose: {xyz_mm: [0, 500, 100]}, expect: never},"
                  " {name: part_present, kind: distance, carrier: table, min_range_mm: 10, "
                  "max_range_mm: 400, receiver_mm: [30, 0, 0], expect: during, "
                  "window_s: [0, 5]}]"));
  const kinematics::CellModel cell = config::buildCell(job);
  ASSERT_EQ(cell.sensors.size(), 2u);
  const Sensor& a = cell.sensors[0];
  EXPECT_EQ(a.kind, Sensor::Kind::kPresence);
  EXPECT_EQ(a.expect.kind, SensorExpectation::Kind::kNever);
  const auto* cyl = std::get_if<kinematics::Cylinder>(&a.volume.geometry);
  ASSERT_NE(cyl, nullptr);
  EXPECT_DOUBLE_EQ(cyl->radius, 0.02);
  EXPECT_DOUBLE_EQ(cyl->length, 0.3);
  EXPECT_TRUE(a.X_CS.translation().isApprox(Eigen::Vector3d(0, 0.5, 0.1)));
  const Sensor& b = cell.sensors[1];
  EXPECT_EQ(b.kind, Sensor::Kind::kDistance);
  EXPECT_EQ(b.carrier, "table");
  EXPECT_DOUBLE_EQ(b.min_range, 0.01);
  EXPECT_DOUBLE_EQ(b.max_range, 0.4);
  ASSERT_TRUE(b.p_SR.has_value());
  EXPECT_TRUE(b.p_SR->isApprox(Eigen::Vector3d(0.03, 0, 0)));
  EXPECT_EQ(b.expect.kind, SensorExpectation::Kind::kDuring);
  EXPECT_EQ(b.expect.t1, 5.0);
  // Written back and read again: the same job.
  EXPECT_NE(config::jobToYaml(job).find("part_present"), std::string::npos);
}

TEST(SensorJob, TheDemosSensorsRoundTripThroughJobShow) {
  const std::string first =
      config::jobToYaml(config::loadJob(test::sourceDir() / "data/jobs/demo_sensors.yaml"));
  for (const char* key : {"light_curtain", "expect: never", "receiver_mm", "max_range_mm: 300",
                          "carrier: table", "shape: cylinder"}) {
    EXPECT_NE(first.find(key), std::string::npos) << key;
  }
  const auto file = std::filesystem::temp_directory_path() /
                    ("scanplan_test_sensors_shown_" + std::to_string(::getpid()) + ".yaml");
  std::ofstream(file) << first;
  const config::JobSpec again = config::loadJob(file);
  std::filesystem::remove(file);
  const std::string second = config::jobToYaml(again);
  EXPECT_EQ(second.substr(second.find('\n')), first.substr(first.find('\n')));
  EXPECT_EQ(config::buildCell(again).sensors.size(), 3u);
}

TEST(SensorJob, EveryBodyOfTheSceneMayCarryASensor) {
  const Demo d = demo();
  const collision::Scene scene = sceneOf(d);
  for (const collision::BodyInfo& body : scene.bodies()) {
    EXPECT_NO_THROW(config::loadJob(
        test::sourceDir() / "data/jobs/demo_rings.yaml",
        withSensors("[{name: s, kind: presence, shape: sphere, radius_mm: 5, carrier: " +
                    body.name + "}]")))
        << body.name;
  }
}

TEST(SensorJob, AnUnknownCarrierNamesTheFileTheKeyAndTheBodies) {
  // The demo job with absolute paths, a sensor on a link the robot does not have.
  std::ifstream in(test::sourceDir() / "data/jobs/demo_sensors.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string data = (test::sourceDir() / "data").string();
  for (const char* dir : {"robots", "parts"}) {
    const std::string from = std::string("../") + dir, to = data + "/" + dir;
    text.replace(text.find(from), from.size(), to);
  }
  text.replace(text.find("carrier: table"), 14, "carrier: link9");
  const auto file = std::filesystem::temp_directory_path() /
                    ("scanplan_test_sensors_" + std::to_string(::getpid()) + ".yaml");
  std::ofstream(file) << text;
  EXPECT_TRUE(
      test::throwsInputError([&] { config::loadJob(file); },
                             {file.string() + ":", "sensors[2].carrier", "'link9'",
                              "world or a body of the cell", "link6", "scanner", "table", "part"}));
  std::filesystem::remove(file);
}

TEST(SensorJob, BadKeysAreRefusedNamingTheKey) {
  EXPECT_TRUE(refused("[{name: s, kind: presence, shape: sphere, radius_mm: 5, carrier: link9}]",
                      {"sensors[0].carrier", "'link9'", "world or a body of the cell", "link6",
                       "scanner", "table", "part"}));
  EXPECT_TRUE(refused("[{name: s, kind: radar}]", {"sensors[0].kind", "radar", "presence"}));
  EXPECT_TRUE(refused("[{name: s, kind: presence, shape: box, size_mm: [10, -1, 10]}]",
                      {"sensors[0].size_mm"}));
  EXPECT_TRUE(refused("[{name: s, kind: presence, shape: cone, radius_mm: 3}]",
                      {"sensors[0].shape", "cone"}));
  EXPECT_TRUE(refused("[{name: s, kind: distance, min_range_mm: 300, max_range_mm: 300}]",
                      {"sensors[0].max_range_mm", "300", "above min_range_mm"}));
  EXPECT_TRUE(refused("[{name: s, kind: distance}]", {"sensors[0]", "max_range_mm"}));
  EXPECT_TRUE(
      refused("[{name: s, kind: presence, shape: sphere, radius_mm: 5, expect: during, "
              "window_s: [4, 2]}]",
              {"sensors[0].window_s", "t0_s <= t1_s"}));
  EXPECT_TRUE(refused("[{name: s, kind: presence, shape: sphere, radius_mm: 5, expect: during}]",
                      {"sensors[0]", "window_s"}));
  EXPECT_TRUE(refused("[{name: s, kind: presence, shape: sphere, radius_mm: 5, expect: sometimes}]",
                      {"sensors[0].expect", "sometimes"}));
  EXPECT_TRUE(
      refused("[{name: 'a,b', kind: presence, shape: sphere, radius_mm: 5}]", {"sensors[0].name"}));
  EXPECT_TRUE(
      refused("[{name: s, kind: presence, shape: sphere, radius_mm: 5}, "
              "{name: s, kind: presence, shape: sphere, radius_mm: 5}]",
              {"sensors", "two sensors named 's'"}));
  // Names whose sensors.csv columns would clash: the time column, or a presence sensor x_mm
  // beside a distance sensor x.
  EXPECT_TRUE(refused("[{name: t_s, kind: presence, shape: sphere, radius_mm: 5}]",
                      {"sensors", "second column 't_s'"}));
  EXPECT_TRUE(
      refused("[{name: x, kind: distance, max_range_mm: 300}, "
              "{name: x_mm, kind: presence, shape: sphere, radius_mm: 5}]",
              {"sensors", "second column 'x_mm'"}));
  std::string many = "[";
  for (std::size_t i = 0; i <= config::kMaxSensors; ++i) {
    many += fmt::format("{}{{name: s{}, kind: presence, shape: sphere, radius_mm: 5}}",
                        i ? ", " : "", i);
  }
  EXPECT_TRUE(refused(many + "]", {"sensors", "64"}));
}

// --- the commands ---------------------------------------------------------------------------

const std::string kSensorJob = (test::sourceDir() / "data/jobs/demo_sensors.yaml").string();

std::vector<std::string> lightly(std::vector<std::string> args) {
  for (const std::string& o : test::kLightDemo) {
    args.push_back("--set");
    args.push_back(o);
  }
  return args;
}

namespace fs = std::filesystem;

class SensorCli : public test::Cli {};

// The demo's sensors through plan, validate and simulate: sensors.csv has a row per validation
// pose and the columns of each sensor, the summary says when each fires, report.json carries
// them, and a broken rule fails validation (exit 3) naming the sensor, the rule and the span.
TEST_F(SensorCli, PlanValidateAndSimulateWriteTheSensorsOutputs) {
  const fs::path out = dir_ / "plan";
  const test::Result plan = scanplan(
      lightly({"plan", kSensorJob, "-o", out.string(), "--set", "simulation.enabled=false"}));
  ASSERT_EQ(plan.exit_code, 0) << test::describe(plan);
  EXPECT_TRUE(test::contains(plan.out, "sensor     light_curtain: never fires; expect never: met"))
      << plan.out;
  EXPECT_TRUE(test::contains(plan.out, "sensor     part_present: reads 0.000–"));
  EXPECT_TRUE(test::contains(plan.out, "expect always: met"));
  const std::string csv = test::readFile(out / "sensors.csv");
  std::istringstream lines(csv);
  std::string header, row;
  std::getline(lines, header);
  EXPECT_EQ(header,
            "t_s,light_curtain,light_curtain_bodies,over_part,over_part_bodies,part_present_mm,"
            "part_present_status,part_present_body");
  std::size_t rows = 0;
  double end = 0.0;  // s, the last pose's time
  while (std::getline(lines, row)) {
    ++rows;
    end = std::stod(row);
    EXPECT_EQ(std::count(row.begin(), row.end(), ','), 7) << row;
    EXPECT_TRUE(test::contains(row, ",0,,")) << row;           // the curtain stays dark
    EXPECT_TRUE(test::contains(row, ",reading,part")) << row;  // the part is always there
  }
  const YAML::Node report = YAML::LoadFile((out / "report.json").string());
  EXPECT_EQ(rows, report["validation"]["poses"].as<std::size_t>());
  ASSERT_EQ(report["sensors"].size(), 3u);
  EXPECT_EQ(report["sensors"][0]["name"].as<std::string>(), "light_curtain");
  EXPECT_TRUE(report["sensors"][0]["rule_met"].as<bool>());
  EXPECT_EQ(report["sensors"][0]["spans"].size(), 0u);
  EXPECT_EQ(report["sensors"][2]["firing_samples"].as<std::size_t>(), rows);

  // The curtain expected to fire all along: the validation of the same trajectory fails.
  const fs::path trajectory = out / "trajectory.csv";
  const test::Result bad =
      scanplan(lightly({"validate", kSensorJob, "-t", trajectory.string(), "-o",
                        (dir_ / "v").string(), "--set", "sensors[0].expect=always"}));
  EXPECT_EQ(bad.exit_code, 3) << test::describe(bad);
  EXPECT_TRUE(test::contains(
      bad.out,
      fmt::format("sensor: light_curtain 0.000 … {:.3f} s: expect always: does not fire", end)))
      << bad.out;
  EXPECT_TRUE(test::contains(bad.out, "expect always: BROKEN"));
  EXPECT_EQ(test::readFile(dir_ / "v" / "sensors.csv"), csv);
  const YAML::Node v = YAML::LoadFile((dir_ / "v" / "validation.json").string());
  EXPECT_FALSE(v["validation"]["valid"].as<bool>());
  EXPECT_EQ(v["validation"]["violations"][0]["kind"].as<std::string>(), "sensor");
  EXPECT_FALSE(v["sensors"][0]["rule_met"].as<bool>());

  // check: the sensors at one pose.
  const test::Result check =
      scanplan({"check", kSensorJob, "--table", "30", "--time", "5", "--json"});
  ASSERT_EQ(check.exit_code, 0) << test::describe(check);
  const YAML::Node c = YAML::Load(check.out);
  ASSERT_EQ(c["sensors"].size(), 3u);
  EXPECT_FALSE(c["sensors"][0]["fires"].as<bool>());
  EXPECT_EQ(c["sensors"][2]["status"].as<std::string>(), "reading");
  EXPECT_EQ(c["sensors"][2]["body"].as<std::string>(), "part");

  // simulate writes the same file beside the cloud.
  const test::Result sim =
      scanplan(lightly({"simulate", kSensorJob, "-t", trajectory.string(), "-o",
                        (dir_ / "s").string(), "--set", "scanner.rays_per_profile=10"}));
  ASSERT_EQ(sim.exit_code, 0) << test::describe(sim);
  EXPECT_TRUE(test::contains(sim.out, "sensor     light_curtain: never fires"));
  EXPECT_EQ(test::readFile(dir_ / "s" / "sensors.csv"), csv);
}

}  // namespace
