#pragma once

#include <array>
#include <string>

#include <scanplan/collision/clearance.h>
#include <scanplan/collision/scene.h>
#include <scanplan/kinematics/robot_model.h>

namespace scanplan::planner {

/// A monotone ramp (docs/design.md §4): 0 below low, 1 at and above high.
struct RampSettings {
  double low = 0.0;
  double high = 1.0;
  double gamma = 1.0;
};

/// The static constraints of a pose (seed §7.2, Eq. 6–8), in SI units.
struct ConstraintSettings {
  std::array<double, kinematics::kNumJoints> joint_gamma{0.2, 0.2, 0.2, 0.2, 0.2, 0.2};  ///< Eq. 7
  RampSettings wrist{0.05, 0.25, 1.0};     ///< on |sin q5|
  RampSettings elbow{0.05, 0.25, 1.0};     ///< on the elbow measure
  RampSettings shoulder{0.03, 0.12, 1.0};  ///< on the wrist centre's distance from J1, m
};

/// Every factor of one pose; f = Π of all (Eq. 6).
struct PoseScore {
  std::array<double, kinematics::kNumJoints> joint{};  ///< f_j, Eq. 7
  double wrist = 1.0;
  double elbow = 1.0;
  double shoulder = 1.0;
  kinematics::SingularityMeasures singularity;
  collision::ClearanceResult clearance;
  double total = 0.0;
  std::string
      limiting;  ///< the lowest factor's name: "joint 3", "wrist", "clearance scanner ↔ part"
};

/// Scores poses of one cell. Holds a clearance evaluator: one per thread.
class PoseEvaluator {
 public:
  /// `geometry`: what the clearance factor measures (kMap: as the configuration maps do).
  PoseEvaluator(const collision::Scene& scene,
                const ConstraintSettings& settings,
                collision::Geometry geometry = collision::Geometry::kExact)
      : scene_(&scene), settings_(settings), clearance_(scene, true, geometry) {}

  /// Every factor, with exact distances below each pair's d_high and witness points.
  PoseScore score(double theta, const kinematics::JointVector& q);

 private:
  const collision::Scene* scene_;
  ConstraintSettings settings_;
  collision::ClearanceEvaluator clearance_;
};

}  // namespace scanplan::planner
