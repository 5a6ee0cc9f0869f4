#pragma once
// The plain spec structs shared by robot and job files (no YAML here: the readers and writers are
// in config/detail/).

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/kinematics/shape.h>

namespace scanplan::config {

/// A path as written in a job or robot file and as resolved against that file's folder.
/// Reading one checks that the file exists.
struct FilePath {
  std::string as_written;
  std::filesystem::path resolved;
};

/// A pose as the user writes it: translation in mm, roll-pitch-yaw in degrees
/// (R = Rz(yaw)·Ry(pitch)·Rx(roll), fixed axes).
struct PoseSpec {
  std::array<double, 3> xyz_mm{};
  std::array<double, 3> rpy_deg{};
};

/// One collision shape as written in a robot or job file.
/// box: size_mm; sphere: radius_mm; cylinder / capsule: radius_mm and either length_mm (along
/// the shape's z, centred at pose) or from_mm + to_mm end points (then pose must be absent);
/// mesh: file, units (mm|m), scale.
struct ShapeSpec {
  std::string type = "box";
  std::array<double, 3> size_mm{};
  double radius_mm = 0.0;
  double length_mm = 0.0;
  bool by_end_points = false;
  std::array<double, 3> from_mm{};
  std::array<double, 3> to_mm{};
  FilePath file;
  std::string units = "mm";
  double scale = 1.0;
  PoseSpec pose;
};

inline const std::vector<std::string> kShapeTypes = {"box", "sphere", "cylinder", "capsule",
                                                     "mesh"};
inline const std::vector<std::string> kLengthUnits = {"mm", "m"};

Eigen::Isometry3d toIsometry(const PoseSpec& pose);
PoseSpec toPoseSpec(const Eigen::Isometry3d& X);
kinematics::Shape toShape(const ShapeSpec& spec);
kinematics::LengthUnit toLengthUnit(const std::string& units);

}  // namespace scanplan::config
