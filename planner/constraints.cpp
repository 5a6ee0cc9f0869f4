#include <scanplan/planner/constraints.h>

#include <scanplan/kinematics/ramp.h>

namespace scanplan::planner {

PoseScore PoseEvaluator::score(double theta, const kinematics::JointVector& q) {
  const kinematics::RobotModel& robot = scene_->cell().robot;
  PoseScore s;
  double lowest = 2.0;
  const auto consider = [&](double f, const std::string& name) {
    if (f < lowest) {
      lowest = f;
      s.limiting = name;
    }
  };
  double total = 1.0;
  for (int j = 0; j < kinematics::kNumJoints; ++j) {
    const auto& joint = robot.joint(j);
    const auto k = static_cast<std::size_t>(j);
    s.joint[k] = jointLimitFactor(q(j), joint.min, joint.max, settings_.joint_gamma[k]);
    total *= s.joint[k];
    consider(s.joint[k], "joint " + std::to_string(j + 1));
  }
  s.singularity = robot.singularity(q);
  const auto ramp = [](double x, const RampSettings& r) {
    return rampFactor(x, r.low, r.high, r.gamma);
  };
  s.wrist = ramp(s.singularity.wrist, settings_.wrist);
  s.elbow = ramp(s.singularity.elbow, settings_.elbow);
  s.shoulder = ramp(s.singularity.shoulder, settings_.shoulder);
  total *= s.wrist * s.elbow * s.shoulder;
  consider(s.wrist, "wrist singularity");
  consider(s.elbow, "elbow singularity");
  consider(s.shoulder, "shoulder singularity");

  s.clearance = clearance_.evaluate(theta, q, {.bounded = true, .witness_points = true});
  total *= s.clearance.factor;
  if (s.clearance.limiting_pair >= 0) {
    const auto& pair = scene_->pairs()[static_cast<std::size_t>(s.clearance.limiting_pair)];
    const auto& bodies = scene_->bodies();
    consider(s.clearance.pairs[static_cast<std::size_t>(s.clearance.limiting_pair)].factor,
             "clearance " + bodies[static_cast<std::size_t>(pair.a)].name + " - " +
                 bodies[static_cast<std::size_t>(pair.b)].name);
  }
  s.total = total;
  if (lowest >= 1.0) s.limiting = "none";
  return s;
}

}  // namespace scanplan::planner
