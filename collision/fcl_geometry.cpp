#include "collision/fcl_geometry.h"

#include <cmath>
#include <limits>

#include <fcl/narrowphase/detail/gjk_solver_libccd.h>
#include <fcl/narrowphase/detail/traversal/distance/mesh_distance_traversal_node.h>
#include <fcl/narrowphase/detail/traversal/distance/mesh_shape_distance_traversal_node.h>
#include <fcl/narrowphase/detail/traversal/traversal_recurse.h>
#include <fcl/narrowphase/distance.h>

namespace scanplan::collision::detail {
namespace {

using Solver = fcl::detail::GJKSolver_libccd<double>;

// fcl::distance's default tolerance, so the bounded and the plain query run the same GJK.
const fcl::DistanceRequestd kDefaultRequest;

// The traversal may skip a subtree whose bounding volume is within this of the best distance
// so far (FCL's abs_err/rel_err, honoured by the traversal-node API): results stay within
// 0.5 nm of the exact distance, and tied triangles on parallel faces are not all visited.
constexpr double kPruneTolerance = 5e-10;  // m

template <class Node>
void allowTolerance(Node& node, double bound) {
  node.abs_err = kPruneTolerance;
  node.rel_err = std::isfinite(bound) && bound > 0.0 ? kPruneTolerance / bound : 0.0;
}

Solver makeSolver() {
  Solver solver;
  solver.distance_tolerance = kDefaultRequest.distance_tolerance;
  return solver;
}

ShapeDistance finish(
    double d, double bound, bool witness, const Eigen::Vector3d& pa, const Eigen::Vector3d& pb) {
  ShapeDistance out;
  if (d >= bound) {
    out.distance = bound;
    out.beyond = true;
  } else if (d <= 0.0) {
    out.distance = 0.0;
    out.penetrating = true;
  } else {
    out.distance = d;
  }
  if (witness) {  // FCL leaves nearest points uninitialised unless they were asked for
    out.p_a = pa;
    out.p_b = pb;
  }
  return out;
}

// FCL 0.7 returns nearest points in frames that depend on the shape pair: GJK gives world
// coordinates, the sphere–triangle special case gives the sphere's point in the sphere frame and
// the triangle's in the mesh frame. Take the reading (world or local, per side) whose points are
// the reported distance apart; with several, prefer world.
void toWorldWitnesses(ShapeDistance& d, const fcl::Transform3d& X_a, const fcl::Transform3d& X_b) {
  if (d.beyond) return;
  const Eigen::Vector3d a[2] = {d.p_a, X_a * d.p_a};
  const Eigen::Vector3d b[2] = {d.p_b, X_b * d.p_b};
  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector3d pa = d.p_a, pb = d.p_b;
  for (const auto& ca : a) {
    for (const auto& cb : b) {
      const double err = std::abs((ca - cb).norm() - d.distance);
      if (err < best - 1e-12) {
        best = err;
        pa = ca;
        pb = cb;
      }
    }
  }
  d.p_a = pa;
  d.p_b = pb;
}

template <class Shape>
ShapeDistance meshShape(const MeshModel& mesh,
                        const fcl::Transform3d& X_mesh,
                        const Shape& shape,
                        const fcl::Transform3d& X_shape,
                        double bound,
                        bool witness) {
  const Solver solver = makeSolver();
  fcl::DistanceRequestd request;
  request.enable_nearest_points = witness;
  fcl::DistanceResultd result;
  // Seeding the result with the bound before initialize() makes the traversal prune every
  // bounding-volume pair at or beyond it (DESIGN.md §9); FCL's preprocess step, which seeds
  // with triangle 0, is skipped on purpose.
  result.min_distance = bound;
  fcl::detail::MeshShapeDistanceTraversalNodeOBBRSS<Shape, Solver> node;
  fcl::detail::initialize(node, mesh, X_mesh, shape, X_shape, &solver, request, result);
  allowTolerance(node, bound);
  if (node.BVTesting(0, 0) < bound) fcl::detail::distanceRecurse(&node, 0, 0, nullptr);
  ShapeDistance d = finish(result.min_distance, bound, witness, result.nearest_points[0],
                           result.nearest_points[1]);
  if (witness) toWorldWitnesses(d, X_mesh, X_shape);
  return d;
}

ShapeDistance meshMesh(const MeshModel& a,
                       const fcl::Transform3d& X_a,
                       const MeshModel& b,
                       const fcl::Transform3d& X_b,
                       double bound,
                       bool witness) {
  fcl::DistanceRequestd request;
  request.enable_nearest_points = witness;
  fcl::DistanceResultd result;
  result.min_distance = bound;
  fcl::detail::MeshDistanceTraversalNodeOBBRSS<double> node;
  fcl::detail::initialize(node, a, X_a, b, X_b, request, result);
  allowTolerance(node, bound);
  if (node.BVTesting(0, 0) < bound) fcl::detail::distanceRecurse(&node, 0, 0, nullptr);
  node.postprocess();  // nearest points from mesh a's frame into the world
  return finish(result.min_distance, bound, witness, result.nearest_points[0],
                result.nearest_points[1]);
}

template <class A, class B>
ShapeDistance shapeShape(const A& a,
                         const fcl::Transform3d& X_a,
                         const B& b,
                         const fcl::Transform3d& X_b,
                         double bound,
                         bool witness) {
  const Solver solver = makeSolver();
  double d = 0.0;
  Eigen::Vector3d pa = Eigen::Vector3d::Zero(), pb = Eigen::Vector3d::Zero();
  if (!solver.shapeDistance(a, X_a, b, X_b, &d, &pa, &pb)) d = 0.0;  // false: in contact
  ShapeDistance out = finish(d, bound, witness, pa, pb);
  if (witness) toWorldWitnesses(out, X_a, X_b);
  return out;
}

template <class F>
auto withPrimitive(const fcl::CollisionGeometryd& g, F&& f) {
  switch (g.getNodeType()) {
    case fcl::GEOM_BOX:
      return f(static_cast<const fcl::Boxd&>(g));
    case fcl::GEOM_SPHERE:
      return f(static_cast<const fcl::Sphered&>(g));
    case fcl::GEOM_CYLINDER:
      return f(static_cast<const fcl::Cylinderd&>(g));
    case fcl::GEOM_CAPSULE:
      return f(static_cast<const fcl::Capsuled&>(g));
    default:
      break;
  }
  throw std::logic_error("collision: unexpected FCL geometry type");
}

bool isMesh(const fcl::CollisionGeometryd& g) { return g.getObjectType() == fcl::OT_BVH; }

ShapeDistance swapped(ShapeDistance d) {
  std::swap(d.p_a, d.p_b);
  return d;
}

// A box's surface, two counter-clockwise (outward) triangles per face. (Subdividing the faces
// to tighten FCL's leaf bounding volumes was measured: no gain, the part's leaves dominate.)
kinematics::TriangleMesh boxSurface(const Eigen::Vector3d& size) {
  kinematics::TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) {  // vertex i: bit 0 = +x, bit 1 = +y, bit 2 = +z
    mesh.vertices.push_back(0.5 * Eigen::Vector3d((i & 1) ? size.x() : -size.x(),
                                                  (i & 2) ? size.y() : -size.y(),
                                                  (i & 4) ? size.z() : -size.z()));
  }
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    mesh.triangles.emplace_back(f[0], f[1], f[2]);
    mesh.triangles.emplace_back(f[0], f[2], f[3]);
  }
  return mesh;
}

}  // namespace

