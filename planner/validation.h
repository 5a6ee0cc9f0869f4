#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/collision/scene.h>
#include <scanplan/collision/sensors.h>
#include <scanplan/kinematics/trajectory.h>

namespace scanplan::planner {

/// How validateTrajectory() samples and judges a trajectory. SI units.
struct ValidationSettings {
  /// s, densification step: the largest time between two checked poses (the caller passes
  /// 1 / the scanner frame rate). > 0.
  double sample_dt = 0.01;
  /// rad/s, |table speed| bound; nullopt: the cell table's max_speed. A bound ≤ 0 is not checked.
  std::optional<double> table_omega_max = std::nullopt;
  /// rad/s², |table acceleration| bound; nullopt: the cell table's max_accel. ≤ 0: not checked.
  std::optional<double> table_alpha_max = std::nullopt;
  /// Relative tolerance on every speed and acceleration bound (value > limit·(1 + tol) fails).
  double speed_tolerance = 1e-6;
  /// m, motion resolution of the continuous collision check: an interval on which a pair's
  /// points can move relative to each other by at most this much and whose clearance still
  /// cannot be proven positive is reported as a collision (both its ends are then within
  /// collision_resolution + 10⁻⁴ m of contact, see validateTrajectory()). > 0.
  double collision_resolution = 1e-4;
};

/// One violated rule over a contiguous run of time. Values and limits are SI (rad, rad/s,
/// rad/s², m); describe() prints them in degrees and mm.
struct Violation {
  enum class Kind {
    kJointLimit,  ///< value: the joint angle, limit: the bound it passes (rad)
    kTableLimit,  ///< a limited table's angle beyond min/max (rad)
    kJointSpeed,  ///< |Δq_j/Δt| between consecutive densified poses vs DhJoint::max_speed
    kTableSpeed,  ///< |Δθ/Δt| between consecutive densified poses vs the table bound
    kTableAccel,  ///< |α| at a knot of the original samples vs the table bound (rad/s²)
    kCollision,   ///< value: the smallest distance found in the run (0: contact), m
    kSensor,      ///< a sensor's rule (job `sensors[].expect`) broken over the run; see `note`
  };
  Kind kind = Kind::kCollision;
  /// "joint 3" (1-based, as users count), "table", or the body pair "scanner - part".
  std::string what;
  int joint = -1;  ///< 0-based joint for kJointLimit / kJointSpeed, else -1
  int pair = -1;   ///< index into Scene::pairs() for kCollision, else -1
  /// s: where the run's worst value occurs; for collisions the first contact. For speeds the
  /// start of the worst interval, for accelerations the knot where the speed changes.
  double t = 0.0;
  double t_start = 0.0;  ///< s, the run's first violating pose / interval start
  double t_end = 0.0;    ///< s, the run's last violating pose / interval end
  double value = 0.0;    ///< the worst value of the run (magnitudes for speeds and accelerations)
  double limit = 0.0;    ///< the bound it breaks; kCollision: collision_resolution
  /// kCollision: the contact point at the first contact, world frame, m (the midpoint of the
  /// pair's witness points at a pose within about collision_resolution of contact). Zero else.
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();
  /// kSensor: the rule and what the sensor did, e.g. "expect never: fires (link6, scanner)".
  std::string note;
};

/// "joint limit", "table limit", "joint speed", "table speed", "table acceleration",
/// "collision", "sensor".
std::string kindName(Violation::Kind kind);
/// One line in user units (s, deg, deg/s, deg/s², mm), e.g.
/// "joint speed: joint 6 at t = 0.200 s (0.200 … 0.600 s): 1145.92 deg/s > 600.00 deg/s".
std::string describe(const Violation& violation);

struct ValidationReport {
  bool valid = false;                        ///< no violation of any kind
  std::vector<Violation> violations;         ///< ordered by t_start, then kind, then what
  std::optional<Violation> first_collision;  ///< the collision run that starts first
  /// m, the smallest exact pair distance at the checked poses (densified and bisection poses):
  /// pairs are measured exactly below their d_high only (as buildTrajectory's min_clearance), so
  /// a pair that stays beyond it does not count. Infinite when no pair came that close.
  double min_distance = 0.0;
  std::string min_distance_pair;  ///< "a - b"; empty when min_distance is infinite
  double min_distance_t = 0.0;    ///< s
  /// The same over the pairs with a body of the cell (part, table, obstacles, the robot's base
  /// against them): what limits the scan.
  double min_cell_distance = 0.0;
  std::string min_cell_distance_pair;
  double min_cell_distance_t = 0.0;
  /// The same over the robot's own pairs (links, and the scanner it carries).
  double min_self_distance = 0.0;
  std::string min_self_distance_pair;
  double min_self_distance_t = 0.0;
  /// m, a certified lower bound on every checked pair's distance over the whole continuous
  /// motion (the conservative-advancement certificate); 0 when a collision was found, infinite
  /// when the scene has no pairs.
  double proven_clearance = 0.0;
  /// The cell's sensors (CellModel::sensors) at every densified pose; absent without sensors.
  /// Their rules' violations are kSensor entries of `violations`.
  std::optional<collision::SensorEvaluation> sensors;
  std::size_t samples = 0;        ///< densified poses
  std::size_t poses_checked = 0;  ///< clearance evaluations: densified + bisection poses
  double seconds = 0.0;           ///< wall time of the validation
};

/// The trajectory sampled at most `dt` (s) apart, with the motion the emitted joint programs
/// imply: table angle and joints linear in time between consecutive samples (a PTP/MOVE to
/// each precision point). Every original sample is kept unchanged; each interval [t_k, t_k+1] is
/// cut into n = ⌈(t_k+1 − t_k)/dt⌉ equal steps. New samples: f unknown (NaN), scanning when
/// both ends scan, X_PS interpolated (translation linear, rotation slerp: the target, not the
/// pose the joints reach), limit empty. Throws std::invalid_argument when dt is not positive and
/// finite or the times are not strictly increasing; InputError (before allocating) when more
/// than 5·10⁶ samples would result.
kinematics::Trajectory densify(const kinematics::Trajectory& trajectory, double dt);

/// Proves a trajectory executable before it goes to the robot, on the densified motion
/// (densify(trajectory, settings.sample_dt)):
///
/// - Joint limits at every densified pose (exact for linear motion: a linear joint is extreme at
///   the poses), and a limited table's travel.
/// - Joint speeds |Δq_j|/Δt between consecutive densified poses vs DhJoint::max_speed; table
///   speed |Δθ|/Δt vs table_omega_max.
/// - Table acceleration on the ORIGINAL samples (the planner's grid), as planner::evaluate()
///   judges it: ω_k = (θ_k − θ_k−1)/Δt_k and α_k = (ω_k − ω_k−1)/Δt̄ with Δt̄ the mean of the two
///   steps (= Δt on a uniform grid), for k ≥ 2 (the table need not start or stop at rest). The
///   piecewise-linear motion changes speed in a step at each knot, so any acceleration computed
///   from the densified poses would only measure the densification step.
/// - Collisions between every pair of Scene::pairs(), continuously: conservative advancement
///   per densified interval. At a pose, ClearanceEvaluator (bounded) gives each pair's distance
///   d (exact below d_high; d_high, a lower bound, beyond), trusted to within a slack
///   s = 5·10⁻⁵ m for FCL's GJK tolerance: the pair is at least δ = d − s apart there. Over an
///   interval, L bounds how far any point of one body can move relative to the other:
///   Σ_j |Δq_j|·R_j over the joints between the two bodies (R_j bounds the body's distance from
///   joint j's axis, from the DH chain and bounding balls of the link's shapes) plus
///   |Δθ|·(the farthest point from the table axis) for a body the table carries. The distance is
///   L-Lipschitz along the interval, so it stays above min(δ_a, δ_b, (δ_a + δ_b − L)/2): the
///   pair is proven clear on the interval when that certificate is > 0. Otherwise the interval
///   is bisected; an interval with both ends penetrating, or whose L is at most
///   collision_resolution and still unproven, is a collision span. A pair is never called clear
///   without this proof. Spans of one pair that touch form one kCollision run: its start is the
///   first contact (to within collision_resolution of motion) with the contact point there.
///   Limitation (FCL meshes are surfaces): a body that starts wholly inside a mesh is not seen.
/// - Sensors (CellModel::sensors, seed §5.1–5.2): each evaluated at every densified pose
///   (collision::evaluateSensors); each run of poses that breaks a sensor's rule is a kSensor
///   violation from its first to its last pose.
///
/// Violations of one kind and subject over consecutive poses / intervals are merged into one
/// entry (the worst value and its time, plus the run's start and end). Poses and intervals are
/// checked in parallel (TBB, one ClearanceEvaluator per thread); the report does not depend on
/// the thread count. Throws std::invalid_argument for an empty trajectory, settings out of range,
/// or what densify() rejects; InputError for what densify() refuses as too long, and before the
/// collision check when its bisection could take more than 5·10⁶ poses in the worst case (each
/// interval's largest unproven L halved down to collision_resolution: a joint thousands of
/// degrees away between two samples).
ValidationReport validateTrajectory(const collision::Scene& scene,
                                    const kinematics::Trajectory& trajectory,
                                    const ValidationSettings& settings = {});

namespace detail {

/// validateTrajectory()'s motion bound for one body of a scene, per unit of joint / table
/// motion (exposed for tests).
struct BodyBound {
  int link = -1;          ///< on the arm's chain: 0 (base) … 6 (link 6, scanner); else -1
  bool on_table = false;  ///< carried by the table
  /// m/rad, for joints i < link: a bound on the distance of the body's points from joint i's
  /// axis over every configuration.
  std::array<double, kinematics::kNumJoints> arm{};
  double table = 0.0;  ///< m/rad: the farthest point of the body from the table axis
};

/// One BodyBound per Scene::bodies() entry (loads the meshes again to bound them).
std::vector<BodyBound> bodyBounds(const collision::Scene& scene);

/// m: a bound on how much the distance between bodies `a` and `b` can change while the joints
/// and the table move linearly by |Δq| = dq (rad) and |Δθ| = dtheta (rad). For two bodies on the
/// arm's chain it bounds the path of the far link's points in the near link's frame; otherwise
/// the sum of both bodies' paths in the world (either bounds the change of the distance).
double pairMotion(const BodyBound& a,
                  const BodyBound& b,
                  const std::array<double, kinematics::kNumJoints>& dq,
                  double dtheta) noexcept;

}  // namespace detail

}  // namespace scanplan::planner
