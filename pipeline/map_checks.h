#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include <scanplan/planner/config_map.h>

namespace scanplan::pipeline {

/// The first time column with f = 0 at every table angle on `branch`: no planner can cross it.
std::optional<std::size_t> blockedColumn(const planner::ConfigMap& map, std::size_t branch);

/// What limits time column `k` of `branch`, e.g. "clearance at 60% of the angles, unreachable
/// at 40% of the angles".
std::string columnLimits(const planner::ConfigMap& map, std::size_t branch, std::size_t k);

}  // namespace scanplan::pipeline
