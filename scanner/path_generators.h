#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/scan_path.h>
#include <scanplan/scanner/laser_model.h>
#include <scanplan/scanner/raycaster.h>

namespace scanplan::scanner {

/// A ring around the part's vertical axis (part frame z): the scanner aims at the axis point
/// at `height`, looking inward and down by `tilt`, and circles it. The laser plane is vertical
/// (it contains the view direction and the part axis), the motion is tangential.
/// All SI: m, rad, rad/s.
struct RingSpec {
  double height = 0.05;
  double tilt = 0.0;
  double start = 0.0;
  double extent = 2.0 * 3.141592653589793;  ///< signed: negative turns clockwise
  double speed = 0.35;                      ///< |angular speed| around the axis
  std::optional<double> distance;           ///< laser origin to the aim point; auto when absent
  std::optional<Eigen::Vector2d> axis_xy;   ///< part-frame axis; the mesh's box centre when absent
};

/// Parallel passes over the part seen from `view` (part frame, the scanner's +z), along
/// `pass_direction`, spread evenly across the part at most the near line length × (1 − overlap)
/// apart; the scanner height follows the surface so it stays in the depth window; `lead` before
/// and after each pass.
struct RasterSpec {
  Eigen::Vector3d view = -Eigen::Vector3d::UnitZ();
  Eigen::Vector3d pass_direction = Eigen::Vector3d::UnitX();
  double overlap = 0.2;
  double lead = 0.02;
  double speed = 0.03;  ///< m/s along a pass
};

struct Waypoint {
  Eigen::Isometry3d X_PS = Eigen::Isometry3d::Identity();
  double speed = 0.05;          ///< m/s to reach this point from the previous one
  double rotation_speed = 0.5;  ///< rad/s limit for the orientation change
  bool scanning = true;
};

struct WaypointSpec {
  std::vector<Waypoint> points;
};

/// A timed path read from CSV: t_s, x_mm, y_mm, z_mm, qw, qx, qy, qz[, scanning].
struct FileSpec {
  std::vector<kinematics::ScanSample> samples;
};

using PathElement = std::variant<RingSpec, RasterSpec, WaypointSpec, FileSpec>;

/// Samples a whole scan path may have (bounds the memory of the path and its maps).
inline constexpr std::size_t kMaxPathSamples = 2'000'000;

struct PathRequest {
  std::vector<PathElement> elements;
  double dt = 0.1;              ///< s, map time step
  double transfer_speed = 0.1;  ///< m/s between elements
  double retreat = 0.05;        ///< m backed off along −z_S before a transfer
};

/// What the generator found, per element, for the report.
struct ElementReport {
  std::string kind;
  double start_time = 0.0;
  double duration = 0.0;
  double depth_min = 0.0;  ///< surface depth seen along the central ray(s), m
  double depth_max = 0.0;
  double coverage_in_window = 1.0;  ///< fraction of probed rays that hit within [z_min, z_max]
  std::string note;
};

struct GeneratedPath {
  kinematics::ScanPath path;
  std::vector<ElementReport> elements;
};

/// Builds the path from its elements (with transfers between them) and samples it every dt.
/// Throws InputError with the element index (`scan.paths[i]`) when an element cannot be built
/// (a ring that misses the part, a raster with no surface under it, …).
GeneratedPath generatePath(const PathRequest& request,
                           const kinematics::TriangleMesh& part,
                           const Raycaster& raycaster,
                           const LaserWindow& window);

/// Parses the CSV text of a path file; errors name `source` and the line.
FileSpec parsePathCsv(const std::string& text, const std::string& source);

/// Writes a sampled path as CSV (t_s, x_mm … qz, scanning), the format parsePathCsv reads.
std::string pathToCsv(const kinematics::ScanPath& path);

}  // namespace scanplan::scanner
