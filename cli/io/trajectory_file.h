#pragma once

#include <filesystem>

#include "kinematics/trajectory.h"

namespace scanplan::cli {

/// A trajectory file: the CSV interchange format, or a program written by `plan`/`export`
/// (by its extension .v2, .src, .mod, .script; a V+ program also by its .PROGRAM line), timed
/// by its own timing statements (URScript: at its step comments' times, atStepTimes()); errors
/// name the file and the line.
kinematics::Trajectory loadTrajectoryFile(const std::filesystem::path& file);

}  // namespace scanplan::cli
