#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "planner/config_map.h"
#include "planner/objective.h"
#include "planner/ompl_planner.h"
#include "planner/plan_result.h"
#include "planner/ray_shooting.h"

namespace scanplan::planner {

/// When a search must end, set by the caller (OMPL's PlannerTerminationCondition). Searches that
/// iterate (OMPL) stop at whichever comes first; DP and Ray Shooting run in bounded time and check
/// the clock only before they start (an expired budget gives kTimeout).
struct Termination {
  std::size_t max_iterations = 0;  ///< iterations of an iterative search, 0: no cap
  double time_limit_s = 0.0;       ///< s, wall clock of one solve(), 0: no limit
};

/// The table-angle problem on one branch of a configuration map (docs/design.md §5). `map` must
/// outlive the solve() call.
struct PlanningProblem {
  const ConfigMap* map = nullptr;
  std::size_t branch = 0;
  PlannerSettings settings;  ///< weights and bounds, SI
  bool continuous = true;    ///< the table turns without end (its grid wraps)
  std::optional<double> start_theta;  ///< rad, a fixed first table angle; nullopt: searched
};

/// A table-angle planner: Ray Shooting, DP or OMPL behind one call. Implementations are
/// immutable after construction; solve() is const and may be called from several threads
/// (OMPL serialises its own calls, see planOmpl()).
class Planner {
 public:
  virtual ~Planner() = default;
  /// The registry name: "ray", "dp" or "ompl".
  virtual std::string name() const = 0;
  /// Solves `problem`. Never throws for a malformed problem: kInvalidInput with the reason.
  /// The result's `seconds` is the planner's own wall time.
  PlanResult solve(const PlanningProblem& problem, const Termination& termination) const;

 protected:
  virtual PlanResult solveChecked(const PlanningProblem& problem,
                                  const Termination& termination) const = 0;
};

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

/// Why `problem` cannot be solved as given (empty when it is well formed): a missing map, a
/// branch out of range, fewer than two time samples, non-positive bounds, a negative weight.
std::string problemError(const PlanningProblem& problem);

}  // namespace scanplan::planner
