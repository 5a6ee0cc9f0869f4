#pragma once
// The table-angle planner interface: a problem on one branch of a map, a termination, and a
// Planner that solves it. The planners themselves are made by name in registry.h.

#include <atomic>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <scanplan/planner/config_map.h>
#include <scanplan/planner/objective.h>
#include <scanplan/planner/plan_result.h>

namespace scanplan::planner {

/// When a search must end, set by the caller (OMPL's PlannerTerminationCondition). Searches that
/// iterate (OMPL) stop at whichever comes first, and poll `cancel` at every iteration; DP and Ray
/// Shooting run in bounded time and check the clock and `cancel` only before they start (an
/// expired budget or a cancelled solve gives kTimeout).
struct Termination {
  std::size_t max_iterations = 0;  ///< iterations of an iterative search, 0: no cap
  double time_limit_s = 0.0;       ///< s, wall clock of one solve(), 0: no limit
  /// Set to true from any thread to end the solves that use this termination (and, through
  /// ScanProblem::planning, a whole pipeline::planScan()); nullptr: never cancelled. The flag
  /// must outlive them.
  const std::atomic<bool>* cancel = nullptr;
  bool cancelled() const { return cancel != nullptr && cancel->load(std::memory_order_relaxed); }
};

/// The table-angle problem on one branch of a configuration map (docs/design.md §5). `map` must
/// outlive the solve() call.
struct PlanningProblem {
  const ConfigMap* map = nullptr;
  std::size_t branch = 0;
  PlannerSettings settings;           ///< weights and bounds, SI
  bool continuous = true;             ///< the table turns without end (its grid wraps)
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

/// Why `problem` cannot be solved as given (empty when it is well formed): a missing map, a
/// branch out of range, fewer than two time samples, non-positive bounds, a negative weight.
std::string problemError(const PlanningProblem& problem);

}  // namespace scanplan::planner
