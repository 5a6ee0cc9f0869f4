// The predictive collision watch (seed §7.3): the motion models of Eq. 9 and Eq. 10 recover the
// motion that made a window and predict its future; the watch warns before a contact that the
// true motion reaches, with the lead time the true motion gives, and stays silent when the
// bodies move apart or stand still. Contact times are found independently by sampling the true
// motion every millisecond with the exact clearance code.
#include <cmath>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <scanplan/collision/clearance.h>
#include <scanplan/collision/scene.h>
#include <scanplan/config/job.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/joint_wrap.h>
#include <scanplan/kinematics/motion_model.h>
#include <scanplan/pipeline/collision_watch.h>
#include <scanplan/pipeline/plan_scan.h>
#include "test_support.h"

namespace {

using namespace scanplan;
using kinematics::AxisSample;
using kinematics::JointVector;
using kinematics::MotionKind;

constexpr double kRate = 250.0;  // Hz, the stream to keep up with
constexpr double kDt = 1.0 / kRate;

struct Cell {
  config::JobSpec job;
  kinematics::CellModel cell;
};

const Cell& demoCell() {
  static const Cell cell = [] {
    config::JobSpec job =
        config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml", test::kLightDemo);
    kinematics::CellModel model = config::buildCell(job);
    return Cell{std::move(job), std::move(model)};
  }();
  return cell;
}

JointVector deg(double a, double b, double c, double d, double e, double f) {
  JointVector q;
  q << a, b, c, d, e, f;
  return q * (M_PI / 180.0);
}

using Motion = std::function<std::optional<AxisSample>(double t)>;

// The first time (1 ms steps) the true motion touches, and the pair that touches; nullopt when it
// does not within `until`.
struct Contact {
  double t = 0.0;
  int pair = -1;
};
std::optional<Contact> trueContact(const collision::Scene& scene,
                                   const Motion& motion,
                                   double until) {
  collision::ClearanceEvaluator evaluator(scene);
  for (double t = 0.0; t <= until; t += 1e-3) {
    const auto s = motion(t);
    if (!s) return std::nullopt;
    const collision::ClearanceResult r = evaluator.evaluate(s->theta, s->q);
    if (!r.collision) continue;
    for (std::size_t k = 0; k < r.pairs.size(); ++k) {
      if (r.pairs[k].penetrating) return Contact{t, static_cast<int>(k)};
    }
  }
  return std::nullopt;
}

struct Streamed {
  std::optional<pipeline::WatchStep> first;       // the first sample warning about `pair`
  std::optional<pipeline::WatchWarning> warning;  // its warning about `pair`
  std::optional<double> contact_warned;           // s, the first warning of `pair` with a contact
  std::optional<double> contact_in;               // s, that warning's predicted time to contact
  std::optional<double> first_stop;               // s
  std::size_t warnings = 0;                       // samples with any warning
  MotionKind kind = MotionKind::kStill;           // the fit at the last sample
};

Streamed stream(pipeline::CollisionWatch& watch, const Motion& motion, double until, int pair) {
  Streamed out;
  for (int i = 0; i * kDt <= until; ++i) {
    const auto s = motion(i * kDt);
    if (!s) break;
    const pipeline::WatchStep step = watch.push(*s);
    out.kind = step.fit.kind;
    if (!step.warnings.empty()) ++out.warnings;
    if (step.stop && !out.first_stop) out.first_stop = step.t;
    for (const pipeline::WatchWarning& w : step.warnings) {
      if (w.pair != pair) continue;
      if (!out.first) out.first = step, out.warning = w;
      if (w.time_to_contact && !out.contact_warned) {
        out.contact_warned = step.t;
        out.contact_in = w.time_to_contact;
      }
    }
  }
  return out;
}

Eigen::Isometry3d toolFrame() { return demoCell().cell.scanner.X_FS; }

// A joint move at constant speed from q0 along `rate` (rad/s per joint, the table still).
Motion jointMove(const JointVector& q0, const JointVector& rate) {
  return [=](double t) -> std::optional<AxisSample> { return AxisSample{t, 0.0, q0 + t * rate}; };
}

// A tool move on a line at `speed` (m/s, base frame) with the orientation held, back to joints by
// IK nearest the previous sample (what a pendant's Cartesian jog does).
Motion linearMove(const JointVector& q0, const Eigen::Vector3d& velocity) {
  const kinematics::RobotModel& robot = demoCell().cell.robot;
  const Eigen::Isometry3d X_BT0 = robot.fk(q0) * toolFrame();
  return [=, &robot](double t) -> std::optional<AxisSample> {
    Eigen::Isometry3d X_BT = X_BT0;
    X_BT.translation() += t * velocity;
    const Eigen::Isometry3d X_BF = X_BT * toolFrame().inverse();
    std::optional<AxisSample> best;
    double nearest = 1e9;
    for (const auto& s : robot.ik(X_BF)) {
      const JointVector q = kinematics::unwrapNear(s.q, q0);
      if ((q - q0).norm() < nearest) {
        nearest = (q - q0).norm();
        best = AxisSample{t, 0.0, q};
      }
    }
    return best;
  };
}

const JointVector kStart = deg(0, -60, 150, 0, 60, 0);

TEST(MotionModel, Eq9RecoversAJointMoveAndPredictsItsFuture) {
  const kinematics::MotionModel model(demoCell().cell.robot, toolFrame());
  JointVector rate;
  rate << 0.1, -0.2, 0.15, 0.0, 0.3, -0.1;
  const double table_rate = 0.05;
  std::vector<AxisSample> window;
  for (int i = 0; i < 25; ++i)
    window.push_back({i * kDt, i * kDt * table_rate, kStart + i * kDt * rate});
  const kinematics::MotionFit fit = model.fit(window);
  EXPECT_EQ(fit.kind, MotionKind::kJoint);
  EXPECT_LT(fit.joint_residual, 1e-12);
  EXPECT_GT(fit.cartesian_residual, 1e-7);
  const double norm = std::hypot(rate.norm(), table_rate);
  EXPECT_NEAR(fit.speed, norm, 1e-9);
  for (const double tau : {0.1, 0.5, 1.0}) {
    const auto p = model.predict(fit, window.back(), tau);
    ASSERT_TRUE(p);
    const double t = window.back().t + tau;
    EXPECT_LT((p->q - (kStart + t * rate)).norm(), 1e-9) << tau;
    EXPECT_NEAR(p->theta, t * table_rate, 1e-9) << tau;
  }
}

TEST(MotionModel, Eq10RecoversALinearToolMoveWithATurnAndPredictsItsFuture) {
  const kinematics::RobotModel& robot = demoCell().cell.robot;
  const kinematics::MotionModel model(robot, toolFrame());
  const JointVector start = deg(0, -90, 180, 0, 90, 0);  // the turning tool stays in reach
  const Eigen::Isometry3d X_BT0 = model.toolPose(start);
  const Eigen::Vector3d v(0.05, -0.03, 0.02);  // m/s
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, -1).normalized();
  const double spin = 0.2;  // rad/s about the tool origin
  const auto truth = [&](double t) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = Eigen::AngleAxisd(spin * t, axis).toRotationMatrix() * X_BT0.linear();
    X.translation() = X_BT0.translation() + t * v;
    return X;
  };
  std::vector<AxisSample> window;
  JointVector previous = start;
  for (int i = 0; i < 25; ++i) {
    const double t = i * kDt;
    double nearest = 1e9;
    JointVector q = previous;
    for (const auto& s : robot.ik(truth(t) * toolFrame().inverse())) {
      const JointVector u = kinematics::unwrapNear(s.q, previous);
      if ((u - previous).norm() < nearest) nearest = (u - previous).norm(), q = u;
    }
    window.push_back({t, 0.0, q});
    previous = q;
  }
  const kinematics::MotionFit fit = model.fit(window);
  EXPECT_EQ(fit.kind, MotionKind::kCartesian);
  EXPECT_LT(fit.cartesian_residual, 1e-9);
  EXPECT_GT(fit.joint_residual, 1e-7);
  for (const double tau : {0.1, 0.5}) {
    const auto p = model.predict(fit, window.back(), tau);
    ASSERT_TRUE(p) << tau;
    const Eigen::Isometry3d want = truth(window.back().t + tau);
    const Eigen::Isometry3d got = model.toolPose(p->q);
    EXPECT_LT((got.translation() - want.translation()).norm(), 1e-9) << tau;
    EXPECT_LT((got.linear() - want.linear()).norm(), 1e-9) << tau;
  }
}

