#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "cli/robot_file.h"
#include "cli/spec.h"
#include "kinematics/cell.h"

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

/// A whole job file, every default filled in.
struct JobSpec {
  std::string name = "job";
  FilePath robot_file;  ///< empty when the robot is given inline
  RobotSpec robot;
  PoseSpec robot_base;
  TableSpec table;
  PartSpec part;
  ScannerSpec scanner;
  std::filesystem::path source;  ///< the job file itself
};

/// Loads and validates a job file (and the robot file it names).
JobSpec loadJob(const std::filesystem::path& file);
/// The fully resolved job as YAML (robot inline, paths absolute, every default present).
std::string jobToYaml(const JobSpec& job);
/// Builds the cell model: robot kinematics (OPW checked against DH), table, part, scanner.
kinematics::CellModel buildCell(const JobSpec& job);

}  // namespace scanplan::cli
