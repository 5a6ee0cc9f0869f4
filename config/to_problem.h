#pragma once
// A job file as the library's problem: config's bridge from the validated JobSpec (mm,
// degrees, names) to pipeline::ScanProblem (SI, models).

#include <scanplan/config/job.h>
#include <scanplan/kinematics/cell.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/pipeline/problem.h>
#include <scanplan/planner/validation.h>

namespace scanplan::config {

/// The job's part mesh (loader warnings logged); errors name the job file and `part.mesh`. A part
/// that reaches below the table top is an error naming `part.pose`; one that reaches beyond the
/// table's radius, a warning.
kinematics::LoadedMesh loadPart(const JobSpec& job, const kinematics::CellModel& cell);

/// The scan path request (pathRequest()) for the part on `cell`'s table: with `part.place: table`
/// ring heights count from the table top (along the part's z), so they move into the part frame.
scanner::PathRequest placedPathRequest(const JobSpec& job, const kinematics::CellModel& cell);

/// The automatic scan's settings (`scan.auto`), SI.
pipeline::AutoScanSettings autoScanSettings(const JobSpec& job);
/// The whole job as a problem: the cell, the part mesh, the scan path request and every
/// stage's settings (validation and simulation nullopt when the job turns them off). Logs
/// checkScannerResolution's warning.
pipeline::ScanProblem toProblem(const JobSpec& job);
/// The simulated scanner's resolution against the spacing coverage is measured at (the problem's
/// simulation settings): InputError naming scanner.rays_per_profile for fewer than 2 rays; the
/// warning (empty when none) when neighbouring rays lie farther apart at mid depth than that
/// spacing, so that coverage counts their tracks only. Nothing without a simulation.
std::string checkScannerResolution(const JobSpec& job, const pipeline::ScanProblem& problem);
/// toProblem(job) with the cell and part mesh already built.
pipeline::ScanProblem toProblem(const JobSpec& job,
                                kinematics::CellModel cell,
                                kinematics::TriangleMesh part);

/// `map`: the grid, the branches and the memory limit, SI.
pipeline::MapSettings mapSettings(const JobSpec& job);
/// `planner` (+ the table's dynamics): the search, its budget, refinement and the DP yardstick.
pipeline::PlanSettings planSettings(const JobSpec& job);
/// The validation settings: densified at the scanner frame rate, the table's bounds.
planner::ValidationSettings validationSettings(const JobSpec& job);
/// The simulation settings: the scanner's fan, cameras, noise, the real table's extra error on
/// `cell`'s table.
pipeline::SimulationSettings simulationSettings(const JobSpec& job,
                                                const kinematics::CellModel& cell);

}  // namespace scanplan::config
