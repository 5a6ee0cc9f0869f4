#pragma once
// Why no path: for a branch whose map is closed at some time (f = 0 at every table angle), the
// time span, the constraint that closes it and, measured again on the span's cells, the body
// pair (clearance), the joint and the value it would need (joint limits) or the measure
// (singularities), with what to change.

#include <cstddef>
#include <string>

#include <scanplan/collision/scene.h>
#include <scanplan/planner/config_map.h>
#include <scanplan/planner/constraints.h>
#include <scanplan/scanner/path_generators.h>

namespace scanplan::pipeline {

/// The first blocked span of `branch`'s map (columns with f = 0 at every angle, from `first`
/// on while they stay blocked), explained, e.g. "t = 12.3–18.0 s (scan.paths[1], ring):
/// clearance scanner – table below d_low on every table angle (closest 14.2 mm, d_low 20 mm):
/// raise the ring (height_mm) or lower its tilt_deg". Empty when the branch is open.
std::string explainBlockedBranch(const collision::Scene& scene,
                                 const planner::ConstraintSettings& settings,
                                 const scanner::GeneratedPath& path,
                                 const planner::ConfigMap& map,
                                 std::size_t branch);

}  // namespace scanplan::pipeline
