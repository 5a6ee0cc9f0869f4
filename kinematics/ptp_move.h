#pragma once
// Point-to-point moves of the seven axes (the table angle and the six arm joints), the way a
// controller's joint move runs them: every axis on the same normalised trapezoidal profile, so
// they start and arrive together, as fast as the slowest axis's speed and acceleration allow.
// Used for the moves between scan passes; the pipeline checks each one for collisions.

#include <array>
#include <vector>

#include <Eigen/Core>

#include <scanplan/kinematics/robot_model.h>
#include <scanplan/kinematics/rotary_table.h>

namespace scanplan::kinematics {

inline constexpr int kNumAxes = kNumJoints + 1;
/// The seven axes in one vector: index 0 the table angle, 1…6 joints 1…6 (rad).
using AxisVector = Eigen::Matrix<double, kNumAxes, 1>;

/// Speed and acceleration bound of each axis (same order as AxisVector), rad/s and rad/s², > 0.
struct AxisLimits {
  AxisVector speed = AxisVector::Constant(1.0);
  AxisVector accel = AxisVector::Constant(4.0);
};

/// The limits a move uses: each joint's max_speed and the table's, times `speed_scale`; each
/// joint's max_accel (or max_speed / accel_time when 0) and the table's max_accel (or its speed /
/// accel_time), times `speed_scale` too. Unset speeds (≤ 0) become 1 rad/s for joints and
/// 0.5 rad/s for the table.
AxisLimits axisLimits(const RobotModel& robot,
                      const RotaryTableModel& table,
                      double speed_scale = 1.0,
                      double accel_time = 0.25);

/// The shortest synchronised rest-to-rest trapezoid for the displacements `delta` (rad): its
/// duration (s) and its acceleration time (s, the same for every axis). Zero displacement: 0.
struct SyncProfile {
  double duration = 0.0;
  double accel_time = 0.0;
  /// The axis whose speed bound sets the cruise (duration − accel_time); −1 for a triangle (no
  /// axis reaches its speed) or no motion.
  int speed_axis = -1;
  /// The axis whose acceleration bound sets the ramps (the whole of a triangle); −1: no motion.
  int accel_axis = -1;
  /// The share of the way (0 … 1) at time t ∈ [0, duration].
  double at(double t) const;
};
SyncProfile syncProfile(const AxisVector& delta, const AxisLimits& limits);

/// A move from `from` (moving at `v_from`, rad/s) to `to` (to arrive moving at `v_to`): each axis
/// first brakes to rest at its own acceleration bound, then all run one synchronised trapezoid,
/// then each speeds up into `v_to` (a brake run backwards), so speed is continuous throughout
/// and no axis exceeds its bounds. Sampled at equal steps no longer than `max_step` s; a move
/// with nothing to do is the one sample `from`.
struct PtpMove {
  std::vector<double> t;         ///< s from the start of the move; t.front() = 0
  std::vector<AxisVector> axes;  ///< positions at t; front = from, back = to
  double duration() const { return t.empty() ? 0.0 : t.back(); }
};
PtpMove ptpMove(const AxisVector& from,
                const AxisVector& to,
                const AxisVector& v_from,
                const AxisVector& v_to,
                const AxisLimits& limits,
                double max_step);

/// ptpMove()'s duration split by the axis that sets each phase's length (s per axis, summing to
/// the duration): the brake out of `v_from` and the one into `v_to` to the axis that brakes
/// longest; of the synchronised trapezoid, the cruise to the axis whose speed bound sets it and
/// the ramps to the axis whose acceleration bound sets them (a triangle, to the latter alone).
/// An axis with a share is one whose faster limits give a shorter move.
AxisVector ptpTimeByAxis(const AxisVector& from,
                         const AxisVector& to,
                         const AxisVector& v_from,
                         const AxisVector& v_to,
                         const AxisLimits& limits);

/// ptpMove()'s duration without sampling it, s.
double ptpDuration(const AxisVector& from,
                   const AxisVector& to,
                   const AxisVector& v_from,
                   const AxisVector& v_to,
                   const AxisLimits& limits);

}  // namespace scanplan::kinematics
