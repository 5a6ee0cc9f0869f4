#pragma once

#include <filesystem>

#include "kinematics/trajectory.h"

namespace scanplan::cli {

/// A trajectory file: the CSV interchange format, or a V+ program written by `plan`/`export`
/// (recognised by its .PROGRAM line); errors name the file and the line.
kinematics::Trajectory loadTrajectoryFile(const std::filesystem::path& file);

}  // namespace scanplan::cli
