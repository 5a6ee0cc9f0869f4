#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "cli/config/yaml_reader.h"
#include "kinematics/shape.h"

namespace scanplan::cli {

/// A pose as the user writes it: translation in mm, roll-pitch-yaw in degrees
/// (R = Rz(yaw)·Ry(pitch)·Rx(roll), fixed axes).
struct PoseSpec {
  std::array<double, 3> xyz_mm{};
  std::array<double, 3> rpy_deg{};
};

template <class A>
void describe(A& a, PoseSpec& s) {
  a.field("xyz_mm", s.xyz_mm);
  a.field("rpy_deg", s.rpy_deg);
}

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

template <class A>
void describe(A& a, ShapeSpec& s) {
  a.require("type");
  a.field("type", s.type, Expect::oneOf(kShapeTypes));
  if (s.type == "box") {
    a.require("size_mm");
    a.field("size_mm", s.size_mm, Expect::positive());
  } else if (s.type == "sphere") {
    a.require("radius_mm");
    a.field("radius_mm", s.radius_mm, Expect::positive());
  } else if (s.type == "cylinder" || s.type == "capsule") {
    a.require("radius_mm");
    a.field("radius_mm", s.radius_mm, Expect::positive());
    if constexpr (A::kReading) s.by_end_points = a.has("from_mm") || a.has("to_mm");
    if (s.by_end_points) {
      a.require("from_mm");
      a.require("to_mm");
      a.field("from_mm", s.from_mm);
      a.field("to_mm", s.to_mm);
      if constexpr (A::kReading) {
        if (a.has("length_mm") || a.has("pose")) {
          a.fail("from_mm", "given with length_mm or pose",
                 "either from_mm + to_mm or length_mm + pose");
        }
        const Eigen::Vector3d d =
            Eigen::Vector3d(s.to_mm.data()) - Eigen::Vector3d(s.from_mm.data());
        if (d.norm() <= 0.0 && s.type == "cylinder") {
          a.fail("to_mm", "equal to from_mm", "a cylinder with positive length");
        }
      }
      return;
    }
    a.require("length_mm");
    a.field("length_mm", s.length_mm,
            s.type == "cylinder" ? Expect::positive() : Expect::nonNegative());
  } else {
    a.require("file");
    a.field("file", s.file);
    a.field("units", s.units, Expect::oneOf(kLengthUnits));
    a.field("scale", s.scale, Expect::positive());
  }
  a.section("pose", s.pose);
}

Eigen::Isometry3d toIsometry(const PoseSpec& pose);
PoseSpec toPoseSpec(const Eigen::Isometry3d& X);
kinematics::Shape toShape(const ShapeSpec& spec);
kinematics::LengthUnit toLengthUnit(const std::string& units);

}  // namespace scanplan::cli
