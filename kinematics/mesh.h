#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace scanplan::kinematics {

enum class LengthUnit { kMillimetre, kMetre };

/// An indexed triangle mesh. Vertices in metres, in the mesh's own frame; triangles are
/// vertex index triples, counter-clockwise seen from outside when the source was oriented.
struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> triangles;

  /// Axis-aligned bounds of the vertices (empty box for an empty mesh), metres.
  Eigen::AlignedBox3d bounds() const;
  /// True when every edge is shared by exactly two triangles that traverse it in opposite
  /// directions (a closed, consistently oriented 2-manifold).
  bool isClosed() const;
  /// Total surface area, m².
  double area() const;
  /// The enclosed volume by the triangles' winding, m³: positive for a closed mesh whose
  /// triangles turn counter-clockwise seen from outside, negative when it is inside out.
  double signedVolume() const;
};

struct MeshLoadOptions {
  /// Length unit of the numbers in the file.
  LengthUnit units = LengthUnit::kMillimetre;
  /// Extra uniform scale applied after the unit conversion (must be finite and > 0).
  double scale = 1.0;
  /// Rotation applied last, e.g. to turn a y-up file z-up (must be a rotation matrix).
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
};

/// What the loader noticed but repaired; the caller decides how to report it.
struct MeshLoadReport {
  std::size_t degenerate_dropped = 0;    ///< zero-area or repeated-index triangles removed
  std::size_t non_triangle_dropped = 0;  ///< points / lines in the file, ignored
  std::size_t normals_disagreeing = 0;   ///< stored facet normals opposite to the winding
  std::vector<std::string> warnings;     ///< one human-readable line per issue noticed
};

struct LoadedMesh {
  TriangleMesh mesh;
  MeshLoadReport report;
};

/// Loads STL (ASCII and binary), OBJ, PLY or OFF through assimp, welds identical vertices and
/// converts to metres. Throws scanplan::InputError naming the file when it is missing, empty,
/// truncated, malformed, holds no triangles, holds a polygon of more than four corners that is
/// not convex (assimp's triangulation can cut across it), or is larger than the loader's bounds
/// (1 GB, 4 000 000 triangles: kinematics/mesh_file.h, checked before assimp does the work).
LoadedMesh loadMesh(const std::filesystem::path& path, const MeshLoadOptions& options = {});

}  // namespace scanplan::kinematics
