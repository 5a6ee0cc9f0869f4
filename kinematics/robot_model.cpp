#include <scanplan/kinematics/robot_model.h>

#include <cmath>
#include <numbers>
#include <random>
#include <sstream>

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/opw.h>
#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/units.h>

namespace scanplan::kinematics {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
// OPW and DH must agree to numerical precision; anything larger is a wrong robot file.
constexpr double kConsistencyPosTol = 1e-9;  // m
constexpr double kConsistencyRotTol = 1e-9;  // rad
constexpr int kConsistencySamples = 200;

JointVector sampleInLimits(const RobotDefinition& def, std::mt19937& rng) {
  JointVector q;
  for (int i = 0; i < kNumJoints; ++i) {
    const auto& j = def.joints[static_cast<std::size_t>(i)];
    q(i) = std::uniform_real_distribution<double>(j.min, j.max)(rng);
  }
  return q;
}

std::string formatJoints(const JointVector& q) {
  std::ostringstream s;
  s.precision(6);
  for (int i = 0; i < kNumJoints; ++i) s << (i ? ", " : "(") << toDeg(q(i));
  s << ") deg";
  return s.str();
}

}  // namespace

namespace {

Eigen::Isometry3d dhWith(const DhJoint& j, double q, double ca, double sa) {
  const double theta = j.direction * q + j.theta_offset;
  const double ct = std::cos(theta), st = std::sin(theta);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() << ct, -st * ca, st * sa, st, ct * ca, -ct * sa, 0.0, sa, ca;
  T.translation() << j.a * ct, j.a * st, j.d;
  return T;
}

}  // namespace

Eigen::Isometry3d dhTransform(const DhJoint& j, double q) {
  return dhWith(j, q, std::cos(j.alpha), std::sin(j.alpha));
}

Eigen::Isometry3d RobotModel::dh(std::size_t i, double q) const {
  return dhWith(definition_.joints[i], q, cos_alpha_[i], sin_alpha_[i]);
}

std::string IkBranch::words() const {
  return std::string(lefty ? "LEFTY" : "RIGHTY") + (below ? " BELOW" : " ABOVE") +
         (flip ? " FLIP" : " NOFLIP");
}

RobotModel::RobotModel(RobotDefinition definition) : definition_(std::move(definition)) {
  for (std::size_t i = 0; i < kNumJoints; ++i) {
    const DhJoint& j = definition_.joints[i];
    cos_alpha_[i] = std::cos(j.alpha);
    sin_alpha_[i] = std::sin(j.alpha);
    // IK gives joints in (−π, π] (fromOpw): a whole turn away can only be inside limits that
    // reach to −π or π (with room for the rounding of q ± 2π).
    turns_[i] = j.min < -std::numbers::pi + 1e-9 || j.max > std::numbers::pi - 1e-9;
  }
  for (int i = 0; i < kNumJoints; ++i) {
    const DhJoint& j = joint(i);
    if (!(j.min < j.max)) {
      throw InputError("joint " + std::to_string(i + 1) + ": limits " +
                       std::to_string(toDeg(j.min)) + " … " + std::to_string(toDeg(j.max)) +
                       " deg: expected min < max");
    }
    if (j.direction != 1 && j.direction != -1) {
      throw InputError("joint " + std::to_string(i + 1) + ": direction must be 1 or -1");
    }
    const int s = definition_.opw.signs[static_cast<std::size_t>(i)];
    if (s != 1 && s != -1) {
      throw InputError("opw.signs[" + std::to_string(i) + "] = " + std::to_string(s) +
                       ": expected 1 or -1");
    }
  }
  const auto& p = definition_.opw;
  if (!(p.c2 > 0.0) || !(std::hypot(p.a2, p.c3) > 0.0)) {
    throw InputError("opw: c2 and the forearm (a2, c3) must have positive length");
  }
  forearm_ = std::hypot(p.a2, p.c3);
  forearm_angle_ = std::atan2(p.a2, p.c3);

  // The OPW tool frame and DH frame 6 may differ by a constant rotation about the approach
  // axis (a naming convention); anything else means the two descriptions disagree.
  const JointVector zero = JointVector::Zero();
  X_opwF_ = detail::opwForward(p, toOpw(zero)).inverse() * fk(zero);
  if (X_opwF_.translation().norm() > kConsistencyPosTol ||
      (X_opwF_.linear().col(2) - Eigen::Vector3d::UnitZ()).norm() > kConsistencyRotTol) {
    std::ostringstream s;
    s << "the OPW parameters disagree with the DH chain at q = 0: the DH flange is offset by ("
      << toMm(X_opwF_.translation().x()) << ", " << toMm(X_opwF_.translation().y()) << ", "
      << toMm(X_opwF_.translation().z())
      << ") mm from the OPW tool frame or tilted from its approach axis; expected the same frame "
         "up to a rotation about z";
    throw InputError(s.str());
  }
  X_opwF_.translation().setZero();
  std::mt19937 rng(12345);
  double max_manipulability = 0.0;
  for (int k = 0; k < kConsistencySamples; ++k) {
    const JointVector q = sampleInLimits(definition_, rng);
    const Eigen::Isometry3d X_dh = fk(q);
    const Eigen::Isometry3d X_opw = detail::opwForward(p, toOpw(q)) * X_opwF_;
    const double dp = (X_dh.translation() - X_opw.translation()).norm();
    const double dr = rotationDistance(X_dh.linear(), X_opw.linear());
    if (dp > kConsistencyPosTol || dr > kConsistencyRotTol) {
      std::ostringstream s;
      s << "the OPW parameters disagree with the DH chain: at q = " << formatJoints(q)
        << " the flange positions differ by " << toMm(dp) << " mm and orientations by " << toDeg(dr)
        << " deg; expected identical forward kinematics (check a1, a2, b, c1–c4, "
        << "offsets and signs against the DH table)";
      throw InputError(s.str());
    }
    const Jacobian J = jacobian(q);
    max_manipulability = std::max(max_manipulability, std::sqrt((J * J.transpose()).determinant()));
  }
  manipulability_scale_ = max_manipulability > 0.0 ? 1.0 / max_manipulability : 1.0;
}

