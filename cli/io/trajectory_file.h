#pragma once

#include <filesystem>

#include <scanplan/kinematics/robot_model.h>
#include <scanplan/kinematics/trajectory.h>

namespace scanplan::cli {

/// A trajectory file: the CSV interchange format, or a program written by `plan`/`export`
/// (by its extension .v2, .src, .mod, .script; a V+ program also by its .PROGRAM line), timed
/// by its own timing statements (URScript: at its step comments' times, atStepTimes()); errors
/// name the file and the line. `robot`'s joint speeds time a V+ program's SPEED, which must not
/// make a move outlast its DURATION (readProgram); null: SPEED is checked for its form only.
/// The CLI's commands pass the job's robot.
kinematics::Trajectory loadTrajectoryFile(const std::filesystem::path& file,
                                          const kinematics::RobotModel* robot = nullptr);

}  // namespace scanplan::cli