TEST(MotionModel, StandingStillIsStill) {
  const kinematics::MotionModel model(demoCell().cell.robot, toolFrame());
  std::vector<AxisSample> window;
  for (int i = 0; i < 10; ++i) window.push_back({i * kDt, 0.3, kStart});
  EXPECT_EQ(model.fit(window).kind, MotionKind::kStill);
}

struct Approach {
  Motion towards;
  Motion away;  // the same path backwards from just before the contact
  Contact contact;
};

// A constant-speed joint move of the given joints towards the first contact found among a few
// directions (found by sampling, not assumed): the scenario and its answer both come from the
// exact clearance code along the true motion.
Approach jointApproach(const collision::Scene& scene) {
  for (const int j : {1, 2}) {
    for (const double sign : {1.0, -1.0}) {
      JointVector rate = JointVector::Zero();
      rate(j) = sign * 0.25;
      const Motion m = jointMove(kStart, rate);
      const auto c = trueContact(scene, m, 6.0);
      if (!c || c->t < 2.0) continue;
      const JointVector near = kStart + (c->t - 0.05) * rate;
      return {m, jointMove(near, -rate), *c};
    }
  }
  ADD_FAILURE() << "no joint move from the start pose reaches a contact within 2-6 s";
  return {};
}

TEST(CollisionWatch, AJointMoveTowardsTheCellWarnsAHorizonAheadWithTheContactTime) {
  const collision::Scene scene(demoCell().cell, config::clearanceConfig(demoCell().job));
  const Approach a = jointApproach(scene);
  ASSERT_TRUE(a.towards);
  pipeline::WatchOptions options;
  pipeline::CollisionWatch watch(scene, toolFrame(), options);
  const Streamed s = stream(watch, a.towards, a.contact.t, a.contact.pair);
  EXPECT_EQ(s.kind, MotionKind::kJoint);
  ASSERT_TRUE(s.first) << "no warning for pair " << a.contact.pair;
  // Constant speed: the prediction is exact. The first warning comes when the pair is predicted
  // within the warning distance, which the true motion confirms at the predicted time.
  collision::ClearanceEvaluator exact(scene);
  const auto then = a.towards(s.first->t + s.warning->time_to_closest);
  const double d =
      exact.evaluate(then->theta, then->q).pairs[static_cast<std::size_t>(a.contact.pair)].distance;
  EXPECT_NEAR(s.warning->closest, d, 1e-6);
  EXPECT_LT(s.warning->closest, options.warn_distance);
  EXPECT_GE(a.contact.t - s.first->t, options.horizon - options.step - kDt);
  // The contact itself is warned as soon as it is within the horizon, with its time.
  ASSERT_TRUE(s.contact_warned);
  const double lead = a.contact.t - *s.contact_warned;
  EXPECT_GE(lead, options.horizon - options.step - kDt);
  EXPECT_LE(lead, options.horizon + kDt);
  EXPECT_NEAR(*s.contact_in, lead, options.step / 32.0 + 2e-3);
}

