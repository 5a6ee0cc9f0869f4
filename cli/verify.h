#pragma once
// Proving and previewing a trajectory: validation (limits, speeds, continuous collisions) and the
// scanner simulation (cloud, coverage) — shared by `plan`, `validate` and `simulate`.

#include <filesystem>
#include <string>

#include "cli/config/job.h"
#include "cli/config/problem.h"
#include "pipeline/simulation.h"
#include "cli/io/json.h"
#include "cli/io/output.h"
#include "kinematics/mesh.h"
#include "kinematics/trajectory.h"
#include "planner/validation.h"
#include "scanner/coverage.h"
#include "scanner/simulator.h"

namespace scanplan::cli {

/// (validationSettings() is in cli/config/problem.h.)

/// A trajectory file: the CSV interchange format, or a V+ program written by `plan`/`export`
/// (recognised by its .PROGRAM line); errors name the file and the line.
kinematics::Trajectory loadTrajectoryFile(const std::filesystem::path& file);

/// Validation summary lines for stdout (every violation, at most `max_lines` of them).
std::string validationSummary(const planner::ValidationReport& report, std::size_t max_lines = 12);
/// The report as a JSON object (lengths in mm, angles in degrees, times in s).
Json validationJson(const planner::ValidationReport& report);

using SimulationRun = pipeline::SimulationRun;

/// The scanner simulated along the trajectory: a profile every 1/frame_rate s while the path
/// scans, the job's fan, cameras, noise and (optional) extra table error.
SimulationRun simulateTrajectory(const JobSpec& job,
                                 const kinematics::CellModel& cell,
                                 const kinematics::TriangleMesh& part,
                                 const kinematics::Trajectory& trajectory);
/// cloud.ply, coverage.ply and cloud.png (the cloud and the coverage from three sides) in `dir`.
void writeSimulationOutputs(const std::filesystem::path& dir,
                            const JobSpec& job,
                            const kinematics::TriangleMesh& part,
                            const SimulationRun& run);
std::string simulationSummary(const SimulationRun& run);
/// The run's counts and the coverage as a JSON object (areas in mm²).
Json simulationJson(const SimulationRun& run);

/// The robot programs of `formats` (names as in programFormatNames()) for the trajectory, into
/// `dir`; returns one summary line (the folder as `shown_as`, the files, the fastest step as % of
/// the joints' max speed, steps that need more than 100 %).
std::string writePrograms(const std::filesystem::path& dir,
                          const std::string& shown_as,
                          const JobSpec& job,
                          const kinematics::CellModel& cell,
                          const kinematics::Trajectory& trajectory,
                          const std::vector<std::string>& formats);

}  // namespace scanplan::cli
