#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "cli/robot_file.h"
#include "cli/spec.h"
#include "collision/scene.h"
#include "kinematics/cell.h"
#include "planner/constraints.h"

namespace scanplan::cli {

/// `table`: the rotary table. Axis frame A at θ = 0 (z = rotation axis, origin at the centre
/// of the table top), its size, travel, dynamics and calibration errors.
struct TableSpec {
  PoseSpec axis{{600.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
  double radius_mm = 200.0;
  double height_mm = 150.0;
  bool continuous = true;
  double min_deg = -180.0;
  double max_deg = 180.0;
  double max_speed_deg_s = 30.0;
  double max_accel_deg_s2 = 60.0;
  std::array<double, 2> eccentricity_mm{};
  std::array<double, 2> tilt_deg{};
};

/// `part`: the part mesh and its placement on the table top (X_RP).
struct PartSpec {
  FilePath mesh;
  std::string units = "mm";
  double scale = 1.0;
  PoseSpec pose;
};

/// `scanner`: the laser frame on the flange (X_FS) and the housing's shapes in that frame.
struct ScannerSpec {
  PoseSpec mount{{0.0, 0.0, 100.0}, {0.0, 0.0, 0.0}};
  std::vector<ShapeSpec> body;
};

/// `obstacles[]`: a fixture or obstacle: a shape (as in robot files) carried by the world or
/// the table. Boxes may be given by `corner_mm` + `size_mm` instead of a centred pose (sizes
/// may then be negative, as workcell tools write them).
struct ObstacleSpec {
  std::string name;
  std::string carrier = "world";
  bool by_corner = false;
  std::array<double, 3> corner_mm{};
  ShapeSpec shape;
};

/// A ramp on a unitless measure (Eq. 8 form).
struct RampSpec {
  double low = 0.0;
  double high = 1.0;
  double gamma = 1.0;
};

/// A ramp on a length, mm.
struct LengthRampSpec {
  double low_mm = 0.0;
  double high_mm = 1.0;
  double gamma = 1.0;
};

/// `constraints.clearance.pairs[]`: a rule for the pairs whose bodies match `a` and `b`.
struct PairRuleSpec {
  std::string a;
  std::string b;
  bool exclude = false;
  bool include = false;
  double d_low_mm = -1.0;   ///< negative: unchanged
  double d_high_mm = -1.0;  ///< negative: unchanged
  double gamma = -1.0;      ///< negative: unchanged
};

struct ClearanceSpec {
  double d_low_mm = 5.0;
  double d_high_mm = 30.0;
  double gamma = 1.0;
  std::vector<PairRuleSpec> pairs;
};

/// `constraints`: the static constraints of a pose (Eq. 6–8).
struct ConstraintsSpec {
  std::array<double, 6> joint_limit_gamma{0.2, 0.2, 0.2, 0.2, 0.2, 0.2};
  RampSpec wrist{0.05, 0.25, 1.0};
  RampSpec elbow{0.05, 0.25, 1.0};
  LengthRampSpec shoulder{30.0, 120.0, 1.0};
  ClearanceSpec clearance;
};

/// A whole job file, every default filled in.
struct JobSpec {
  std::string name = "job";
  FilePath robot_file;  ///< empty when the robot is given inline
  RobotSpec robot;
  PoseSpec robot_base;
  TableSpec table;
  PartSpec part;
  ScannerSpec scanner;
  std::vector<ObstacleSpec> obstacles;
  ConstraintsSpec constraints;
  std::filesystem::path source;  ///< the job file itself
};

/// Loads and validates a job file (and the robot file it names).
JobSpec loadJob(const std::filesystem::path& file);
/// The fully resolved job as YAML (robot inline, paths absolute, every default present).
std::string jobToYaml(const JobSpec& job);
/// Builds the cell model: robot kinematics (OPW checked against DH), table, part, scanner,
/// obstacles.
kinematics::CellModel buildCell(const JobSpec& job);
/// The job's clearance thresholds and pair rules, SI.
collision::ClearanceConfig clearanceConfig(const JobSpec& job);
/// The job's pose constraints (Eq. 7, singularity ramps), SI.
planner::ConstraintSettings constraintSettings(const JobSpec& job);

}  // namespace scanplan::cli