TEST(CollisionWatch, MovingAwayFromTheContactIsSilent) {
  const collision::Scene scene(demoCell().cell, config::clearanceConfig(demoCell().job));
  const Approach a = jointApproach(scene);
  ASSERT_TRUE(a.away);
  pipeline::CollisionWatch watch(scene, toolFrame());
  const Streamed s = stream(watch, a.away, 2.0, a.contact.pair);
  EXPECT_EQ(s.warnings, 0u);
}

TEST(CollisionWatch, StandingStillNearTheCellIsSilent) {
  const collision::Scene scene(demoCell().cell, config::clearanceConfig(demoCell().job));
  const Approach a = jointApproach(scene);
  ASSERT_TRUE(a.away);
  const auto near = a.away(0.0);
  pipeline::CollisionWatch watch(scene, toolFrame());
  const Streamed s = stream(
      watch,
      [&](double t) {
        return AxisSample{t, near->theta, near->q};
      },
      0.5, a.contact.pair);
  EXPECT_EQ(s.kind, MotionKind::kStill);
  EXPECT_EQ(s.warnings, 0u);
}

TEST(CollisionWatch, ALinearToolMoveTowardsTheTableWarnsAndAwayIsSilent) {
  const collision::Scene scene(demoCell().cell, config::clearanceConfig(demoCell().job));
  const Motion down = linearMove(kStart, Eigen::Vector3d(0, 0, -0.05));
  const auto c = trueContact(scene, down, 8.0);
  ASSERT_TRUE(c) << "the tool going down never touches";
  pipeline::WatchOptions options;
  pipeline::CollisionWatch watch(scene, toolFrame(), options);
  const Streamed s = stream(watch, down, c->t, c->pair);
  EXPECT_EQ(s.kind, MotionKind::kCartesian);
  ASSERT_TRUE(s.contact_warned);
  EXPECT_GE(c->t - *s.contact_warned, options.horizon - options.step - kDt);
  EXPECT_NEAR(*s.contact_in, c->t - *s.contact_warned, options.step / 32.0 + 2e-3);

  const auto near = down(c->t - 0.05);
  pipeline::CollisionWatch back(scene, toolFrame(), options);
  const Streamed up = stream(back, linearMove(near->q, Eigen::Vector3d(0, 0, 0.05)), 1.5, c->pair);
  EXPECT_EQ(up.warnings, 0u);
}

