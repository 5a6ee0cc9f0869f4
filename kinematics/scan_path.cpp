#include "kinematics/scan_path.h"

namespace scanplan::kinematics {

Eigen::Isometry3d interpolatePose(const Eigen::Isometry3d& a,
                                  const Eigen::Isometry3d& b,
                                  double s) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = (1.0 - s) * a.translation() + s * b.translation();
  X.linear() =
      Eigen::Quaterniond(a.linear()).slerp(s, Eigen::Quaterniond(b.linear())).toRotationMatrix();
  return X;
}

}  // namespace scanplan::kinematics
