#pragma once

#include <filesystem>
#include <string>
#include <variant>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/kinematics/mesh.h>

namespace scanplan::kinematics {

/// Box centred on its frame; full side lengths in m.
struct Box {
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
};
/// Sphere centred on its frame; m.
struct Sphere {
  double radius = 0.0;
};
/// Cylinder along its frame's z axis, centred; m.
struct Cylinder {
  double radius = 0.0;
  double length = 0.0;
};
/// Capsule (cylinder with hemispherical caps) along z, centred; length without the caps; m.
struct Capsule {
  double radius = 0.0;
  double length = 0.0;
};
/// A mesh file; loaded by the module that needs triangles (collision, scanner).
struct MeshFile {
  std::filesystem::path path;
  MeshLoadOptions options;
};

using ShapeGeometry = std::variant<Box, Sphere, Cylinder, Capsule, MeshFile>;

/// One piece of collision/visual geometry rigidly attached to a body frame B.
struct Shape {
  ShapeGeometry geometry;
  Eigen::Isometry3d X_BG = Eigen::Isometry3d::Identity();  ///< shape frame G in the body frame
};

/// Short human-readable kind name ("box", "mesh", …).
std::string shapeKindName(const ShapeGeometry& geometry);

/// How finely round primitives are tessellated into triangles.
struct TessellationOptions {
  /// Largest distance between a round surface and its chords, m.
  double chord_tolerance = 1e-4;
  int min_segments = 12;   ///< around the axis, at least
  int max_segments = 256;  ///< around the axis, at most
};

/// The shape's surface as a closed triangle mesh (counter-clockwise seen from outside) in its
/// body frame B (X_BG applied), m. Boxes are exact (12 triangles); spheres, cylinders and
/// capsules are inscribed polyhedra within `chord_tolerance` of the true surface; mesh files
/// are loaded (loadMesh, with their options; throws InputError as loadMesh does).
TriangleMesh shapeSurface(const Shape& shape, const TessellationOptions& options = {});

}  // namespace scanplan::kinematics
