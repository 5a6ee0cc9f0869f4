#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/kinematics/robot_model.h>
#include <scanplan/kinematics/rotary_table.h>
#include <scanplan/kinematics/shape.h>

namespace scanplan::kinematics {

/// The part on the table: its mesh and its placement X_RP on the table top (m).
struct PartModel {
  MeshFile mesh;
  Eigen::Isometry3d X_RP = Eigen::Isometry3d::Identity();
};

/// The scanner on the flange: the laser frame S in the flange frame (X_FS, m) and the
/// housing's collision shapes in frame S.
struct ScannerMount {
  Eigen::Isometry3d X_FS = Eigen::Isometry3d::Identity();
  std::vector<Shape> body;
};

/// What carries a body: it stays put in the world, or turns with the table.
enum class Carrier { kWorld, kTable };

/// A fixture or obstacle in the cell. Its shapes are in the carrier's frame: the world frame
/// for kWorld, the table-top frame R for kTable.
struct Obstacle {
  std::string name;
  Carrier carrier = Carrier::kWorld;
  std::vector<Shape> shapes;
};

/// What a sensor's output must do along a trajectory (the job's `expect`), judged at the
/// validation's sample times. A sensor "fires" when a presence volume overlaps some body, or when
/// a distance sensor has a reading.
struct SensorExpectation {
  enum class Kind {
    kAny,        ///< no rule: the output is only recorded
    kNever,      ///< never fires (a light curtain)
    kAlways,     ///< fires at every sample
    kDuring,     ///< fires at every sample within [t0, t1] and at none outside
    kNotDuring,  ///< does not fire within [t0, t1]; outside anything goes
  };
  Kind kind = Kind::kAny;
  double t0 = 0.0;  ///< s, kDuring / kNotDuring
  double t1 = 0.0;  ///< s, ≥ t0
};

/// A presence or distance sensor of the cell (seed §5.1–5.2). Its frame C is mounted on a
/// carrier: the world (`carrier` empty or "world") or a body of the collision scene by name (a
/// robot link, "scanner", "table", "part", an obstacle), whose frame it moves with: W for the
/// world and world obstacles, link k's DH frame, S for the scanner, the table top R for the
/// table, the part and table-carried obstacles. The carrier body itself is never seen by its
/// own sensor.
struct Sensor {
  enum class Kind {
    kPresence,  ///< a sensitive volume: which bodies overlap it (Boolean output)
    kDistance,  ///< a beam along +z of the sensor frame: the first hit's range
  };
  std::string name;
  Kind kind = Kind::kPresence;
  std::string carrier = "world";
  Eigen::Isometry3d X_CS = Eigen::Isometry3d::Identity();  ///< sensor frame S in the carrier, m
  /// kPresence: the volume (a box, sphere, cylinder or capsule) in the sensor frame S, m.
  Shape volume;
  /// kDistance: the measuring range along the beam from the emitter (origin of S), m.
  double min_range = 0.0;
  double max_range = 1.0;
  /// kDistance: the receiver (triangulation lens) in S, m; nullopt: coaxial with the emitter
  /// (time of flight). With a receiver, the ray from the hit point to it must be free (seed
  /// §5.2's concave-region rule).
  std::optional<Eigen::Vector3d> p_SR;
  SensorExpectation expect;
};

/// The whole cell, built once from a validated job and never mutated.
struct CellModel {
  CellModel(std::string cell_name, RobotModel cell_robot)
      : name(std::move(cell_name)), robot(std::move(cell_robot)) {}

  std::string name;
  RobotModel robot;
  Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();  ///< robot base in the world
  RotaryTableModel table;
  PartModel part;
  ScannerMount scanner;
  std::vector<Obstacle> obstacles;
  std::vector<Sensor> sensors;  ///< presence and distance sensors (none: no sensor outputs)

  /// Flange target X_BF for a sensor pose X_PS (part frame) with the table at θ (rad):
  /// kinematics::flangeTarget, product for product (the same bits).
  Eigen::Isometry3d flangeTarget(double theta, const Eigen::Isometry3d& X_PS) const {
    return flangeTarget(partIn(theta), X_PS);
  }
  /// The same in two steps, for many sensor poses at one θ: X_BF = flangeTarget(partIn(θ),
  /// X_PS).
  Eigen::Isometry3d partIn(double theta) const {
    return X_WB.inverse() * table.X_WR(theta) * part.X_RP;
  }
  Eigen::Isometry3d flangeTarget(const Eigen::Isometry3d& part_in_base,
                                 const Eigen::Isometry3d& X_PS) const {
    return part_in_base * X_PS * scanner.X_FS.inverse();
  }
};

}  // namespace scanplan::kinematics
