#pragma once

#include <filesystem>
#include <random>
#include <string>

#include "cli/robot_file.h"
#include "kinematics/robot_model.h"

namespace scanplan::test {

inline std::filesystem::path sourceDir() { return SCANPLAN_SOURCE_DIR; }
inline std::filesystem::path sharedDataDir() { return SCANPLAN_SHARED_DATA_DIR; }

/// A bundled robot file, e.g. "viper_s650".
inline kinematics::RobotModel bundledRobot(const std::string& name) {
  const auto file = sourceDir() / "data" / "robots" / (name + ".yaml");
  return cli::buildRobotModel(cli::loadRobotFile(file), file.string());
}

inline kinematics::JointVector randomJoints(const kinematics::RobotModel& robot,
                                            std::mt19937& rng) {
  kinematics::JointVector q;
  for (int i = 0; i < kinematics::kNumJoints; ++i) {
    q(i) = std::uniform_real_distribution<double>(robot.joint(i).min, robot.joint(i).max)(rng);
  }
  return q;
}

}  // namespace scanplan::test
