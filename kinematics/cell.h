#pragma once

#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "kinematics/robot_model.h"
#include "kinematics/rotary_table.h"
#include "kinematics/shape.h"

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

  /// Flange target X_BF for a sensor pose X_PS (part frame) with the table at θ (rad).
  Eigen::Isometry3d flangeTarget(double theta, const Eigen::Isometry3d& X_PS) const {
    return kinematics::flangeTarget(X_WB, table, theta, part.X_RP, X_PS, scanner.X_FS);
  }
};

}  // namespace scanplan::kinematics
