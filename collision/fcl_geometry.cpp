#include <scanplan/collision/fcl_geometry.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include <fcl/narrowphase/detail/convexity_based_algorithm/minkowski_diff.h>
#include <fcl/narrowphase/detail/gjk_solver_indep.h>
#include <fcl/narrowphase/detail/gjk_solver_libccd.h>
#include <fcl/narrowphase/detail/primitive_shape_algorithm/triangle_distance.h>
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

// Surfaces closer than this touch: a picometre is far below any modelling accuracy and above
// the rounding of the different ways (FCL's triangle test, the box-frame gap) to measure a
// contact that was built exactly, e.g. a face laid on a plane.
constexpr double kContactTolerance = 1e-12;  // m

// Convex hulls go to FCL's own GJK: libccd's stops up to 25 µm long on hulls of a few hundred
// vertices (the hull would then read farther than its mesh); FCL's meets 1e-6 m there
// (test_convex_hull). Everything else keeps libccd, as fcl::distance does.
template <class A, class B = A>
using SolverFor =
    std::conditional_t<std::is_same_v<A, fcl::Convexd> || std::is_same_v<B, fcl::Convexd>,
                       fcl::detail::GJKSolver_indep<double>,
                       Solver>;

template <class S = Solver>
S makeSolver() {
  S solver;  // FCL's GJK keeps its own tolerance (2e-14 relative)
  if constexpr (std::is_same_v<S, Solver>)
    solver.distance_tolerance = kDefaultRequest.distance_tolerance;
  return solver;
}

