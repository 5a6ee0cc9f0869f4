#pragma once

// The demo's head and table for the candidate-pass tests (test_pass_speed, test_aimed_spin).
#include <Eigen/Core>

#include <scanplan/kinematics/units.h>
#include <scanplan/scanner/laser_model.h>
#include <scanplan/scanner/part_on_table.h>
#include <scanplan/scanner/scan_passes.h>

namespace scanplan::test {

/// The demo's table top (data/jobs/demo.yaml): 200 mm radius, 150 mm high.
constexpr scanner::TableTop kDemoTable{0.2, 0.15};

/// The demo head (data/jobs/demo.yaml): camera 100 mm beside the laser along x_S, depth window
/// 107 … 196 mm (Eq. 5), a 0.5 mm spacing at 100 profiles per second; no housing.
inline scanner::PassSettings demoHead() {
  scanner::PassSettings s;
  s.window = scanner::laserWindow({0.1, 0.0, deg(35.0), deg(8.0)});
  s.cameras = {Eigen::Vector3d(0.1, 0.0, 0.0)};
  s.point_spacing = 5e-4;
  s.frame_rate = 100.0;
  return s;
}

}  // namespace scanplan::test
