#include <scanplan/pipeline/no_path.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <vector>

#include <fmt/format.h>

#include <scanplan/kinematics/ramp.h>
#include <scanplan/kinematics/units.h>

namespace scanplan::pipeline {
namespace {

bool blocked(const planner::ConfigMap& map, std::size_t b, std::size_t k) {
  for (std::size_t a = 0; a < map.angles.size(); ++a) {
    if (map.f[map.index(b, a, k)] > 0.0f) return false;
  }
  return true;
}

// The pass a time falls in: "scan.paths[i], ring", or the move between two.
std::string passAt(const scanner::GeneratedPath& path, double t) {
  for (std::size_t i = 0; i < path.elements.size(); ++i) {
    const scanner::ElementReport& e = path.elements[i];
    if (t >= e.start_time - 1e-9 && t <= e.start_time + e.duration + 1e-9) {
      return fmt::format("scan.paths[{}], {}", i, e.kind);
    }
  }
  return "a move between passes";
}

// The most frequent limit over the span's reachable cells (unreachable when none is).
planner::Limit dominantLimit(const planner::ConfigMap& map,
                             std::size_t b,
                             std::size_t k0,
                             std::size_t k1) {
  std::array<std::size_t, planner::kLimitCount> count{};
  for (std::size_t k = k0; k <= k1; ++k) {
    for (std::size_t a = 0; a < map.angles.size(); ++a) ++count[map.limit[map.index(b, a, k)]];
  }
  // Unreachable cells only close what the others leave open: at any time a pass is usually out
  // of reach at some table angles, and what closes the rest is the story.
  planner::Limit most = planner::Limit::kUnreachable;
  std::size_t most_count = 0;
  for (const planner::Limit l :
       {planner::Limit::kJointLimit, planner::Limit::kSingularity, planner::Limit::kClearance}) {
    const std::size_t n = count[static_cast<std::size_t>(l)];
    if (n > most_count) {
      most = l;
      most_count = n;
    }
  }
  return most;
}

// The cells to measure again: every angle of the given time columns.
std::vector<std::pair<std::size_t, std::size_t>> probeCells(
    const planner::ConfigMap& map, const std::vector<std::size_t>& columns) {
  std::vector<std::pair<std::size_t, std::size_t>> out;
  for (const std::size_t k : columns) {
    for (std::size_t a = 0; a < map.angles.size(); ++a) out.emplace_back(a, k);
  }
  return out;
}

// The branch's IK solutions at a cell (all, or those within the limits).
std::vector<kinematics::IkSolution> branchSolutions(const collision::Scene& scene,
                                                    const scanner::GeneratedPath& path,
                                                    const planner::ConfigMap& map,
                                                    std::size_t b,
                                                    std::size_t a,
                                                    std::size_t k,
                                                    bool within_limits) {
  const kinematics::CellModel& cell = scene.cell();
  const Eigen::Isometry3d X_BF = cell.flangeTarget(map.angles[a], path.path.samples[k].X_PS);
  std::vector<kinematics::IkSolution> out;
  for (const kinematics::IkSolution& s :
       cell.robot.ik(X_BF, {.within_limits_only = within_limits})) {
    if (s.branch == map.branches[b]) out.push_back(s);
  }
  return out;
}

// Calls f(angle index, joints) at each cell of `columns` the branch reaches within the limits,
// with its first solution there.
template <class F>
void forEachReached(const collision::Scene& scene,
                    const scanner::GeneratedPath& path,
                    const planner::ConfigMap& map,
                    std::size_t b,
                    const std::vector<std::size_t>& columns,
                    F&& f) {
  for (const auto& [a, k] : probeCells(map, columns)) {
    const auto solutions = branchSolutions(scene, path, map, b, a, k, true);
    if (!solutions.empty()) f(a, solutions.front().q);
  }
}

bool isLink(const collision::BodyInfo& body) {
  return body.motion == collision::BodyMotion::kRobotLink;
}

std::string clearanceAdvice(const collision::BodyInfo& a, const collision::BodyInfo& b) {
  using collision::BodyMotion;
  if (isLink(a) && isLink(b)) {
    return "if the two overlap by design, allow the pair in the robot file (allowed_collisions; "
           "scanplan robot check lists such pairs), else another branch (map.branch)";
  }
  const bool scanner = a.motion == BodyMotion::kScanner || b.motion == BodyMotion::kScanner;
  const std::string& other = a.motion == BodyMotion::kScanner ? b.name : a.name;
  if (scanner && other == "table")
    return "raise the pass above the table (height_mm) or lower its tilt_deg";
  if (scanner && other == "part") return "a larger standoff from the part or another tilt_deg";
  if (scanner) return "move the pass away from the " + other;
  return "the arm itself meets the " + (isLink(a) ? b.name : a.name) +
         ": move table.axis or try another branch (map.branch)";
}

std::string explainClearance(const collision::Scene& scene,
                             const planner::ConstraintSettings& settings,
                             const scanner::GeneratedPath& path,
                             const planner::ConfigMap& map,
                             std::size_t b,
                             const std::vector<std::size_t>& columns) {
  planner::PoseEvaluator evaluator(scene, settings, collision::Geometry::kMap);
  std::map<int, std::pair<std::size_t, double>> pairs;  // pair → cells limited, least distance
  forEachReached(
      scene, path, map, b, columns, [&](std::size_t a, const kinematics::JointVector& q) {
        const planner::PoseScore s = evaluator.score(map.angles[a], q);
        const int p = s.clearance.limiting_pair;
        if (p < 0) return;
        auto& [cells, least] =
            pairs.try_emplace(p, 0, std::numeric_limits<double>::infinity()).first->second;
        ++cells;
        least = std::min(least, s.clearance.pairs[static_cast<std::size_t>(p)].distance);
      });
  if (pairs.empty()) return "clearance";
  const auto worst = std::max_element(pairs.begin(), pairs.end(), [](const auto& x, const auto& y) {
    return x.second.first < y.second.first;
  });
  const collision::PairInfo& pair = scene.pairs()[static_cast<std::size_t>(worst->first)];
  const collision::BodyInfo& A = scene.bodies()[static_cast<std::size_t>(pair.a)];
  const collision::BodyInfo& B = scene.bodies()[static_cast<std::size_t>(pair.b)];
  return fmt::format(
      "clearance {} – {} below d_low on every table angle (closest {:.1f} mm, d_low "
      "{:.1f} mm): {}",
      A.name, B.name, toMm(worst->second.second), toMm(pair.thresholds.d_low),
      clearanceAdvice(A, B));
}

std::string explainJointLimit(const collision::Scene& scene,
                              const scanner::GeneratedPath& path,
                              const planner::ConfigMap& map,
                              std::size_t b,
                              const std::vector<std::size_t>& columns) {
  const kinematics::RobotModel& robot = scene.cell().robot;
  // The solution nearest to the limits: the least of each solution's largest overshoot, and
  // the joint that overshoots most in it (widening another would not open the cell).
  int joint = -1;
  double excess = std::numeric_limits<double>::infinity(), needed = 0.0;
  for (const auto& [a, k] : probeCells(map, columns)) {
    for (const kinematics::IkSolution& s : branchSolutions(scene, path, map, b, a, k, false)) {
      int worst = -1;
      double worst_out = 0.0;
      for (int j = 0; j < kinematics::kNumJoints; ++j) {
        const double q = s.q(j), lo = robot.joint(j).min, hi = robot.joint(j).max;
        const double out = q < lo ? lo - q : q > hi ? q - hi : 0.0;
        if (out > worst_out) {
          worst_out = out;
          worst = j;
        }
      }
      if (worst >= 0 && worst_out < excess) {
        excess = worst_out;
        joint = worst;
        needed = s.q(worst);
      }
    }
  }
  if (joint < 0) return "joint limits on every table angle";
  return fmt::format(
      "joint limits: J{} would need {:.1f}° (limits {:.1f} … {:.1f}°) at best: "
      "another branch (map.branch), or move the pass or table.axis",
      joint + 1, toDeg(needed), toDeg(robot.joint(joint).min), toDeg(robot.joint(joint).max));
}

std::string explainSingularity(const collision::Scene& scene,
                               const planner::ConstraintSettings& settings,
                               const scanner::GeneratedPath& path,
                               const planner::ConfigMap& map,
                               std::size_t b,
                               const std::vector<std::size_t>& columns) {
  std::array<std::size_t, 3> at{};  // wrist, elbow, shoulder at or below their low
  forEachReached(scene, path, map, b, columns, [&](std::size_t, const kinematics::JointVector& q) {
    const kinematics::SingularityMeasures m = scene.cell().robot.singularity(q, false);
    at[0] += m.wrist <= settings.wrist.low ? 1 : 0;
    at[1] += m.elbow <= settings.elbow.low ? 1 : 0;
    at[2] += m.shoulder <= settings.shoulder.low ? 1 : 0;
  });

  if (at == std::array<std::size_t, 3>{}) return "singularities on every table angle";
  const auto most = std::max_element(at.begin(), at.end()) - at.begin();
  static const std::array<const char*, 3> text{
      "wrist singularity (J5 near 0°): tilt the scanner (tilt_deg) so that J5 leaves 0°",
      "elbow singularity (the arm stretched or folded): move table.axis",
      "shoulder singularity (the wrist centre over the J1 axis): move table.axis off it"};
  return text[static_cast<std::size_t>(most)];
}

}  // namespace

std::string explainBlockedBranch(const collision::Scene& scene,
                                 const planner::ConstraintSettings& settings,
                                 const scanner::GeneratedPath& path,
                                 const planner::ConfigMap& map,
                                 std::size_t branch) {
  std::size_t k0 = 0;
  while (k0 < map.times.size() && !blocked(map, branch, k0)) ++k0;
  if (k0 == map.times.size()) return {};
  std::size_t k1 = k0;
  while (k1 + 1 < map.times.size() && blocked(map, branch, k1 + 1)) ++k1;
  // Clearance and singularities measured at the span's ends and middle; joint limits (one IK a
  // cell) on all of it.
  const std::vector<std::size_t> ends{k0, (k0 + k1) / 2, k1};
  std::vector<std::size_t> all;
  for (std::size_t k = k0; k <= k1; ++k) all.push_back(k);
  std::string why;
  switch (dominantLimit(map, branch, k0, k1)) {
    case planner::Limit::kClearance:
      why = explainClearance(scene, settings, path, map, branch, ends);
      // The clearance-closed cells may lie between the probed columns: then all of them.
      if (why == "clearance") why = explainClearance(scene, settings, path, map, branch, all);
      break;
    case planner::Limit::kJointLimit:
      why = explainJointLimit(scene, path, map, branch, all);
      break;
    case planner::Limit::kSingularity:
      why = explainSingularity(scene, settings, path, map, branch, ends);
      break;
    default:
      why =
          "the sensor poses are out of the arm's reach at every table angle: move table.axis "
          "toward the robot or the pass nearer the table's axis";
  }
  return fmt::format("t = {:.1f}–{:.1f} s ({}): {}", map.times[k0], map.times[k1],
                     passAt(path, map.times[k0]), why);
}

}  // namespace scanplan::pipeline
