#pragma once
// Internal to collision/: the FCL side of the scene. Nothing outside collision/ includes this.

#include <memory>
#include <optional>
#include <vector>

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/convex.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/math/bv/OBBRSS.h>
#include <Eigen/Geometry>

#include <scanplan/collision/primitive_distance.h>
#include <scanplan/collision/scene.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/shape.h>

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
  /// For the closed forms (collision/primitive_distance): the primitive's kind and half sizes,
  /// its pose left at identity; absent for meshes.
  std::optional<Primitive> primitive;
  /// For meshes: their axis-aligned bounding box in the shape frame, as a box primitive whose
  /// pose is the box centre: the closed forms against it bound the mesh's distance from below.
  std::optional<Primitive> bounding_box;
};

struct BodyGeometry {
  std::vector<CollisionShape> shapes;
  /// Convex shapes that hold every shape (a link's hulls around its convex pieces), or none: a
  /// bounded query measures them first, and when they lie at or beyond the bound so does the
  /// body.
  std::vector<CollisionShape> gate;
};

struct SceneGeometry {
  std::vector<BodyGeometry> bodies;
  /// The same bodies as the configuration maps measure them (Geometry::kMap): robot link meshes
  /// replaced by their hulls when the scene's config says so.
  std::vector<BodyGeometry> map_bodies;

  const std::vector<BodyGeometry>& of(Geometry g) const {
    return g == Geometry::kMap ? map_bodies : bodies;
  }
};

/// FCL geometry for a kinematics shape; meshes are loaded (through `meshes`, a cache keyed by
/// file and options) and built as OBBRSS BVH models.
CollisionShape makeCollisionShape(const kinematics::Shape& shape);

/// Builds an OBBRSS BVH model from a triangle mesh (m).
std::shared_ptr<MeshModel> makeMeshModel(const kinematics::TriangleMesh& mesh);

/// A BVH model's triangles back as a mesh (its vertices and triangles, in the model's frame).
kinematics::TriangleMesh meshOf(const MeshModel& model);

/// A mesh shape's convex hull (collision/convex_hull) as an FCL convex polytope, measured by
/// GJK against everything but meshes, which are walked with GJK at their triangles. Keeps the
/// mesh's pose; its bounding box and sphere are the hull's; `polyhedron` is the hull's surface
/// (the exact reference's geometry against meshes). `hull`: closed, outward triangles.
CollisionShape makeHullShape(const CollisionShape& mesh_shape,
                             const kinematics::TriangleMesh& hull);

/// Distance between two shapes at world poses, by FCL's traversal seeded with `bound` (a box
/// against a mesh: scanplan's traversal of FCL's BVH in the box frame): anything at or beyond
/// `bound` is reported as `bound` with `beyond` set; distances below it match plain
/// fcl::distance within 1e-9 m. The closed forms (collision/primitive_distance) come first: they
/// settle pairs beyond the bound, and measure primitive pairs they have an exact form for
/// (spheres, capsules, boxes, a capsule with a cylinder) when no witness points are asked
/// for; those numbers are exact, where FCL's GJK stops within its 1e-6 m tolerance. Returns 0 with
/// `penetrating` set when the shapes touch (closer than 1 pm) or overlap (for meshes: when surfaces
/// cross; a solid wholly inside a mesh is not seen, and the witness points of penetrating pairs are
/// arbitrary). Witness points (world) only when asked for, zero otherwise.
struct ShapeDistance {
  double distance = 0.0;
  bool beyond = false;
  /// A lower bound on the true distance: `distance` itself unless beyond; beyond, at least
  /// `bound` (more when a closed form or the bounding box showed more). The configuration maps
  /// carry it forward to skip later queries (motion-bound skipping).
  double lower = 0.0;
  bool penetrating = false;
  Eigen::Vector3d p_a = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_b = Eigen::Vector3d::Zero();
};
ShapeDistance shapeDistance(const CollisionShape& a,
                            const Eigen::Isometry3d& X_Wa,
                            const CollisionShape& b,
                            const Eigen::Isometry3d& X_Wb,
                            double bound,
                            bool witness_points,
                            bool closed_forms = true);

/// The least distance over the shape pairs of two bodies at their world poses, as
/// shapeDistance reports it, below `bound`; a bounding-sphere broad phase skips shape pairs that
/// cannot come closer. `exact`: plain fcl::distance on every shape pair instead (no bound).
ShapeDistance bodyDistance(const BodyGeometry& a,
                           const Eigen::Isometry3d& X_Wa,
                           const BodyGeometry& b,
                           const Eigen::Isometry3d& X_Wb,
                           double bound,
                           bool exact,
                           bool witness,
                           bool closed_forms = true);

/// The separation of two convex shapes (hulls, primitives) at world poses along the direction n
/// (world, from a towards b; normalised here): min over b of n·b minus max over a of n·a, by
/// their support points. A lower bound on their distance for every n, equal to it along the
/// direction between their nearest points: the certificate shapeDistance() checks GJK's convex
/// answers against. Throws std::invalid_argument for a mesh.
double separationAlong(const CollisionShape& a,
                       const Eigen::Isometry3d& X_Wa,
                       const CollisionShape& b,
                       const Eigen::Isometry3d& X_Wb,
                       const Eigen::Vector3d& n);

/// Plain fcl::distance between two shapes (no bound, FCL's own dispatch): the reference the
/// bounded query must agree with.
ShapeDistance exactShapeDistance(const CollisionShape& a,
                                 const Eigen::Isometry3d& X_Wa,
                                 const CollisionShape& b,
                                 const Eigen::Isometry3d& X_Wb);

}  // namespace scanplan::collision::detail