std::array<Eigen::Isometry3d, kNumJoints + 1> RobotModel::linkFrames(const JointVector& q) const {
  return linkFrames(q, Eigen::Isometry3d::Identity());
}

std::array<Eigen::Isometry3d, kNumJoints + 1> RobotModel::linkFrames(
    const JointVector& q, const Eigen::Isometry3d& X_0) const {
  std::array<Eigen::Isometry3d, kNumJoints + 1> frames;
  frames[0] = X_0;
  for (std::size_t i = 0; i < kNumJoints; ++i) {
    frames[i + 1] = frames[i] * dh(i, q(static_cast<int>(i)));
  }
  return frames;
}

Eigen::Isometry3d RobotModel::chain(int from, int to, const JointVector& q) const {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  for (int i = from; i < to; ++i) X = X * dh(static_cast<std::size_t>(i), q(i));
  return X;
}

Eigen::Isometry3d RobotModel::fk(const JointVector& q) const {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  for (std::size_t i = 0; i < kNumJoints; ++i) X = X * dh(i, q(static_cast<int>(i)));
  return X;
}

Jacobian RobotModel::jacobian(const JointVector& q) const {
  const auto frames = linkFrames(q);
  const Eigen::Vector3d p_end = frames[kNumJoints].translation();
  Jacobian J;
  for (int i = 0; i < kNumJoints; ++i) {
    const auto& X = frames[static_cast<std::size_t>(i)];
    const Eigen::Vector3d z = X.linear().col(2) * joint(i).direction;
    J.block<3, 1>(0, i) = z.cross(p_end - X.translation());
    J.block<3, 1>(3, i) = z;
  }
  return J;
}

JointVector RobotModel::toOpw(const JointVector& q) const {
  JointVector out;
  for (std::size_t i = 0; i < kNumJoints; ++i) {
    const int k = static_cast<int>(i);
    out(k) = definition_.opw.signs[i] * q(k) - definition_.opw.offsets[i];
  }
  return out;
}

JointVector RobotModel::fromOpw(const JointVector& q_opw) const {
  JointVector out;
  for (std::size_t i = 0; i < kNumJoints; ++i) {
    const int k = static_cast<int>(i);
    // OPW angles lie within a turn or two of zero: a loop wraps faster than remainder().
    double a = definition_.opw.signs[i] * (q_opw(k) + definition_.opw.offsets[i]);
    while (a > std::numbers::pi) a -= kTwoPi;
    while (a <= -std::numbers::pi) a += kTwoPi;
    out(k) = a;
  }
  return out;
}

bool RobotModel::withinLimits(const JointVector& q) const {
  for (int i = 0; i < kNumJoints; ++i) {
    if (!(q(i) >= joint(i).min && q(i) <= joint(i).max)) return false;
  }
  return true;
}

Eigen::Vector3d RobotModel::wristCentre(const JointVector& q) const {
  const Eigen::Isometry3d X_tool = detail::opwForward(definition_.opw, toOpw(q));
  return X_tool.translation() - definition_.opw.c4 * X_tool.linear().col(2);
}

