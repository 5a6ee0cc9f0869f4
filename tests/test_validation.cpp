// Trajectory validation: densification, limits and rates, and the continuous collision check —
// its motion bound holds on random motions, a motion through an obstacle between two clear
// samples is caught (cross-checked against brute-force sampling), a planned demo trajectory
// passes, and the report does not depend on the thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include <scanplan/collision/clearance.h>
#include <scanplan/collision/scene.h>
#include <scanplan/config/job.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/shape.h>
#include <scanplan/kinematics/trajectory.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/pipeline/plan_scan.h>
#include <scanplan/planner/trajectory_builder.h>
#include <scanplan/planner/validation.h>
#include "cli/commands/commands.h"
#include "test_support.h"

namespace {

using namespace scanplan;
using kinematics::JointVector;
using kinematics::Trajectory;
using kinematics::TrajectorySample;
using planner::ValidationReport;
using planner::ValidationSettings;
using planner::Violation;

// Speeds are formed as Δq/Δt from sample values: exact to rounding.
constexpr double kRateTol = 1e-9;
// The first contact is found to collision_resolution (1e-4 m) of relative motion, and an end
// within ~2e-4 m of contact already counts: the reported first contact may lead the first
// penetrating brute-force sample by the time the bodies take to close well under 1 mm.
// The swept arm's scanner moves at ~0.8 m/s: 1 mm in ~1.3 ms.
constexpr double kSweepLead = 2e-3;  // s
// The table-carried spike moves at 0.15 m · 30°/s ≈ 0.08 m/s: 1 mm in ~13 ms.
constexpr double kTableLead = 2e-2;  // s
// The contact point: the midpoint of witness points ≤ ~2e-4 m apart, off the obstacle by half.
constexpr double kContactPointTol = 1e-3;  // m

JointVector jointsDeg(double q1, double q2, double q3, double q4, double q5, double q6) {
  JointVector q;
  q << deg(q1), deg(q2), deg(q3), deg(q4), deg(q5), deg(q6);
  return q;
}

// The arm folded over itself, scanner pointing down (docs/design.md §3.1 golden pose, J1 turned).
JointVector home(double q1_deg) { return jointsDeg(q1_deg, -90.0, 180.0, 0.0, 90.0, 0.0); }

TrajectorySample sample(double t, double theta, const JointVector& q) {
  TrajectorySample s;
  s.t = t;
  s.theta = theta;
  s.q = q;
  return s;
}

struct DemoCell {
  config::JobSpec job;
  kinematics::CellModel cell;
};

DemoCell demoCell() {
  config::JobSpec job =
      config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml", test::kLightDemo);
  kinematics::CellModel cell = config::buildCell(job);
  return {std::move(job), std::move(cell)};
}

kinematics::Obstacle box(const std::string& name,
                         kinematics::Carrier carrier,
                         const Eigen::Vector3d& centre,
                         const Eigen::Vector3d& size) {
  kinematics::Shape shape;
  shape.geometry = kinematics::Box{size};
  shape.X_BG.translation() = centre;
  return {name, carrier, {shape}};
}

// Distance from a point to an axis-aligned box (0 inside).
double distanceToBox(const Eigen::Vector3d& p,
                     const Eigen::Vector3d& centre,
                     const Eigen::Vector3d& size) {
  const Eigen::Vector3d d = ((p - centre).cwiseAbs() - 0.5 * size).cwiseMax(0.0);
  return d.norm();
}

// The first time a linear motion between two samples penetrates, sampling every `step` (s);
// negative when no sample does.
double bruteFirstContact(const collision::Scene& scene,
                         const TrajectorySample& a,
                         const TrajectorySample& b,
                         double step) {
  collision::ClearanceEvaluator evaluator(scene);
  const auto steps = static_cast<int>(std::ceil((b.t - a.t) / step));
  for (int i = 0; i <= steps; ++i) {
    const double s = static_cast<double>(i) / steps;
    if (evaluator.evaluate(a.theta + s * (b.theta - a.theta), a.q + s * (b.q - a.q)).collision) {
      return a.t + s * (b.t - a.t);
    }
  }
  return -1.0;
}

::testing::AssertionResult noPenetration(const collision::Scene& scene, const Trajectory& tr) {
  collision::ClearanceEvaluator evaluator(scene);
  for (const TrajectorySample& s : tr.samples) {
    if (evaluator.evaluate(s.theta, s.q).collision) {
      return ::testing::AssertionFailure() << "the sample at t = " << s.t << " s penetrates";
    }
  }
  return ::testing::AssertionSuccess();
}

std::string listed(const ValidationReport& r) {
  std::string out;
  for (const Violation& v : r.violations) out += "\n  " + planner::describe(v);
  return out;
}

std::vector<Violation> ofKind(const ValidationReport& r, Violation::Kind kind) {
  std::vector<Violation> out;
  for (const Violation& v : r.violations) {
    if (v.kind == kind) out.push_back(v);
  }
  return out;
}

TEST(Densify, KeepsTheSamplesAndIsLinearBetweenThem) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Trajectory tr;
  double t = 0.3;
  for (int k = 0; k < 30; ++k) {
    JointVector q;
    for (int j = 0; j < kinematics::kNumJoints; ++j) q(j) = 2.0 * u(rng);
    tr.samples.push_back(sample(t, 5.0 * u(rng), q));
    tr.samples.back().scanning = k % 3 != 0;
    t += k == 7 ? 0.074 : 0.05 + 0.2 * (1.0 + u(rng));  // 0.074 = exactly 2 steps of 0.037
  }
  const double dt = 0.037;
  const Trajectory d = planner::densify(tr, dt);
  std::size_t next = 0;  // the next original sample to find
  for (std::size_t i = 0; i < d.samples.size(); ++i) {
    const TrajectorySample& s = d.samples[i];
    if (i > 0) {
      ASSERT_GT(s.t, d.samples[i - 1].t) << i;
      EXPECT_LE(s.t - d.samples[i - 1].t, dt * (1.0 + 1e-9)) << i;
    }
    if (next < tr.samples.size() && s.t == tr.samples[next].t) {
      EXPECT_EQ(s.theta, tr.samples[next].theta);
      EXPECT_EQ(s.q, tr.samples[next].q);
      EXPECT_EQ(s.scanning, tr.samples[next].scanning);
      ++next;
      continue;
    }
    ASSERT_GT(next, 0u);
    ASSERT_LT(next, tr.samples.size());
    const TrajectorySample &a = tr.samples[next - 1], &b = tr.samples[next];
    const double w = (s.t - a.t) / (b.t - a.t);
    EXPECT_NEAR(s.theta, a.theta + w * (b.theta - a.theta), 1e-12);
    EXPECT_LT((s.q - (a.q + w * (b.q - a.q))).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_TRUE(std::isnan(s.f));
    EXPECT_EQ(s.scanning, a.scanning && b.scanning);
  }
  EXPECT_EQ(next, tr.samples.size());  // every original sample is there, in order
  // n = ⌈Δt/dt⌉ steps per interval: the 0.074 s interval gets exactly one new sample.
  std::size_t expected = tr.samples.size();
  for (std::size_t k = 0; k + 1 < tr.samples.size(); ++k) {
    expected +=
        static_cast<std::size_t>(std::ceil((tr.samples[k + 1].t - tr.samples[k].t) / dt - 1e-9)) -
        1;
  }
  EXPECT_EQ(d.samples.size(), expected);
}

TEST(Densify, RejectsABadStepAndTimesThatDoNotIncrease) {
  Trajectory tr;
  tr.samples = {sample(0.0, 0.0, home(0.0)), sample(1.0, 0.0, home(0.0))};
  EXPECT_THROW(planner::densify(tr, 0.0), std::invalid_argument);
  EXPECT_THROW(planner::densify(tr, -0.1), std::invalid_argument);
  EXPECT_THROW(planner::densify(tr, std::nan("")), std::invalid_argument);
  EXPECT_EQ(planner::densify(tr, 5.0).samples.size(), 2u);  // a step longer than the interval
  tr.samples[1].t = 0.0;
  EXPECT_THROW(planner::densify(tr, 0.1), std::invalid_argument);
  // Too many poses is the input's fault (a 100 000 s trajectory at 100 Hz): an InputError
  // naming the duration and the bound, before anything is allocated.
  tr.samples[1].t = 100000.0;
  try {
    planner::densify(tr, 0.01);
    ADD_FAILURE() << "no error";
  } catch (const scanplan::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "100000 s sampled every 0.01 s would be more than 5000000 poses"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(planner::densify(tr, 1000.0).samples.size(), 101u);
}

// A joint faster than its max_speed is one kJointSpeed run with its joint, value and limit.
TEST(Validate, JointSpeedViolationIsOneRunWithJointValueAndLimit) {
  const DemoCell d = demoCell();
  const collision::Scene scene(d.cell, config::clearanceConfig(d.job));
  // J6 (max 600°/s) turns at 20 rad/s ≈ 1146°/s from t = 0.2 to 0.6 s; still otherwise. The
  // scanner spins about its own axis away from the table: nothing else can fail.
  Trajectory tr;
  double q6 = 0.0;
  for (int k = 0; k <= 10; ++k) {
    const double t = 0.1 * k;
    if (k >= 3 && k <= 6) q6 += 20.0 * 0.1;
    JointVector q = home(-90.0);
    q(5) = q6 - 4.0;
    tr.samples.push_back(sample(t, 0.0, q));
  }
  const ValidationReport r = planner::validateTrajectory(scene, tr, {.sample_dt = 0.01});
  EXPECT_FALSE(r.valid);
  ASSERT_EQ(r.violations.size(), 1u) << listed(r);
  const Violation& v = r.violations[0];
  EXPECT_EQ(v.kind, Violation::Kind::kJointSpeed);
  EXPECT_EQ(v.joint, 5);
  EXPECT_EQ(v.what, "joint 6");
  EXPECT_NEAR(v.value, 20.0, 20.0 * kRateTol);
  EXPECT_NEAR(v.limit, deg(600.0), 1e-12);
  EXPECT_NEAR(v.t_start, 0.2, 1e-12);
  EXPECT_NEAR(v.t_end, 0.6, 1e-12);
  EXPECT_FALSE(r.first_collision);
  EXPECT_GT(r.min_distance, 0.0);
  EXPECT_NE(planner::describe(v).find("deg/s > 600.00 deg/s"), std::string::npos)
      << planner::describe(v);
}

// Robustness catalogue: a joint thousands of degrees away between two samples gave
// the continuous collision check an interval it splits without end (bad_alloc after minutes).
// Its worst case is estimated first, from the motion bounds, and refused over the limit.
TEST(Validate, ARefinementWithoutEndIsRefusedBeforeItRuns) {
  const DemoCell d = demoCell();
  const collision::Scene scene(d.cell, config::clearanceConfig(d.job));
  // J2 through 100 000° in 0.1 s: bounds of about 100 m per 10 ms step, 2^20 halvings of
  // 0.1 mm each on every step whose ends do not prove the pairs apart.
  Trajectory tr;
  tr.samples.push_back(sample(0.0, 0.0, home(-90.0)));
  JointVector far = home(-90.0);
  far(1) += deg(100000.0);
  tr.samples.push_back(sample(0.1, 0.0, far));
  EXPECT_TRUE(
      test::throwsInputError([&] { planner::validateTrajectory(scene, tr, {.sample_dt = 0.01}); },
                             {"the continuous collision check could need up to ", " poses",
                              "more than 5000000", "validation.collision_resolution_mm"}));
  // A step a joint can take is judged as before.
  tr.samples.back().q(1) = home(-90.0)(1) + deg(10.0);
  EXPECT_NO_THROW(planner::validateTrajectory(scene, tr, {.sample_dt = 0.01}));
}

// Table: ω_max = 30°/s ≈ 0.524 rad/s, α_max = 60°/s² ≈ 1.047 rad/s² (the demo job). Speeds per
// 0.1 s step 0, 0.5, 0.5, 0.5, 1.0, 1.0, 0.5 rad/s: α = ±5 rad/s² at the knots 0.1, 0.4 and
// 0.6 s; ω > ω_max on [0.4, 0.6].
TEST(Validate, TableSpeedAndAccelerationAreJudgedOnTheirOwnSamples) {
  const DemoCell d = demoCell();
  const collision::Scene scene(d.cell, config::clearanceConfig(d.job));
  const std::vector<double> omega{0.0, 0.5, 0.5, 0.5, 1.0, 1.0, 0.5};
  Trajectory tr;
  double theta = 0.0;
  tr.samples.push_back(sample(0.0, theta, home(-90.0)));
  for (std::size_t k = 0; k < omega.size(); ++k) {
    theta += omega[k] * 0.1;
    tr.samples.push_back(sample(0.1 * static_cast<double>(k + 1), theta, home(-90.0)));
  }
  const ValidationReport r = planner::validateTrajectory(scene, tr, {.sample_dt = 0.01});
  EXPECT_FALSE(r.valid);
  const auto speed = ofKind(r, Violation::Kind::kTableSpeed);
  ASSERT_EQ(speed.size(), 1u) << listed(r);
  EXPECT_EQ(speed[0].what, "table");
  EXPECT_NEAR(speed[0].value, 1.0, kRateTol);
  EXPECT_NEAR(speed[0].limit, deg(30.0), 1e-12);
  EXPECT_NEAR(speed[0].t_start, 0.4, 1e-12);
  EXPECT_NEAR(speed[0].t_end, 0.6, 1e-12);
  // Densifying at 0.01 s adds no acceleration: it is judged on the original samples only.
  const auto accel = ofKind(r, Violation::Kind::kTableAccel);
  ASSERT_EQ(accel.size(), 3u) << listed(r);
  const double knots[] = {0.1, 0.4, 0.6};
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_NEAR(accel[i].t, knots[i], 1e-12);
    EXPECT_NEAR(accel[i].value, 5.0, 5.0 * kRateTol);
    EXPECT_NEAR(accel[i].limit, deg(60.0), 1e-12);
  }
  EXPECT_EQ(r.violations.size(), 4u) << listed(r);
  // Explicit bounds override the cell's table.
  const ValidationReport loose = planner::validateTrajectory(
      scene, tr, {.sample_dt = 0.01, .table_omega_max = 1.0, .table_alpha_max = 5.0});
  EXPECT_TRUE(loose.valid) << listed(loose);
}

// θ = α·t²/2 sampled every 0.1 s has second differences exactly α: α = 1 rad/s² < 60°/s² and
// ω ≤ 0.5 rad/s < 30°/s pass.
TEST(Validate, SmoothTableMotionWithinBoundsPasses) {
  const DemoCell d = demoCell();
  const collision::Scene scene(d.cell, config::clearanceConfig(d.job));
  Trajectory tr;
  for (int k = 0; k <= 5; ++k) {
    const double t = 0.1 * k;
    tr.samples.push_back(sample(t, 0.5 * t * t, home(-90.0)));
  }
  const ValidationReport r = planner::validateTrajectory(scene, tr, {.sample_dt = 0.01});
  EXPECT_TRUE(r.valid) << listed(r);
  EXPECT_GT(r.proven_clearance, 0.0);
}

// J6 (±360°) passes +360° at 20°/s: one kJointLimit run from the first densified pose beyond it.
TEST(Validate, JointLimitViolationIsOneRunWithTheWorstValue) {
  const DemoCell d = demoCell();
  const collision::Scene scene(d.cell, config::clearanceConfig(d.job));
  Trajectory tr;
  for (int k = 0; k <= 10; ++k) {
    JointVector q = home(-90.0);
    q(5) = deg(350.0 + 2.0 * k);
    tr.samples.push_back(sample(0.1 * k, 0.0, q));
  }
  const ValidationReport r = planner::validateTrajectory(scene, tr, {.sample_dt = 0.01});
  ASSERT_EQ(r.violations.size(), 1u) << listed(r);
  const Violation& v = r.violations[0];
  EXPECT_EQ(v.kind, Violation::Kind::kJointLimit);
  EXPECT_EQ(v.joint, 5);
  EXPECT_NEAR(v.t_start, 0.51, 1e-9);  // 350° + 20°/s·t > 360° from t = 0.5 on
  EXPECT_NEAR(v.t_end, 1.0, 1e-12);
  EXPECT_NEAR(v.t, 1.0, 1e-12);
  EXPECT_NEAR(v.value, deg(370.0), 1e-12);
  EXPECT_NEAR(v.limit, deg(360.0), 1e-12);
}

// Surface points of every scene body in its body frame (the frame Scene::bodyPoses places),
// collected independently of the validator from the cell's shapes.
std::vector<std::vector<Eigen::Vector3d>> bodyPoints(const collision::Scene& scene) {
  const kinematics::CellModel& cell = scene.cell();
  const kinematics::TessellationOptions coarse{
      .chord_tolerance = 1e-3, .min_segments = 12, .max_segments = 24};
  std::vector<std::vector<Eigen::Vector3d>> out;
  for (const collision::BodyInfo& body : scene.bodies()) {
    std::vector<kinematics::Shape> shapes;
    if (body.motion == collision::BodyMotion::kRobotLink) {
      shapes = cell.robot.definition().links[static_cast<std::size_t>(body.link)].shapes;
    } else if (body.motion == collision::BodyMotion::kScanner) {
      shapes = cell.scanner.body;
    } else if (body.name == "table") {
      kinematics::Shape s;
      s.geometry = kinematics::Cylinder{cell.table.radius, cell.table.height};
      s.X_BG.translation().z() = -0.5 * cell.table.height;
      shapes = {s};
    } else if (body.name == "part") {
      kinematics::Shape s;
      s.geometry = cell.part.mesh;
      s.X_BG = cell.part.X_RP;
      shapes = {s};
    } else {
      for (const auto& o : cell.obstacles) {
        if (o.name == body.name) shapes = o.shapes;
      }
    }
    std::vector<Eigen::Vector3d> points;
    for (const auto& shape : shapes) {
      const kinematics::TriangleMesh mesh = kinematics::shapeSurface(shape, coarse);
      const std::size_t stride = std::max<std::size_t>(1, mesh.vertices.size() / 400);
      for (std::size_t i = 0; i < mesh.vertices.size(); i += stride) {
        points.push_back(mesh.vertices[i]);
      }
    }
    out.push_back(std::move(points));
  }
  return out;
}

// The conservative-advancement bound holds over random linear motions of the joints and the
// table (16 steps along each). The distance of two bodies is Lipschitz in either of two
// displacements: that of one body's points in the other's frame (d(u') ≤ |p − X_AB(u')·q| ≤
// d(u) + |ΔX_AB·q| for the closest p, q), or the sum of both bodies' world displacements.
// pairMotion() bounds the first for two bodies on the arm's chain (the far link's points in the
// near link's frame) and the second otherwise; each is measured here on surface points.
TEST(MotionBound, BoundsTheRelativeMotionOfEveryPair) {
  DemoCell d = demoCell();
  d.cell.obstacles.push_back(box("fixture", kinematics::Carrier::kTable,
                                 Eigen::Vector3d(0.1, -0.05, 0.2),
                                 Eigen::Vector3d(0.05, 0.1, 0.2)));
  d.cell.obstacles.push_back(box("wall", kinematics::Carrier::kWorld,
                                 Eigen::Vector3d(0.0, -0.6, 0.5), Eigen::Vector3d(1.0, 0.02, 1.0)));
  d.cell.table.tilt = Eigen::Vector2d(0.02, -0.01);  // an imperfect table: the bound must hold
  d.cell.table.eccentricity = Eigen::Vector2d(0.003, 0.001);
  const collision::Scene scene(d.cell, config::clearanceConfig(d.job));
  const auto bounds = planner::detail::bodyBounds(scene);
  const auto points = bodyPoints(scene);
  ASSERT_EQ(bounds.size(), scene.bodies().size());
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double tightest = 0.0;  // the largest displacement / bound seen
  for (int trial = 0; trial < 20; ++trial) {
    const JointVector qa = test::randomJoints(d.cell.robot, rng);
    JointVector dq_signed;
    for (int j = 0; j < kinematics::kNumJoints; ++j) dq_signed(j) = 0.4 * u(rng);
    const double theta_a = 3.0 * u(rng), dtheta_signed = 0.6 * u(rng);
    std::array<double, kinematics::kNumJoints> dq{};
    for (int j = 0; j < kinematics::kNumJoints; ++j) {
      dq[static_cast<std::size_t>(j)] = std::abs(dq_signed(j));
    }
    std::vector<std::vector<Eigen::Isometry3d>> X(17);
    for (int k = 0; k <= 16; ++k) {
      const double s = k / 16.0;
      scene.bodyPoses(theta_a + s * dtheta_signed, qa + s * dq_signed,
                      X[static_cast<std::size_t>(k)]);
    }
    for (const collision::PairInfo& pair : scene.pairs()) {
      const auto a = static_cast<std::size_t>(pair.a), b = static_cast<std::size_t>(pair.b);
      const double L =
          planner::detail::pairMotion(bounds[a], bounds[b], dq, std::abs(dtheta_signed));
      const auto displacement = [&](std::size_t moving, std::optional<std::size_t> frame) {
        double worst = 0.0;
        for (const Eigen::Vector3d& p : points[moving]) {
          const auto at = [&](std::size_t k) {
            const Eigen::Vector3d p_W = X[k][moving] * p;
            return frame ? Eigen::Vector3d(X[k][*frame].inverse() * p_W) : p_W;
          };
          const Eigen::Vector3d p0 = at(0);
          for (std::size_t k = 1; k <= 16; ++k) worst = std::max(worst, (at(k) - p0).norm());
        }
        return worst;
      };
      const int la = scene.bodies()[a].link, lb = scene.bodies()[b].link;
      const double moved = la >= 0 && lb >= 0
                               ? (la >= lb ? displacement(a, b) : displacement(b, a))
                               : displacement(a, std::nullopt) + displacement(b, std::nullopt);
      ASSERT_LE(moved, L * (1.0 + 1e-9) + 1e-12)
          << scene.bodies()[a].name << " - " << scene.bodies()[b].name << ", trial " << trial;
      if (L > 0.0) tightest = std::max(tightest, moved / L);
    }
  }
  // Not vacuous: some pair comes within a factor of 2 of its bound.
  EXPECT_GT(tightest, 0.5);
  std::printf("motion bound: largest displacement / bound %.3f\n", tightest);
}

// A limited table (±90°) turned to 100° at 20°/s: one kTableLimit run.
TEST(Validate, LimitedTableTravelIsChecked) {
  DemoCell d = demoCell();
  d.cell.table.continuous = false;
  d.cell.table.min = deg(-90.0);
  d.cell.table.max = deg(90.0);
  const collision::Scene scene(d.cell, config::clearanceConfig(d.job));
  Trajectory tr;
  tr.samples = {sample(0.0, deg(60.0), home(-90.0)), sample(2.0, deg(100.0), home(-90.0))};
  const ValidationReport r = planner::validateTrajectory(scene, tr, {.sample_dt = 0.1});
  ASSERT_EQ(r.violations.size(), 1u) << listed(r);
  const Violation& v = r.violations[0];
  EXPECT_EQ(v.kind, Violation::Kind::kTableLimit);
  EXPECT_NEAR(v.t_start, 1.6, 1e-9);  // the first pose past 90°: 60° + 20°/s · 1.6 s = 92°
  EXPECT_NEAR(v.t, 2.0, 1e-12);
  EXPECT_NEAR(v.value, deg(100.0), 1e-12);
  EXPECT_NEAR(v.limit, deg(90.0), 1e-12);
}

// The arm sweeps J1 from 30° to 150° in 1 s past a post standing where the scanner is at 90°.
struct Sweep {
  DemoCell demo = demoCell();
  Eigen::Vector3d post_centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d post_size{0.06, 0.06, 0.06};
  Trajectory trajectory;