ShapeDistance finish(
    double d, double bound, bool witness, const Eigen::Vector3d& pa, const Eigen::Vector3d& pb) {
  ShapeDistance out;
  if (d >= bound) {
    out.distance = bound;
    out.beyond = true;
  } else if (d <= kContactTolerance) {
    out.distance = 0.0;
    out.penetrating = true;
  } else {
    out.distance = d;
  }
  out.lower = out.distance;
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
  using ShapeSolver = SolverFor<Shape>;
  const ShapeSolver solver = makeSolver<ShapeSolver>();
  fcl::DistanceRequestd request;
  request.enable_nearest_points = witness;
  fcl::DistanceResultd result;
  // Seeding the result with the bound before initialize() makes the traversal prune every
  // bounding-volume pair at or beyond it (docs/design.md §9); FCL's preprocess step, which seeds
  // with triangle 0, is skipped on purpose.
  result.min_distance = bound;
  fcl::detail::MeshShapeDistanceTraversalNodeOBBRSS<Shape, ShapeSolver> node;
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

// A box against a mesh, in the box's frame. FCL's mesh–mesh traversal of the box's 12
// triangles measured 2 000–7 000 leaf tests per query near a curved part (docs/design.md §9): the
// RSS rectangle around each of the box's big triangles reaches past the box, and the part
// triangles under a box face all lie within the slack of their own leaf volumes. Here the
// traversal walks FCL's own BVH of the part with bounds taken in the box frame, where the box is
// axis-aligned:
// - a node's OBB, seen from the box frame, has an axis-aligned hull; the gap between that hull
//   and the box is a lower bound of the node's distance (cheap: one 3×3 product);
// - a triangle's gap is its vertices' axis-aligned hull against the box; when the triangle lies
//   beyond one face and within the other two slabs, that gap IS the distance (the closest point
//   is a vertex over the face), the common case under a face, so most leaves need no exact test;
// - a triangle wholly inside the box is at its nearest vertex's distance to the surface (the
//   surface distance, as for the polyhedron the exact reference uses: no contact);
// - otherwise FCL's triangle–triangle distance against the faces the triangle reaches beyond.
// Subtrees are skipped within kPruneTolerance of the best so far, as in FCL's traversal.
class BoxMeshDistance {
 public:
  BoxMeshDistance(const Eigen::Vector3d& size,
                  const MeshModel& mesh,
                  const fcl::Transform3d& X_box,
                  const fcl::Transform3d& X_mesh,
                  double bound)
      : h_(0.5 * size), mesh_(mesh), best_(bound) {
    const fcl::Transform3d X_BM = X_box.inverse(Eigen::Isometry) * X_mesh;
    R_ = X_BM.linear();
    t_ = X_BM.translation();
    for (int i = 0; i < 8; ++i) {
      corner_[i] = Eigen::Vector3d((i & 1) ? h_.x() : -h_.x(), (i & 2) ? h_.y() : -h_.y(),
                                   (i & 4) ? h_.z() : -h_.z());
    }
  }

  /// Runs the traversal; the result in the box frame (p_box on the box, p_mesh on the mesh).
  void run() {
    if (mesh_.getNumBVs() <= 0) return;
    struct Entry {
      int node;
      double gap2;
    };
    // Depth-first, the closer child on top; one stack per thread, kept between queries.
    thread_local std::vector<Entry> stack;
    stack.clear();
    stack.push_back({0, nodeGap2(0)});
    while (!stack.empty()) {
      const Entry e = stack.back();
      stack.pop_back();
      if (pruned(e.gap2)) continue;
      const auto& node = mesh_.getBV(e.node);
      if (node.isLeaf()) {
        leaf(node.primitiveId());
        if (best_ <= 0.0) return;
        continue;
      }
      const int l = node.leftChild(), r = node.rightChild();
      const double gl = nodeGap2(l), gr = nodeGap2(r);
      if (gl <= gr) {
        stack.push_back({r, gr});
        stack.push_back({l, gl});
      } else {
        stack.push_back({l, gl});
        stack.push_back({r, gr});
      }
    }
  }

  double best() const { return best_; }
  bool found() const { return found_; }
  const Eigen::Vector3d& pBox() const { return p_box_; }
  const Eigen::Vector3d& pMesh() const { return p_mesh_; }

 private:
  // Pruned when the lower bound is within the tolerance of the best so far.
  bool pruned(double gap2) const {
    const double limit = best_ - kPruneTolerance;
    return limit <= 0.0 || gap2 >= limit * limit;
  }

  double nodeGap2(int id) const {
    const fcl::OBBd& obb = mesh_.getBV(id).bv.obb;
    const Eigen::Vector3d c = R_ * obb.To + t_;
    const Eigen::Matrix3d A = R_ * obb.axis;
    const Eigen::Vector3d half = A.cwiseAbs() * obb.extent;
    return (c.cwiseAbs() - half - h_).cwiseMax(0.0).squaredNorm();
  }

  void leaf(int primitive) {
    const fcl::Triangle& tri = mesh_.tri_indices[primitive];
    Eigen::Vector3d v[3];
    for (int k = 0; k < 3; ++k) v[k] = R_ * mesh_.vertices[tri[k]] + t_;
    const Eigen::Vector3d lo = v[0].cwiseMin(v[1]).cwiseMin(v[2]);
    const Eigen::Vector3d hi = v[0].cwiseMax(v[1]).cwiseMax(v[2]);
    const Eigen::Vector3d gap = (lo - h_).cwiseMax(-h_ - hi).cwiseMax(0.0);
    if (pruned(gap.squaredNorm())) return;
    // Beyond one face, inside the other two slabs: the gap is the distance.
    int beyond = -1, count = 0;
    for (int i = 0; i < 3; ++i) {
      if (gap[i] > 0.0) {
        beyond = i;
        ++count;
      } else if (lo[i] < -h_[i] || hi[i] > h_[i]) {
        count = 2;  // reaches past a face it is not beyond: not the simple case
      }
    }
    if (count == 1) {
      const int i = beyond;
      const bool plus = lo[i] > h_[i];
      int k = 0;
      for (int j = 1; j < 3; ++j) {
        if (plus ? v[j][i] < v[k][i] : v[j][i] > v[k][i]) k = j;
      }
      best_ = gap[i];
      found_ = true;
      p_mesh_ = v[k];
      p_box_ = v[k];
      p_box_[i] = plus ? h_[i] : -h_[i];
      return;
    }
    bool inside = true;
    for (int i = 0; i < 3; ++i) inside = inside && hi[i] <= h_[i] && lo[i] >= -h_[i];
    if (inside) {
      // Wholly inside the box: its distance to the box's surface (a concave function of the
      // point) is least at a vertex, towards that vertex's nearest face.
      for (int k = 0; k < 3; ++k) {
        for (int i = 0; i < 3; ++i) {
          const double d = h_[i] - std::abs(v[k][i]);
          if (d < best_) {
            best_ = d;
            found_ = true;
            p_mesh_ = v[k];
            p_box_ = v[k];
            p_box_[i] = v[k][i] < 0.0 ? -h_[i] : h_[i];
          }
        }
      }
      return;
    }
    for (int face = 0; face < 6; ++face) {
      const int axis = face / 2;
      const bool plus = face % 2 == 1;
      if (!(plus ? hi[axis] > h_[axis] : lo[axis] < -h_[axis])) continue;
      faceTest(axis, plus, v);
      if (best_ <= 0.0) return;
    }
  }

  // The two triangles of one face against the mesh triangle.
  void faceTest(int axis, bool plus, const Eigen::Vector3d v[3]) {
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    const int fixed = plus ? (1 << axis) : 0;
    const Eigen::Vector3d& c00 = corner_[fixed];
    const Eigen::Vector3d& c10 = corner_[fixed | (1 << a)];
    const Eigen::Vector3d& c11 = corner_[fixed | (1 << a) | (1 << b)];
    const Eigen::Vector3d& c01 = corner_[fixed | (1 << b)];
    Eigen::Vector3d p, q;
    for (const auto& [x, y] : {std::pair{&c10, &c11}, std::pair{&c11, &c01}}) {
      const double d =
          fcl::detail::TriangleDistance<double>::triDistance(c00, *x, *y, v[0], v[1], v[2], p, q);
      if (d < best_) {
        best_ = d;
        found_ = true;
        p_box_ = p;
        p_mesh_ = q;
      }
    }
  }

  Eigen::Vector3d h_;
  const MeshModel& mesh_;
  double best_;
  bool found_ = false;
  Eigen::Matrix3d R_;
  Eigen::Vector3d t_;
  Eigen::Vector3d corner_[8];
  Eigen::Vector3d p_box_ = Eigen::Vector3d::Zero(), p_mesh_ = Eigen::Vector3d::Zero();
};

// Distance from a box (a) to a mesh (b); witness points in the world frame.
ShapeDistance boxMesh(const fcl::Boxd& box,
                      const fcl::Transform3d& X_box,
                      const MeshModel& mesh,
                      const fcl::Transform3d& X_mesh,
                      double bound,
                      bool witness) {
  BoxMeshDistance query(box.side, mesh, X_box, X_mesh, bound);
  query.run();
  const double d = query.found() ? query.best() : bound;
  return finish(d, bound, witness, X_box * query.pBox(), X_box * query.pMesh());
}

// The separation of convex shapes a and b along the unit direction n (world, from a towards b):
// min over b of n·b minus max over a of n·a, by their support points (FCL's). A lower bound on
// their distance for any n; the distance itself along the direction of the nearest points.
template <class A, class B>
double separation(const A& a,
                  const fcl::Transform3d& X_a,
                  const B& b,
                  const fcl::Transform3d& X_b,
                  const Eigen::Vector3d& n) {
  const Eigen::Vector3d n_a = X_a.linear().transpose() * n;
  const Eigen::Vector3d n_b = X_b.linear().transpose() * -n;
  const Eigen::Vector3d far_a = X_a * fcl::detail::getSupport<double>(&a, n_a);
  const Eigen::Vector3d near_b = X_b * fcl::detail::getSupport<double>(&b, n_b);
  return n.dot(near_b - far_a);
}

// FCL's GJK answer for a separated convex pair stands when the shapes' separation along its own
// witness direction meets it within this.
constexpr double kCertifiedGap = 1e-9;  // m

// Whether d, GJK's distance between its witness points pa on a and pb on b (world), is certified:
// the separation along pb − pa, a lower bound on the distance, meets it within kCertifiedGap.
// A certified d is never more than kCertifiedGap above the distance.
template <class A, class B>
bool certified(const A& a,
               const fcl::Transform3d& X_a,
               const B& b,
               const fcl::Transform3d& X_b,
               const Eigen::Vector3d& pa,
               const Eigen::Vector3d& pb,
               double d) {
  const Eigen::Vector3d gap = pb - pa;
  if (!(d > 0.0) || !(gap.norm() > 0.5 * d)) return false;
  return d - separation(a, X_a, b, X_b, gap.normalized()) <= kCertifiedGap;
}

template <class A, class B>
ShapeDistance shapeShape(const A& a,
                         const fcl::Transform3d& X_a,
                         const B& b,
                         const fcl::Transform3d& X_b,
                         double bound,
                         bool witness) {
  double d = 0.0;
  Eigen::Vector3d pa = Eigen::Vector3d::Zero(), pb = Eigen::Vector3d::Zero();
  if constexpr (!std::is_same_v<SolverFor<A, B>, Solver>) {
    // Most convex pairs of a map lie beyond the bound (85 % with the KR6 R700's pieces), and
    // their separation along the line between their boxes' centres shows it for most of them
    // (81 %), from two support points where GJK takes many.
    const Eigen::Vector3d axis = X_b * b.aabb_center - X_a * a.aabb_center;
    if (axis.norm() > 0.0) {
      const double apart = separation(a, X_a, b, X_b, axis.normalized());
      if (apart >= bound) {
        ShapeDistance out = finish(bound, bound, witness, pa, pb);
        out.lower = apart;
        return out;
      }
    }
  }
  const SolverFor<A, B> solver = makeSolver<SolverFor<A, B>>();
  if (!solver.shapeDistance(a, X_a, b, X_b, &d, &pa, &pb)) d = 0.0;  // false: in contact
  if constexpr (!std::is_same_v<SolverFor<A, B>, Solver>) {
    // FCL's GJK can stop short on a polytope whose face lies parallel to a box's (0.3 mm long
    // on an L block's pieces, test_link_standin); libccd then meets it. Both give the distance
    // between two points of the shapes, never less than the truth: the smaller is kept. A
    // certified answer needs no second opinion.
    if (!certified(a, X_a, b, X_b, pa, pb, d)) {
      double d_ccd = 0.0;
      Eigen::Vector3d qa = Eigen::Vector3d::Zero(), qb = Eigen::Vector3d::Zero();
      if (!makeSolver<Solver>().shapeDistance(a, X_a, b, X_b, &d_ccd, &qa, &qb)) d_ccd = 0.0;
      if (d_ccd < d) {
        d = d_ccd;
        pa = qa;
        pb = qb;
      }
    }
  }
  ShapeDistance out = finish(d, bound, witness, pa, pb);
  // FCL's GJK measured the whole distance (to 2e-14 relative, libccd's only to 1e-6 m and
  // wrong on some curved pairs): beyond the bound, it is the lower bound the maps carry on.
  if (out.beyond && !std::is_same_v<SolverFor<A, B>, Solver>) out.lower = std::max(bound, d - 1e-9);
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
    case fcl::GEOM_CONVEX:
      return f(static_cast<const fcl::Convexd&>(g));
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

Primitive capsuleLike(Primitive::Kind kind, double radius, double length) {
  return Primitive{kind, Eigen::Isometry3d::Identity(),
                   Eigen::Vector3d(radius, radius, 0.5 * length)};
}

// The closed forms first (collision/primitive_distance): a pair they put at or beyond `bound`
// is answered without FCL. Nearer pairs still go to FCL's GJK, so every distance below the
// bound is FCL's number, as the exact reference computes it.
// The shape as a primitive at its world pose: itself, or a mesh's bounding box.
Primitive placed(const CollisionShape& shape, const Eigen::Isometry3d& X_W) {
  if (shape.primitive) {  // its pose is the identity: the product would give X_W exactly
    Primitive p = *shape.primitive;
    p.X_W = X_W;
    return p;
  }
  Primitive p = *shape.bounding_box;
  p.X_W = X_W * p.X_W;
  return p;
}

// The closed forms first (collision/primitive_distance), on the primitives themselves or a
// mesh's bounding box. A pair they put at or beyond `bound` is answered without FCL; so is a
// nearer pair of primitives with an exact closed form. Otherwise FCL measures. (FCL 0.7's
// libccd GJK is not only inexact, 1e-6 m, but on some capsule–cylinder poses wrong by
// centimetres: test_primitive_distance keeps one such pose.)
std::optional<ShapeDistance> closedForm(const CollisionShape& a,
                                        const Eigen::Isometry3d& X_Wa,
                                        const CollisionShape& b,
                                        const Eigen::Isometry3d& X_Wb,
                                        double bound,
                                        bool witness) {
  if (!(a.primitive || a.bounding_box) || !(b.primitive || b.bounding_box)) return std::nullopt;
  const Primitive pa = placed(a, X_Wa), pb = placed(b, X_Wb);
  using Kind = Primitive::Kind;
  // Two boxes (a mesh's included) stop at the gap: the exact form costs ten times as much.
  const bool boxes = pa.kind == Kind::kBox && pb.kind == Kind::kBox;
  const bool primitives = a.primitive && b.primitive;
  // With one box the quick bound is the distance itself: measured once.
  std::optional<PrimitiveDistance> d;
  if ((pa.kind == Kind::kBox) != (pb.kind == Kind::kBox)) d = primitiveDistance(pa, pb);
  double lower = d ? d->distance : quickLowerBound(pa, pb);
  if (lower < bound && (!boxes || primitives)) {
    if (!d) d = primitiveDistance(pa, pb);
    if (d->exact && primitives && d->distance < bound) {
      return finish(d->distance, bound, witness, d->p_a, d->p_b);
    }
    lower = std::max(lower, d->distance);
  }
  if (lower < bound) return std::nullopt;
  ShapeDistance beyond;
  beyond.distance = bound;
  beyond.beyond = true;
  beyond.lower = lower;
  return beyond;
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

namespace {

// A body's bounding sphere (centre, radius) and box over vertices, in the shape frame.
void boundVertices(const std::vector<Eigen::Vector3d>& vertices, CollisionShape& out) {
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& v : vertices) box.extend(v);
  out.centre_G = box.center();
  double r = 0.0;
  for (const Eigen::Vector3d& v : vertices) r = std::max(r, (v - out.centre_G).norm());
  out.radius = r;
  out.bounding_box =
      Primitive{Primitive::Kind::kBox, Eigen::Isometry3d::Identity(), 0.5 * box.sizes()};
  out.bounding_box->X_W.translation() = box.center();
}

}  // namespace

kinematics::TriangleMesh meshOf(const MeshModel& model) {
  kinematics::TriangleMesh mesh;
  mesh.vertices.assign(model.vertices, model.vertices + model.num_vertices);
  mesh.triangles.reserve(static_cast<std::size_t>(model.num_tris));
  for (int i = 0; i < model.num_tris; ++i) {
    const fcl::Triangle& t = model.tri_indices[i];
    mesh.triangles.emplace_back(static_cast<int>(t[0]), static_cast<int>(t[1]),
                                static_cast<int>(t[2]));
  }
  return mesh;
}

CollisionShape makeHullShape(const CollisionShape& mesh_shape,
                             const kinematics::TriangleMesh& hull) {
  CollisionShape out;
  out.X_BG = mesh_shape.X_BG;
  boundVertices(hull.vertices, out);
  auto vertices = std::make_shared<std::vector<Eigen::Vector3d>>(hull.vertices);
  auto faces = std::make_shared<std::vector<int>>();
  faces->reserve(4 * hull.triangles.size());
  for (const Eigen::Vector3i& t : hull.triangles)
    faces->insert(faces->end(), {3, t[0], t[1], t[2]});
  // Validated (edges shared by two faces): FCL then finds support points by walking edges. A
  // hull FCL does not take as valid is still convex: its support points come from every vertex.
  const int count = static_cast<int>(hull.triangles.size());
  try {
    out.geometry = std::make_shared<fcl::Convexd>(vertices, count, faces, true);
  } catch (const std::exception&) {
    out.geometry = std::make_shared<fcl::Convexd>(vertices, count, faces, false);
  }
  out.geometry->computeLocalAABB();
  out.polyhedron = makeMeshModel(hull);
  out.triangles = hull.triangles.size();
  return out;
}

CollisionShape makeCollisionShape(const kinematics::Shape& shape) {
  CollisionShape out;
  out.X_BG = shape.X_BG;
  struct Builder {
    CollisionShape& out;
    void operator()(const kinematics::Box& b) const {
      out.primitive = Primitive{Primitive::Kind::kBox, Eigen::Isometry3d::Identity(), 0.5 * b.size};
      out.geometry = std::make_shared<fcl::Boxd>(b.size);
      out.radius = 0.5 * b.size.norm();
      out.polyhedron = makeMeshModel(boxSurface(b.size));
    }
    void operator()(const kinematics::Sphere& s) const {
      // A zero-length capsule, not fcl::Sphere: FCL 0.7's sphere–triangle distance with
      // nearest points (the path every mesh–sphere query takes) leaves the distance unset when
      // the sphere overlaps the triangle, so a penetrating sphere reads as an arbitrary number.
      // Capsule–triangle goes through GJK, which reports overlap correctly.
      out.primitive = capsuleLike(Primitive::Kind::kCapsule, s.radius, 0.0);
      out.geometry = std::make_shared<fcl::Capsuled>(s.radius, 0.0);
      out.radius = s.radius;
    }
    void operator()(const kinematics::Cylinder& c) const {
      out.primitive = capsuleLike(Primitive::Kind::kCylinder, c.radius, c.length);
      out.geometry = std::make_shared<fcl::Cylinderd>(c.radius, c.length);
      out.radius = std::hypot(c.radius, 0.5 * c.length);
    }
    void operator()(const kinematics::Capsule& c) const {
      out.primitive = capsuleLike(Primitive::Kind::kCapsule, c.radius, c.length);
      out.geometry = std::make_shared<fcl::Capsuled>(c.radius, c.length);
      out.radius = c.radius + 0.5 * c.length;
    }
    void operator()(const kinematics::MeshFile& m) const {
      const kinematics::LoadedMesh loaded = kinematics::loadMesh(m.path, m.options);
      boundVertices(loaded.mesh.vertices, out);
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
                            bool witness_points,
                            bool closed_forms) {
  if (closed_forms) {
    if (auto d = closedForm(a, X_Wa, b, X_Wb, bound, witness_points)) return *d;
  }
  const fcl::Transform3d X_a(X_Wa.matrix()), X_b(X_Wb.matrix());
  const bool mesh_a = isMesh(*a.geometry), mesh_b = isMesh(*b.geometry);
  if (mesh_b && a.geometry->getNodeType() == fcl::GEOM_BOX) {
    return boxMesh(static_cast<const fcl::Boxd&>(*a.geometry), X_a,
                   static_cast<const MeshModel&>(*b.geometry), X_b, bound, witness_points);
  }
  if (mesh_a && b.geometry->getNodeType() == fcl::GEOM_BOX) {
    return swapped(boxMesh(static_cast<const fcl::Boxd&>(*b.geometry), X_b,
                           static_cast<const MeshModel&>(*a.geometry), X_a, bound, witness_points));
  }
  if (mesh_a && mesh_b) {
    return meshMesh(static_cast<const MeshModel&>(*a.geometry), X_a,
                    static_cast<const MeshModel&>(*b.geometry), X_b, bound, witness_points);
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
  // Primitive pairs with an exact closed form are measured by it here too: it is exact where
  // FCL's GJK is not (see closedForm).
  if (a.primitive && b.primitive) {
    Primitive pa = *a.primitive, pb = *b.primitive;
    pa.X_W = X_Wa * pa.X_W;
    pb.X_W = X_Wb * pb.X_W;
    const PrimitiveDistance d = primitiveDistance(pa, pb);
    if (d.exact) {
      return finish(d.distance, std::numeric_limits<double>::infinity(), true, d.p_a, d.p_b);
    }
  }
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

double separationAlong(const CollisionShape& a,
                       const Eigen::Isometry3d& X_Wa,
                       const CollisionShape& b,
                       const Eigen::Isometry3d& X_Wb,
                       const Eigen::Vector3d& n) {
  if (isMesh(*a.geometry) || isMesh(*b.geometry))
    throw std::invalid_argument(
        "separationAlong: a mesh is not convex (expected hulls or primitives)");
  const fcl::Transform3d X_a(X_Wa.matrix()), X_b(X_Wb.matrix());
  const Eigen::Vector3d unit = n.normalized();
  return withPrimitive(*a.geometry, [&](const auto& shape_a) {
    return withPrimitive(*b.geometry, [&](const auto& shape_b) {
      return separation(shape_a, X_a, shape_b, X_b, unit);
    });
  });
}

}  // namespace scanplan::collision::detail