TEST(CollisionWatch, AStopComesWhenTheStopDistanceIsWithinTheStopTime) {
  const collision::Scene scene(demoCell().cell, config::clearanceConfig(demoCell().job));
  const Approach a = jointApproach(scene);
  ASSERT_TRUE(a.towards);
  pipeline::WatchOptions options;
  options.stop_distance = 0.0;  // a stop just before touching
  options.stop_time = 0.2;
  pipeline::CollisionWatch watch(scene, toolFrame(), options);
  const Streamed s = stream(watch, a.towards, a.contact.t, a.contact.pair);
  ASSERT_TRUE(s.first_stop);
  const double lead = a.contact.t - *s.first_stop;
  EXPECT_GE(lead, options.stop_time - options.step - kDt);
  EXPECT_LE(lead, options.stop_time + kDt);
}

// The demo's own trajectory with joint 2 offset so that it collides, streamed at 250 Hz along the
// joint-linear motion between its samples: the watch must warn before the true contact.
TEST(CollisionWatch, TheDemoTrajectoryWithAJointOffsetIsWarnedBeforeItsContact) {
  std::vector<std::string> overrides = test::kLightDemo;
  overrides.push_back("map.branch=RIGHTY ABOVE NOFLIP");
  overrides.push_back("simulation.enabled=false");
  const pipeline::ScanProblem problem = config::toProblem(
      config::loadJob(test::sourceDir() / "data/jobs/demo_rings.yaml", overrides));
  const pipeline::ScanPlan plan = pipeline::planScan(problem);
  ASSERT_TRUE(plan.planned()) << plan.reason;
  const auto& samples = plan.trajectory->trajectory.samples;
  const collision::Scene scene(problem.cell, problem.clearance);
  for (const double offset_deg : {4.0, 8.0, 12.0, 16.0, 20.0, 25.0, 30.0}) {
    const Motion replay = [&](double t) -> std::optional<AxisSample> {
      if (t > samples.back().t) return std::nullopt;
      std::size_t k = 0;
      while (k + 2 < samples.size() && samples[k + 1].t <= t) ++k;
      const double s = (t - samples[k].t) / (samples[k + 1].t - samples[k].t);
      JointVector q = samples[k].q + s * (samples[k + 1].q - samples[k].q);
      q(1) += offset_deg * M_PI / 180.0;
      return AxisSample{t, samples[k].theta + s * (samples[k + 1].theta - samples[k].theta), q};
    };
    const auto c = trueContact(scene, replay, samples.back().t);
    if (!c || c->t < 1.0) continue;
    pipeline::CollisionWatch watch(scene, toolFrame());
    const Streamed s = stream(watch, replay, c->t, c->pair);
    ASSERT_TRUE(s.first) << "offset " << offset_deg << "°: contact at " << c->t << " s not warned";
    EXPECT_GT(c->t - s.first->t, 0.1) << "offset " << offset_deg << "°";
    return;
  }
  FAIL() << "no joint 2 offset makes the demo collide after 1 s";
}

