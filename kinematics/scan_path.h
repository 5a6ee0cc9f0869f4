#pragma once

#include <vector>

#include <Eigen/Geometry>

namespace scanplan::kinematics {

/// One sample of a scan path: the scanner (laser) frame S in the part frame P at time t.
struct ScanSample {
  double t = 0.0;                                          ///< s
  Eigen::Isometry3d X_PS = Eigen::Isometry3d::Identity();  ///< m
  bool scanning = false;                                   ///< the laser is acquiring
};

/// A scan path sampled at a fixed time step (the map's time axis).
struct ScanPath {
  double dt = 0.1;  ///< s
  std::vector<ScanSample> samples;

  double duration() const { return samples.empty() ? 0.0 : samples.back().t; }
};

/// Pose between two samples: linear position, slerp orientation, s in [0, 1].
Eigen::Isometry3d interpolatePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double s);

}  // namespace scanplan::kinematics
