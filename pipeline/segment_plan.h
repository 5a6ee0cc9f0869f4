#pragma once
// Internal to the pipeline: planning a scan path of several segments (ScanPath::breaks, the
// automatic scan's passes). Each segment gets its own map slice, its own path search on every
// branch (the best executable branch chosen per segment) and its own trajectory; the program
// joins them with point-to-point moves (program_moves.h).

#include <cstddef>
#include <string>

#include <scanplan/pipeline/plan_scan.h>
#include <scanplan/planner/config_map.h>
#include <scanplan/planner/trajectory_builder.h>

namespace scanplan::pipeline {

/// Why a built trajectory cannot be executed; empty when it can.
std::string executableReason(const planner::TrajectoryBuild& build);

/// The time samples [begin, end) of every branch of `map`.
planner::ConfigMap sliceMap(const planner::ConfigMap& map, std::size_t begin, std::size_t end);

/// A segment's first budget for an iterative search (OMPL's): the whole path's iterations and
/// time limit (`whole`, 0 = none) in proportion to its time samples, at least 1 000 iterations
/// and 1 s, at most `whole`. planSegments() doubles it, up to `whole`, while the budget is what
/// ended the search (an approximate path or a timeout) on some branch.
planner::Termination segmentBudget(const planner::Termination& whole,
                                   std::size_t samples,
                                   std::size_t path_samples);

/// planPrepared() for a path with breaks: fills plan.choice (the segments' choices joined),
/// plan.trajectory (the joined program), plan.program and plan.dropped, or a status and reason.
void planSegments(const ScanProblem& problem, const PlanOptions& options, ScanPlan& plan);

}  // namespace scanplan::pipeline
