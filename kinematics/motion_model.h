#pragma once
// Motion models for predicting where a jogged or programmed arm and table go next (seed §7.3,
// Eq. 9 and Eq. 10): fitted over a sliding window of measured axis positions, then extrapolated
// over a horizon. Used by the predictive collision watch (pipeline/collision_watch.h).

#include <optional>
#include <span>

#include <Eigen/Geometry>

#include <scanplan/kinematics/robot_model.h>

namespace scanplan::kinematics {

/// One measured sample of the seven axes.
struct AxisSample {
  double t = 0.0;                       ///< s
  double theta = 0.0;                   ///< table angle, rad
  JointVector q = JointVector::Zero();  ///< arm joints, rad
};

enum class MotionKind {
  kStill,      ///< nothing moved over the window: nothing to predict
  kJoint,      ///< Eq. 9: every axis at a fixed share of one speed factor
  kCartesian,  ///< Eq. 10: the tool on a line, turning about a fixed axis; the table at a share
};

/// Seven coordinates: Eq. 9's joints q1…q6 and the table (rad), or Eq. 10's tool displacement
/// (m), rotation vector scaled by MotionModelOptions::lever (m) and table angle × lever (m).
using MotionVector = Eigen::Matrix<double, 7, 1>;

/// A fitted model. Both are fitted; `kind` is the one with the lower residual.
struct MotionFit {
  MotionKind kind = MotionKind::kStill;
  /// RMS over the window of each model's reconstruction error, measured the same way for both
  /// (tool position error + lever × tool rotation error + lever × table angle error), m.
  double joint_residual = 0.0;
  double cartesian_residual = 0.0;
  /// Unit direction of the chosen model (Eq. 9's δj or Eq. 10's [δx δy δz δθ·axis]), oriented
  /// along the motion.
  MotionVector direction = MotionVector::Zero();
  /// The speed factor s now: the rate of the path parameter along `direction` at the window's
  /// last sample (rad/s for kJoint, m/s for kCartesian), from the window's last samples.
  double speed = 0.0;
};

struct MotionModelOptions {
  /// Weight of angles against lengths in Eq. 10's fit and in the residuals, m per rad.
  double lever = 0.1;
  /// Below this travel over the window (rad in joint space, m for the tool) the axes stand still.
  double still = 1e-7;
  /// The speed factor is fitted on this many of the window's newest samples (≥ 2).
  std::size_t speed_samples = 5;
};

/// Fits Eq. 9 and Eq. 10 to a window of samples (oldest first, strictly increasing times).
/// Both models are rank-one: every sample's displacement from the first is the speed factor's
/// integral times a constant direction, so each fit is the window's first singular vector (the
/// least-squares optimum of the seed's "linear regression" and "nonlinear minimization").
/// The tool frame is X_FT on the flange (m). Fewer than 3 samples: kStill.
class MotionModel {
 public:
  MotionModel(const RobotModel& robot,
              const Eigen::Isometry3d& X_FT,
              const MotionModelOptions& options = {});

  MotionFit fit(std::span<const AxisSample> window) const;

  /// The axes `tau` s after `last` (the window's newest sample) under `fit`, the speed factor
  /// held. Eq. 10 goes back to joints by IK, taking the solution nearest `last` (each joint's
  /// 2π-equivalent nearest it); std::nullopt when the tool pose leaves the arm's reach or
  /// limits. kStill: `last` itself.
  std::optional<AxisSample> predict(const MotionFit& fit, const AxisSample& last, double tau) const;

  /// The tool pose in the robot base frame, m.
  Eigen::Isometry3d toolPose(const JointVector& q) const { return robot_->fk(q) * X_FT_; }

 private:
  const RobotModel* robot_;
  Eigen::Isometry3d X_FT_;
  MotionModelOptions options_;
};

}  // namespace scanplan::kinematics
