#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "cli/config/spec.h"
#include "cli/config/yaml_reader.h"
#include "kinematics/robot_model.h"

namespace scanplan::cli {

/// One DH row of a robot file (DESIGN.md §3.1): mm, degrees, deg/s.
struct JointSpec {
  double a_mm = 0.0;
  double d_mm = 0.0;
  double alpha_deg = 0.0;
  double theta_offset_deg = 0.0;
  int direction = 1;
  double min_deg = -180.0;
  double max_deg = 180.0;
  double max_speed_deg_s = 180.0;
};

/// OPW parameters of a robot file (DESIGN.md §3.2), mm and degrees.
struct OpwSpec {
  double a1_mm = 0.0, a2_mm = 0.0, b_mm = 0.0, c1_mm = 0.0, c2_mm = 0.0, c3_mm = 0.0, c4_mm = 0.0;
  std::array<double, 6> offsets_deg{};
  std::array<int, 6> signs{1, 1, 1, 1, 1, 1};
};

struct LinkSpec {
  std::string name;
  std::vector<ShapeSpec> shapes;
};

/// A robot file: name, DH table, OPW parameters, link geometry (base + 6 links).
struct RobotSpec {
  std::string name;
  std::vector<JointSpec> dh;
  OpwSpec opw;
  std::vector<LinkSpec> links;
};

void describe(YamlIn& a, RobotSpec& s);
void describe(YamlOut& a, RobotSpec& s);

/// Reads and validates a robot mapping (a robot file's top level or a job's inline `robot`).
RobotSpec readRobot(YamlIn& in);
/// Loads a robot file; errors name the file.
RobotSpec loadRobotFile(const std::filesystem::path& file);
/// Builds the kinematic model, checking OPW against DH; errors name `source` (the file).
kinematics::RobotModel buildRobotModel(const RobotSpec& spec, const std::string& source);

}  // namespace scanplan::cli
