#pragma once

#include <Eigen/Geometry>

namespace scanplan::kinematics {

/// A rotary table (docs/design.md §2, seed §5.6). Frame A is the axis frame at θ = 0: z along the
/// rotation axis, origin at the centre of the table top. Frame R is the table top, turning
/// with θ. A real table is never ideal: the top can sit off the axis (eccentricity) and be
/// tilted on it; both turn with the table.
struct RotaryTableModel {
  Eigen::Isometry3d X_WA = Eigen::Isometry3d::Identity();  ///< axis frame in the world, m
  Eigen::Vector2d eccentricity =
      Eigen::Vector2d::Zero();                     ///< top centre off the axis, in R at θ, m
  Eigen::Vector2d tilt = Eigen::Vector2d::Zero();  ///< top tilt about x then y, rad
  double radius = 0.25;                            ///< m
  double height = 0.1;                             ///< below the top, m
  bool continuous = true;                          ///< turns without end stops
  double min = -3.141592653589793;                 ///< rad, used when not continuous
  double max = 3.141592653589793;                  ///< rad
  double max_speed = 0.0;                          ///< rad/s
  double max_accel = 0.0;                          ///< rad/s²

  /// The axis error transform: top frame R in the ideally rotated frame.
  Eigen::Isometry3d axisError() const;
  /// Table-top pose X_WR(θ) = X_WA · Rz(θ) · E, θ in rad.
  Eigen::Isometry3d X_WR(double theta) const;
};

/// The 7-DOF chain (docs/design.md §2): the flange pose the arm must reach for a sensor pose X_PS
/// on a part placed at X_RP on a table turned to θ, with the sensor mounted at X_FS.
/// X_BF = X_WB⁻¹ · X_WA · Rz(θ) · E · X_RP · X_PS · X_FS⁻¹. All poses in m.
Eigen::Isometry3d flangeTarget(const Eigen::Isometry3d& X_WB,
                               const RotaryTableModel& table,
                               double theta,
                               const Eigen::Isometry3d& X_RP,
                               const Eigen::Isometry3d& X_PS,
                               const Eigen::Isometry3d& X_FS);

}  // namespace scanplan::kinematics