// Bounded queries measure a pair only below the distances that matter: every warning is the same
// as with every pair's exact distance at every predicted pose.
TEST(CollisionWatch, BoundedQueriesChangeNoWarning) {
  const collision::Scene scene(demoCell().cell, config::clearanceConfig(demoCell().job));
  const Approach a = jointApproach(scene);
  ASSERT_TRUE(a.towards);
  pipeline::WatchOptions skip, every;
  skip.stop_distance = every.stop_distance = 0.005;
  skip.horizon = every.horizon = 0.15;  // exact distances to the housing take milliseconds
  skip.step = every.step = 0.05;
  every.bounded = false;
  pipeline::CollisionWatch fast(scene, toolFrame(), skip), slow(scene, toolFrame(), every);
  std::size_t warnings = 0;
  for (int i = 0; i * kDt <= 0.25; ++i) {
    const auto s = a.towards(a.contact.t - 0.25 + i * kDt);
    const pipeline::WatchStep x = fast.push(*s), y = slow.push(*s);
    ASSERT_EQ(x.warnings.size(), y.warnings.size()) << x.t;
    EXPECT_EQ(x.predicted, y.predicted);
    EXPECT_EQ(x.stop, y.stop);
    for (std::size_t k = 0; k < x.warnings.size(); ++k) {
      EXPECT_EQ(x.warnings[k].pair, y.warnings[k].pair);
      EXPECT_NEAR(x.warnings[k].closest, y.warnings[k].closest, 1e-6);  // FCL's GJK tolerance
      EXPECT_EQ(x.warnings[k].time_to_closest, y.warnings[k].time_to_closest);
      EXPECT_EQ(x.warnings[k].time_to_contact, y.warnings[k].time_to_contact);
    }
    warnings += x.warnings.size();
  }
  EXPECT_GT(warnings, 20u);
}

// In contact now: still going in (or standing in it) is a warning with contact now and a stop;
// backing out of it is not warned.
TEST(CollisionWatch, InContactGoingOnIsAStopBackingOutIsSilent) {
  const collision::Scene scene(demoCell().cell, config::clearanceConfig(demoCell().job));
  const Approach a = jointApproach(scene);
  ASSERT_TRUE(a.towards);
  const auto inside = a.towards(a.contact.t + 0.01);
  const JointVector rate = (a.towards(1.0)->q - a.towards(0.0)->q);
  pipeline::WatchOptions options;
  options.stop_distance = 0.0;
  pipeline::CollisionWatch on(scene, toolFrame(), options);
  const Streamed deeper = stream(on, jointMove(inside->q, rate), 0.1, a.contact.pair);
  ASSERT_TRUE(deeper.first);
  EXPECT_TRUE(deeper.warning->stop);
  ASSERT_TRUE(deeper.contact_in);
  EXPECT_LT(*deeper.contact_in, 1e-3);
  pipeline::CollisionWatch off(scene, toolFrame(), options);
  const Streamed out = stream(off, jointMove(inside->q, -rate), 0.3, a.contact.pair);
  EXPECT_EQ(out.warnings, 0u);
  EXPECT_FALSE(out.first_stop);
}

// An endless table reported within ±180° (and joints wrapped as some controllers report them) is
// the same motion: the same warnings as the continuous stream.
TEST(CollisionWatch, WrappedAnglesAreTheSameMotion) {
  const collision::Scene scene(demoCell().cell, config::clearanceConfig(demoCell().job));
  const Approach a = jointApproach(scene);
  ASSERT_TRUE(a.towards);
  pipeline::CollisionWatch plain(scene, toolFrame()), wrapped(scene, toolFrame());
  const auto wrap = [](double v) { return std::remainder(v, 2.0 * M_PI); };
  std::size_t warnings = 0;
  for (int i = 0; i * kDt <= a.contact.t; ++i) {
    AxisSample s = *a.towards(i * kDt);
    s.theta = 3.0 * i * kDt;  // the table spins through ±180° several times
    const pipeline::WatchStep x = plain.push(s);
    s.theta = wrap(s.theta);
    for (int j = 0; j < 6; ++j) s.q(j) = wrap(s.q(j));
    const pipeline::WatchStep y = wrapped.push(s);
    ASSERT_EQ(x.warnings.size(), y.warnings.size()) << x.t;
    for (std::size_t k = 0; k < x.warnings.size(); ++k) {
      EXPECT_EQ(x.warnings[k].pair, y.warnings[k].pair);
      EXPECT_NEAR(x.warnings[k].closest, y.warnings[k].closest, 1e-9);
    }
    warnings += x.warnings.size();
  }
  EXPECT_GT(warnings, 0u);
}

TEST(CollisionWatch, RefusesBadSamplesAndOptions) {
  const collision::Scene scene(demoCell().cell, config::clearanceConfig(demoCell().job));
  pipeline::CollisionWatch watch(scene, toolFrame());
  watch.push({0.0, 0.0, kStart});
  EXPECT_THROW(watch.push({0.0, 0.0, kStart}), std::invalid_argument);
  EXPECT_THROW(watch.push({1.0, NAN, kStart}), std::invalid_argument);
  pipeline::WatchOptions bad;
  bad.window = 2;
  EXPECT_THROW(pipeline::CollisionWatch(scene, toolFrame(), bad), std::invalid_argument);
}

}  // namespace
