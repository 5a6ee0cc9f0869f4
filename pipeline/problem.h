#pragma once
// The whole scan-planning problem in SI units: what planScan() needs, and nothing about files.
// A front end (the job file reader in config/, or a C++ caller) fills it in; checkProblem()
// validates it before anything runs.

#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <scanplan/collision/scene.h>
#include <scanplan/kinematics/cell.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/planner/config_map.h>
#include <scanplan/planner/constraints.h>
#include <scanplan/planner/objective.h>
#include <scanplan/planner/refine.h>
#include <scanplan/planner/registry.h>
#include <scanplan/planner/validation.h>
#include <scanplan/scanner/coverage.h>
#include <scanplan/scanner/laser_model.h>
#include <scanplan/scanner/path_generators.h>
#include <scanplan/scanner/simulator.h>

namespace scanplan::pipeline {

/// The configuration map grid (docs/design.md §4).
struct MapSettings {
  double angle_step = 0.017453292519943295;  ///< rad, table-angle grid step
  /// IK branches to map and plan on; empty: all eight.
  std::vector<kinematics::IkBranch> branches;
  std::size_t memory_limit_bytes = std::size_t{8192} << 20;  ///< the maps refuse to exceed it
};

/// How the table-angle path is searched, refined and judged (docs/design.md §5).
struct PlanSettings {
  std::string method = "ray";          ///< a planner::plannerNames() entry
  planner::PlannerSettings objective;  ///< weights and table bounds, SI
  bool continuous = true;              ///< the table turns without end
  std::optional<double> start_theta;   ///< rad, a fixed first table angle; nullopt: searched
  planner::PlannerConfig planners;     ///< every planner's own settings
  /// Each planner run's budget (per branch); OMPL honours both, see planner::Termination.
  planner::Termination termination;
  bool refine = true;  ///< NLopt refinement of each candidate path (docs/design.md §5.4)
  planner::RefineSettings refine_settings;
  bool dp_gap = true;  ///< also run DP on the chosen branch: the gap to the optimum
};

/// The scanner simulation along the planned motion (docs/design.md §6).
struct SimulationSettings {
  double frame_rate_hz = 100.0;         ///< profiles per second while the path scans
  scanner::SimulationSettings scanner;  ///< fan, cameras, noise, real table error
  scanner::CoverageSettings coverage;
  /// m, the point spacing an area sample is covered within; 0: the line's point pitch at the
  /// middle of the depth window (line width there / (rays per profile − 1)).
  double point_spacing = 0.0;
  /// Area samples at most (one per (2 · point spacing)² of area, coarser when there would be
  /// more): bounds the time and memory of the area coverage.
  std::size_t max_area_samples = 200'000;
  /// Camera images (scanner::ScanSimulator::renderImage) of this many profiles to keep in the
  /// run, for a person to look at: those with the most points, at least a tenth of the run apart
  /// where possible.
  std::size_t profile_images = 0;
  /// rad, the largest angle between a surface normal and the laser ray for a point to count
  /// (the table-facing share of the area uses it).
  double max_incidence = 1.0471975511965976;  // 60°
};

/// The automatic scan (docs/design.md §11, job keys scan.auto), SI.
struct AutoScanSettings {
  /// rad, the largest angle between a surface normal and the laser ray, and the camera ray, for a
  /// point to count.
  double max_incidence = 1.0471975511965976;  // 60°
  /// m, an area counts as covered when a point lies within this; 0: the line's point pitch at
  /// the middle of the depth window. The passes move at most 0.9 spacing per profile on the
  /// surface they see (scanner::timePass).
  double point_spacing = 0.0;
  double target_coverage = 0.98;  ///< of the scannable area
  std::size_t max_passes = 250;
  double time_budget = 60.0;  ///< s of planning for choosing the passes
  /// s, the program's time at most (passes chosen by the most new area per second until their
  /// estimated time fills it; the passes that would run past it are left out); 0: no limit.
  double max_program = 0.0;
  double sample_spacing = 0.003;  ///< m between the area samples the passes are chosen on
};

/// A whole planning problem: the cell (robot, table, part pose, scanner, obstacles), the part
/// mesh, the scan path request, the constraints and every stage's settings. SI throughout.
struct ScanProblem {
  explicit ScanProblem(kinematics::CellModel cell_model) : cell(std::move(cell_model)) {}

  std::string name = "job";  ///< shown in reports
  kinematics::CellModel cell;
  kinematics::TriangleMesh part;  ///< the part mesh, metres, part frame P
  scanner::LaserOptics optics;    ///< Eq. 5 geometry of the scanner
  scanner::PathRequest path;      ///< the scan path, relative to the part
  /// Generate passes that cover the part (after `path`'s elements, which may be empty).
  std::optional<AutoScanSettings> auto_scan;
  collision::ClearanceConfig clearance;
  planner::ConstraintSettings constraints;
  MapSettings map;
  PlanSettings planning;
  /// The check of the planned motion (limits, speeds, continuous collisions); nullopt: skipped.
  std::optional<planner::ValidationSettings> validation;
  /// The scanner simulation (cloud, coverage); nullopt: skipped.
  std::optional<SimulationSettings> simulation;
};

/// Throws scanplan::InputError naming the field (e.g. "planning.method") when the problem
/// cannot be planned as given: an empty part or path, an unknown planner, non-finite or
/// non-positive steps, rates and bounds.
void checkProblem(const ScanProblem& problem);

/// The IK branches the maps cover: `settings.branches`, or all eight.
std::vector<kinematics::IkBranch> mapBranches(const MapSettings& settings);
/// The map request of `settings` for planner::buildConfigMap().
planner::MapRequest mapRequest(const MapSettings& settings);

}  // namespace scanplan::pipeline
