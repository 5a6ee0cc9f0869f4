#include <scanplan/planner/trajectory_builder.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <scanplan/kinematics/joint_wrap.h>
#include <scanplan/kinematics/ramp.h>
#include <scanplan/kinematics/units.h>

namespace scanplan::planner {

namespace {

constexpr double kMaxJointStep = std::numbers::pi / 2;  // rad between samples: more is a jump

struct Track {
  std::vector<kinematics::JointVector> q;
  double worst_joint_factor = 1.0;
  std::string broken;   // why the track cannot continue
  int wrap_joint = -1;  // broken because this joint's continuous value leaves its limits
};

// IK on the branch at every sample (independent: parallel).
std::vector<std::vector<kinematics::JointVector>> branchSolutions(
    const kinematics::CellModel& cell,
    const kinematics::ScanPath& path,
    const std::vector<double>& theta,
    const kinematics::IkBranch& branch) {
  std::vector<std::vector<kinematics::JointVector>> solutions(theta.size());
  tbb::parallel_for(std::size_t{0}, theta.size(), [&](std::size_t k) {
    for (const auto& s : cell.robot.ik(cell.flangeTarget(theta[k], path.samples[k].X_PS),
                                       {.within_limits_only = false})) {
      if (s.branch == branch) solutions[k].push_back(s.q);
    }
  });
  return solutions;
}

double jointFactor(const kinematics::RobotModel& robot,
                   const ConstraintSettings& settings,
                   const kinematics::JointVector& q) {
  double f = 1.0;
  for (int j = 0; j < kinematics::kNumJoints; ++j) {
    f *= jointLimitFactor(q(j), robot.joint(j).min, robot.joint(j).max,
                          settings.joint_gamma[static_cast<std::size_t>(j)]);
  }
  return f;
}

// Why the nearest continuation is too far to step to: the joints jump (a singularity).
std::string jumpReason(const kinematics::ScanPath& path,
                       const kinematics::IkBranch& branch,
                       std::size_t k,
                       const kinematics::JointVector& from,
                       const kinematics::JointVector& to) {
  int joint = 0;
  const double step = (to - from).cwiseAbs().maxCoeff(&joint);
  return fmt::format(
      "time sample {} (t = {:.3f} s): joint {} would jump by {:.1f} deg between samples (the pose "
      "passes a singularity); no continuous motion on branch {}",
      k, path.samples[k].t, joint + 1, toDeg(step), branch.words());
}

// The first joint of the continuation `next` outside its limits (-1: none).
int jointOutside(const kinematics::RobotModel& robot, const kinematics::JointVector& next) {
  for (int j = 0; j < kinematics::kNumJoints; ++j) {
    if (!(next(j) >= robot.joint(j).min && next(j) <= robot.joint(j).max)) return j;
  }
  return -1;
}

// Why the track cannot continue within the limits: joint j would need `next(j)`.
std::string wrapReason(const kinematics::RobotModel& robot,
                       const kinematics::ScanPath& path,
                       std::size_t k,
                       int j,
                       const kinematics::JointVector& next,
                       const kinematics::JointVector& inside) {
  const auto& limits = robot.joint(j);
  return fmt::format(
      "time sample {} (t = {:.3f} s): joint {} would have to pass its limit ({:.0f} … {:.0f} deg) "
      "to follow the path continuously: it would need {:.0f} deg (the map's cells there use the "
      "other whole-turn solution, {:.0f} deg away)",
      k, path.samples[k].t, j + 1, toDeg(limits.min), toDeg(limits.max), toDeg(next(j)),
      toDeg(std::abs(inside(j) - next(j))));
}

// The joint that turns a whole turn from `prev` to `q` while every other joint steps less than
// kMaxJointStep; -1 when there is none.
int wholeTurnJoint(const kinematics::JointVector& prev, const kinematics::JointVector& q) {
  int joint = -1;
  for (int j = 0; j < kinematics::kNumJoints; ++j) {
    const double d = q(j) - prev(j);
    if (std::abs(d) <= kMaxJointStep) continue;
    if (joint >= 0 || std::abs(std::abs(d) - 2.0 * std::numbers::pi) > kMaxJointStep) return -1;
    joint = j;
  }
  return joint;
}

// Where the track must jump a whole turn of one joint at sample k and the path does not scan
// there, the joint unwinds over the stretch of non-scanning samples before k instead (a move
// between passes): it turns by that whole turn evenly over the stretch, the flange rolling about
// the joint's axis off the planned pose. Only when the stretch is long enough at 80% of the
// joint's speed limit, and every unwound sample within the joint's limits. False: no such
// stretch (the track stays broken).
bool unwindBefore(const kinematics::RobotModel& robot,
                  const kinematics::ScanPath& path,
                  std::size_t k,
                  const kinematics::JointVector& next,
                  std::vector<kinematics::JointVector>& q) {
  if (path.samples[k].scanning) return false;
  const int j = wholeTurnJoint(q.back(), next);
  if (j < 0) return false;
  std::size_t a = k - 1;
  while (a > 0 && !path.samples[a].scanning) --a;
  const double span = path.samples[k].t - path.samples[a].t;
  const double turn =
      std::round((next(j) - q.back()(j)) / (2.0 * std::numbers::pi)) * 2.0 * std::numbers::pi;
  const double speed = robot.joint(j).max_speed;
  if (!(span > 0.0) || (speed > 0.0 && std::abs(turn) / span > 0.8 * speed)) return false;
  // Every unwound sample inside the joint's limits, or none is changed.
  const auto unwound = [&](std::size_t i) {
    return q[i](j) + turn * (path.samples[i].t - path.samples[a].t) / span;
  };
  const kinematics::DhJoint& limits = robot.joint(j);
  for (std::size_t i = a + 1; i < k; ++i) {
    if (!(unwound(i) >= limits.min && unwound(i) <= limits.max)) return false;
  }
  for (std::size_t i = a + 1; i < k; ++i) q[i](j) = unwound(i);
  return true;
}

// Follows the start solution q0 continuously (joint wrap, kinematics/joint_wrap.h): at each
// sample every solution is moved by whole turns to the equivalent nearest the last sample, and
// the nearest of them continues the track; its limits are checked on those unwrapped values.
// When the continuation leaves a joint's limits but an equivalent inside them exists, the joint
// would have to re-wind a whole turn: allowed over a stretch that does not scan (unwindBefore()),
// else the track breaks there (wrap_joint says which joint).
Track followTrack(const kinematics::RobotModel& robot,
                  const ConstraintSettings& settings,
                  const kinematics::ScanPath& path,
                  const kinematics::IkBranch& branch,
                  const std::vector<std::vector<kinematics::JointVector>>& solutions,
                  const kinematics::JointVector& q0) {
  const std::size_t n = solutions.size();
  Track track;
  track.q.reserve(n);
  track.q.push_back(q0);
  track.worst_joint_factor = jointFactor(robot, settings, q0);
  for (std::size_t k = 1; k < n && track.broken.empty(); ++k) {
    const kinematics::JointVector prev = track.q.back();
    kinematics::JointVector next = prev;
    double nearest_step = std::numeric_limits<double>::infinity();
    const kinematics::JointVector* inside = nullptr;  // the nearest solution within the limits
    double inside_step = std::numeric_limits<double>::infinity();
    for (const kinematics::JointVector& q : solutions[k]) {
      const kinematics::JointVector u = kinematics::unwrapNear(q, prev);
      const double step = (u - prev).cwiseAbs().maxCoeff();
      if (step < nearest_step) {
        nearest_step = step;
        next = u;
      }
      const double raw_step = (q - prev).cwiseAbs().maxCoeff();
      if (robot.withinLimits(q) && raw_step < inside_step) {
        inside_step = raw_step;
        inside = &q;
      }
    }
    if (const int j = jointOutside(robot, next); j >= 0 && inside) {
      // A whole-turn re-wind of joint j to the equivalent inside its limits.
      if (!unwindBefore(robot, path, k, *inside, track.q)) {
        track.broken = wrapReason(robot, path, k, j, next, *inside);
        track.wrap_joint = j;
        break;
      }
      next = *inside;
    } else if (nearest_step > kMaxJointStep) {
      track.broken = jumpReason(path, branch, k, prev, next);
      break;
    }
    track.q.push_back(next);
    track.worst_joint_factor =
        std::min(track.worst_joint_factor, jointFactor(robot, settings, next));
  }
  return track;
}

// Scores every pose in full (exact distances below d_high, names of the limiting constraint)
// into out.trajectory, and the lowest f and clearance.
void scorePoses(const collision::Scene& scene,
                const ConstraintSettings& settings,
                const kinematics::ScanPath& path,
                const std::vector<double>& theta,
                const std::vector<kinematics::JointVector>& q,
                TrajectoryBuild& out) {
  const std::size_t n = theta.size();
  out.trajectory.samples.resize(n);
  std::vector<double> min_distance(n, std::numeric_limits<double>::infinity());
  tbb::enumerable_thread_specific<PoseEvaluator> evaluators(
      [&] { return PoseEvaluator(scene, settings); });
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t k) {
    PoseEvaluator& evaluator = evaluators.local();
    const PoseScore score = evaluator.score(theta[k], q[k]);
    kinematics::TrajectorySample& s = out.trajectory.samples[k];
    s.t = path.samples[k].t;
    s.theta = theta[k];
    s.q = q[k];
    s.f = score.total;
    s.scanning = path.samples[k].scanning;
    s.X_PS = path.samples[k].X_PS;
    s.limit = score.limiting;
    for (const auto& pair : score.clearance.pairs) {
      if (!pair.beyond_bound) min_distance[k] = std::min(min_distance[k], pair.distance);
    }
  });
  out.min_f = std::numeric_limits<double>::infinity();
  out.min_clearance = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < n; ++k) {
    if (out.trajectory.samples[k].f < out.min_f) {
      out.min_f = out.trajectory.samples[k].f;
      out.min_f_sample = k;
    }
    out.min_clearance = std::min(out.min_clearance, min_distance[k]);
  }
}

}  // namespace

