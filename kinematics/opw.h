#pragma once

#include <array>
#include <cstddef>

#include <Eigen/Geometry>

#include "kinematics/robot_model.h"

namespace scanplan::kinematics::detail {

/// OPW forward kinematics in OPW joint coordinates (no offsets or signs applied), m / rad.
/// Returns the tool frame (z = approach) in the base frame.
Eigen::Isometry3d opwForward(const OpwParameters& p, const JointVector& q_opw);

/// Raw OPW inverse: up to 8 solutions in OPW joint coordinates, written to `out`;
/// returns how many are valid. Solutions come in wrist pairs (no flip, flip).
std::size_t opwInverse(const OpwParameters& p,
                       const Eigen::Isometry3d& X_tool,
                       std::array<JointVector, 8>& out);

}  // namespace scanplan::kinematics::detail
