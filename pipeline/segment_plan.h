#pragma once
// Internal to the pipeline: planning a scan path of several segments (ScanPath::breaks, the
// automatic scan's passes). Each segment gets its own map slice, its own path search on every
// branch (the best executable branch chosen per segment) and its own trajectory; the program
// joins them with point-to-point moves (program_moves.h).

#include <cstddef>
#include <string>

#include "pipeline/plan_scan.h"
#include "planner/config_map.h"
#include "planner/trajectory_builder.h"

namespace scanplan::pipeline {

/// Why a built trajectory cannot be executed; empty when it can.
std::string executableReason(const planner::TrajectoryBuild& build);

/// The time samples [begin, end) of every branch of `map`.
planner::ConfigMap sliceMap(const planner::ConfigMap& map, std::size_t begin, std::size_t end);

/// planPrepared() for a path with breaks: fills plan.choice (the segments' choices joined),
/// plan.trajectory (the joined program), plan.program and plan.dropped, or a status and reason.
void planSegments(const ScanProblem& problem, const PlanOptions& options, ScanPlan& plan);

}  // namespace scanplan::pipeline
