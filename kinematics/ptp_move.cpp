#include <scanplan/kinematics/ptp_move.h>

#include <algorithm>
#include <cmath>

namespace scanplan::kinematics {

namespace {

// Each axis's brake from speed v at deceleration a: how long it takes and how far it goes.
struct Brake {
  AxisVector time = AxisVector::Zero();
  AxisVector travel = AxisVector::Zero();
  double duration() const { return time.maxCoeff(); }
};

Brake brake(const AxisVector& v, const AxisLimits& limits) {
  Brake b;
  for (int j = 0; j < kNumAxes; ++j) {
    b.time(j) = std::abs(v(j)) / limits.accel(j);
    b.travel(j) = 0.5 * v(j) * b.time(j);
  }
  return b;
}

// Axis j, `u` s into a brake from speed v: the distance travelled since its start.
double braked(double v, double a, double stop, double u) {
  const double s = std::min(u, stop);
  return v * s - 0.5 * std::copysign(a, v) * s * s;
}

}  // namespace

AxisLimits axisLimits(const RobotModel& robot,
                      const RotaryTableModel& table,
                      double speed_scale,
                      double accel_time) {
  AxisLimits l;
  const double table_speed = table.max_speed > 0.0 ? table.max_speed : 0.5;
  l.speed(0) = table_speed;
  l.accel(0) = table.max_accel > 0.0 ? table.max_accel : table_speed / accel_time;
  for (int j = 0; j < kNumJoints; ++j) {
    const DhJoint& joint = robot.joint(j);
    const double speed = joint.max_speed > 0.0 ? joint.max_speed : 1.0;
    l.speed(j + 1) = speed;
    l.accel(j + 1) = joint.max_accel > 0.0 ? joint.max_accel : speed / accel_time;
  }
  l.speed *= speed_scale;
  l.accel *= speed_scale;
  return l;
}

double SyncProfile::at(double t) const {
  if (!(duration > 0.0)) return 1.0;
  t = std::clamp(t, 0.0, duration);
  const double ta = accel_time;
  const double v = 1.0 / (duration - ta);  // cruise speed of the shared profile
  const double a = v / ta;
  if (t < ta) return 0.5 * a * t * t;
  if (t <= duration - ta) return 0.5 * v * ta + v * (t - ta);
  const double u = duration - t;
  return 1.0 - 0.5 * a * u * u;
}

// Every axis runs x_j(t) = x_j(0) + Δ_j · s(t) on one trapezoid s with acceleration time τ and
// duration T: its cruise speed is |Δ_j| / (T − τ) and its acceleration |Δ_j| / (τ (T − τ)).
// With R = max |Δ_j| / v_j and Q = max |Δ_j| / a_j the shortest feasible T is R + Q / R with
// τ = Q / R when Q < R² (the slowest axis reaches its speed), else 2√Q with τ = √Q (a triangle).
SyncProfile syncProfile(const AxisVector& delta, const AxisLimits& limits) {
  int jr = 0, jq = 0;
  const double r = (delta.array().abs() / limits.speed.array()).maxCoeff(&jr);
  const double q = (delta.array().abs() / limits.accel.array()).maxCoeff(&jq);
  SyncProfile p;
  if (!(r > 0.0)) return p;
  p.accel_axis = jq;
  if (q < r * r) {
    p.speed_axis = jr;
    p.accel_time = q / r;
    p.duration = r + q / r;
  } else {
    p.accel_time = std::sqrt(q);
    p.duration = 2.0 * p.accel_time;
  }
  return p;
}

namespace {

// A move's three phases: each axis's brake out of its start speed, the synchronised trapezoid
// between, each axis's brake into its end speed (run backwards).
struct Phases {
  Brake out, in;
  SyncProfile mid;
};

Phases phases(const AxisVector& from,
              const AxisVector& to,
              const AxisVector& v_from,
              const AxisVector& v_to,
              const AxisLimits& limits) {
  Phases m{brake(v_from, limits), brake(v_to, limits), {}};
  m.mid = syncProfile((to - m.in.travel) - (from + m.out.travel), limits);
  return m;
}

}  // namespace

AxisVector ptpTimeByAxis(const AxisVector& from,
                         const AxisVector& to,
                         const AxisVector& v_from,
                         const AxisVector& v_to,
                         const AxisLimits& limits) {
  const Phases m = phases(from, to, v_from, v_to, limits);
  AxisVector by_axis = AxisVector::Zero();
  int j = 0;
  m.out.time.maxCoeff(&j);
  by_axis(j) += m.out.duration();
  m.in.time.maxCoeff(&j);
  by_axis(j) += m.in.duration();
  if (m.mid.speed_axis >= 0) {
    by_axis(m.mid.speed_axis) += m.mid.duration - m.mid.accel_time;
    by_axis(m.mid.accel_axis) += m.mid.accel_time;
  } else if (m.mid.accel_axis >= 0) {
    by_axis(m.mid.accel_axis) += m.mid.duration;
  }
  return by_axis;
}

double ptpDuration(const AxisVector& from,
                   const AxisVector& to,
                   const AxisVector& v_from,
                   const AxisVector& v_to,
                   const AxisLimits& limits) {
  const Phases m = phases(from, to, v_from, v_to, limits);
  return m.out.duration() + m.mid.duration + m.in.duration();
}

PtpMove ptpMove(const AxisVector& from,
                const AxisVector& to,
                const AxisVector& v_from,
                const AxisVector& v_to,
                const AxisLimits& limits,
                double max_step) {
  const Phases m = phases(from, to, v_from, v_to, limits);
  const Brake &out = m.out, &in = m.in;
  const AxisVector start = from + out.travel, end = to - in.travel;
  const SyncProfile& mid = m.mid;
  const double t1 = out.duration(), t2 = t1 + mid.duration, total = t2 + in.duration();
  PtpMove move;
  if (!(total > 0.0)) {
    move.t.push_back(0.0);
    move.axes.push_back(from);
    return move;
  }
  const int steps = std::max(1, static_cast<int>(std::ceil(total / max_step - 1e-9)));
  for (int k = 0; k <= steps; ++k) {
    const double t = k == steps ? total : total * k / steps;
    AxisVector x;
    for (int j = 0; j < kNumAxes; ++j) {
      if (t <= t1) {
        x(j) = from(j) + braked(v_from(j), limits.accel(j), out.time(j), t);
      } else if (t <= t2) {
        x(j) = start(j) + (end(j) - start(j)) * mid.at(t - t1);
      } else {
        // The brake into `to` run backwards: u s before the end.
        x(j) = to(j) - braked(v_to(j), limits.accel(j), in.time(j), total - t);
      }
    }
    move.t.push_back(t);
    move.axes.push_back(x);
  }
  move.axes.front() = from;
  move.axes.back() = to;
  return move;
}

}  // namespace scanplan::kinematics
