#include <scanplan/kinematics/rotary_table.h>

#include <scanplan/kinematics/pose.h>

namespace scanplan::kinematics {

Eigen::Isometry3d RotaryTableModel::axisError() const {
  Eigen::Isometry3d E = Eigen::Isometry3d::Identity();
  E.translation() << eccentricity.x(), eccentricity.y(), 0.0;
  E.linear() = rotY(tilt.y()) * rotX(tilt.x());
  return E;
}

Eigen::Isometry3d RotaryTableModel::X_WR(double theta) const {
  Eigen::Isometry3d Rz = Eigen::Isometry3d::Identity();
  Rz.linear() = rotZ(theta);
  return X_WA * Rz * axisError();
}

Eigen::Isometry3d flangeTarget(const Eigen::Isometry3d& X_WB,
                               const RotaryTableModel& table,
                               double theta,
                               const Eigen::Isometry3d& X_RP,
                               const Eigen::Isometry3d& X_PS,
                               const Eigen::Isometry3d& X_FS) {
  return X_WB.inverse() * table.X_WR(theta) * X_RP * X_PS * X_FS.inverse();
}

}  // namespace scanplan::kinematics
