#include "planner/trajectory_builder.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "kinematics/ramp.h"
#include "kinematics/units.h"

namespace scanplan::planner {

namespace {

constexpr double kMaxJointStep = std::numbers::pi / 2;  // rad between samples: more is a jump

struct Track {
  std::vector<kinematics::JointVector> q;
  double worst_joint_factor = 1.0;
  std::string broken;  // why the track cannot continue
};

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
  const kinematics::RobotModel& robot = cell.robot;
  const std::size_t n = theta.size();
  TrajectoryBuild out;
  if (n == 0) {
    out.reason = "the path has no samples";
    return out;
  }

  // IK on the branch at every sample (independent: parallel).
  std::vector<std::vector<kinematics::JointVector>> solutions(n);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t k) {
    for (const auto& s : robot.ik(cell.flangeTarget(theta[k], path.samples[k].X_PS),
                                  {.within_limits_only = false})) {
      if (s.branch == branch) solutions[k].push_back(s.q);
    }
  });
  for (std::size_t k = 0; k < n; ++k) {
    if (solutions[k].empty()) {
      out.reason = fmt::format(
          "time sample {} (t = {:.3f} s, table {:.2f} deg): the target pose is unreachable on "
          "branch {}",
          k, path.samples[k].t, toDeg(theta[k]), branch.words());
      return out;
    }
  }
  const auto jointFactor = [&](const kinematics::JointVector& q) {
    double f = 1.0;
    for (int j = 0; j < kinematics::kNumJoints; ++j) {
      f *= jointLimitFactor(q(j), robot.joint(j).min, robot.joint(j).max,
                            settings.joint_gamma[static_cast<std::size_t>(j)]);
    }
    return f;
  };

  // Follow each start solution continuously; keep the best track.
  Track best;
  bool have = false;
  for (const kinematics::JointVector& q0 : solutions[0]) {
    Track track;
    track.q.reserve(n);
    track.q.push_back(q0);
    track.worst_joint_factor = jointFactor(q0);
    for (std::size_t k = 1; k < n && track.broken.empty(); ++k) {
      const kinematics::JointVector& prev = track.q.back();
      const kinematics::JointVector* nearest = nullptr;
      double nearest_step = std::numeric_limits<double>::infinity();
      for (const kinematics::JointVector& q : solutions[k]) {
        const double step = (q - prev).cwiseAbs().maxCoeff();
        if (step < nearest_step) {
          nearest_step = step;
          nearest = &q;
        }
      }
      if (nearest_step > kMaxJointStep) {
        int joint = 0;
        (*nearest - prev).cwiseAbs().maxCoeff(&joint);
        const auto& limits = robot.joint(joint);
        track.broken =
            nearest_step > 1.5 * std::numbers::pi
                ? fmt::format(
                      "time sample {} (t = {:.3f} s): joint {} would have to pass its limit "
                      "({:.0f} … {:.0f} deg) to follow the path continuously (the map's cells "
                      "there use the other whole-turn solution, {:.0f} deg away)",
                      k, path.samples[k].t, joint + 1, toDeg(limits.min), toDeg(limits.max),
                      toDeg(nearest_step))
                : fmt::format(
                      "time sample {} (t = {:.3f} s): joint {} would jump by {:.1f} deg between "
                      "samples (the pose passes a singularity); no continuous motion on branch {}",
                      k, path.samples[k].t, joint + 1, toDeg(nearest_step), branch.words());
        break;
      }
      track.q.push_back(*nearest);
      track.worst_joint_factor = std::min(track.worst_joint_factor, jointFactor(*nearest));
    }
    if (!have || (track.broken.empty() &&
                  (!best.broken.empty() || track.worst_joint_factor > best.worst_joint_factor))) {
      best = std::move(track);
      have = true;
    }
  }
  if (!best.broken.empty()) {
    out.reason = best.broken;
    return out;
  }

  // Score every pose in full (exact distances below d_high, names of the limiting constraint).
  out.trajectory.samples.resize(n);
  std::vector<double> min_distance(n, std::numeric_limits<double>::infinity());
  tbb::enumerable_thread_specific<PoseEvaluator> evaluators(
      [&] { return PoseEvaluator(scene, settings); });
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t k) {
    PoseEvaluator& evaluator = evaluators.local();
    const PoseScore score = evaluator.score(theta[k], best.q[k]);
    kinematics::TrajectorySample& s = out.trajectory.samples[k];
    s.t = path.samples[k].t;
    s.theta = theta[k];
    s.q = best.q[k];
    s.f = score.total;
    s.scanning = path.samples[k].scanning;
    s.X_PS = path.samples[k].X_PS;
    s.limit = score.limiting;
    for (const auto& pair : score.clearance.pairs) {
      if (!pair.beyond_bound) min_distance[k] = std::min(min_distance[k], pair.distance);
    }
  });
  out.ok = true;
  out.min_f = std::numeric_limits<double>::infinity();
  out.min_clearance = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < n; ++k) {
    if (out.trajectory.samples[k].f < out.min_f) {
      out.min_f = out.trajectory.samples[k].f;
      out.min_f_sample = k;
    }
    out.min_clearance = std::min(out.min_clearance, min_distance[k]);
  }
  return out;
}

}  // namespace scanplan::planner
