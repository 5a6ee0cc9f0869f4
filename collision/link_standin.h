#pragma once
// A tight, conservative stand-in for a robot link mesh in the configuration maps: a few convex
// pieces whose union holds the mesh's surface and stands at most a certified margin outside its
// solid. For any body B outside the mesh, d(B, pieces) ≤ d(B, mesh) ≤ d(B, pieces) + margin, and
// the distances come from GJK on the pieces, never from the mesh's triangles.

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/kinematics/mesh.h>

namespace scanplan::collision {

struct StandInOptions {
  double margin = 0.002;        ///< m: the most the pieces may stand outside the mesh's solid
  std::size_t max_pieces = 64;  ///< per mesh; more pieces make the maps slower
  double tolerance = 2.5e-4;    ///< m: the margin bound is within this of the largest measured
};

/// The pieces of one mesh and what they guarantee.
struct StandIn {
  std::vector<kinematics::TriangleMesh> pieces;  ///< convex, closed, counter-clockwise outside
  /// m: an upper bound on how far a point of a piece's surface lies from the mesh's solid (0
  /// inside it), by branch and bound against the mesh (collision/mesh_distance.h).
  double margin = 0.0;
  bool fits = false;         ///< margin ≤ StandInOptions::margin within max_pieces
  std::size_t vertices = 0;  ///< over all pieces
};

/// Splits the mesh's surface (its triangles cut to at most a few margins long) into clusters, by
/// the plane that leaves the least hull volume on its two sides, until each cluster's convex hull
/// stands within the margin outside the solid; a flat cluster gets a sliver of depth inward. The
/// mesh should be closed and outward (inside is decided by ray parity); at max_pieces it stops
/// and returns what it has with `fits` false. Deterministic.
StandIn fitStandIn(const kinematics::TriangleMesh& mesh, const StandInOptions& options);

/// A cylinder about a line that holds a mesh: a link round about its own joint's axis (a
/// flange) stands in as it, and turning that joint does not move it (ChainLevers: weight 0).
struct AxisCylinder {
  Eigen::Isometry3d X_MC = Eigen::Isometry3d::Identity();  ///< in the mesh's frame: centred, z
                                                           ///< along the line
  double radius = 0.0;                                     ///< m
  double length = 0.0;                                     ///< m
  /// A closed convex prism of kCylinderSides sides around the cylinder (mesh frame), what
  /// pictures draw and what the margin is measured on.
  kinematics::TriangleMesh prism;
  /// m: an upper bound on how far the prism (so the cylinder) stands outside the mesh's solid:
  /// at most `give_up` when that is certain (the measuring then stops: the bound may be loose up
  /// to it), else above it.
  double margin = 0.0;
};
inline constexpr int kCylinderSides = 96;

/// The narrowest cylinder about the line through o along the unit u (mesh frame) that holds
/// the mesh's vertices (so the mesh: the cylinder is convex), and its margin, measured as the
/// pieces' are, within `tolerance`, until it is certainly at most `give_up` or above it.
/// std::nullopt for an empty mesh or a line it does not surround.
std::optional<AxisCylinder> axisCylinder(const kinematics::TriangleMesh& mesh,
                                         const Eigen::Vector3d& o,
                                         const Eigen::Vector3d& u,
                                         double tolerance,
                                         double give_up);

/// The cache key of a mesh's stand-in: a hash of its vertices, triangles and the options, and
/// the fitting method's version, as hex.
std::string standInKey(const kinematics::TriangleMesh& mesh, const StandInOptions& options);

/// Reads a stand-in written by saveStandIn; std::nullopt when the file is absent, unreadable,
/// of another key or damaged in any way, a piece that is not a closed convex polytope included
/// (the caller fits it again).
std::optional<StandIn> loadStandIn(const std::filesystem::path& file, const std::string& key);

/// Writes the stand-in (its pieces' vertices and triangles, to the bit) under its key,
/// atomically: a reader sees the old file or the new one. Returns false when it cannot write
/// (a read-only folder): the stand-in then lives only in memory.
bool saveStandIn(const std::filesystem::path& file, const std::string& key, const StandIn& standin);

}  // namespace scanplan::collision
