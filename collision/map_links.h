#pragma once
// What the configuration maps measure for a robot's mesh links, without a cell: `robot import`
// and `robot check` report each link's hull and convex pieces (fitting them into the cache)
// before any job uses the robot.

#include <cstddef>
#include <functional>
#include <vector>

#include <scanplan/collision/scene.h>
#include <scanplan/kinematics/robot_model.h>

namespace scanplan::collision {

/// One MapHull per link of `robot` with meshes (`body`: the link's index, 0 the base … 6 the
/// flange), as a Scene of that robot under `config` measures it: the hull, the convex pieces
/// (fitted, or read from config.piece_cache and fitted into it) or the mesh. Empty with
/// LinkMeshes::kExact. `progress` (links done, links in all) is called after each link.
std::vector<MapHull> robotMapLinks(
    const kinematics::RobotModel& robot,
    const ClearanceConfig& config,
    const std::function<void(std::size_t, std::size_t)>& progress = {});

}  // namespace scanplan::collision
