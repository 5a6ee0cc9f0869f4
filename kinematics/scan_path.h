#pragma once

#include <utility>
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
  /// Sample indices where a new segment starts, ascending, each in (0, samples.size()); empty:
  /// one segment. The path does not connect one segment to the next: the table and the arm are
  /// planned per segment, and the program joins segments with point-to-point moves of every
  /// axis (kinematics/ptp_move.h). The automatic scan makes each pass a segment.
  std::vector<std::size_t> breaks;
  /// Per segment (segmentRanges() order), the time it takes at its own speed, s. Its samples
  /// stand a whole number of dt apart, so they span that time rounded up; the program runs each
  /// segment in its own time where the axes allow (pipeline::retimeSegment()). Empty, or of
  /// another size: the samples' span.
  std::vector<double> own_durations;

  double duration() const { return samples.empty() ? 0.0 : samples.back().t; }
};

/// The segments of `path` as [begin, end) sample ranges, in order (one range without breaks).
std::vector<std::pair<std::size_t, std::size_t>> segmentRanges(const ScanPath& path);

/// The samples [begin, end) of `path` as a path of their own (times unchanged, no breaks).
ScanPath slicePath(const ScanPath& path, std::size_t begin, std::size_t end);

/// Pose between two samples: linear position, slerp orientation, s in [0, 1].
Eigen::Isometry3d interpolatePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double s);

}  // namespace scanplan::kinematics
