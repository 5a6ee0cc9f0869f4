#pragma once
// Presence and distance sensors in the cell (seed §5.1–5.2), evaluated on the collision scene's
// exact geometry (not the maps' hulls) at poses of a trajectory, and the job's rules on them.

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/collision/scene.h>
#include <scanplan/kinematics/cell.h>
#include <scanplan/kinematics/trajectory.h>

namespace scanplan::collision {

/// A distance sensor's outcome at one pose.
enum class BeamStatus {
  kReading,           ///< a target within [min_range, max_range], seen by the receiver
  kNoTarget,          ///< nothing along the beam up to max_range
  kTooClose,          ///< the first hit is nearer than min_range (it blocks the beam)
  kReceiverOccluded,  ///< the ray from the hit point to the receiver is blocked (§5.2)
};
/// "reading", "no_target", "too_close", "receiver_occluded".
std::string_view beamStatusName(BeamStatus status);

/// One sensor's output at one pose.
struct SensorReading {
  /// The Boolean output: a presence volume overlaps a body, or a distance sensor reads.
  bool fires = false;
  /// Presence: the bodies overlapping the volume, indices into Scene::bodies(), ascending.
  std::vector<int> bodies;
  BeamStatus beam = BeamStatus::kNoTarget;  ///< distance sensors
  /// m, distance sensors: the range from the emitter to the first hit along the beam (also when
  /// kTooClose or kReceiverOccluded); 0 for kNoTarget.
  double distance = 0.0;
  int body = -1;  ///< distance sensors: the body hit first, -1 for kNoTarget
};

/// Every sensor of the cell at each of a series of poses.
struct SensorEvaluation {
  std::vector<double> t;  ///< s, the sample times
  /// readings[s][k]: sensor s (CellModel::sensors order) at sample k.
  std::vector<std::vector<SensorReading>> readings;
};

/// The body names a sensor may be mounted on ("world", then the scene's bodies), for messages.
std::string carrierChoices(const Scene& scene);

/// Evaluates the cell's sensors (Scene::cell().sensors) at poses. Presence: each body whose
/// exact geometry overlaps the volume (solid against solid; a mesh counts when one of its
/// triangles meets the volume, so a volume wholly inside a closed mesh is not seen). Distance:
/// the beam from the sensor origin along +z of the sensor frame, the first hit on the bodies'
/// exact surfaces (primitives in closed form, meshes triangle by triangle); with a receiver,
/// the ray from the hit point to it must be free of every body (the hit body included) beyond
/// kReceiverClearance of both ends. The carrier body is never seen by its own sensor. Holds
/// per-thread scratch: make one per thread; the scene is shared.
class SensorEvaluator {
 public:
  /// Throws InputError when a sensor's carrier names no body of the scene (listing them).
  explicit SensorEvaluator(const Scene& scene);
  ~SensorEvaluator();
  /// A copy shares the immutable geometry (volumes, the meshes' ray-cast trees) and has scratch
  /// of its own: one per thread.
  SensorEvaluator(const SensorEvaluator& other);
  SensorEvaluator(SensorEvaluator&&) noexcept;
  SensorEvaluator& operator=(SensorEvaluator&&) noexcept;

  /// Every sensor at table angle θ and arm joints q (rad); throws std::invalid_argument for a
  /// non-finite pose (as Scene::bodyPoses).
  std::vector<SensorReading> evaluate(double theta, const kinematics::JointVector& q);
  /// The world pose of sensor `s`'s frame at the pose last evaluated (m).
  const Eigen::Isometry3d& sensorPose(std::size_t s) const;
  /// Index of sensor `s`'s carrier in Scene::bodies(), -1 for the world.
  int carrierBody(std::size_t s) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// m: the return ray to the receiver ignores hits this close to either end (its start lies on
/// the hit surface).
inline constexpr double kReceiverClearance = 1e-6;

/// The most readings (sensors × samples) evaluateSensors() makes: about 0.5 GB.
inline constexpr std::size_t kMaxSensorReadings = 10'000'000;
/// The most body entries the presence readings may list (samples × the scene's bodies for each
/// presence sensor, the worst case): about 0.2 GB.
inline constexpr std::size_t kMaxSensorBodyEntries = 50'000'000;

/// Every sensor at every sample (in order). Deterministic. Throws InputError, before allocating,
/// when that would be more than kMaxSensorReadings readings or kMaxSensorBodyEntries bodies.
SensorEvaluation evaluateSensors(const Scene& scene,
                                 const std::vector<kinematics::TrajectorySample>& samples);

/// A run of consecutive samples, [t_start, t_end] their first and last times (s).
struct SensorSpan {
  double t_start = 0.0;
  double t_end = 0.0;
  std::vector<int> bodies;  ///< presence: every body seen during the run, ascending
};
/// The runs of samples at which sensor `s` fires.
std::vector<SensorSpan> firingSpans(const SensorEvaluation& evaluation, std::size_t s);

/// A broken rule (kinematics::SensorExpectation) over a run of samples.
struct SensorRuleViolation {
  std::size_t sensor = 0;  ///< index into CellModel::sensors
  bool fired = false;      ///< the sensor fired where it must not (else: silent where it must fire)
  SensorSpan span;
};
/// "never", "always", "during [1.000, 2.500] s", "not during [1.000, 2.500] s", "any".
std::string describeExpectation(const kinematics::SensorExpectation& expect);
/// The rules of the cell's sensors on an evaluation: runs of samples where a sensor fires
/// against its rule, or is silent where it must fire (kDuring, kAlways). A window's ends count
/// as inside it (to 1e-9 s). The part of a kDuring window beyond the first or last sample is a
/// violation (silent): the rule asks for firing there, and no sample shows it. In order of
/// sensor, then time.
std::vector<SensorRuleViolation> checkSensorRules(const std::vector<kinematics::Sensor>& sensors,
                                                  const SensorEvaluation& evaluation);

}  // namespace scanplan::collision
