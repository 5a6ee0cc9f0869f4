#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include <scanplan/planner/objective.h>

namespace scanplan::planner {

/// How a planner's search ended (in the spirit of OMPL's PlannerStatus).
enum class PlannerStatus {
  kExact,         ///< a complete path to the last time sample, feasible per evaluate()
  kApproximate,   ///< the search ended with a partial path only (OMPL); no path is returned
  kNoPath,        ///< the search ended without a path; `reason` says where and why
  kTimeout,       ///< the termination condition ended the search before any path was found
  kInvalidInput,  ///< the problem was malformed (branch, map, settings); `reason` says which
};

/// "exact", "approximate", "no_path", "timeout", "invalid_input".
std::string_view statusName(PlannerStatus status);

/// A planner's answer. A partial path is never returned: `theta` is empty unless kExact.
struct PlanResult {
  using Status = PlannerStatus;
  Status status = Status::kNoPath;
  std::vector<double> theta;  ///< rad, one per time sample, unwrapped (see evaluate())
  ObjectiveTerms terms;       ///< of `theta` (kExact only)
  double seconds = 0.0;       ///< wall time spent planning
  std::size_t branch = 0;     ///< the map branch planned on
  std::string reason;  ///< not kExact: the first time sample no feasible path reaches, and why
  std::string detail;  ///< planner-specific notes, e.g. OMPL's planner, exact/approximate,
                       ///< iterations and tree size (empty for DP and Ray Shooting)
  bool solved() const { return status == Status::kExact; }
};

}  // namespace scanplan::planner
