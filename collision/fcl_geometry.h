#pragma once
// Internal to collision/: the FCL side of the scene. Nothing outside collision/ includes this.

#include <memory>
#include <vector>

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/math/bv/OBBRSS.h>
#include <Eigen/Geometry>

#include "collision/scene.h"
#include "kinematics/mesh.h"
#include "kinematics/shape.h"

namespace scanplan::collision::detail {

using MeshModel = fcl::BVHModel<fcl::OBBRSSd>;

/// One FCL geometry rigidly attached to a body, with a bounding sphere for the broad phase.
struct CollisionShape {
  std::shared_ptr<fcl::CollisionGeometryd> geometry;
  /// The same solid as a triangle mesh when that is exact (boxes): what the exact reference
  /// (exactShapeDistance) measures against meshes; the bounded query has its own box–mesh
  /// traversal.
  std::shared_ptr<MeshModel> polyhedron;
  Eigen::Isometry3d X_BG = Eigen::Isometry3d::Identity();  ///< shape in its body frame
  Eigen::Vector3d centre_G = Eigen::Vector3d::Zero();      ///< bounding-sphere centre, shape frame
  double radius = 0.0;                                     ///< bounding-sphere radius, m
  std::size_t triangles = 0;
};

struct BodyGeometry {
  std::vector<CollisionShape> shapes;
};

struct SceneGeometry {
  std::vector<BodyGeometry> bodies;
};

/// FCL geometry for a kinematics shape; meshes are loaded (through `meshes`, a cache keyed by
/// file and options) and built as OBBRSS BVH models.
CollisionShape makeCollisionShape(const kinematics::Shape& shape);

/// Builds an OBBRSS BVH model from a triangle mesh (m).
std::shared_ptr<MeshModel> makeMeshModel(const kinematics::TriangleMesh& mesh);

/// Distance between two shapes at world poses, by FCL's traversal seeded with `bound` (a box
/// against a mesh: scanplan's traversal of FCL's BVH in the box frame): anything at or beyond
/// `bound` is reported as `bound` with `beyond` set; distances below it match plain
/// fcl::distance within 1e-9 m. Returns 0 with `penetrating` set when the shapes touch (closer
/// than 1 pm) or overlap (for meshes: when surfaces cross; a solid wholly inside a mesh is not
/// seen, and the witness points of penetrating pairs are arbitrary). Witness points (world) only
/// when asked for, zero otherwise.
struct ShapeDistance {
  double distance = 0.0;
  bool beyond = false;
  bool penetrating = false;
  Eigen::Vector3d p_a = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_b = Eigen::Vector3d::Zero();
};
ShapeDistance shapeDistance(const CollisionShape& a,
                            const Eigen::Isometry3d& X_Wa,
                            const CollisionShape& b,
                            const Eigen::Isometry3d& X_Wb,
                            double bound,
                            bool witness_points);

/// Plain fcl::distance between two shapes (no bound, FCL's own dispatch): the reference the
/// bounded query must agree with.
ShapeDistance exactShapeDistance(const CollisionShape& a,
                                 const Eigen::Isometry3d& X_Wa,
                                 const CollisionShape& b,
                                 const Eigen::Isometry3d& X_Wb);

}  // namespace scanplan::collision::detail
