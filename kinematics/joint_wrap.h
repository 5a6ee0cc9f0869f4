#pragma once

#include <cmath>
#include <numbers>

#include <scanplan/kinematics/robot_model.h>

namespace scanplan::kinematics {

/// Joint wrap. A revolute joint's value q and q ± 2π give the same pose; the
/// IK returns each joint in (−π, π] plus the ±2π variants that lie inside the limits
/// (RobotModel::ik()). A joint is continuous within its limits: a joint whose limits reach ±π or
/// beyond crosses ±π like any other angle, and along a motion each sample takes the equivalent
/// nearest the previous sample (unwrapNear()); only then are its limits checked. A value outside
/// the limits whose other equivalent is inside is a re-wind of a whole turn, not a continuation.

inline constexpr double kTurn = 2.0 * std::numbers::pi;

/// q + 2π·n (n whole) nearest `reference`, rad. Halfway cases go to the larger value.
inline double nearestTurn(double q, double reference) {
  return q + kTurn * std::floor((reference - q) / kTurn + 0.5);
}

/// Each joint of q moved by whole turns to the equivalent nearest `reference` (rad).
inline JointVector unwrapNear(const JointVector& q, const JointVector& reference) {
  JointVector out;
  for (int j = 0; j < kNumJoints; ++j) out(j) = nearestTurn(q(j), reference(j));
  return out;
}

/// True when two 2π-equivalent values can both lie within the joint's limits (range > 2π, e.g.
/// ABB J4 ±200°, J6 ±400°): which of them a continuous motion uses depends on its history.
inline bool turnsMoreThanOnce(const DhJoint& joint) { return joint.max - joint.min > kTurn; }

}  // namespace scanplan::kinematics
