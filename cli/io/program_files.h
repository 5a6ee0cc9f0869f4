#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <scanplan/config/job.h>
#include <scanplan/kinematics/cell.h>
#include <scanplan/kinematics/trajectory.h>
#include <scanplan/programs/programs.h>

namespace scanplan::cli {

/// The job's program options: name, table speed and endlessness (table.continuous), the tool
/// (the scanner's mount X_FS), the payload (scanner.mass_kg, cog_mm or the housing's centre),
/// the trigger (outputs.trigger) and URScript's servo period (outputs.servo_period_s).
programs::ProgramOptions programOptions(const config::JobSpec& job, const kinematics::CellModel& cell);

/// The robot programs of `formats` (names as in programFormatNames()) for the trajectory, into
/// `dir`; returns one summary line (the folder as `shown_as`, the files, the fastest step as % of
/// the joints' max speed, steps that need more than 100 %, a warning for another vendor's
/// language than the robot's controller). A program its language cannot hold (URScript over
/// kUrscriptMaxBytes) throws InputError, or with `skip_refused` is left out with a warning that
/// the summary line repeats (`plan`: the rest of the plan is still written).
std::string writePrograms(const std::filesystem::path& dir,
                          const std::string& shown_as,
                          const config::JobSpec& job,
                          const kinematics::CellModel& cell,
                          const kinematics::Trajectory& trajectory,
                          const std::vector<std::string>& formats,
                          bool skip_refused = false);

}  // namespace scanplan::cli
