#include "kinematics/opw.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "kinematics/pose.h"

namespace scanplan::kinematics::detail {
namespace {

constexpr double kPi = std::numbers::pi;
// acos arguments this far beyond ±1 are rounding at a stretched or folded elbow, not an
// unreachable target; clamp them instead of dropping the solution.
constexpr double kAcosSlack = 1e-10;

bool safeAcos(double x, double& angle) {
  if (!(std::abs(x) <= 1.0 + kAcosSlack)) return false;  // also rejects NaN
  angle = std::acos(std::clamp(x, -1.0, 1.0));
  return true;
}

// Rz(a) · Ry(b), written out: this is on the IK hot path (DESIGN.md §3.2: ~1 µs per solve).
Eigen::Matrix3d rotZY(double a, double b) {
  const double ca = std::cos(a), sa = std::sin(a), cb = std::cos(b), sb = std::sin(b);
  Eigen::Matrix3d R;
  R << ca * cb, -sa, ca * sb, sa * cb, ca, sa * sb, -sb, 0.0, cb;
  return R;
}

// Rotation of the OPW "c" frame (after joints 1–3): Rz(q1) · Ry(q2 + q3).
Eigen::Matrix3d armRotation(double q1, double q23) { return rotZY(q1, q23); }

// Joints 4–6 from the wrist rotation R_ce = Rz(q4) · Ry(q5) · Rz(q6), both wrist solutions.
// q6 is solved last from the full matrix, so a poorly conditioned q4 near q5 = 0 is absorbed
// and the composed rotation stays exact.
void solveWrist(const Eigen::Matrix3d& R_ce, JointVector& no_flip, JointVector& flip) {
  const double s5 = std::hypot(R_ce(0, 2), R_ce(1, 2));
  const double q5 = std::atan2(s5, R_ce(2, 2));
  const double q4 = s5 > 1e-12 ? std::atan2(R_ce(1, 2), R_ce(0, 2)) : 0.0;
  const auto finish = [&](double a4, double a5, JointVector& q) {
    const Eigen::Matrix3d rest = rotZY(a4, a5).transpose() * R_ce;
    q(3) = a4;
    q(4) = a5;
    q(5) = std::atan2(rest(1, 0), rest(0, 0));
  };
  finish(q4, q5, no_flip);
  finish(q4 + kPi, -q5, flip);
}

}  // namespace

bool elbowBelow(const Eigen::Vector2d& S, const Eigen::Vector2d& W, const Eigen::Vector2d& E) {
  const Eigen::Vector2d d = W - S;
  const double side = d.x() >= 0.0 ? 1.0 : -1.0;
  return (E - S).dot(side * Eigen::Vector2d(-d.y(), d.x())) < 0.0;
}

Eigen::Isometry3d opwForward(const OpwParameters& p, const JointVector& q) {
  const double k = std::hypot(p.a2, p.c3);
  const double psi3 = std::atan2(p.a2, p.c3);
  const double q23 = q(1) + q(2);
  const Eigen::Vector3d c_arm(p.c2 * std::sin(q(1)) + k * std::sin(q23 + psi3) + p.a1, p.b,
                              p.c2 * std::cos(q(1)) + k * std::cos(q23 + psi3) + p.c1);
  const Eigen::Vector3d c = rotZ(q(0)) * c_arm;  // the c1 term is along z, unchanged
  const Eigen::Matrix3d R = armRotation(q(0), q23) * rotZ(q(3)) * rotY(q(4)) * rotZ(q(5));
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = R;
  X.translation() = c + p.c4 * R.col(2);
  return X;
}

std::size_t opwInverse(const OpwParameters& p,
                       const Eigen::Isometry3d& X_tool,
                       std::array<OpwSolution, 8>& out) {
  const Eigen::Matrix3d& R = X_tool.linear();
  const Eigen::Vector3d c = X_tool.translation() - p.c4 * R.col(2);  // wrist centre

  const double radial_sq = c.x() * c.x() + c.y() * c.y() - p.b * p.b;
  if (!(radial_sq >= 0.0)) return 0;
  const double nx1 = std::sqrt(radial_sq) - p.a1;
  const double base = std::atan2(c.y(), c.x());
  const double offset = std::atan2(p.b, nx1 + p.a1);
  const double theta1_front = base - offset;
  const double theta1_back = base + offset - kPi;

  const double dz = c.z() - p.c1;
  const double kappa_sq = p.a2 * p.a2 + p.c3 * p.c3;
  const double kappa = std::sqrt(kappa_sq);
  const double c2_sq = p.c2 * p.c2;
  const double psi3 = std::atan2(p.a2, p.c3);

  // Front (s1) and back (s2) reach: distance from shoulder to wrist centre in the arm plane.
  const double s1_sq = nx1 * nx1 + dz * dz;
  const double back_x = nx1 + 2.0 * p.a1;
  const double s2_sq = back_x * back_x + dz * dz;

  const Eigen::Vector2d shoulder(p.a1, p.c1);
  const double reach = std::sqrt(radial_sq);
  std::size_t n = 0;
  const auto emit = [&](double t1, double t2, double t3, bool back) {
    const Eigen::Matrix3d R_ce = armRotation(t1, t2 + t3).transpose() * R;
    const Eigen::Vector2d wrist(back ? -reach : reach, c.z());
    const Eigen::Vector2d elbow = shoulder + p.c2 * Eigen::Vector2d(std::sin(t2), std::cos(t2));
    const bool below = elbowBelow(shoulder, wrist, elbow);
    OpwSolution& a = out[n++];
    OpwSolution& b = out[n++];
    a.q(0) = b.q(0) = t1;
    a.q(1) = b.q(1) = t2;
    a.q(2) = b.q(2) = t3;
    a.back = b.back = back;
    a.below = b.below = below;
    solveWrist(R_ce, a.q, b.q);
    if (!a.q.allFinite() || !b.q.allFinite()) n -= 2;
  };

  double g2 = 0.0;
  double g3 = 0.0;
  if (safeAcos((s1_sq + c2_sq - kappa_sq) / (2.0 * std::sqrt(s1_sq) * p.c2), g2) &&
      safeAcos((s1_sq - c2_sq - kappa_sq) / (2.0 * p.c2 * kappa), g3)) {
    const double phi = std::atan2(nx1, dz);
    emit(theta1_front, phi - g2, g3 - psi3, false);
    // At a stretched or folded elbow (g3 = 0 or π) the second solution repeats the first.
    if (g2 != 0.0 || (g3 != 0.0 && g3 != kPi)) emit(theta1_front, phi + g2, -g3 - psi3, false);
  }
  if (safeAcos((s2_sq + c2_sq - kappa_sq) / (2.0 * std::sqrt(s2_sq) * p.c2), g2) &&
      safeAcos((s2_sq - c2_sq - kappa_sq) / (2.0 * p.c2 * kappa), g3)) {
    const double phi = std::atan2(back_x, dz);
    emit(theta1_back, -phi - g2, g3 - psi3, true);
    if (g2 != 0.0 || (g3 != 0.0 && g3 != kPi)) emit(theta1_back, -phi + g2, -g3 - psi3, true);
  }
  return n;
}

}  // namespace scanplan::kinematics::detail
