#pragma once
// How the spec structs map to YAML keys: one describe(A&, Spec&) per struct, read by YamlIn and
// written by YamlOut. Private to config/ (only its .cpp files include this).

#include <Eigen/Geometry>

#include <scanplan/config/detail/yaml_reader.h>
#include <scanplan/config/robot_file.h>
#include <scanplan/config/spec.h>

namespace scanplan::config {

template <class A>
void describe(A& a, PoseSpec& s) {
  a.field("xyz_mm", s.xyz_mm);
  a.field("rpy_deg", s.rpy_deg);
}

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

void describe(YamlIn& a, RobotSpec& s);
void describe(YamlOut& a, RobotSpec& s);

/// Reads and validates a robot mapping (a robot file's top level or a job's inline `robot`).
RobotSpec readRobot(YamlIn& in);
/// Throws InputError (naming `source`) unless `spec` is what a robot file may say: the robot
/// file reader's checks (ranges, limits, files) on a spec that did not come from YAML.
void checkAsRobotFile(const RobotSpec& spec, const std::string& source);
/// Reads a robot given as a URDF (a mapping with `urdf:`, robot_urdf.h) and imports it.
RobotSpec readUrdfRobot(YamlIn& in);

}  // namespace scanplan::config
