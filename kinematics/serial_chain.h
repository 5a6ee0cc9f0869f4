#pragma once
// A 6R serial chain as URDF describes it (joint origins and axes), and its conversion to the
// robot model's standard DH rows and OPW parameters (docs/design.md §3, §12). Pure Eigen: the URDF
// reader lives in config/.

#include <array>
#include <string>

#include <Eigen/Geometry>

#include <scanplan/kinematics/robot_model.h>

namespace scanplan::kinematics {

/// One revolute joint of a serial chain (m, rad, rad/s).
struct ChainJoint {
  std::string name;
  /// This joint's frame J_i in the previous joint's frame J_{i−1} (after that joint's rotation;
  /// J_0 is the base), with every fixed joint in between folded in.
  Eigen::Isometry3d X_prev = Eigen::Isometry3d::Identity();
  /// The rotation axis in J_i (need not be unit; not zero): q_i > 0 turns counter-clockwise
  /// about it, as in URDF.
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double min = 0.0;
  double max = 0.0;
  double max_speed = 0.0;
};

/// A chain of six revolute joints from a base frame B to a tip frame T.
struct SerialChain {
  std::array<ChainJoint, kNumJoints> joints;
  Eigen::Isometry3d X_J6T = Eigen::Isometry3d::Identity();  ///< the tip in joint 6's frame
};

/// The joint frames X_BJ1 … X_BJ6 (each after its rotation) and the tip X_BT at q, m.
struct ChainFrames {
  std::array<Eigen::Isometry3d, kNumJoints> X_BJ;
  Eigen::Isometry3d X_BT = Eigen::Isometry3d::Identity();
};
ChainFrames chainFrames(const SerialChain& chain, const JointVector& q);

/// A joint axis as a line in the base frame: a point on it and its unit direction (the sense
/// in which the joint turns positive).
struct AxisLine {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
};
/// The six joint axes at q.
std::array<AxisLine, kNumJoints> chainAxes(const SerialChain& chain, const JointVector& q);

/// Standard DH rows with the chain's forward kinematics: DH frame 0 is the base B, DH frame 6 the
/// tip T, and θ_i = direction·q_i + theta_offset for the chain's own joint values (limits and
/// speeds copied). Each DH z axis points along the joint's axis as written (in its own frame)
/// when that axis's largest component is positive, else against it (`direction` −1): an axis
/// `0 0 -1` gives direction −1. Throws InputError when B or T cannot be DH frames: the J1 axis
/// must be B's z axis (either sense, through its origin), and T's x axis must cross the J6 axis
/// at a right angle (a tool frame with z along the J6 axis does).
std::array<DhJoint, kNumJoints> dhFromChain(const SerialChain& chain);

/// The OPW parameters (Brandstötter et al. 2014; docs/design.md §3.2, §12) of the chain, with the
/// offsets and signs for the chain's joint values and the tip as the OPW tool frame. Throws
/// InputError naming every ortho-parallel condition the chain breaks and by how much: J1 along
/// B's z, J2 ⟂ J1, J3 ∥ J2 (and apart), J4 ⟂ J3, J5 ⟂ J4, J6 ⟂ J5, the J4, J5, J6 axes meeting
/// in one point, T on the J6 axis with z along it.
OpwParameters opwFromChain(const SerialChain& chain);

}  // namespace scanplan::kinematics
