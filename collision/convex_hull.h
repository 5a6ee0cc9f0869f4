#pragma once
// Convex hulls of link meshes for the configuration maps: a hull contains its mesh,
// so a distance to the hull never exceeds the distance to the mesh, and exceeds it by at most
// the hull's margin (below). The maps measure hulls; validation keeps the exact meshes.

#include <cstddef>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include <scanplan/kinematics/mesh.h>

namespace scanplan::collision {

/// The convex hull of the vertices the mesh's triangles use (qhull), as a closed triangle mesh,
/// counter-clockwise seen from outside. std::nullopt when they span no volume (a flat mesh).
std::optional<kinematics::TriangleMesh> convexHull(const kinematics::TriangleMesh& mesh);

/// The convex hull of points, as convexHull gives it; std::nullopt when they span no volume.
std::optional<kinematics::TriangleMesh> convexHullOf(const std::vector<Eigen::Vector3d>& points);

/// A convex polytope of at most `max_vertices` vertices (≥ 8) that contains `hull` (a convex
/// hull, as convexHull gives): the hull itself when it has no more vertices; else the bounding
/// box cut by the hull's own face planes, each round the plane that the vertex farthest outside
/// the hull lies farthest beyond, while the vertices stay within the budget. Fewer vertices
/// make GJK faster and the margin (below) larger. std::nullopt when the hull is degenerate.
std::optional<kinematics::TriangleMesh> simplifiedHull(const kinematics::TriangleMesh& hull,
                                                       std::size_t max_vertices);

/// How far the hull's surface (or any closed surface around the mesh: a simplified hull)
/// reaches outside the mesh: an upper bound h on the largest
/// distance from a point of the hull's surface to the mesh's surface, within `tolerance` (m) of
/// that largest distance. For any body B outside the mesh, d(B, hull) ≤ d(B, mesh) ≤
/// d(B, hull) + h: the margin the maps give away. Branch and bound over the hull's triangles
/// (the distance to the mesh moves by at most the distance moved), at most `max_queries`
/// point–mesh distances, after which the bound is only looser, never lower than the truth.
struct HullMargin {
  double margin = 0.0;  ///< m, the upper bound h
  double found = 0.0;   ///< m, the largest distance actually measured (h − found ≤ tolerance
                        ///< unless the queries ran out)
  std::size_t queries = 0;                          ///< point–mesh distances measured
  Eigen::Vector3d where = Eigen::Vector3d::Zero();  ///< m, where `found` was measured
};
HullMargin hullMargin(const kinematics::TriangleMesh& hull,
                      const kinematics::TriangleMesh& mesh,
                      double tolerance = 5e-4,
                      std::size_t max_queries = 200000);

}  // namespace scanplan::collision
