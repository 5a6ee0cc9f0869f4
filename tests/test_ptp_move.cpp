// Point-to-point moves of the seven axes (kinematics/ptp_move.h): bounds kept, ends met, times
// against the single-axis trapezoid derived by hand.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include <scanplan/kinematics/ptp_move.h>

namespace scanplan::kinematics {
namespace {

// Finite differences of a finely sampled move stay within the bounds up to this share (the
// difference quotient of a C¹ profile with bounded second derivative never exceeds the bound;
// the slack covers rounding).
constexpr double kBoundSlack = 1e-6;

AxisLimits someLimits() {
  AxisLimits l;
  l.speed << 0.5, 5.7, 5.2, 6.5, 6.5, 6.5, 10.5;
  l.accel << 1.0, 20.0, 21.0, 26.0, 26.0, 26.0, 42.0;
  return l;
}

// One axis moving D from rest to rest at speed v and acceleration a: D/v + v/a when it reaches
// v (D ≥ v²/a), else 2·sqrt(D/a) (a triangle).
double trapezoidTime(double d, double v, double a) {
  return d >= v * v / a ? d / v + v / a : 2.0 * std::sqrt(d / a);
}

// Speeds and accelerations of a sampled move from its samples.
void expectWithinBounds(const PtpMove& m, const AxisLimits& l) {
  for (std::size_t k = 1; k < m.t.size(); ++k) {
    const double dt = m.t[k] - m.t[k - 1];
    ASSERT_GT(dt, 0.0);
    const AxisVector v = (m.axes[k] - m.axes[k - 1]) / dt;
    for (int j = 0; j < kNumAxes; ++j)
      EXPECT_LE(std::abs(v(j)), l.speed(j) * (1 + kBoundSlack)) << "axis " << j << " step " << k;
    if (k + 1 < m.t.size()) {
      const double dt2 = m.t[k + 1] - m.t[k];
      const AxisVector v2 = (m.axes[k + 1] - m.axes[k]) / dt2;
      const AxisVector a = (v2 - v) / (0.5 * (dt + dt2));
      for (int j = 0; j < kNumAxes; ++j)
        EXPECT_LE(std::abs(a(j)), l.accel(j) * (1 + kBoundSlack) + 1e-9)
            << "axis " << j << " step " << k;
    }
  }
}

TEST(SyncProfile, OneAxisTakesTheTrapezoidTimeAndTheOthersWaitForIt) {
  const AxisLimits l = someLimits();
  for (const double d : {0.01, 0.1, 0.5, 2.0}) {
    AxisVector delta = AxisVector::Zero();
    delta(0) = d;  // the table, the slowest axis
    const SyncProfile p = syncProfile(delta, l);
    EXPECT_NEAR(p.duration, trapezoidTime(d, l.speed(0), l.accel(0)), 1e-12) << d;
    delta(3) = -d;  // a fast joint moving as far does not lengthen the move
    EXPECT_NEAR(syncProfile(delta, l).duration, p.duration, 1e-12);
    EXPECT_NEAR(p.at(0.0), 0.0, 1e-12);
    EXPECT_NEAR(p.at(p.duration), 1.0, 1e-12);
    EXPECT_NEAR(p.at(0.5 * p.duration), 0.5, 1e-12);  // symmetric
  }
}

TEST(PtpMove, RestToRestKeepsEveryBoundAndEndsExactly) {
  const AxisLimits l = someLimits();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-3.0, 3.0);
  for (int trial = 0; trial < 50; ++trial) {
    AxisVector a, b;
    for (int j = 0; j < kNumAxes; ++j) {
      a(j) = angle(rng);
      b(j) = angle(rng);
    }
    const PtpMove m = ptpMove(a, b, AxisVector::Zero(), AxisVector::Zero(), l, 0.005);
    EXPECT_EQ(m.axes.front(), a);
    EXPECT_EQ(m.axes.back(), b);
    expectWithinBounds(m, l);
    // No axis is faster than its own trapezoid, and no shorter shared trapezoid exists: at
    // 0.999 of the duration every acceleration time breaks some axis's speed or acceleration.
    double slowest = 0.0;
    for (int j = 0; j < kNumAxes; ++j)
      slowest = std::max(slowest, trapezoidTime(std::abs(b(j) - a(j)), l.speed(j), l.accel(j)));
    EXPECT_GE(m.duration(), slowest - 1e-12);
    const double shorter = 0.999 * m.duration();
    for (int i = 1; i <= 1000; ++i) {
      const double ta = 0.5 * shorter * i / 1000.0;
      double worst = 0.0;
      for (int j = 0; j < kNumAxes; ++j) {
        const double d = std::abs(b(j) - a(j));
        worst = std::max(
            {worst, d / (shorter - ta) / l.speed(j), d / (ta * (shorter - ta)) / l.accel(j)});
      }
      EXPECT_GT(worst, 1.0) << "a shorter profile fits with acceleration time " << ta;
    }
    EXPECT_NEAR(ptpDuration(a, b, AxisVector::Zero(), AxisVector::Zero(), l), m.duration(), 1e-12);
  }
}

TEST(PtpMove, LeavesAndArrivesAtTheGivenSpeedsWithinTheAccelerationBounds) {
  const AxisLimits l = someLimits();
  AxisVector a = AxisVector::Zero(), b = AxisVector::Constant(0.3);
  AxisVector va = AxisVector::Zero(), vb = AxisVector::Zero();
  va(0) = 0.4;   // the table still turning at the end of a spin
  vb(0) = -0.3;  // and turning the other way into the next one
  va(4) = 2.0;
  const double step = 0.002;
  const PtpMove m = ptpMove(a, b, va, vb, l, step);
  expectWithinBounds(m, l);
  const AxisVector first = (m.axes[1] - m.axes[0]) / (m.t[1] - m.t[0]);
  const std::size_t n = m.t.size();
  const AxisVector last = (m.axes[n - 1] - m.axes[n - 2]) / (m.t[n - 1] - m.t[n - 2]);
  for (int j = 0; j < kNumAxes; ++j) {
    // The mean speed over the first step differs from the start speed by at most a·dt/2.
    EXPECT_NEAR(first(j), va(j), 0.5 * l.accel(j) * step * (1 + kBoundSlack)) << j;
    EXPECT_NEAR(last(j), vb(j), 0.5 * l.accel(j) * step * (1 + kBoundSlack)) << j;
  }
}

TEST(PtpMove, AFasterRobotMovesFaster) {
  const AxisLimits slow = someLimits();
  AxisLimits fast = slow;
  fast.speed.tail<6>() *= 2.0;
  fast.accel.tail<6>() *= 4.0;
  AxisVector a = AxisVector::Zero(), b = AxisVector::Zero();
  b.tail<6>() << 1.0, -0.5, 0.8, 2.0, 1.0, -3.0;
  const double t_slow = ptpDuration(a, b, AxisVector::Zero(), AxisVector::Zero(), slow);
  const double t_fast = ptpDuration(a, b, AxisVector::Zero(), AxisVector::Zero(), fast);
  EXPECT_LT(t_fast, t_slow);
  // Speed doubled and acceleration quadrupled: the same profile in half the time (x(t) becomes
  // x(2t)), so the time halves exactly.
  EXPECT_NEAR(t_fast, 0.5 * t_slow, 1e-12);
}

// The move's time split by the axes that set it: the parts sum to the duration, and the axes
// named are those whose limits matter — speeding one up shortens the move, speeding up any
// other does not.
TEST(PtpMove, TheTimeByAxisNamesTheAxesWhoseLimitsSetTheMove) {
  const AxisLimits l = someLimits();
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int trial = 0; trial < 200; ++trial) {
    AxisVector a, b, va = AxisVector::Zero(), vb = AxisVector::Zero();
    for (int j = 0; j < kNumAxes; ++j) {
      a(j) = u(rng);
      b(j) = u(rng);
    }
    const AxisVector by = ptpTimeByAxis(a, b, va, vb, l);
    const double t = ptpDuration(a, b, va, vb, l);
    EXPECT_NEAR(by.sum(), t, 1e-12);
    EXPECT_LE((by.array() > 0.0).count(), 2);  // the cruise's axis and the ramps'
    for (int j = 0; j < kNumAxes; ++j) {
      AxisLimits faster = l;
      faster.speed(j) *= 1.5;
      faster.accel(j) *= 1.5;
      const double t_j = ptpDuration(a, b, va, vb, faster);
      if (by(j) > 0.0) {
        EXPECT_LT(t_j, t - 1e-9) << "trial " << trial << " axis " << j;
      } else {
        EXPECT_NEAR(t_j, t, 1e-12) << "trial " << trial << " axis " << j;
      }
    }
  }
  // Braking out of a table still turning: that brake is the table's.
  AxisVector va = AxisVector::Zero();
  va(0) = 0.4;
  const AxisVector by =
      ptpTimeByAxis(AxisVector::Zero(), AxisVector::Zero(), va, AxisVector::Zero(), l);
  EXPECT_NEAR(by(0), ptpDuration(AxisVector::Zero(), AxisVector::Zero(), va, AxisVector::Zero(), l),
              1e-12);
}

TEST(PtpMove, NothingToDoIsOneSample) {
  const AxisVector a = AxisVector::Constant(0.2);
  const PtpMove m = ptpMove(a, a, AxisVector::Zero(), AxisVector::Zero(), someLimits(), 0.1);
  ASSERT_EQ(m.t.size(), 1u);
  EXPECT_EQ(m.axes.front(), a);
}

}  // namespace
}  // namespace scanplan::kinematics
