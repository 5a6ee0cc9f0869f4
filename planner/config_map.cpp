#include "planner/config_map.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>
#include <string>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "kinematics/error.h"
#include "kinematics/ramp.h"
#include "kinematics/units.h"

namespace scanplan::planner {

const char* limitName(Limit limit) {
  switch (limit) {
    case Limit::kNone:
      return "none";
    case Limit::kUnreachable:
      return "unreachable";
    case Limit::kJointLimit:
      return "joint limit";
    case Limit::kSingularity:
      return "singularity";
    case Limit::kClearance:
      return "clearance";
  }
  return "?";
}

std::size_t mapBytes(std::size_t branches, std::size_t angles, std::size_t times) {
  return branches * angles * times * (4 * sizeof(float) + sizeof(std::uint8_t));
}

std::vector<double> mapAngles(const kinematics::RotaryTableModel& table, double step) {
  std::vector<double> angles;
  if (table.continuous) {
    const auto n = static_cast<std::size_t>(std::llround(2.0 * std::numbers::pi / step));
    for (std::size_t i = 0; i < n; ++i)
      angles.push_back(static_cast<double>(i) * 2.0 * std::numbers::pi / static_cast<double>(n));
  } else {
    const auto n = static_cast<std::size_t>(std::floor((table.max - table.min) / step + 1e-9)) + 1;
    for (std::size_t i = 0; i < n; ++i) angles.push_back(table.min + static_cast<double>(i) * step);
  }
  return angles;
}

CellScore scoreCell(const collision::Scene& scene,
                    const ConstraintSettings& settings,
                    collision::ClearanceEvaluator& clearance,
                    const std::vector<kinematics::IkSolution>& solutions,
                    const kinematics::IkBranch& branch,
                    double theta,
                    bool exact_distances) {
  const kinematics::RobotModel& robot = scene.cell().robot;
  CellScore best;
  bool any = false;
  // Among this branch's solutions (they differ only by whole turns of joints like J6), the one
  // farthest from the limits.
  for (const kinematics::IkSolution& s : solutions) {
    if (!(s.branch == branch)) continue;
    double joint = 1.0;
    for (int j = 0; j < kinematics::kNumJoints; ++j) {
      const auto& limits = robot.joint(j);
      joint *= jointLimitFactor(s.q(j), limits.min, limits.max,
                                settings.joint_gamma[static_cast<std::size_t>(j)]);
    }
    if (!any || joint > best.joint) {
      best.joint = static_cast<float>(joint);
      best.q = s.q;
      any = true;
    }
  }
  if (!any) return best;  // unreachable on this branch
  if (best.joint <= 0.0f) {
    best.limit = Limit::kJointLimit;
    best.singularity = 0.0f;
    return best;
  }
  const kinematics::SingularityMeasures m = robot.singularity(best.q, false);
  const double sing =
      rampFactor(m.wrist, settings.wrist.low, settings.wrist.high, settings.wrist.gamma) *
      rampFactor(m.elbow, settings.elbow.low, settings.elbow.high, settings.elbow.gamma) *
      rampFactor(m.shoulder, settings.shoulder.low, settings.shoulder.high,
                 settings.shoulder.gamma);
  best.singularity = static_cast<float>(sing);
  double c = 1.0;
  if (sing > 0.0) {
    c = exact_distances ? clearance.evaluate(theta, best.q, {.bounded = false}).factor
                        : clearance.factor(theta, best.q);
  }
  best.clearance = static_cast<float>(c);
  best.f = static_cast<float>(static_cast<double>(best.joint) * sing * c);
  const float lowest = std::min({best.joint, best.singularity, best.clearance});
  best.limit = lowest >= 1.0f               ? Limit::kNone
               : best.joint == lowest       ? Limit::kJointLimit
               : best.singularity == lowest ? Limit::kSingularity
                                            : Limit::kClearance;
  return best;
}

ConfigMap buildConfigMap(const collision::Scene& scene,
                         const ConstraintSettings& settings,
                         const kinematics::ScanPath& path,
                         const MapRequest& request,
                         const ProgressFn& progress) {
  ConfigMap map;
  map.angles = mapAngles(scene.cell().table, request.angle_step);
  for (const auto& s : path.samples) map.times.push_back(s.t);
  map.branches = request.branches;
  const std::size_t nb = map.branches.size(), na = map.angles.size(), nt = map.times.size();
  const std::size_t bytes = mapBytes(nb, na, nt);
  if (bytes > request.memory_limit_bytes) {
    const auto mb = [](std::size_t b) {
      return fmt::format("{:.1f}", static_cast<double>(b) / (1 << 20));
    };
    throw InputError(fmt::format(
        "map: {} branch(es) x {} angles x {} time samples need {} MB, over map.memory_limit_mb "
        "({}): expected a "
        "coarser map.angle_step_deg, a larger scan.dt_s, a fixed map.branch or a higher limit",
        nb, na, nt, mb(bytes), mb(request.memory_limit_bytes)));
  }
  const std::size_t cells = na * nt;
  map.f.assign(nb * cells, 0.0f);
  map.joint.assign(nb * cells, 0.0f);
  map.singularity.assign(nb * cells, 0.0f);
  map.clearance.assign(nb * cells, 1.0f);
  map.limit.assign(nb * cells, static_cast<std::uint8_t>(Limit::kUnreachable));

  const kinematics::CellModel& cell = scene.cell();
  tbb::enumerable_thread_specific<collision::ClearanceEvaluator> evaluators(std::cref(scene));
  std::atomic<std::size_t> done{0};
  const std::size_t report_every = std::max<std::size_t>(1, cells / 200);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, cells, 64), [&](const tbb::blocked_range<std::size_t>& r) {
        collision::ClearanceEvaluator& evaluator = evaluators.local();
        for (std::size_t c = r.begin(); c != r.end(); ++c) {
          const std::size_t a = c / nt, t = c % nt;
          const double theta = map.angles[a];
          const auto solutions = cell.robot.ik(cell.flangeTarget(theta, path.samples[t].X_PS));
          for (std::size_t b = 0; b < nb; ++b) {
            const CellScore s = scoreCell(scene, settings, evaluator, solutions, map.branches[b],
                                          theta, request.exact_distances);
            const std::size_t i = map.index(b, a, t);
            map.f[i] = s.f;
            map.joint[i] = s.joint;
            map.singularity[i] = s.singularity;
            map.clearance[i] = s.clearance;
            map.limit[i] = static_cast<std::uint8_t>(s.limit);
          }
          const std::size_t n = done.fetch_add(1, std::memory_order_relaxed) + 1;
          if (progress && (n % report_every == 0 || n == cells)) progress(n, cells);
        }
      });
  return map;
}

}  // namespace scanplan::planner
