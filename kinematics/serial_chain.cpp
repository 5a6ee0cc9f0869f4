#include <scanplan/kinematics/serial_chain.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/units.h>

namespace scanplan::kinematics {
namespace {

constexpr double kPi = std::numbers::pi;
// The geometry must hold to the precision RobotModel checks OPW against DH with (1e-9 m and rad
// over the workspace): a chain off by more is not the arm its idealised parameters describe.
constexpr double kAngleTol = 1e-9;   // rad
constexpr double kLengthTol = 1e-9;  // m

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", std::abs(v) < 1e-9 ? 0.0 : v);  // no "-1e-31"
  return buf;
}

std::string jointLabel(const SerialChain& chain, int i) {
  const std::string& name = chain.joints[static_cast<std::size_t>(i)].name;
  return "J" + std::to_string(i + 1) + (name.empty() ? "" : " (" + name + ")");
}

// Angle between two directions, 0 … π.
double angleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Signed angle from a to b about the unit axis n (a, b perpendicular to n).
double angleAbout(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& n) {
  return std::atan2(a.cross(b).dot(n), a.dot(b));
}

// The closest points of two lines: on a, on b; for parallel lines the foot of a's point on b.
std::pair<Eigen::Vector3d, Eigen::Vector3d> closestPoints(const AxisLine& a, const AxisLine& b) {
  const Eigen::Vector3d w = a.point - b.point;
  const double c = a.direction.dot(b.direction);
  const double sin = a.direction.cross(b.direction).norm();  // 1 − c² loses small angles
  const double den = sin * sin;
  if (sin < kAngleTol) {
    return {a.point, b.point + w.dot(b.direction) * b.direction};
  }
  const double d = a.direction.dot(w), e = b.direction.dot(w);
  const double s = (c * e - d) / den, t = (e - c * d) / den;
  return {a.point + s * a.direction, b.point + t * b.direction};
}

double lineDistance(const AxisLine& a, const AxisLine& b) {
  const auto [pa, pb] = closestPoints(a, b);
  return (pb - pa).norm();
}

// +1 when the axis as written points along its largest component, else −1.
int writtenSense(const Eigen::Vector3d& axis) {
  Eigen::Index k = 0;
  axis.cwiseAbs().maxCoeff(&k);
  return axis(k) >= 0.0 ? 1 : -1;
}

// A DH frame: origin, x and z axes in the base frame.
struct DhFrame {
  Eigen::Vector3d o = Eigen::Vector3d::Zero();
  Eigen::Vector3d x = Eigen::Vector3d::UnitX();
  Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
};

// The DH row from frame `prev` to the frame `next` (whose x must cross prev.z at a right angle).
DhJoint dhRow(const DhFrame& prev, const DhFrame& next) {
  DhJoint j;
  const Eigen::Vector3d r = next.o - prev.o;
  j.d = r.dot(prev.z);
  j.a = r.dot(next.x);
  j.theta_offset = angleAbout(prev.x, next.x, prev.z);
  j.alpha = angleAbout(prev.z, next.z, next.x);
  return j;
}

// DH frame i (z along `axis`, the joint i+1 axis) after frame `prev`: x along the common normal,
// turned to the side of prev.x (so offsets stay small and a may be negative).
DhFrame nextDhFrame(const DhFrame& prev, const AxisLine& axis) {
  const auto [a, b] = closestPoints({prev.o, prev.z}, axis);
  DhFrame f{b, prev.x, axis.direction};
  const Eigen::Vector3d normal = b - a;
  const Eigen::Vector3d cross = prev.z.cross(axis.direction);
  if (normal.norm() > kLengthTol) {
    f.x = normal.normalized();
  } else if (cross.norm() > kAngleTol) {
    f.x = cross.normalized();
  }  // else the same line: keep prev.x
  if (f.x.dot(prev.x) < 0.0) f.x = -f.x;
  return f;
}

// DH frame 0 is the base: the J1 axis must be its z axis.
void requireJ1OnBaseZ(const SerialChain& chain, const AxisLine& j1) {
  const double tilt = std::min(angleBetween(j1.direction, Eigen::Vector3d::UnitZ()),
                               angleBetween(-j1.direction, Eigen::Vector3d::UnitZ()));
  const Eigen::Vector3d off = j1.point - j1.point.dot(j1.direction) * j1.direction;
  if (tilt <= kAngleTol && off.norm() <= kLengthTol) return;
  throw InputError(jointLabel(chain, 0) + ": its axis is " + number(toDeg(tilt)) +
                   " deg from the base z axis and passes " + number(toMm(off.norm())) +
                   " mm from the base origin; expected the base frame's z axis (DH frame 0 is "
                   "the base: choose a base link whose origin is on J1 and whose z axis is "
                   "along it)");
}

// Frame 6 is the tip: its x axis must cross the J6 axis at a right angle.
DhFrame tipDhFrame(const SerialChain& chain, const DhFrame& frame5, const Eigen::Isometry3d& X_BT) {
  const DhFrame tip{X_BT.translation(), X_BT.linear().col(0), X_BT.linear().col(2)};
  const double skew = std::abs(kPi / 2 - angleBetween(tip.x, frame5.z));
  Eigen::Vector3d r = tip.o - frame5.o;
  r -= r.dot(frame5.z) * frame5.z;
  const double off = (r - r.dot(tip.x) * tip.x).norm();
  if (skew <= kAngleTol && off <= kLengthTol) return tip;
  throw InputError("the tip frame cannot be DH frame 6 of " + jointLabel(chain, 5) +
                   ": its x axis is " + number(toDeg(skew)) +
                   " deg from perpendicular to the J6 axis and its origin " + number(toMm(off)) +
                   " mm off the line that axis would need; expected a tip whose x axis crosses "
                   "the J6 axis at a right angle, e.g. a flange or tool0 frame with z along J6");
}

double parallelOff(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double angle = angleBetween(a, b);
  return std::min(angle, kPi - angle);
}

// Every ortho-parallel condition (docs/design.md §12) the chain breaks at q = 0, with by how much.
std::vector<std::string> orthoParallelFailures(const SerialChain& chain,
                                               const std::array<AxisLine, kNumJoints>& ax,
                                               const Eigen::Isometry3d& X_BT) {
  std::vector<std::string> out;
  const auto dir = [&](int i) { return ax[static_cast<std::size_t>(i)].direction; };
  const auto perpendicular = [&](int i, int j) {
    const double angle = angleBetween(dir(i), dir(j));
    if (std::abs(kPi / 2 - angle) <= kAngleTol) return;
    out.push_back(jointLabel(chain, i) + " is not perpendicular to " + jointLabel(chain, j) +
                  ": the axes are " + number(toDeg(angle)) + " deg apart, expected 90");
  };
  const double tilt = parallelOff(dir(0), Eigen::Vector3d::UnitZ());
  if (tilt > kAngleTol) {
    out.push_back(jointLabel(chain, 0) + " is " + number(toDeg(tilt)) +
                  " deg from the base z axis, expected along it");
  }
  perpendicular(1, 0);
  if (const double off = parallelOff(dir(2), dir(1)); off > kAngleTol) {
    out.push_back(jointLabel(chain, 2) + " is not parallel to " + jointLabel(chain, 1) + ": " +
                  number(toDeg(off)) + " deg apart");
  } else if (lineDistance(ax[1], ax[2]) <= kLengthTol) {
    out.push_back("J2 and J3 are the same line: expected an upper arm of positive length");
  }
  perpendicular(3, 2);
  perpendicular(4, 3);
  perpendicular(5, 4);
  const double d45 = lineDistance(ax[3], ax[4]), d56 = lineDistance(ax[4], ax[5]);
  if (d45 > kLengthTol) {
    out.push_back("the J4 and J5 axes do not intersect: they pass " + number(toMm(d45)) +
                  " mm apart");
  }
  if (d56 > kLengthTol) {
    out.push_back("the J5 and J6 axes do not intersect: they pass " + number(toMm(d56)) +
                  " mm apart");
  }
  const double apart =
      (closestPoints(ax[3], ax[4]).second - closestPoints(ax[5], ax[4]).second).norm();
  if (d45 <= kLengthTol && d56 <= kLengthTol && apart > kLengthTol) {
    out.push_back("the J4, J5 and J6 axes do not meet in one point: J4 crosses J5 " +
                  number(toMm(apart)) + " mm from where J6 does");
  }
  const double tip_off = lineDistance({X_BT.translation(), ax[5].direction}, ax[5]);
  const double tip_tilt = parallelOff(X_BT.linear().col(2), ax[5].direction);
  if (tip_off > kLengthTol || tip_tilt > kAngleTol) {
    out.push_back("the tip is " + number(toMm(tip_off)) + " mm off the J6 axis and its z axis " +
                  number(toDeg(tip_tilt)) + " deg from it, expected on it and along it");
  }
  return out;
}

// The chain's joint values q* at the OPW zero pose (arm upright, J2, J3, J5 along +y, J1, J4,
// J6 and the tool z along +z, tool x along +x) and the signs s (q_opw = s·q − s·q*), found joint
// by joint: each q*_i turns the next axis (or arm segment) into its OPW place.
struct OpwZero {
  JointVector q = JointVector::Zero();
  std::array<int, kNumJoints> signs{1, 1, 1, 1, 1, 1};
};

int signOf(double v) { return v >= 0.0 ? 1 : -1; }

// The wrist centre (where J4 crosses J5) at q.
Eigen::Vector3d wristCentre(const std::array<AxisLine, kNumJoints>& ax) {
  return closestPoints(ax[3], ax[4]).first;
}

OpwZero findOpwZero(const SerialChain& chain) {
  OpwZero z;
  auto& q = z.q;
  auto& s = z.signs;
  const auto axes = [&] { return chainAxes(chain, q); };
  const auto tip = [&] { return chainFrames(chain, q).X_BT; };
  // J1: J2's axis along +y, on the side of positive a1 (the shoulder offset in front).
  s[0] = signOf(axes()[0].direction.z());
  Eigen::Vector3d u = axes()[1].direction;
  q(0) = s[0] * (kPi / 2 - std::atan2(u.y(), u.x()));
  if (axes()[1].point.x() < -kLengthTol) q(0) += s[0] * kPi;
  // J2: the upper arm (J2 → J3 axis) straight up.
  auto ax = axes();
  s[1] = signOf(ax[1].direction.y());
  const Eigen::Vector3d arm = ax[2].point - ax[1].point;
  q(1) = -s[1] * std::atan2(arm.x(), arm.z());
  // J3: the J4 axis up, in the sense that makes the forearm length c3 positive.
  ax = axes();
  s[2] = signOf(ax[2].direction.y());
  u = ax[3].direction;
  if ((wristCentre(ax) - ax[2].point).dot(u) < 0.0) u = -u;
  q(2) = -s[2] * std::atan2(u.x(), u.z());
  // J4: J5's axis along +y.
  ax = axes();
  s[3] = signOf(ax[3].direction.z());
  u = ax[4].direction;
  q(3) = s[3] * (kPi / 2 - std::atan2(u.y(), u.x()));
  // J5: the tool's z axis up.
  s[4] = signOf(axes()[4].direction.y());
  u = tip().linear().col(2);
  q(4) = -s[4] * std::atan2(u.x(), u.z());
  // J6: the tool's x axis along +x.
  s[5] = signOf(axes()[5].direction.dot(tip().linear().col(2)));
  u = tip().linear().col(0);
  q(5) = -s[5] * std::atan2(u.y(), u.x());
  return z;
}

}  // namespace

