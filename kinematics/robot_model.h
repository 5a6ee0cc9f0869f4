#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/kinematics/shape.h>

namespace scanplan::kinematics {

inline constexpr int kNumJoints = 6;
using JointVector = Eigen::Matrix<double, kNumJoints, 1>;
using Jacobian = Eigen::Matrix<double, 6, kNumJoints>;

/// One revolute joint, standard DH (docs/design.md §3.1, Eq. 1):
/// T_i = Rz(θ_i) · T(a_i, 0, d_i) · Rx(α_i) with θ_i = direction · q_i + theta_offset.
/// Lengths in m, angles in rad, speed in rad/s, acceleration in rad/s².
struct DhJoint {
  double a = 0.0;
  double d = 0.0;
  double alpha = 0.0;
  double theta_offset = 0.0;
  int direction = 1;
  double min = 0.0;
  double max = 0.0;
  double max_speed = 0.0;
  double max_accel = 0.0;  ///< rad/s²; 0: unknown (moves assume full speed in 0.25 s)
};

/// The transform of one DH row at joint value q (Eq. 1): DH frame i in frame i − 1, m.
Eigen::Isometry3d dhTransform(const DhJoint& joint, double q);

/// Ortho-parallel-wrist parameters (Brandstötter et al. 2014), m and rad:
/// q_opw = sign · q − offset.
struct OpwParameters {
  double a1 = 0.0, a2 = 0.0, b = 0.0, c1 = 0.0, c2 = 0.0, c3 = 0.0, c4 = 0.0;
  std::array<double, kNumJoints> offsets{};
  std::array<int, kNumJoints> signs{1, 1, 1, 1, 1, 1};
};

/// A robot link: its name and collision geometry in the DH frame of the link (frame 0 is the
/// base, frame k is carried by joint k).
struct Link {
  std::string name;
  std::vector<Shape> shapes;
};

/// Everything a robot file says; RobotModel checks it.
struct RobotDefinition {
  std::string name;
  std::array<DhJoint, kNumJoints> joints{};
  OpwParameters opw;
  std::array<Link, kNumJoints + 1> links{};
  /// Link pairs never checked for clearance (they touch or overlap by design), by link name
  /// (the names the collision scene gives them: the link's name, else base, link1 … link6).
  std::vector<std::array<std::string, 2>> allowed_collisions;
};

/// The V+ configuration words of an IK branch (docs/design.md §3.2).
/// RIGHTY: the wrist centre is in front of the J1 axis (on the side of the shoulder offset);
/// LEFTY: behind it. ABOVE: the elbow is above the line from shoulder to wrist centre.
/// FLIP: joint 5 negative.
struct IkBranch {
  bool lefty = false;
  bool below = false;
  bool flip = false;

  /// 0..7, bit 2 = lefty, bit 1 = below, bit 0 = flip.
  int index() const { return (lefty ? 4 : 0) | (below ? 2 : 0) | (flip ? 1 : 0); }
  static IkBranch fromIndex(int index) {
    return {(index & 4) != 0, (index & 2) != 0, (index & 1) != 0};
  }
  /// "RIGHTY ABOVE NOFLIP" style.
  std::string words() const;
  bool operator==(const IkBranch&) const = default;
};

struct IkSolution {
  JointVector q = JointVector::Zero();  ///< rad
  IkBranch branch;
  bool within_limits = false;
};

struct IkRequest {
  /// Drop solutions outside the joint limits.
  bool within_limits_only = false;
};

/// Normalised singularity measures of a configuration (docs/design.md §3.3); each is 0 at the
/// singularity. `shoulder` is a length (m): the wrist centre's distance from the J1 axis.
struct SingularityMeasures {
  double wrist = 0.0;           ///< |sin q5|
  double elbow = 0.0;           ///< |sin| of the elbow angle away from stretched/folded
  double shoulder = 0.0;        ///< m
  double manipulability = 0.0;  ///< Yoshikawa √det(J Jᵀ) / its maximum over the workspace
};

/// Immutable 6-axis arm model: FK, Jacobian, analytic IK. Thread-safe (all const).
class RobotModel {
 public:
  /// Validates the definition: limits ordered, OPW consistent with the DH chain (checked
  /// numerically over seeded random configurations). Throws scanplan::InputError otherwise.
  explicit RobotModel(RobotDefinition definition);

  const std::string& name() const { return definition_.name; }
  const RobotDefinition& definition() const { return definition_; }
  const DhJoint& joint(int i) const { return definition_.joints[static_cast<std::size_t>(i)]; }

  /// Flange pose X_BF (DH frame 6 in the base frame), m.
  Eigen::Isometry3d fk(const JointVector& q) const;
  /// All DH frames X_B0 (= identity) … X_B6.
  std::array<Eigen::Isometry3d, kNumJoints + 1> linkFrames(const JointVector& q) const;
  /// The same in the frame where the base is at X_0 (X_0 · X_B0 … X_0 · X_B6), chained from
  /// X_0: six products instead of thirteen.
  std::array<Eigen::Isometry3d, kNumJoints + 1> linkFrames(const JointVector& q,
                                                           const Eigen::Isometry3d& X_0) const;
  /// dhTransform of joint i (0-based) at q, with its α's cosine and sine computed once.
  Eigen::Isometry3d dh(std::size_t i, double q) const;
  /// DH frame `to` in DH frame `from` (0 ≤ from ≤ to ≤ 6): rows from + 1 … to at q, the other
  /// joints unread.
  Eigen::Isometry3d chain(int from, int to, const JointVector& q) const;
  /// Geometric Jacobian at the flange origin, base frame: rows vx vy vz wx wy wz.
  Jacobian jacobian(const JointVector& q) const;

  /// Every IK solution for the flange pose X_BF: up to 8 branches, each with every ±2π
  /// variant inside the limits of joints whose range exceeds 2π. Unreachable → empty.
  /// Never returns NaN.
  std::vector<IkSolution> ik(const Eigen::Isometry3d& X_BF, const IkRequest& request = {}) const;

  bool withinLimits(const JointVector& q) const;
  IkBranch branchOf(const JointVector& q) const;
  /// The measures of docs/design.md §3.3; manipulability (a Jacobian and a determinant) only when
  /// asked for, the rest is a few trigonometric terms.
  SingularityMeasures singularity(const JointVector& q, bool with_manipulability = true) const;

 private:
  JointVector toOpw(const JointVector& q) const;
  JointVector fromOpw(const JointVector& q_opw) const;
  Eigen::Vector3d wristCentre(const JointVector& q) const;
  void appendTurnVariants(const JointVector& q,
                          const IkBranch& branch,
                          const IkRequest& request,
                          std::vector<IkSolution>& out) const;

  RobotDefinition definition_;
  Eigen::Isometry3d X_opwF_ = Eigen::Isometry3d::Identity();  ///< DH flange in the OPW tool frame
  std::array<double, kNumJoints> cos_alpha_{}, sin_alpha_{};
  std::array<bool, kNumJoints> turns_{};  ///< joints whose limits may hold q ± 2π
  double manipulability_scale_ = 1.0;
  double forearm_ = 0.0;        ///< √(a2² + c3²), m
  double forearm_angle_ = 0.0;  ///< atan2(a2, c3)
};

}  // namespace scanplan::kinematics