IkBranch RobotModel::branchOf(const JointVector& q) const {
  const auto& p = definition_.opw;
  const JointVector qo = toOpw(q);
  // Arm-plane coordinates (r along the J1-rotated x axis, z up) of shoulder, elbow, wrist.
  const Eigen::Vector2d shoulder(p.a1, p.c1);
  const Eigen::Vector2d elbow = shoulder + p.c2 * Eigen::Vector2d(std::sin(qo(1)), std::cos(qo(1)));
  const Eigen::Vector3d c = rotZ(-qo(0)) * wristCentre(q);
  const Eigen::Vector2d wrist(c.x(), c.z());
  return {wrist.x() < 0.0, detail::elbowBelow(shoulder, wrist, elbow), q(4) < 0.0};
}

void RobotModel::appendTurnVariants(const JointVector& q,
                                    const IkBranch& branch,
                                    const IkRequest& request,
                                    std::vector<IkSolution>& out) const {
  // Joints whose range exceeds 2π (J6 ±360°) can reach the same pose at q ± 2π: list each.
  std::array<std::array<double, 3>, kNumJoints> choices{};
  std::array<int, kNumJoints> counts{};
  bool all_in = true;
  for (int i = 0; i < kNumJoints; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    const DhJoint& j = joint(i);
    if (!turns_[ui]) {  // within (−π, π]: q ± 2π is outside the limits
      if (q(i) >= j.min && q(i) <= j.max)
        choices[ui][static_cast<std::size_t>(counts[ui]++)] = q(i);
    } else {
      for (double shift : {0.0, -kTwoPi, kTwoPi}) {
        const double v = q(i) + shift;
        if (v >= j.min && v <= j.max) choices[ui][static_cast<std::size_t>(counts[ui]++)] = v;
      }
    }
    if (counts[ui] == 0) {
      all_in = false;
      choices[ui][0] = q(i);
      counts[ui] = 1;
    }
  }
  if (!all_in) {
    if (!request.within_limits_only) out.push_back({q, branch, false});
    return;
  }
  std::array<int, kNumJoints> idx{};
  while (true) {
    IkSolution s{q, branch, true};
    for (int i = 0; i < kNumJoints; ++i) {
      const auto ui = static_cast<std::size_t>(i);
      s.q(i) = choices[ui][static_cast<std::size_t>(idx[ui])];
    }
    out.push_back(s);
    int i = 0;
    for (; i < kNumJoints; ++i) {
      const auto ui = static_cast<std::size_t>(i);
      if (++idx[ui] < counts[ui]) break;
      idx[ui] = 0;
    }
    if (i == kNumJoints) break;
  }
}

std::vector<IkSolution> RobotModel::ik(const Eigen::Isometry3d& X_BF,
                                       const IkRequest& request) const {
  std::vector<IkSolution> solutions;
  if (!X_BF.matrix().allFinite()) return solutions;
  std::array<detail::OpwSolution, 8> raw;
  const std::size_t n = detail::opwInverse(definition_.opw, X_BF * X_opwF_.inverse(), raw);
  solutions.reserve(2 * n);
  for (std::size_t k = 0; k < n; ++k) {
    const JointVector q = fromOpw(raw[k].q);
    appendTurnVariants(q, {raw[k].back, raw[k].below, q(4) < 0.0}, request, solutions);
  }
  return solutions;
}

SingularityMeasures RobotModel::singularity(const JointVector& q, bool with_manipulability) const {
  const auto& p = definition_.opw;
  const JointVector qo = toOpw(q);
  SingularityMeasures m;
  m.wrist = std::abs(std::sin(qo(4)));
  // Stretched or folded elbow: the forearm (a2, c3) is parallel to the upper arm.
  m.elbow = std::abs(std::sin(qo(2) + forearm_angle_));
  // The wrist centre's distance from the J1 axis: in the arm plane (J1 turns it about that
  // axis) a1 + c2·sin q2 + |forearm|·sin(q2 + q3 + ψ3) out and b across (opwForward's c).
  const double out = p.c2 * std::sin(qo(1)) + forearm_ * std::sin(qo(1) + qo(2) + forearm_angle_);
  m.shoulder = std::hypot(out + p.a1, p.b);
  if (!with_manipulability) return m;
  const Jacobian J = jacobian(q);
  m.manipulability =
      std::sqrt(std::max(0.0, (J * J.transpose()).determinant())) * manipulability_scale_;
  return m;
}

}  // namespace scanplan::kinematics
