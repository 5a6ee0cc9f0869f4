#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include <scanplan/config/spec.h>
#include <scanplan/kinematics/robot_model.h>

namespace scanplan::config {

/// One DH row of a robot file (docs/design.md §3.1): mm, degrees, deg/s.
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

/// OPW parameters of a robot file (docs/design.md §3.2), mm and degrees.
struct OpwSpec {
  double a1_mm = 0.0, a2_mm = 0.0, b_mm = 0.0, c1_mm = 0.0, c2_mm = 0.0, c3_mm = 0.0, c4_mm = 0.0;
  std::array<double, 6> offsets_deg{};
  std::array<int, 6> signs{1, 1, 1, 1, 1, 1};
};

struct LinkSpec {
  std::string name;
  std::vector<ShapeSpec> shapes;
};

/// The robot controllers a robot file can name (`controller:`): each runs one program language.
/// "none": the file does not say (the default), so `plan` writes only the CSV.
inline const std::vector<std::string> kControllers = {"adept_vplus", "kuka_krl", "abb_rapid",
                                                      "ur_script", "none"};

/// A robot file: name, controller, DH table, OPW parameters, link geometry (base + 6 links).
struct RobotSpec {
  std::string name;
  std::string controller = "none";  ///< one of kControllers
  std::vector<JointSpec> dh;
  OpwSpec opw;
  std::vector<LinkSpec> links;
  /// Link pairs never checked against each other (they touch or overlap by design), by name:
  /// `allowed_collisions: [[link4, link6]]`.
  std::vector<std::array<std::string, 2>> allowed_collisions;
};

/// The program format (a name of programFormatNames()) the controller runs: vplus, krl, rapid,
/// urscript; "" for none.
std::string controllerProgramFormat(const std::string& controller);
/// The programs `plan` writes when the job's outputs.programs does not say: the controller's
/// language and the CSV; the CSV alone when the robot names no controller.
std::vector<std::string> defaultPrograms(const RobotSpec& robot);
/// The formats among `formats` that are another vendor's language than the robot's controller
/// (the CSV is nobody's; a robot with controller none has no vendor, so nothing is foreign).
std::vector<std::string> foreignPrograms(const RobotSpec& robot,
                                         const std::vector<std::string>& formats);

/// Loads a robot file; errors name the file.
RobotSpec loadRobotFile(const std::filesystem::path& file);
/// The robot file text (YAML) of `spec`, read back by loadRobotFile to the same spec: `header`
/// first as comment lines, then every key; mesh paths as written (`FilePath::as_written`).
std::string robotToYaml(const RobotSpec& spec, const std::string& header);
/// Builds the kinematic model, checking OPW against DH; errors name `source` (the file).
kinematics::RobotModel buildRobotModel(const RobotSpec& spec, const std::string& source);

}  // namespace scanplan::config
