#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "cli/config/job.h"
#include "planner/config_map.h"
#include "planner/dp_planner.h"
#include "planner/refine.h"

namespace scanplan::cli {

/// One planner run over the map: every branch tried, the best solved one kept.
struct PlannerOutcome {
  std::string method;                         ///< ray | dp | ompl
  planner::PlanResult result;                 ///< the best branch's (kExact), or why none
  std::vector<planner::PlanResult> branches;  ///< per map branch (status kNoPath when skipped)
  double seconds = 0.0;                       ///< all branches
};

/// The planning stage of `plan`: the chosen planner, refinement, the DP yardstick, comparisons.
struct PlanningOutcome {
  PlannerOutcome chosen;
  std::optional<planner::RefineResult> refine;  ///< when refinement ran
  std::vector<double> theta;                    ///< the final path (refined when that helped)
  planner::ObjectiveTerms terms;                ///< evaluate() of `theta`
  std::optional<planner::PlanResult> dp;        ///< DP on the chosen branch (the yardstick)
  int dp_subdivisions = 1;                      ///< DP's angle grid: map step / this
  std::vector<PlannerOutcome> others;           ///< --compare: the other planners, same branch
  /// Branches whose path the check turned down, best J first, with the reason.
  std::vector<std::pair<std::size_t, std::string>> rejected;
  bool solved() const { return chosen.result.status == planner::PlanResult::Status::kExact; }
  /// (J − J_dp) / J_dp of the final path, when DP solved; negative when the continuous path beats
  /// DP's grid.
  std::optional<double> dpGap() const;
};

/// The planners' map settings: "continuous" comes from the job's table.
bool continuousTable(const JobSpec& job);

/// Runs `method` on `branch` (or on every branch of the map when nullopt, keeping the lowest J).
PlannerOutcome runPlanner(const std::string& method,
                          const planner::ConfigMap& map,
                          const JobSpec& job,
                          std::optional<std::size_t> branch = {});

/// Judges a planned path on a map branch before it is accepted: empty when the path can be
/// executed, otherwise why not (e.g. a joint would have to pass its limit to follow it).
using PathCheck = std::function<std::string(std::size_t branch, const std::vector<double>& theta)>;

/// The whole planning stage. `method` empty: the job's. The solved branches are taken in order
/// of J: refined (when `refine` or the job says) and checked; the first that passes is chosen.
/// Then the DP yardstick and, with `compare`, the other planners run on the chosen branch.
PlanningOutcome planJob(const planner::ConfigMap& map,
                        const JobSpec& job,
                        std::string method,
                        bool compare,
                        bool refine,
                        const PathCheck& check = {});

}  // namespace scanplan::cli
