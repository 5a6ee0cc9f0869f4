#pragma once
// The planners by name: Ray Shooting ("ray"), exact dynamic programming ("dp") and OMPL
// ("ompl"), each behind the Planner interface of planner.h with its own settings.

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <scanplan/planner/ompl_planner.h>
#include <scanplan/planner/planner.h>
#include <scanplan/planner/ray_shooting.h>

namespace scanplan::planner {

/// Each planner's own settings; the registry hands every planner its part.
struct PlannerConfig {
  RayShootingSettings ray;
  /// DP's angle grid: map step / this; 0: autoAngleSubdivisions().
  int dp_subdivisions = 0;
  /// OMPL's search (its time_limit_s and max_iterations are replaced by the Termination).
  OmplSettings ompl;
};

/// The names makePlanner() knows, in a fixed order: "ray", "dp", "ompl".
const std::vector<std::string>& plannerNames();

/// The planner called `name` with its settings from `config`; nullptr for an unknown name.
std::unique_ptr<Planner> makePlanner(std::string_view name, const PlannerConfig& config);

/// DP's angle-grid subdivision for `problem`: `config.dp_subdivisions`, or automatic when 0.
int dpSubdivisions(const PlanningProblem& problem, const PlannerConfig& config);

}  // namespace scanplan::planner