ChainFrames chainFrames(const SerialChain& chain, const JointVector& q) {
  ChainFrames f;
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  for (std::size_t i = 0; i < kNumJoints; ++i) {
    const ChainJoint& j = chain.joints[i];
    X = X * j.X_prev;
    X.linear() = X.linear() * Eigen::AngleAxisd(q(static_cast<int>(i)), j.axis.normalized());
    f.X_BJ[i] = X;
  }
  f.X_BT = X * chain.X_J6T;
  return f;
}

std::array<AxisLine, kNumJoints> chainAxes(const SerialChain& chain, const JointVector& q) {
  const ChainFrames f = chainFrames(chain, q);
  std::array<AxisLine, kNumJoints> axes;
  for (std::size_t i = 0; i < kNumJoints; ++i) {
    const Eigen::Vector3d& axis = chain.joints[i].axis;
    if (!(axis.norm() > 0.0) || !axis.allFinite()) {
      throw InputError(jointLabel(chain, static_cast<int>(i)) + ": axis (" + number(axis.x()) +
                       ", " + number(axis.y()) + ", " + number(axis.z()) +
                       "): expected a non-zero direction");
    }
    axes[i] = {f.X_BJ[i].translation(), f.X_BJ[i].linear() * axis.normalized()};
  }
  return axes;
}