TrajectoryBuild buildTrajectory(const collision::Scene& scene,
                                const ConstraintSettings& settings,
                                const kinematics::ScanPath& path,
                                const std::vector<double>& theta,
                                const kinematics::IkBranch& branch) {
  if (theta.size() != path.samples.size()) {
    throw std::logic_error("buildTrajectory: one table angle per path sample expected");
  }
  const kinematics::CellModel& cell = scene.cell();
  const std::size_t n = theta.size();
  TrajectoryBuild out;
  if (n == 0) {
    out.reason = "the path has no samples";
    return out;
  }

  const std::vector<std::vector<kinematics::JointVector>> solutions =
      branchSolutions(cell, path, theta, branch);
  for (std::size_t k = 0; k < n; ++k) {
    if (solutions[k].empty()) {
      out.reason = fmt::format(
          "time sample {} (t = {:.3f} s, table {:.2f} deg): the target pose is unreachable on "
          "branch {}",
          k, path.samples[k].t, toDeg(theta[k]), branch.words());
      return out;
    }
  }

  // Follow each start solution continuously; keep the best track.
  Track best;
  bool have = false;
  for (const kinematics::JointVector& q0 : solutions[0]) {
    Track track = followTrack(cell.robot, settings, path, branch, solutions, q0);
    if (!have || (track.broken.empty() &&
                  (!best.broken.empty() || track.worst_joint_factor > best.worst_joint_factor))) {
      best = std::move(track);
      have = true;
    }
  }
  if (!best.broken.empty()) {
    out.reason = best.broken;
    out.wrap_joint = best.wrap_joint;
    return out;
  }
  scorePoses(scene, settings, path, theta, best.q, out);
  out.ok = true;
  return out;
}

}  // namespace scanplan::planner
