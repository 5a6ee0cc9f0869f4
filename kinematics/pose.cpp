#include <scanplan/kinematics/pose.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace scanplan::kinematics {

Eigen::Matrix3d rotX(double angle) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX()).toRotationMatrix();
}
Eigen::Matrix3d rotY(double angle) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()).toRotationMatrix();
}
Eigen::Matrix3d rotZ(double angle) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

Eigen::Matrix3d rotationFromRpy(const Eigen::Vector3d& rpy) {
  return rotZ(rpy.z()) * rotY(rpy.y()) * rotX(rpy.x());
}

Eigen::Vector3d rpyFromRotation(const Eigen::Matrix3d& R) {
  const double pitch = std::atan2(-R(2, 0), std::hypot(R(0, 0), R(1, 0)));
  if (std::hypot(R(0, 0), R(1, 0)) < 1e-12) {
    // Gimbal lock: only roll ∓ yaw is defined; put it all in roll.
    return {std::atan2(-R(1, 2), R(1, 1)), pitch, 0.0};
  }
  return {std::atan2(R(2, 1), R(2, 2)), pitch, std::atan2(R(1, 0), R(0, 0))};
}

Eigen::Matrix3d rotationFromZyz(const Eigen::Vector3d& ypr) {
  return rotZ(ypr.x()) * rotY(ypr.y()) * rotZ(ypr.z());
}

Eigen::Vector3d zyzFromRotation(const Eigen::Matrix3d& R) {
  const double s = std::hypot(R(0, 2), R(1, 2));
  const double p = std::atan2(s, R(2, 2));
  if (s < 1e-12) {
    // p = 0: R = Rz(y + r); p = π: R = Rz(y - r)·Ry(π). Put the free angle in r.
    if (R(2, 2) > 0) return {0.0, p, std::atan2(R(1, 0), R(0, 0))};
    return {0.0, p, std::atan2(R(1, 0), -R(0, 0))};
  }
  return {std::atan2(R(1, 2), R(0, 2)), p, std::atan2(R(2, 1), -R(2, 0))};
}

Eigen::Isometry3d poseFromXyzRpy(const Eigen::Vector3d& xyz, const Eigen::Vector3d& rpy) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = rotationFromRpy(rpy);
  X.translation() = xyz;
  return X;
}

Eigen::Isometry3d frameFromAxes(const Eigen::Vector3d& p,
                                const Eigen::Vector3d& z,
                                const Eigen::Vector3d& x) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d zn = z.normalized();
  const Eigen::Vector3d xn = (x - x.dot(zn) * zn).normalized();
  X.linear().col(0) = xn;
  X.linear().col(1) = zn.cross(xn);
  X.linear().col(2) = zn;
  X.translation() = p;
  return X;
}

double rotationDistance(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B) {
  // atan2 form stays accurate for tiny angles, where acos((tr-1)/2) loses half the digits.
  const Eigen::Matrix3d D = A.transpose() * B;
  const Eigen::Vector3d axis_sin(D(2, 1) - D(1, 2), D(0, 2) - D(2, 0), D(1, 0) - D(0, 1));
  return std::atan2(0.5 * axis_sin.norm(), 0.5 * (D.trace() - 1.0));
}

double wrapToPi(double angle) {
  double a = std::remainder(angle, 2.0 * std::numbers::pi);
  if (a <= -std::numbers::pi) a += 2.0 * std::numbers::pi;
  return a;
}

}  // namespace scanplan::kinematics
