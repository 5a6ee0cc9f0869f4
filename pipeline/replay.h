#pragma once
// What a 3D replay of a plan shows (OUT/replay.html): the cell's bodies as triangle meshes in the
// frames that carry them, the carriers' poses over time, the growing cloud, the part's coverage
// and the certificate's uncovered areas, and the closest approach. Geometry and poses only: the
// viewer draws them.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/kinematics/cell.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/pipeline/plan_scan.h>

namespace scanplan::pipeline {

/// The frames that carry bodies: the robot's links 0 … 6 (X_WB · X_Bk), the scanner's laser
/// frame S, the table top R; world bodies have none.
inline constexpr int kReplayScannerFrame = 7;
inline constexpr int kReplayTableFrame = 8;
inline constexpr int kReplayFrames = 9;
inline constexpr int kReplayWorld = -1;

struct ReplayBody {
  std::string name;  ///< as the collision scene names it (base, link1 …, scanner, table, part)
  int frame = kReplayWorld;
  kinematics::TriangleMesh mesh;                     ///< in its frame, m
  std::vector<std::array<std::uint8_t, 3>> colours;  ///< per triangle; empty: the body's own
  /// The part only, per triangle: s, when the first point of the cloud lands on it (its colour
  /// holds from then on); +infinity: never. Empty for other bodies and without a simulation.
  std::vector<float> covered_t;
  /// A robot link's stand-in in the maps (its hull or its convex pieces, collision::MapHull),
  /// coloured piece by piece, to draw over the link's mesh on request; in the link's frame.
  bool standin = false;
};

struct ReplayFrame {
  double t = 0.0;  ///< s
  bool scanning = false;
  std::array<Eigen::Isometry3d, kReplayFrames> poses;  ///< world frame
};

struct ReplayScene {
  std::vector<ReplayBody> bodies;
  Eigen::Isometry3d X_RP = Eigen::Isometry3d::Identity();  ///< the part frame on the table top
  std::vector<ReplayFrame> frames;
  /// The laser fan in the scanner frame: origin and the window's near and far edges (Eq. 5).
  std::array<Eigen::Vector3d, 5> fan{};
  /// The cloud (part frame, m), a subsample in time order, with each point's time.
  std::vector<Eigen::Vector3f> cloud;
  std::vector<float> cloud_t;
  std::size_t cloud_total = 0;  ///< points in the whole cloud
  /// points/mm², the top of the part's density colour scale (viridis from 0; 0: no coverage)
  double density_top_per_mm2 = 0.0;
  /// Area samples the certificate leaves uncovered (part frame, m) and their class.
  std::vector<Eigen::Vector3f> uncovered;
  std::vector<std::uint8_t> uncovered_class;
  /// The closest approach of the scanner or a link to the cell, and within the robot.
  struct Closest {
    std::string a, b;
    double t = 0.0, distance = 0.0;  ///< s, m
  };
  std::vector<Closest> closest;
};

struct ReplayOptions {
  std::size_t max_frames =
      2000;  ///< the trajectory's samples (evenly spaced in time) thinned evenly to this many
  std::size_t max_points = 150000;  ///< the cloud's subsample
  double chord_tolerance = 1e-3;    ///< m, round primitives' tessellation
};

/// The replay of a planned scan: `plan` must have a trajectory; the cloud, coverage and
/// certificate when it has them. `part` is the part's mesh (part frame).
ReplayScene replayScene(const kinematics::CellModel& cell,
                        const kinematics::TriangleMesh& part,
                        const ScanPlan& plan,
                        const ReplayOptions& options = {});

}  // namespace scanplan::pipeline