std::shared_ptr<MeshModel> makeMeshModel(const kinematics::TriangleMesh& mesh) {
  auto model = std::make_shared<MeshModel>();
  std::vector<fcl::Vector3d> points(mesh.vertices.begin(), mesh.vertices.end());
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(mesh.triangles.size());
  for (const Eigen::Vector3i& t : mesh.triangles) {
    triangles.emplace_back(static_cast<std::size_t>(t[0]), static_cast<std::size_t>(t[1]),
                           static_cast<std::size_t>(t[2]));
  }
  model->beginModel(static_cast<int>(triangles.size()), static_cast<int>(points.size()));
  model->addSubModel(points, triangles);
  model->endModel();
  model->computeLocalAABB();
  return model;
}

CollisionShape makeCollisionShape(const kinematics::Shape& shape) {
  CollisionShape out;
  out.X_BG = shape.X_BG;
  struct Builder {
    CollisionShape& out;
    void operator()(const kinematics::Box& b) const {
      out.geometry = std::make_shared<fcl::Boxd>(b.size);
      out.radius = 0.5 * b.size.norm();
      out.polyhedron = makeMeshModel(boxSurface(b.size));
    }
    void operator()(const kinematics::Sphere& s) const {
      // A zero-length capsule, not fcl::Sphere: FCL 0.7's sphere–triangle distance with
      // nearest points (the path every mesh–sphere query takes) leaves the distance unset when
      // the sphere overlaps the triangle, so a penetrating sphere reads as an arbitrary number.
      // Capsule–triangle goes through GJK, which reports overlap correctly.
      out.geometry = std::make_shared<fcl::Capsuled>(s.radius, 0.0);
      out.radius = s.radius;
    }
    void operator()(const kinematics::Cylinder& c) const {
      out.geometry = std::make_shared<fcl::Cylinderd>(c.radius, c.length);
      out.radius = std::hypot(c.radius, 0.5 * c.length);
    }
    void operator()(const kinematics::Capsule& c) const {
      out.geometry = std::make_shared<fcl::Capsuled>(c.radius, c.length);
      out.radius = c.radius + 0.5 * c.length;
    }
    void operator()(const kinematics::MeshFile& m) const {
      const kinematics::LoadedMesh loaded = kinematics::loadMesh(m.path, m.options);
      const Eigen::AlignedBox3d box = loaded.mesh.bounds();
      out.centre_G = box.center();
      double r = 0.0;
      for (const Eigen::Vector3d& v : loaded.mesh.vertices)
        r = std::max(r, (v - out.centre_G).norm());
      out.radius = r;
      out.triangles = loaded.mesh.triangles.size();
      out.geometry = makeMeshModel(loaded.mesh);
    }
  };
  std::visit(Builder{out}, shape.geometry);
  return out;
}