  Sweep() {
    // The scanner housing's centre (55 mm up the laser axis from S) at J1 = 90°.
    const Eigen::Isometry3d X_WS =
        demo.cell.X_WB * demo.cell.robot.fk(home(90.0)) * demo.cell.scanner.X_FS;
    post_centre = X_WS * Eigen::Vector3d(0.0, 0.0, -0.055);
    demo.cell.obstacles.push_back(box("post", kinematics::Carrier::kWorld, post_centre, post_size));
    trajectory.samples = {sample(0.0, 0.0, home(30.0)), sample(1.0, 0.0, home(150.0))};
  }
};

TEST(Validate, MotionThroughAnObstacleBetweenClearSamplesIsCaught) {
  const Sweep sweep;
  const collision::Scene scene(sweep.demo.cell, config::clearanceConfig(sweep.demo.job));
  // Step 0.34 s: poses at J1 = 30, 70, 110, 150° — all clear of the post (checked), which sits
  // between the 2nd and the 3rd.
  const ValidationSettings settings{.sample_dt = 0.34};
  const Trajectory dense = planner::densify(sweep.trajectory, settings.sample_dt);
  ASSERT_EQ(dense.samples.size(), 4u);
  ASSERT_TRUE(noPenetration(scene, dense));

  const ValidationReport r = planner::validateTrajectory(scene, sweep.trajectory, settings);
  EXPECT_FALSE(r.valid);
  ASSERT_TRUE(r.first_collision) << listed(r);
  const Violation& c = *r.first_collision;
  EXPECT_EQ(c.kind, Violation::Kind::kCollision);
  EXPECT_NE(c.what.find("post"), std::string::npos) << c.what;
  EXPECT_GT(c.t, dense.samples[1].t);
  EXPECT_LT(c.t, dense.samples[2].t);
  EXPECT_LE(c.t_start, c.t);
  EXPECT_GT(c.t_end, c.t);  // the scanner is inside the post for a while
  EXPECT_LT(c.value, 3e-4);
  EXPECT_LT(distanceToBox(c.p_W, sweep.post_centre, sweep.post_size), kContactPointTol)
      << c.p_W.transpose();
  // Sound and tight: never after the first penetrating pose of brute-force sampling, and not
  // much before it.
  // (One pose every 1e-4 s: the scanner moves < 0.1 mm between them.)
  const double brute =
      bruteFirstContact(scene, sweep.trajectory.samples[0], sweep.trajectory.samples[1], 1e-4);
  ASSERT_GT(brute, 0.0);
  EXPECT_LE(c.t, brute);
  EXPECT_GT(c.t, brute - kSweepLead);
  // Only the post's pairs collide, each in one run.
  for (const Violation& v : r.violations) {
    EXPECT_EQ(v.kind, Violation::Kind::kCollision) << planner::describe(v);
    EXPECT_NE(v.what.find("post"), std::string::npos) << v.what;
  }
  EXPECT_EQ(r.min_distance, 0.0);
  EXPECT_EQ(r.proven_clearance, 0.0);
  std::printf("sweep: %zu poses checked, first contact %s\n", r.poses_checked,
              planner::describe(c).c_str());
}

// Static arm, turning table: a post the table carries passes through the scanner between two
// samples 4 s apart (table at 30°/s, nothing densified in between).
TEST(Validate, TableCarriedObstacleBetweenSamplesIsCaught) {
  DemoCell d = demoCell();
  // The scanner hangs at x = 370 mm, 150 mm from the table axis towards the robot: the post, at
  // 120° on a 150 mm circle of the table top, reaches it when the table has turned by 60°.
  const Eigen::Isometry3d X_WS = d.cell.X_WB * d.cell.robot.fk(home(0.0)) * d.cell.scanner.X_FS;
  const Eigen::Vector3d p_WS = X_WS * Eigen::Vector3d(0.0, 0.0, -0.055);
  const Eigen::Vector3d p_AS = d.cell.table.X_WA.inverse() * p_WS;
  const double radius = p_AS.head<2>().norm();
  const double at = std::atan2(p_AS.y(), p_AS.x()) - deg(60.0);
  const Eigen::Vector3d centre(radius * std::cos(at), radius * std::sin(at), p_AS.z());
  const Eigen::Vector3d size(0.03, 0.03, 0.06);
  d.cell.obstacles.push_back(box("spike", kinematics::Carrier::kTable, centre, size));
  const collision::Scene scene(d.cell, config::clearanceConfig(d.job));

  Trajectory tr;
  tr.samples = {sample(0.0, 0.0, home(0.0)), sample(4.0, deg(120.0), home(0.0))};
  const ValidationSettings settings{.sample_dt = 5.0};
  ASSERT_EQ(planner::densify(tr, settings.sample_dt).samples.size(), 2u);
  ASSERT_TRUE(noPenetration(scene, tr));
  const ValidationReport r = planner::validateTrajectory(scene, tr, settings);
  ASSERT_TRUE(r.first_collision) << listed(r);
  const Violation& c = *r.first_collision;
  EXPECT_NE(c.what.find("spike"), std::string::npos) << c.what;
  EXPECT_GT(c.t, 0.0);
  EXPECT_LT(c.t, 2.0);  // before the centres meet at 60° (t = 2 s)
  const double brute = bruteFirstContact(scene, tr.samples[0], tr.samples[1], 1e-3);
  ASSERT_GT(brute, 0.0);
  EXPECT_LE(c.t, brute);
  EXPECT_GT(c.t, brute - kTableLead);
  // The contact point is on the spike where it is at that time: back into the table frame.
  const double theta = deg(120.0) * c.t / 4.0;
  const Eigen::Vector3d p_R = d.cell.table.X_WR(theta).inverse() * c.p_W;
  EXPECT_LT(distanceToBox(p_R, centre, size), kContactPointTol) << p_R.transpose();
}

// Soundness over seeded random arm motions past the post: whenever brute-force sampling finds a
// penetrating pose, validation reports a collision no later; when validation calls the motion
// clear, no sample penetrates.
TEST(Validate, NeverCallsAPenetratingMotionClear) {
  const Sweep sweep;
  const collision::Scene scene(sweep.demo.cell, config::clearanceConfig(sweep.demo.job));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int hits = 0, misses = 0;
  for (int trial = 0; trial < 16; ++trial) {
    JointVector q0 = home(90.0 - 50.0 + 10.0 * u(rng)), q1 = home(90.0 + 50.0 + 10.0 * u(rng));
    for (int j = 1; j < 5; ++j) {
      q0(j) += deg(25.0) * u(rng);
      q1(j) += deg(25.0) * u(rng);
    }
    Trajectory tr;
    tr.samples = {sample(0.0, 0.0, q0), sample(0.5, 0.0, q1)};
    const ValidationReport r = planner::validateTrajectory(scene, tr, {.sample_dt = 1.0});
    const double brute = bruteFirstContact(scene, tr.samples[0], tr.samples[1], 1e-4);
    SCOPED_TRACE("trial " + std::to_string(trial) + listed(r));
    if (brute >= 0.0) {
      ++hits;
      ASSERT_TRUE(r.first_collision);
      EXPECT_LE(r.first_collision->t, brute);
      EXPECT_GT(r.first_collision->t, brute - kSweepLead);
    } else if (!r.first_collision) {
      ++misses;
    }
  }
  EXPECT_GT(hits, 0);
  EXPECT_GT(misses, 0);
}

// The demo job planned on a coarse map (2° × 0.2 s), as `plan` does it.
struct DemoPlan {
  DemoCell demo = demoCell();
  collision::Scene scene{demo.cell, config::clearanceConfig(demo.job)};
  planner::TrajectoryBuild built;
};

const DemoPlan& demoPlan() {
  static const DemoPlan plan = [] {
    DemoPlan p;
    const scanner::GeneratedPath path = cli::generateScanPath(p.demo.job, p.demo.cell);
    const cli::MapRun run = cli::computeMap(p.demo.job, p.scene, path.path);
    const pipeline::PathChoice outcome = pipeline::choosePath(
        run.map, config::planSettings(p.demo.job), {.method = "ray"},
        [&](std::size_t b, const std::vector<double>& theta) {
          p.built = planner::buildTrajectory(p.scene, config::constraintSettings(p.demo.job),
                                             path.path, theta, run.map.branches[b]);
          return p.built.ok && p.built.min_f > 0.0 ? std::string() : "not ok: " + p.built.reason;
        });
    if (!outcome.solved()) p.built.ok = false;
    return p;
  }();
  return plan;
}

TEST(Validate, PlannedDemoTrajectoryPasses) {
  const DemoPlan& plan = demoPlan();
  ASSERT_TRUE(plan.built.ok) << plan.built.reason;
  const Trajectory& tr = plan.built.trajectory;
  const ValidationReport r = planner::validateTrajectory(plan.scene, tr, {.sample_dt = 0.01});
  EXPECT_TRUE(r.valid) << listed(r);
  EXPECT_TRUE(r.violations.empty());
  EXPECT_FALSE(r.first_collision);
  EXPECT_GT(r.min_distance, 0.0);
  EXPECT_FALSE(r.min_distance_pair.empty());
  EXPECT_GT(r.proven_clearance, 0.0);
  EXPECT_LE(r.proven_clearance, r.min_distance);
  // The samples' own clearance (exact below d_high) is among the poses checked.
  EXPECT_LE(r.min_distance, plan.built.min_clearance + 1e-12);
  EXPECT_GE(r.samples, static_cast<std::size_t>(tr.duration() / 0.01));
  EXPECT_GE(r.poses_checked, r.samples);
  // The closest pair split: the robot's own bodies apart from the cell's; the overall minimum is
  // the smaller of the two, and each names a pair of its kind.
  EXPECT_EQ(r.min_distance, std::min(r.min_cell_distance, r.min_self_distance));
  const auto carried = [&](const std::string& name) {
    for (const collision::BodyInfo& b : plan.scene.bodies()) {
      if (b.name == name) {
        return b.motion == collision::BodyMotion::kRobotLink ||
               b.motion == collision::BodyMotion::kScanner;
      }
    }
    ADD_FAILURE() << "no body " << name;
    return false;
  };
  const auto bodiesOf = [](const std::string& pair) {
    const std::size_t dash = pair.find(" - ");
    return std::pair{pair.substr(0, dash), pair.substr(dash + 3)};
  };
  ASSERT_FALSE(r.min_self_distance_pair.empty());
  const auto [s0, s1] = bodiesOf(r.min_self_distance_pair);
  EXPECT_TRUE(carried(s0) && carried(s1)) << r.min_self_distance_pair;
  if (!r.min_cell_distance_pair.empty()) {
    const auto [c0, c1] = bodiesOf(r.min_cell_distance_pair);
    EXPECT_FALSE(carried(c0) && carried(c1)) << r.min_cell_distance_pair;
  }
  std::printf(
      "demo: %zu samples over %.1f s -> %zu poses (%zu checked) in %.2f s; min distance "
      "%.2f mm (%s at %.2f s), proven %.2f mm\n",
      tr.samples.size(), tr.duration(), r.samples, r.poses_checked, r.seconds, toMm(r.min_distance),
      r.min_distance_pair.c_str(), r.min_distance_t, toMm(r.proven_clearance));
}

::testing::AssertionResult sameReport(const ValidationReport& a, const ValidationReport& b) {
  if (a.violations.size() != b.violations.size()) {
    return ::testing::AssertionFailure()
           << a.violations.size() << " vs " << b.violations.size() << " violations";
  }
  for (std::size_t i = 0; i < a.violations.size(); ++i) {
    const Violation &x = a.violations[i], &y = b.violations[i];
    if (x.kind != y.kind || x.what != y.what || x.t != y.t || x.t_start != y.t_start ||
        x.t_end != y.t_end || x.value != y.value || x.limit != y.limit || x.p_W != y.p_W) {
      return ::testing::AssertionFailure()
             << "violation " << i << ": " << planner::describe(x) << " vs " << planner::describe(y);
    }
  }
  if (a.valid != b.valid || a.min_distance != b.min_distance ||
      a.min_distance_pair != b.min_distance_pair || a.min_distance_t != b.min_distance_t ||
      a.proven_clearance != b.proven_clearance || a.samples != b.samples ||
      a.poses_checked != b.poses_checked) {
    return ::testing::AssertionFailure()
           << "min distance " << a.min_distance << " vs " << b.min_distance << ", proven "
           << a.proven_clearance << " vs " << b.proven_clearance << ", poses " << a.poses_checked
           << " vs " << b.poses_checked;
  }
  return ::testing::AssertionSuccess();
}

TEST(Validate, ReportDoesNotDependOnTheThreadCount) {
  const Sweep sweep;
  const collision::Scene scene(sweep.demo.cell, config::clearanceConfig(sweep.demo.job));
  const DemoPlan& plan = demoPlan();
  ASSERT_TRUE(plan.built.ok) << plan.built.reason;
  const auto run = [&](int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                              static_cast<std::size_t>(threads));
    return std::make_pair(
        planner::validateTrajectory(scene, sweep.trajectory, {.sample_dt = 0.05}),
        planner::validateTrajectory(plan.scene, plan.built.trajectory, {.sample_dt = 0.05}));
  };
  const auto one = run(1);
  for (const int threads : {2, 4}) {
    const auto many = run(threads);
    EXPECT_TRUE(sameReport(one.first, many.first)) << threads << " threads";
    EXPECT_TRUE(sameReport(one.second, many.second)) << threads << " threads";
  }
}

}  // namespace
