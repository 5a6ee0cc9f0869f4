#include <scanplan/kinematics/opw.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include <scanplan/kinematics/pose.h>

namespace scanplan::kinematics::detail {
namespace {

constexpr double kPi = std::numbers::pi;
// acos arguments this far beyond ±1 are rounding at a stretched or folded elbow, not an
// unreachable target; clamp them instead of dropping the solution.
constexpr double kAcosSlack = 1e-10;

// atan2 through atan, the quadrant set by hand: glibc's atan2 costs 17 ns here and atan 10, and
// the inverse takes 17 of them. Within an ulp or two of atan2; NaN stays NaN. The
// representative may differ by 2π at ±π (atan2(−0, −1)): every caller wraps the result.
double atan2ViaAtan(double y, double x) {
  constexpr double kHalfPi = std::numbers::pi / 2;
  const double ax = std::abs(x), ay = std::abs(y);
  if (ay <= ax) {
    if (ax == 0.0) return 0.0;
    const double a = std::atan(y / x);
    if (x >= 0.0) return a;
    return y >= 0.0 ? a + kPi : a - kPi;
  }
  const double a = std::atan(x / y);  // also NaN when either is NaN (the comparison failed)
  return y > 0.0 ? kHalfPi - a : -kHalfPi - a;
}

// An angle with its cosine and sine. The inverse needs the sines and cosines of the angles
// it solves for (to build the wrist rotation and the elbow); they follow algebraically from the
// ratios the angles come from, and by the angle-sum rules from each other, so the inverse calls
// no sin or cos at all (it was 40 of its calls).
struct Angle {
  double rad = 0.0, c = 1.0, s = 0.0;
};

// atan2(y, x), with cos = x / r and sin = y / r (0 for a zero vector, as atan2).
Angle angleOf(double y, double x) {
  const double r = std::sqrt(x * x + y * y);
  if (!(r > 0.0)) return {atan2ViaAtan(y, x), 1.0, 0.0};
  return {atan2ViaAtan(y, x), x / r, y / r};
}

Angle operator+(const Angle& a, const Angle& b) {
  return {a.rad + b.rad, a.c * b.c - a.s * b.s, a.s * b.c + a.c * b.s};
}
Angle operator-(const Angle& a) { return {-a.rad, a.c, -a.s}; }
Angle operator-(const Angle& a, const Angle& b) { return a + (-b); }

// acos(x) for x within rounding of [−1, 1]; false beyond (and for NaN). sin = √((1−x)(1+x)):
// 1 − x is exact near x = 1, so a nearly stretched elbow keeps its sine's precision; the angle
// is atan2(sin, cos), which is also cheaper than acos here.
bool safeAcos(double x, Angle& angle) {
  if (!(std::abs(x) <= 1.0 + kAcosSlack)) return false;  // also rejects NaN
  const double c = std::clamp(x, -1.0, 1.0);
  const double s = std::sqrt((1.0 - c) * (1.0 + c));
  angle = {atan2ViaAtan(s, c), c, s};
  return true;
}

// Rz(a) · Ry(b), written out (forward kinematics).
Eigen::Matrix3d rotZY(double a, double b) {
  const double ca = std::cos(a), sa = std::sin(a), cb = std::cos(b), sb = std::sin(b);
  Eigen::Matrix3d R;
  R << ca * cb, -sa, ca * sb, sa * cb, ca, sa * sb, -sb, 0.0, cb;
  return R;
}

// Rotation of the OPW "c" frame (after joints 1–3): Rz(q1) · Ry(q2 + q3).
Eigen::Matrix3d armRotation(double q1, double q23) { return rotZY(q1, q23); }

// The columns 0 and 2 of the wrist rotation R_ce = (Rz(q1) · Ry(q23))ᵀ · R, all the wrist
// solution reads, from the sines and cosines of q1 and q23 (no matrix product, no trig).
struct WristColumns {
  Eigen::Vector3d x, z;
};

WristColumns wristColumns(double c1, double s1, double c23, double s23, const Eigen::Matrix3d& R) {
  const auto row = [&](const Eigen::Vector3d& col) {
    return Eigen::Vector3d(c23 * (c1 * col.x() + s1 * col.y()) - s23 * col.z(),
                           -s1 * col.x() + c1 * col.y(),
                           s23 * (c1 * col.x() + s1 * col.y()) + c23 * col.z());
  };
  return {row(R.col(0)), row(R.col(2))};
}

// Joints 4–6 from the wrist rotation R_ce = Rz(q4) · Ry(q5) · Rz(q6), both wrist solutions.
// q6 is solved last from the full matrix, (Rz(q4) · Ry(q5))ᵀ · R_ce, so a poorly conditioned q4
// near q5 = 0 is absorbed and the composed rotation stays exact. The sines and cosines of q4
// and q5 are the ratios atan2 took them from; the flipped wrist (q4 + π, −q5) negates both
// entries q6 is read from, so its q6 is the other one's ± π.
void solveWrist(const WristColumns& R_ce, JointVector& no_flip, JointVector& flip) {
  const double s5 = std::sqrt(R_ce.z.x() * R_ce.z.x() + R_ce.z.y() * R_ce.z.y());
  const double q5 = atan2ViaAtan(s5, R_ce.z.z());
  const bool wrist_bent = s5 > 1e-12;
  const double q4 = wrist_bent ? atan2ViaAtan(R_ce.z.y(), R_ce.z.x()) : 0.0;
  const double inv_s5 = wrist_bent ? 1.0 / s5 : 0.0;
  const double c4 = wrist_bent ? R_ce.z.x() * inv_s5 : 1.0;
  const double s4 = R_ce.z.y() * inv_s5;
  const double inv_n5 = 1.0 / std::sqrt(s5 * s5 + R_ce.z.z() * R_ce.z.z());
  const double c5 = R_ce.z.z() * inv_n5;
  const double sin5 = s5 * inv_n5;
  const double y = -s4 * R_ce.x.x() + c4 * R_ce.x.y();
  const double x = c5 * (c4 * R_ce.x.x() + s4 * R_ce.x.y()) - sin5 * R_ce.x.z();
  const double q6 = atan2ViaAtan(y, x);
  no_flip(3) = q4;
  no_flip(4) = q5;
  no_flip(5) = q6;
  flip(3) = q4 + kPi;
  flip(4) = -q5;
  flip(5) = q6 > 0.0 ? q6 - kPi : q6 + kPi;
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
  const double reach = std::sqrt(radial_sq);
  const double nx1 = reach - p.a1;
  const Angle base = angleOf(c.y(), c.x());
  const Angle offset = angleOf(p.b, nx1 + p.a1);
  const Angle half_turn{kPi, -1.0, 0.0};
  const Angle theta1_front = base - offset;
  const Angle theta1_back = base + offset - half_turn;

  const double dz = c.z() - p.c1;
  const double kappa_sq = p.a2 * p.a2 + p.c3 * p.c3;
  const double kappa = std::sqrt(kappa_sq);
  const double c2_sq = p.c2 * p.c2;
  const Angle psi3 = angleOf(p.a2, p.c3);

  // Front (s1) and back (s2) reach: distance from shoulder to wrist centre in the arm plane.
  const double s1_sq = nx1 * nx1 + dz * dz;
  const double back_x = nx1 + 2.0 * p.a1;
  const double s2_sq = back_x * back_x + dz * dz;

  const Eigen::Vector2d shoulder(p.a1, p.c1);
  std::size_t n = 0;
  const auto emit = [&](const Angle& t1, const Angle& t2, const Angle& t3, bool back) {
    const Angle q23 = t2 + t3;
    const WristColumns R_ce = wristColumns(t1.c, t1.s, q23.c, q23.s, R);
    const Eigen::Vector2d wrist(back ? -reach : reach, c.z());
    const Eigen::Vector2d elbow = shoulder + p.c2 * Eigen::Vector2d(t2.s, t2.c);
    const bool below = elbowBelow(shoulder, wrist, elbow);
    OpwSolution& a = out[n++];
    OpwSolution& b = out[n++];
    a.q(0) = b.q(0) = t1.rad;
    a.q(1) = b.q(1) = t2.rad;
    a.q(2) = b.q(2) = t3.rad;
    a.back = b.back = back;
    a.below = b.below = below;
    solveWrist(R_ce, a.q, b.q);
    if (!a.q.allFinite() || !b.q.allFinite()) n -= 2;
  };

  Angle g2, g3;
  if (safeAcos((s1_sq + c2_sq - kappa_sq) / (2.0 * std::sqrt(s1_sq) * p.c2), g2) &&
      safeAcos((s1_sq - c2_sq - kappa_sq) / (2.0 * p.c2 * kappa), g3)) {
    const Angle phi = angleOf(nx1, dz);
    emit(theta1_front, phi - g2, g3 - psi3, false);
    // At a stretched or folded elbow (g3 = 0 or π) the second solution repeats the first.
    if (g2.rad != 0.0 || (g3.rad != 0.0 && g3.rad != kPi)) {
      emit(theta1_front, phi + g2, -g3 - psi3, false);
    }
  }
  if (safeAcos((s2_sq + c2_sq - kappa_sq) / (2.0 * std::sqrt(s2_sq) * p.c2), g2) &&
      safeAcos((s2_sq - c2_sq - kappa_sq) / (2.0 * p.c2 * kappa), g3)) {
    const Angle phi = angleOf(back_x, dz);
    emit(theta1_back, -phi - g2, g3 - psi3, true);
    if (g2.rad != 0.0 || (g3.rad != 0.0 && g3.rad != kPi)) {
      emit(theta1_back, -phi + g2, -g3 - psi3, true);
    }
  }
  return n;
}

}  // namespace scanplan::kinematics::detail