ShapeDistance shapeDistance(const CollisionShape& a,
                            const Eigen::Isometry3d& X_Wa,
                            const CollisionShape& b,
                            const Eigen::Isometry3d& X_Wb,
                            double bound,
                            bool witness_points) {
  const fcl::Transform3d X_a(X_Wa.matrix()), X_b(X_Wb.matrix());
  const bool mesh_a = isMesh(*a.geometry), mesh_b = isMesh(*b.geometry);
  if ((mesh_a || mesh_b) && (mesh_a || a.polyhedron) && (mesh_b || b.polyhedron)) {
    return meshMesh(mesh_a ? static_cast<const MeshModel&>(*a.geometry) : *a.polyhedron, X_a,
                    mesh_b ? static_cast<const MeshModel&>(*b.geometry) : *b.polyhedron, X_b, bound,
                    witness_points);
  }
  if (mesh_a) {
    return withPrimitive(*b.geometry, [&](const auto& shape) {
      return meshShape(static_cast<const MeshModel&>(*a.geometry), X_a, shape, X_b, bound,
                       witness_points);
    });
  }
  if (mesh_b) {
    return swapped(withPrimitive(*a.geometry, [&](const auto& shape) {
      return meshShape(static_cast<const MeshModel&>(*b.geometry), X_b, shape, X_a, bound,
                       witness_points);
    }));
  }
  return withPrimitive(*a.geometry, [&](const auto& sa) {
    return withPrimitive(*b.geometry, [&](const auto& sb) {
      return shapeShape(sa, X_a, sb, X_b, bound, witness_points);
    });
  });
}

ShapeDistance exactShapeDistance(const CollisionShape& a,
                                 const Eigen::Isometry3d& X_Wa,
                                 const CollisionShape& b,
                                 const Eigen::Isometry3d& X_Wb) {
  // Against a mesh, a box is its polyhedron in both queries, so they compare like for like.
  const bool meshes = isMesh(*a.geometry) || isMesh(*b.geometry);
  const auto geometry = [meshes](const CollisionShape& s) -> const fcl::CollisionGeometryd* {
    return meshes && s.polyhedron ? s.polyhedron.get() : s.geometry.get();
  };
  const fcl::Transform3d X_a(X_Wa.matrix()), X_b(X_Wb.matrix());
  fcl::DistanceRequestd request;
  request.enable_nearest_points = true;
  fcl::DistanceResultd result;
  // The geometry-and-transform overload: constructing fcl::CollisionObject would recompute
  // (write) the shared geometry's local AABB, a data race between threads.
  fcl::distance(geometry(a), X_a, geometry(b), X_b, request, result);
  ShapeDistance d = finish(result.min_distance, std::numeric_limits<double>::infinity(), true,
                           result.nearest_points[0], result.nearest_points[1]);
  toWorldWitnesses(d, X_a, X_b);
  return d;
}

}  // namespace scanplan::collision::detail
