#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <scanplan/collision/scene.h>
#include <scanplan/kinematics/robot_model.h>
#include <scanplan/kinematics/scan_path.h>
#include <scanplan/kinematics/trajectory.h>
#include <scanplan/planner/constraints.h>

namespace scanplan::planner {

/// A planned table path turned into the 7-DOF trajectory, with the true score of every pose.
struct TrajectoryBuild {
  kinematics::Trajectory trajectory;  ///< complete only when `ok`
  bool ok = false;                    ///< every sample reachable on the branch, joints continuous
  double min_f = 0.0;                 ///< lowest true f (Eq. 6, exact distances below d_high)
  std::size_t min_f_sample = 0;
  double min_clearance = 0.0;  ///< m, smallest pair distance seen below its d_high (else inf)
  std::string reason;          ///< !ok: the first sample that fails, and why
  /// !ok because this joint (0-based) would have to leave its limits to follow the path
  /// continuously (a whole-turn re-wind while scanning); -1 otherwise.
  int wrap_joint = -1;
};

/// IK at every sample of `path` with the table at theta[k] (rad), on `branch` only, followed
/// continuously (joint wrap, kinematics/joint_wrap.h): each sample takes the branch's solution
/// whose 2π-equivalent is nearest the previous sample, so a joint crosses ±180° like any angle,
/// and the limits are checked on those unwrapped values. Every solution of the first sample
/// (each in-limit whole-turn variant) is tried as a start, keeping the track whose worst
/// joint-limit factor is best. Where the continuation would leave a joint's limits, the joint
/// re-winds a whole turn to the equivalent inside them only over a stretch that does not scan
/// (a move between passes, at most 80 % of its speed); while scanning the track is broken there
/// (not ok, `wrap_joint` set). A step of more than 90° in any joint between samples is a
/// discontinuity (the IK branch flips), reported as not ok. Each pose is then scored in full
/// (PoseEvaluator, in parallel, deterministic): f and the limiting constraint go into the
/// samples. A pose with f = 0 leaves ok = true but min_f = 0 — the caller decides (the map's
/// interpolation said f > 0 there). The trajectory's joint values are the unwrapped ones: the
/// validation and the programs take them as they are.
TrajectoryBuild buildTrajectory(const collision::Scene& scene,
                                const ConstraintSettings& settings,
                                const kinematics::ScanPath& path,
                                const std::vector<double>& theta,
                                const kinematics::IkBranch& branch);

}  // namespace scanplan::planner