std::array<DhJoint, kNumJoints> dhFromChain(const SerialChain& chain) {
  const JointVector zero = JointVector::Zero();
  auto axes = chainAxes(chain, zero);
  requireJ1OnBaseZ(chain, axes[0]);
  // DH z axes: along each joint's axis, or against it (direction −1).
  std::array<int, kNumJoints> directions{};
  for (std::size_t i = 0; i < kNumJoints; ++i) {
    directions[i] =
        i == 0 ? (axes[0].direction.z() > 0.0 ? 1 : -1) : writtenSense(chain.joints[i].axis);
    axes[i].direction *= directions[i];
  }
  std::array<DhJoint, kNumJoints> rows;
  DhFrame prev;
  for (std::size_t i = 0; i < kNumJoints; ++i) {
    const ChainJoint& j = chain.joints[i];
    const DhFrame next = i + 1 < kNumJoints
                             ? nextDhFrame(prev, axes[i + 1])
                             : tipDhFrame(chain, prev, chainFrames(chain, zero).X_BT);
    rows[i] = dhRow(prev, next);
    rows[i].direction = directions[i];
    rows[i].min = j.min;
    rows[i].max = j.max;
    rows[i].max_speed = j.max_speed;
    prev = next;
  }
  return rows;
}

OpwParameters opwFromChain(const SerialChain& chain) {
  const JointVector zero = JointVector::Zero();
  const std::vector<std::string> failures =
      orthoParallelFailures(chain, chainAxes(chain, zero), chainFrames(chain, zero).X_BT);
  if (!failures.empty()) {
    std::string message =
        "not an ortho-parallel arm with a spherical wrist, so there is no analytic (OPW) inverse "
        "kinematics for it: ";
    for (std::size_t i = 0; i < failures.size(); ++i) message += (i ? "; " : "") + failures[i];
    throw InputError(message);
  }
  const OpwZero z = findOpwZero(chain);
  const auto ax = chainAxes(chain, z.q);
  const Eigen::Vector3d c = wristCentre(ax);
  const Eigen::Vector3d forearm = c - ax[2].point;
  OpwParameters p;
  p.a1 = ax[1].point.x();
  p.c1 = ax[1].point.z();
  p.c2 = ax[2].point.z() - p.c1;
  p.a2 = forearm.x();
  p.c3 = forearm.z();
  p.b = c.y();
  p.c4 = (chainFrames(chain, z.q).X_BT.translation() - c).z();
  for (std::size_t i = 0; i < kNumJoints; ++i) {
    p.signs[i] = z.signs[i];
    p.offsets[i] = wrapToPi(z.signs[i] * z.q(static_cast<int>(i)));
  }
  return p;
}

}  // namespace scanplan::kinematics
