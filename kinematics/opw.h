#pragma once

#include <array>
#include <cstddef>

#include <Eigen/Geometry>

#include <scanplan/kinematics/robot_model.h>

namespace scanplan::kinematics::detail {

/// OPW forward kinematics in OPW joint coordinates (no offsets or signs applied), m / rad.
/// Returns the tool frame (z = approach) in the base frame.
Eigen::Isometry3d opwForward(const OpwParameters& p, const JointVector& q_opw);

/// Is the elbow E below the line from shoulder S to wrist centre W? Arm-plane coordinates
/// (r along the J1-rotated x axis, z up); "up" is the line's normal on the upper side
/// whichever way the arm reaches.
bool elbowBelow(const Eigen::Vector2d& S, const Eigen::Vector2d& W, const Eigen::Vector2d& E);

/// One raw OPW solution with the arm configuration it was built for.
struct OpwSolution {
  JointVector q;       ///< OPW joint coordinates, rad
  bool back = false;   ///< wrist centre behind the J1 axis (LEFTY)
  bool below = false;  ///< elbow below the shoulder–wrist line
};

/// Raw OPW inverse: up to 8 solutions in OPW joint coordinates, written to `out`;
/// returns how many are valid (all finite). Solutions come in wrist pairs (no flip, flip).
std::size_t opwInverse(const OpwParameters& p,
                       const Eigen::Isometry3d& X_tool,
                       std::array<OpwSolution, 8>& out);

}  // namespace scanplan::kinematics::detail
