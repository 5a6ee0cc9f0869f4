#pragma once

#include <string>

#include <scanplan/collision/scene.h>
#include <scanplan/config/job.h>
#include <scanplan/kinematics/cell.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/pipeline/plan_scan.h>
#include <scanplan/planner/config_map.h>
#include <scanplan/scanner/laser_model.h>
#include <scanplan/scanner/path_generators.h>

namespace scanplan::cli {

/// The job, robot, table and part lines.
std::string cellSummary(const config::JobSpec& job,
                        const kinematics::CellModel& cell,
                        const kinematics::LoadedMesh& part);
/// The scanner window and one line per path element, then the samples.
/// The automatic scan's passes and prediction (`scan.auto`).
std::string autoScanSummary(const pipeline::AutoScanReport& report);

std::string pathSummary(const scanner::LaserWindow& window,
                        const scanner::GeneratedPath& generated);
/// How the maps measured robot link meshes: one line per link meshed as a hull (triangles,
/// hull vertices, margin), or one line for exact meshes; empty without link meshes.
std::string linkMeshSummary(const collision::Scene& scene);
/// The per-link lines of linkMeshSummary() for links named `names[h.body]`, and their heading.
std::string linkMeshLines(const std::vector<std::string>& names,
                          const std::vector<collision::MapHull>& hulls);
/// One line for the map (`seconds` to build it), one per branch.
std::string mapSummary(const planner::ConfigMap& map, double seconds);
/// The plan's lines after the map: the chosen path, rejected branches, refinement, the DP gap,
/// comparisons and the trajectory. `plan` must hold a trajectory.
std::string choiceSummary(const pipeline::ScanPlan& plan);
/// The program's time: scanning, moving, the moves between passes and passes left out.
std::string programSummary(const pipeline::ScanPlan& plan);
/// The times to 90, 95 and 98 % of the scannable area (empty without a coverage curve).
std::string curveSummary(const pipeline::ScanPlan& plan);

}  // namespace scanplan::cli
