#include <algorithm>
#include <cstdio>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <scanplan/collision/scene.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/planner/constraints.h>
#include "cli/commands/commands.h"
#include "cli/io/output.h"

namespace scanplan::cli {

// Without a scan path: can the sensor reach 150 mm above the part top, looking down, as the
// table turns? A first look at whether the cell is laid out sensibly.
std::string reachCheck(const config::JobSpec& job,
                       const kinematics::CellModel& cell,
                       const kinematics::LoadedMesh& part) {
  const Eigen::AlignedBox3d box = part.mesh.bounds();
  const Eigen::Isometry3d X_WP = cell.table.X_WR(0.0) * cell.part.X_RP;
  const Eigen::Vector3d top_centre_P(box.center().x(), box.center().y(), box.max().z());
  constexpr double kStandoff = 0.15;
  Eigen::Isometry3d X_PS = Eigen::Isometry3d::Identity();
  X_PS.linear() = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();  // z_S points down
  X_PS.translation() = top_centre_P + Eigen::Vector3d(0, 0, kStandoff);
  const collision::Scene scene(cell, config::clearanceConfig(job));
  planner::PoseEvaluator evaluator(scene, config::constraintSettings(job));
  int reachable = 0, feasible = 0;
  double best_f = 0.0;
  std::string best_limit;
  constexpr int kAngles = 12;
  for (int k = 0; k < kAngles; ++k) {
    const double theta = deg(30.0 * k);
    const auto solutions =
        cell.robot.ik(cell.flangeTarget(theta, X_PS), {.within_limits_only = true});
    if (solutions.empty()) continue;
    ++reachable;
    double angle_best = 0.0;
    for (const auto& s : solutions) {
      const planner::PoseScore score = evaluator.score(theta, s.q);
      angle_best = std::max(angle_best, score.total);
      if (score.total > best_f) {
        best_f = score.total;
        best_limit = score.limiting;
      }
    }
    feasible += angle_best > 0.0 ? 1 : 0;
  }
  const Eigen::Vector3d top_W = X_WP * top_centre_P * kMToMm;
  std::string s = fmt::format(
      "reach      no scan path in the job; sensor 150 mm above the part top ({:.0f}, {:.0f}, "
      "{:.0f}) mm, looking down: "
      "reachable at {}/{} table angles (every 30 deg), collision-free and feasible at {}\n",
      top_W.x(), top_W.y(), top_W.z(), reachable, kAngles, feasible);
  s += fmt::format(
      "score      best f = {:.3f} over those poses (limited by {}); {} body pairs checked\n",
      best_f, best_limit.empty() ? "-" : best_limit, scene.pairs().size());
  return s;
}

ExitCode runJobShow(const std::filesystem::path& job_file,
                    const std::vector<std::string>& overrides) {
  const config::JobSpec job = config::loadJob(job_file, overrides);
  config::buildCell(job);  // the robot model checks (OPW against DH) belong to "valid"
  std::fputs(config::jobToYaml(job).c_str(), stdout);
  return ExitCode::kOk;
}

ExitCode runJobSchema() {
  std::fputs(config::jobSchema().c_str(), stdout);
  return ExitCode::kOk;
}

}  // namespace scanplan::cli
