#pragma once

#include <Eigen/Geometry>

namespace scanplan::kinematics {

/// Elementary rotations and the boundary Euler conventions (docs/design.md §2). Angles in rad.
Eigen::Matrix3d rotX(double angle);
Eigen::Matrix3d rotY(double angle);
Eigen::Matrix3d rotZ(double angle);

/// Roll-pitch-yaw about fixed axes: R = Rz(yaw) · Ry(pitch) · Rx(roll).
Eigen::Matrix3d rotationFromRpy(const Eigen::Vector3d& rpy);
/// Inverse of rotationFromRpy; pitch in [-π/2, π/2].
Eigen::Vector3d rpyFromRotation(const Eigen::Matrix3d& R);

/// V+ TRANS(x, y, z, y, p, r) orientation, ZYZ' Euler: R = Rz(y) · Ry(p) · Rz(r).
Eigen::Matrix3d rotationFromZyz(const Eigen::Vector3d& ypr);
/// Inverse of rotationFromZyz with p in [0, π]; at p = 0 or π the split is y = 0.
Eigen::Vector3d zyzFromRotation(const Eigen::Matrix3d& R);

/// Pose from a translation (m) and an RPY rotation (rad).
Eigen::Isometry3d poseFromXyzRpy(const Eigen::Vector3d& xyz, const Eigen::Vector3d& rpy);

/// Angle (rad, in [0, π]) of the rotation that takes A onto B.
double rotationDistance(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B);

/// The frame at `p` whose z axis is along `z` and whose x axis is `x` made orthogonal to it
/// (y = z × x). Precondition: z ≠ 0 and x not parallel to z.
Eigen::Isometry3d frameFromAxes(const Eigen::Vector3d& p,
                                const Eigen::Vector3d& z,
                                const Eigen::Vector3d& x);

/// Wraps an angle into (-π, π].
double wrapToPi(double angle);

}  // namespace scanplan::kinematics
