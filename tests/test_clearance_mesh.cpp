// Mesh distances of the clearance constraint (docs/design.md §4 Eq. 8, §9) cross-checked against an
// independent brute-force triangle–triangle distance written here without FCL: the plain
// fcl::distance reference (exactShapeDistance) must match the brute force, and the bounded
// query (shapeDistance) must match the reference below its bound and report "beyond" at or
// above it.

#include <scanplan/collision/fcl_geometry.h>

#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/shape.h>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <variant>
#include <vector>

namespace scanplan::collision {
namespace {

namespace fs = std::filesystem;
using detail::CollisionShape;
using detail::ShapeDistance;
using Eigen::Isometry3d;
using Eigen::Vector3d;
using kinematics::TriangleMesh;

constexpr double kInf = std::numeric_limits<double>::infinity();

// FCL's mesh–mesh distance and the brute force below evaluate closed-form distances between the
// same triangles in double precision; with coordinates below ~2 m the rounding differences are
// ~1e-15 m. 1e-9 m leaves a wide margin and is still six orders below any clearance threshold.
constexpr double kExactTol = 1e-9;
// The bounded query must reproduce the reference's number (same triangle or GJK routine on the
// same inputs), not merely approximate it.
constexpr double kSameTol = 1e-9;
// A witness point must lie on its own surface: same closed-form rounding argument as kExactTol.
constexpr double kOnSurfaceTol = 1e-9;
// Mesh against a primitive runs GJK (libccd) with DistanceRequest::distance_tolerance = 1e-6 m.
// A box is a polytope (GJK ends on the exact closest feature pair, and triangle–triangle code is
// exact anyway), so its brute-force reference is met to that tolerance; witness points are
// checked to it for every primitive.
constexpr double kGjkTol = 1e-6;
// Against curved supports (sphere, capsule) GJK stops once an iteration improves the distance by
// less than 1e-6 m, which does not bound the error (FCL documents as much for
// GJKSignedDistance): over these seeds it overshoots the true distance by up to ~9e-6 m for
// spheres and ~8e-5 m for capsules. It never undershoots (its distance is attained by a point
// pair of the two shapes), which is checked to kExactTol.
constexpr double kGjkCurvedTol = 1e-4;

// Hand-derived triangle cases: unit-sized coordinates, a few ulps of rounding.
constexpr double kHandTol = 1e-15;
// A closed form against sampling: the closed form may not lose to any sample by more than this.
constexpr double kSampleSlack = 1e-12;

// The bounds of the bounded query exercised everywhere: d_low/d_high-like values and +inf.
constexpr std::array<double, 4> kBounds{0.005, 0.020, 0.050, kInf};
constexpr std::size_t k20mm = 1, k50mm = 2;  // indices into kBounds

// Brute force, independent of FCL (Ericson, Real-Time Collision Detection, 2005).

struct Tri {
  Vector3d a, b, c;
};

// Ericson §5.1.5 ClosestPtPointTriangle: Voronoi regions of the vertices, then of the edges,
// else the face interior (barycentric coordinates).
Vector3d closestPointOnTriangle(const Vector3d& p, const Tri& t) {
  const Vector3d ab = t.b - t.a, ac = t.c - t.a, ap = p - t.a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return t.a;
  const Vector3d bp = p - t.b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return t.b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return t.a + (d1 / (d1 - d3)) * ab;
  const Vector3d cp = p - t.c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return t.c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return t.a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
    return t.b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (t.c - t.b);
  }
  const double sum = va + vb + vc;
  if (!(sum > 0.0)) return t.a;  // degenerate sliver: every region test above was inconclusive
  return t.a + (vb / sum) * ab + (vc / sum) * ac;
}

double pointTriangleDistance(const Vector3d& p, const Tri& t) {
  return (p - closestPointOnTriangle(p, t)).norm();
}

// Ericson §5.1.9 ClosestPtSegmentSegment: squared distance between segments p1q1 and p2q2.
double segmentSegmentDistanceSq(const Vector3d& p1,
                                const Vector3d& q1,
                                const Vector3d& p2,
                                const Vector3d& q2) {
  constexpr double kDegenerate = 1e-300;  // only exactly collapsed segments are points
  const Vector3d d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0.0, t = 0.0;
  if (a <= kDegenerate && e <= kDegenerate) {
    return r.squaredNorm();
  }
  if (a <= kDegenerate) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= kDegenerate) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 0.0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;  // parallel: any s
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return ((p1 + s * d1) - (p2 + t * d2)).squaredNorm();
}

// Does segment pq cross triangle t? The endpoints must lie on opposite sides of (or on) the
// plane, and the line pq must pass inside all three edges: Ericson §5.3.4's scalar triple
// products, accepted with either sign (both faces). Coplanar segments are left to the
// vertex–triangle and edge–edge terms, which find their zero distance.
bool segmentCrossesTriangle(const Vector3d& p, const Vector3d& q, const Tri& t) {
  const Vector3d n = (t.b - t.a).cross(t.c - t.a);
  const double dp = n.dot(p - t.a), dq = n.dot(q - t.a);
  if ((dp > 0.0 && dq > 0.0) || (dp < 0.0 && dq < 0.0) || (dp == 0.0 && dq == 0.0)) return false;
  const Vector3d pq = q - p;
  const double u = pq.dot((t.c - p).cross(t.b - p));
  const double v = pq.dot((t.a - p).cross(t.c - p));
  const double w = pq.dot((t.b - p).cross(t.a - p));
  return (u >= 0.0 && v >= 0.0 && w >= 0.0) || (u <= 0.0 && v <= 0.0 && w <= 0.0);
}

// Distance between two triangles. If they intersect, some edge of one crosses the other: 0.
// Otherwise the closest pair has a vertex of one triangle and a point of the other, or a point
// on an edge of each: min over the 6 vertex–triangle and 9 edge–edge distances.
double triangleDistance(const Tri& s, const Tri& t) {
  const std::array<Vector3d, 3> sv{s.a, s.b, s.c}, tv{t.a, t.b, t.c};
  for (std::size_t i = 0; i < 3; ++i) {
    if (segmentCrossesTriangle(sv[i], sv[(i + 1) % 3], t)) return 0.0;
    if (segmentCrossesTriangle(tv[i], tv[(i + 1) % 3], s)) return 0.0;
  }
  double best_sq = kInf;
  for (std::size_t i = 0; i < 3; ++i) {
    best_sq = std::min(best_sq, (sv[i] - closestPointOnTriangle(sv[i], t)).squaredNorm());
    best_sq = std::min(best_sq, (tv[i] - closestPointOnTriangle(tv[i], s)).squaredNorm());
    for (std::size_t j = 0; j < 3; ++j) {
      best_sq = std::min(best_sq,
                         segmentSegmentDistanceSq(sv[i], sv[(i + 1) % 3], tv[j], tv[(j + 1) % 3]));
    }
  }
  return std::sqrt(best_sq);
}

// Distance between segment pq and triangle t, from the same pieces.
double segmentTriangleDistance(const Vector3d& p, const Vector3d& q, const Tri& t) {
  if (segmentCrossesTriangle(p, q, t)) return 0.0;
  const std::array<Vector3d, 3> tv{t.a, t.b, t.c};
  double best_sq = std::min((p - closestPointOnTriangle(p, t)).squaredNorm(),
                            (q - closestPointOnTriangle(q, t)).squaredNorm());
  for (std::size_t j = 0; j < 3; ++j) {
    best_sq = std::min(best_sq, segmentSegmentDistanceSq(p, q, tv[j], tv[(j + 1) % 3]));
  }
  return std::sqrt(best_sq);
}

// A mesh's triangles in the world, each with a bounding sphere (centroid, farthest corner).
struct WorldMesh {
  std::vector<Tri> tris;
  std::vector<Vector3d> centre;
  std::vector<double> radius;
};

WorldMesh toWorld(const TriangleMesh& mesh, const Isometry3d& X_WM) {
  WorldMesh out;
  out.tris.reserve(mesh.triangles.size());
  for (const Eigen::Vector3i& f : mesh.triangles) {
    const auto v = [&](int k) {
      return Vector3d(X_WM * mesh.vertices[static_cast<std::size_t>(f[k])]);
    };
    const Tri t{v(0), v(1), v(2)};
    const Vector3d c = (t.a + t.b + t.c) / 3.0;
    out.tris.push_back(t);
    out.centre.push_back(c);
    out.radius.push_back(std::max({(t.a - c).norm(), (t.b - c).norm(), (t.c - c).norm()}));
  }
  return out;
}

double pointMeshDistance(const Vector3d& p, const WorldMesh& m) {
  double best = kInf;
  for (std::size_t i = 0; i < m.tris.size(); ++i) {
    if ((p - m.centre[i]).norm() - m.radius[i] >= best) continue;  // cannot beat best
    best = std::min(best, pointTriangleDistance(p, m.tris[i]));
  }
  return best;
}

double segmentMeshDistance(const Vector3d& p, const Vector3d& q, const WorldMesh& m) {
  double best = kInf;
  for (const Tri& t : m.tris) best = std::min(best, segmentTriangleDistance(p, q, t));
  return best;
}

// Minimum of triangleDistance over all triangle pairs. A pair whose bounding spheres are
// already at least `best` apart cannot lower the minimum, so it is skipped; the pair with the
// closest spheres is evaluated first to make that test bite early. The result is the same
// minimum as the full double loop.
double meshMeshDistance(const WorldMesh& a, const WorldMesh& b) {
  const auto lowerBound = [&](std::size_t i, std::size_t j) {
    return (a.centre[i] - b.centre[j]).norm() - a.radius[i] - b.radius[j];
  };
  std::size_t seed_i = 0, seed_j = 0;
  double seed_lb = kInf;
  for (std::size_t i = 0; i < a.tris.size(); ++i) {
    for (std::size_t j = 0; j < b.tris.size(); ++j) {
      const double lb = lowerBound(i, j);
      if (lb < seed_lb) {
        seed_lb = lb;
        seed_i = i;
        seed_j = j;
      }
    }
  }
  double best = triangleDistance(a.tris[seed_i], b.tris[seed_j]);
  for (std::size_t i = 0; i < a.tris.size() && best > 0.0; ++i) {
    for (std::size_t j = 0; j < b.tris.size(); ++j) {
      if (lowerBound(i, j) >= best) continue;
      best = std::min(best, triangleDistance(a.tris[i], b.tris[j]));
    }
  }
  return best;
}

// Generated meshes (m), seeded.

// Icosahedron subdivided `levels` times, projected on the unit sphere: 20·4^levels triangles,
// counter-clockwise seen from outside.
TriangleMesh unitIcosphere(int levels) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  TriangleMesh m;
  m.vertices = {{-1, g, 0},  {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
                {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<int, int>, int> midpoint;
    const auto mid = [&](int i, int j) {
      const auto key = std::minmax(i, j);
      const auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      m.vertices.push_back(0.5 * (m.vertices[static_cast<std::size_t>(i)] +
                                  m.vertices[static_cast<std::size_t>(j)]));
      const int k = static_cast<int>(m.vertices.size()) - 1;
      midpoint.emplace(key, k);
      return k;
    };
    std::vector<Eigen::Vector3i> finer;
    for (const Eigen::Vector3i& f : m.triangles) {
      const int ab = mid(f[0], f[1]), bc = mid(f[1], f[2]), ca = mid(f[2], f[0]);
      finer.emplace_back(f[0], ab, ca);
      finer.emplace_back(f[1], bc, ab);
      finer.emplace_back(f[2], ca, bc);
      finer.emplace_back(ab, bc, ca);
    }
    m.triangles = std::move(finer);
  }
  for (Vector3d& v : m.vertices) v.normalize();
  return m;
}

// A lumpy sphere: each vertex of a 320-triangle icosphere moved radially by up to ±jitter.
TriangleMesh lumpySphere(double radius, double jitter, std::mt19937& rng) {
  TriangleMesh m = unitIcosphere(2);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  for (Vector3d& v : m.vertices) v *= radius * (1.0 + u(rng));
  return m;
}

// A rounded box: icosphere vertices pushed towards the cube (|x|^0.3 per coordinate), scaled
// to the half extents, then jittered; closed, 320 triangles, flat-ish faces and sharp-ish edges.
TriangleMesh roundedBox(const Vector3d& half, double jitter, std::mt19937& rng) {
  TriangleMesh m = unitIcosphere(2);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  for (Vector3d& v : m.vertices) {
    for (int k = 0; k < 3; ++k) {
      v[k] = std::copysign(std::pow(std::abs(v[k]), 0.3), v[k]) * half[k] + u(rng);
    }
  }
  return m;
}

// An open wavy sheet (a height field over a square): n·n·2 triangles, boundary edges free.
TriangleMesh wavySheet(double size, int n, double amplitude, std::mt19937& rng) {
  TriangleMesh m;
  std::uniform_real_distribution<double> u(-0.1 * amplitude, 0.1 * amplitude);
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      const double x = size * (i / static_cast<double>(n) - 0.5);
      const double y = size * (j / static_cast<double>(n) - 0.5);
      const double z = amplitude * std::sin(3.0 * std::numbers::pi * x / size) *
                           std::cos(2.0 * std::numbers::pi * y / size) +
                       u(rng);
      m.vertices.emplace_back(x, y, z);
    }
  }
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const int v00 = i * (n + 1) + j, v10 = v00 + n + 1;
      m.triangles.emplace_back(v00, v10, v10 + 1);
      m.triangles.emplace_back(v00, v10 + 1, v00 + 1);
    }
  }
  return m;
}

// Bodies and poses.

// A shape under test: the FCL side plus what the brute force needs (triangles or the primitive).
struct Body {
  std::string name;
  CollisionShape shape;
  std::optional<TriangleMesh> mesh;
  kinematics::ShapeGeometry primitive;
};

Body meshBody(std::string name, TriangleMesh mesh) {
  Body body;
  body.name = std::move(name);
  body.shape.geometry = detail::makeMeshModel(mesh);
  body.shape.triangles = mesh.triangles.size();
  body.mesh = std::move(mesh);
  return body;
}

Body primitiveBody(std::string name, kinematics::ShapeGeometry geometry) {
  Body body;
  body.name = std::move(name);
  kinematics::Shape shape;
  shape.geometry = geometry;
  body.shape = detail::makeCollisionShape(shape);
  body.primitive = std::move(geometry);
  return body;
}

// max over the body of u·p_W: how far the body at X_WG reaches along the unit vector u.
double support(const Body& body, const Isometry3d& X_WG, const Vector3d& u) {
  if (body.mesh) {
    double best = -kInf;
    for (const Vector3d& v : body.mesh->vertices) best = std::max(best, u.dot(X_WG * v));
    return best;
  }
  const Vector3d u_G = X_WG.linear().transpose() * u;  // direction in the shape frame
  const double along_z = std::abs(u_G.z()),
               across_z = std::sqrt(std::max(0.0, 1.0 - u_G.z() * u_G.z()));
  const double reach = std::visit(
      [&](const auto& g) -> double {
        using G = std::decay_t<decltype(g)>;
        if constexpr (std::is_same_v<G, kinematics::Sphere>) return g.radius;
        if constexpr (std::is_same_v<G, kinematics::Box>) return 0.5 * g.size.dot(u_G.cwiseAbs());
        if constexpr (std::is_same_v<G, kinematics::Capsule>)
          return 0.5 * g.length * along_z + g.radius;
        if constexpr (std::is_same_v<G, kinematics::Cylinder>) {
          return 0.5 * g.length * along_z + g.radius * across_z;
        }
        return kInf;  // MeshFile: never a primitive here
      },
      body.primitive);
  return u.dot(X_WG.translation()) + reach;
}

Eigen::Matrix3d randomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
}

Vector3d randomUnit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vector3d(n(rng), n(rng), n(rng)).normalized();
}

Isometry3d randomPose(std::mt19937& rng, double extent) {
  std::uniform_real_distribution<double> t(-extent, extent);
  Isometry3d X = Isometry3d::Identity();
  X.linear() = randomRotation(rng);
  X.translation() << t(rng), t(rng), t(rng);
  return X;
}

struct PosePair {
  Isometry3d X_Wa;
  Isometry3d X_Wb;
};

// a anywhere within ±0.5 m of the origin, b at a random orientation with a slab of width `gap`
// (drawn from [gap_min, gap_max], negative: overlapping) between the two along a random
// direction u, shifted sideways by up to `lateral`. The true distance is at least the gap, and
// for these compact shapes usually within a few mm of it.
PosePair posesWithGap(const Body& a,
                      const Body& b,
                      double gap_min,
                      double gap_max,
                      double lateral,
                      std::mt19937& rng) {
  PosePair poses{randomPose(rng, 0.5), Isometry3d::Identity()};
  poses.X_Wb.linear() = randomRotation(rng);
  const Vector3d u = randomUnit(rng);
  const double gap = std::uniform_real_distribution<double>(gap_min, gap_max)(rng);
  const double reach_a = support(a, poses.X_Wa, u);
  const double back_b = support(b, poses.X_Wb, -u);  // b's extent towards a, before moving b
  Vector3d side = randomUnit(rng);
  side -= side.dot(u) * u;
  side = side.normalized() * std::uniform_real_distribution<double>(0.0, lateral)(rng);
  const Vector3d& t_a = poses.X_Wa.translation();
  poses.X_Wb.translation() = t_a + (reach_a - u.dot(t_a) + gap + back_b) * u + side;
  return poses;
}

std::string describe(const ShapeDistance& d) {
  std::ostringstream s;
  s.precision(17);
  s << "{distance " << d.distance << (d.beyond ? ", beyond" : "")
    << (d.penetrating ? ", penetrating" : "") << ", p_a " << d.p_a.transpose() << ", p_b "
    << d.p_b.transpose() << "}";
  return s.str();
}

// The bounded query's contract against the reference: below the bound the same number (and
// the same contact flag); at or beyond it, `beyond` with the distance equal to the bound.
::testing::AssertionResult boundedAgrees(const ShapeDistance& bounded,
                                         const ShapeDistance& exact,
                                         double bound,
                                         double tol) {
  if (exact.distance < bound) {
    if (!bounded.beyond && bounded.penetrating == exact.penetrating &&
        std::abs(bounded.distance - exact.distance) <= tol) {
      return ::testing::AssertionSuccess();
    }
    return ::testing::AssertionFailure() << "bound " << bound << ": exact " << describe(exact)
                                         << " is below the bound but bounded gave "
                                         << describe(bounded) << " (tolerance " << tol << ")";
  }
  if (bounded.beyond && bounded.distance == bound && !bounded.penetrating) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure()
         << "bound " << bound << ": exact " << describe(exact)
         << " is at or beyond the bound but bounded gave " << describe(bounded);
}

::testing::AssertionResult near(double actual, double expected, double tol, const char* what) {
  if (std::abs(actual - expected) <= tol) return ::testing::AssertionSuccess();
  std::ostringstream s;
  s.precision(17);
  s << what << ": got " << actual << ", expected " << expected << " (difference "
    << actual - expected << ", tolerance " << tol << ")";
  return ::testing::AssertionFailure() << s.str();
}

// Witness points: |p_a − p_b| is the distance and each point lies on its own mesh.
::testing::AssertionResult witnessesConsistent(const ShapeDistance& d,
                                               const std::optional<WorldMesh>& mesh_a,
                                               const std::optional<WorldMesh>& mesh_b,
                                               double tol) {
  const double gap = (d.p_a - d.p_b).norm();
  if (std::abs(gap - d.distance) > tol) {
    return ::testing::AssertionFailure() << "|p_a - p_b| = " << gap << " but " << describe(d);
  }
  if (mesh_a) {
    const double off = pointMeshDistance(d.p_a, *mesh_a);
    if (off > tol)
      return ::testing::AssertionFailure() << "p_a is " << off << " m off mesh a: " << describe(d);
  }
  if (mesh_b) {
    const double off = pointMeshDistance(d.p_b, *mesh_b);
    if (off > tol)
      return ::testing::AssertionFailure() << "p_b is " << off << " m off mesh b: " << describe(d);
  }
  return ::testing::AssertionSuccess();
}

// How often each side of each bound was seen, so a test can insist both were exercised.
struct Coverage {
  std::array<int, kBounds.size()> below{}, beyond{};
  int penetrating = 0;
  int witnesses_checked = 0;

  void expectBothSidesOfEveryFiniteBound(const std::string& what) const {
    for (std::size_t k = 0; k < kBounds.size(); ++k) {
      EXPECT_GT(below[k], 0) << what << ": no distance below the bound " << kBounds[k];
      if (std::isfinite(kBounds[k])) {
        EXPECT_GT(beyond[k], 0) << what << ": no distance at or beyond the bound " << kBounds[k];
      } else {
        EXPECT_EQ(beyond[k], 0) << what << ": +inf bound reported beyond";
      }
    }
  }
};

// 1. The brute force itself, on hand-derived cases.

TEST(BruteForceTriangleDistance, ParallelOffsetTrianglesAreTheOffsetApart) {
  // T1 in z = 0; T2 the same shape shifted by (0.1, 0.1, h): the planes are parallel and the
  // projections overlap, so every closest pair is vertical and the distance is h. Rotating T2
  // in its plane keeps the overlap and the distance.
  const Tri t1{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (const double h : {0.3, 1e-3, 2.5}) {
    const Vector3d s(0.1, 0.1, h);
    EXPECT_TRUE(near(triangleDistance(t1, {t1.a + s, t1.b + s, t1.c + s}), h, kHandTol, "shifted"));
    const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Vector3d::UnitZ()).toRotationMatrix();
    EXPECT_TRUE(near(triangleDistance(t1, {R * t1.a + s, R * t1.b + s, R * t1.c + s}), h, kHandTol,
                     "shifted and turned in plane"));
  }
}

TEST(BruteForceTriangleDistance, CrossingEdgesAtRightAnglesAreTheGapApart) {
  // T1 hangs below the x axis in the plane y = 0 (z ≤ 0); T2 stands on the line x = 0, z = h
  // in the plane x = 0 (z ≥ h). The slab 0 < z < h separates them and the edges touch its
  // faces at (0, 0, 0) and (0, 0, h): distance h, attained edge–edge only (interior points).
  const Tri t1{{-1, 0, 0}, {1, 0, 0}, {0, 0, -1}};
  const double h = 0.25;
  const Tri t2{{0, -1, h}, {0, 1, h}, {0, 0, h + 1}};
  EXPECT_TRUE(near(triangleDistance(t1, t2), h, kHandTol, "T1–T2"));
  EXPECT_TRUE(near(triangleDistance(t2, t1), h, kHandTol, "T2–T1"));
}

TEST(BruteForceTriangleDistance, SkewEdgesAreTheLineDistanceApart) {
  // T1 as above (plane y = 0, z ≤ 0, top edge on the x axis). T2 in the plane x = 0 with its
  // edge on the line (0, t, h + t) and its third vertex on the side z − y > h. The normal
  // n = (0, −1, 1)/√2 separates them: n·p = z/√2 ≤ 0 on T1, n·p = (z − y)/√2 ≥ h/√2 on T2.
  // The lines' common perpendicular joins (0, 0, 0) and (0, −h/2, h/2), both inside the edges,
  // so the distance is exactly the slab width h/√2.
  const Tri t1{{-1, 0, 0}, {1, 0, 0}, {0, 0, -1}};
  const double h = 0.4;
  const Tri t2{{0, -1, h - 1}, {0, 1, h + 1}, {0, -1, h + 1}};
  EXPECT_TRUE(near(triangleDistance(t1, t2), h / std::sqrt(2.0), kHandTol, "skew edges"));
}

TEST(BruteForceTriangleDistance, VertexAboveFaceAndPiercingTriangles) {
  // A vertex of T2 at height h over T1's interior, T2 opening upwards: distance h.
  const Tri t1{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const double h = 0.05;
  const Tri above{{0.25, 0.25, h}, {-1, -1, h + 1}, {1.5, -1, h + 1}};
  EXPECT_TRUE(near(triangleDistance(t1, above), h, kHandTol, "vertex over face"));
  // T2 pierces T1's interior with two edges; no vertex or edge of either is near the other's
  // boundary, so only the crossing test can find the contact: distance 0 (both orders).
  const Tri piercing{{0.2, 0.2, -1}, {0.3, 0.2, 1}, {0.2, 0.3, 1}};
  EXPECT_EQ(triangleDistance(t1, piercing), 0.0);
  EXPECT_EQ(triangleDistance(piercing, t1), 0.0);
  // Standing in the vertical plane x + y = 1.2 instead, beyond T1's hypotenuse (x + y = 1), a
  // triangle crossing z = 0 is the slab width 0.2/√2 away; its edge crosses z = 0 at
  // (0.65, 0.55, 0), whose foot on the hypotenuse (0.55, 0.45, 0) is inside that edge.
  const Tri beside{{0.7, 0.5, -1}, {0.6, 0.6, 1}, {0.5, 0.7, -1}};
  EXPECT_TRUE(near(triangleDistance(t1, beside), 0.2 / std::sqrt(2.0), kHandTol, "beside"));
}

TEST(BruteForceTriangleDistance, PointAndSegmentPiecesNeverBeatDenseSampling) {
  // Property: the closed forms are minima, so no sampled point pair may be closer, and a fine
  // sampling must come within its resolution of them.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> c(-1.0, 1.0);
  const auto point = [&] { return Vector3d(c(rng), c(rng), c(rng)); };
  constexpr int kSteps = 60;
  for (int trial = 0; trial < 50; ++trial) {
    const Tri t{point(), point(), point()};
    const Vector3d p = point() * 2.0;
    const double closed = pointTriangleDistance(p, t);
    double sampled = kInf;
    for (int i = 0; i <= kSteps; ++i) {
      for (int j = 0; i + j <= kSteps; ++j) {
        const double u = i / double{kSteps}, v = j / double{kSteps};
        sampled = std::min(sampled, (p - (t.a + u * (t.b - t.a) + v * (t.c - t.a))).norm());
      }
    }
    const double spacing = std::max({(t.b - t.a).norm(), (t.c - t.a).norm()}) / kSteps;
    EXPECT_LE(closed, sampled + kSampleSlack) << "trial " << trial;
    EXPECT_GE(closed, sampled - spacing) << "trial " << trial;

    const Vector3d p1 = point(), q1 = point(), p2 = point(), q2 = point();
    const double seg = std::sqrt(segmentSegmentDistanceSq(p1, q1, p2, q2));
    double seg_sampled = kInf;
    for (int i = 0; i <= 400; ++i) {
      for (int j = 0; j <= 400; ++j) {
        seg_sampled = std::min(
            seg_sampled, ((p1 + (i / 400.0) * (q1 - p1)) - (p2 + (j / 400.0) * (q2 - p2))).norm());
      }
    }
    const double seg_spacing = std::max((q1 - p1).norm(), (q2 - p2).norm()) / 400.0;
    EXPECT_LE(seg, seg_sampled + kSampleSlack) << "trial " << trial;
    EXPECT_GE(seg, seg_sampled - seg_spacing) << "trial " << trial;
  }
  // Parallel segments (denominator 0): overlapping ones are the line distance apart, disjoint
  // ones the end-to-end distance.
  EXPECT_TRUE(
      near(std::sqrt(segmentSegmentDistanceSq({0, 0, 0}, {1, 0, 0}, {0.5, 0.3, 0}, {2, 0.3, 0})),
           0.3, kHandTol, "parallel overlapping"));
  EXPECT_TRUE(
      near(std::sqrt(segmentSegmentDistanceSq({0, 0, 0}, {1, 0, 0}, {1.4, 0.3, 0}, {2, 0.3, 0})),
           0.5, kHandTol, "parallel disjoint"));
}

// 2. Mesh against mesh: brute force = exact = bounded, over random poses.

void crossCheckMeshMesh(const Body& a, const Body& b, unsigned seed, int poses_count) {
  std::mt19937 rng(seed);
  Coverage seen;
  for (int i = 0; i < poses_count; ++i) {
    const PosePair poses = posesWithGap(a, b, -0.012, 0.055, 0.02, rng);
    SCOPED_TRACE(a.name + " vs " + b.name + ", pose " + std::to_string(i));
    const std::optional<WorldMesh> world_a = toWorld(*a.mesh, poses.X_Wa);
    const std::optional<WorldMesh> world_b = toWorld(*b.mesh, poses.X_Wb);
    const double brute = meshMeshDistance(*world_a, *world_b);
    const ShapeDistance exact =
        detail::exactShapeDistance(a.shape, poses.X_Wa, b.shape, poses.X_Wb);
    ASSERT_TRUE(near(exact.distance, brute, kExactTol, "exactShapeDistance vs brute force"));
    EXPECT_EQ(exact.penetrating, brute == 0.0) << describe(exact) << ", brute force " << brute;
    if (exact.penetrating) ++seen.penetrating;
    for (std::size_t k = 0; k < kBounds.size(); ++k) {
      const double bound = kBounds[k];
      for (const bool witness : {false, true}) {
        const ShapeDistance bounded =
            detail::shapeDistance(a.shape, poses.X_Wa, b.shape, poses.X_Wb, bound, witness);
        EXPECT_TRUE(boundedAgrees(bounded, exact, bound, kSameTol)) << "witness " << witness;
        if (!bounded.beyond) {
          EXPECT_TRUE(near(bounded.distance, brute, kExactTol, "bounded vs brute force"));
        }
        // In contact the points are not defined (FCL's triangle routine leaves those of the
        // last edge pair it tried), so they are checked for separated pairs only.
        if (witness && !bounded.beyond && !bounded.penetrating) {
          EXPECT_TRUE(witnessesConsistent(bounded, world_a, world_b, kOnSurfaceTol));
          ++seen.witnesses_checked;
        }
      }
      (exact.distance < bound ? seen.below : seen.beyond)[k]++;
    }
    if (!exact.penetrating) {
      EXPECT_TRUE(witnessesConsistent(exact, world_a, world_b, kOnSurfaceTol)) << "exact";
    }
  }
  seen.expectBothSidesOfEveryFiniteBound(a.name + " vs " + b.name);
  EXPECT_GT(seen.penetrating, 0) << "no overlapping pose: the contact path was not exercised";
  EXPECT_GT(seen.witnesses_checked, 0);
}

constexpr int kPosesPerPair = 200;

TEST(MeshMeshDistance, LumpySphereVsRoundedBoxMatchesBruteForceAndBoundsAgree) {
  std::mt19937 rng(101);
  const Body a = meshBody("lumpy sphere", lumpySphere(0.06, 0.12, rng));
  const Body b = meshBody("rounded box", roundedBox({0.07, 0.045, 0.03}, 0.002, rng));
  crossCheckMeshMesh(a, b, 1, kPosesPerPair);
}

TEST(MeshMeshDistance, RoundedBoxVsOpenSheetMatchesBruteForceAndBoundsAgree) {
  std::mt19937 rng(102);
  const Body a = meshBody("rounded box", roundedBox({0.08, 0.05, 0.025}, 0.003, rng));
  const Body b = meshBody("open sheet", wavySheet(0.16, 10, 0.015, rng));
  crossCheckMeshMesh(a, b, 2, kPosesPerPair);
}

TEST(MeshMeshDistance, OpenSheetVsLumpySphereMatchesBruteForceAndBoundsAgree) {
  std::mt19937 rng(103);
  const Body a = meshBody("open sheet", wavySheet(0.12, 10, 0.02, rng));
  const Body b = meshBody("small lumpy sphere", lumpySphere(0.03, 0.2, rng));
  crossCheckMeshMesh(a, b, 3, kPosesPerPair);
}

// 3. Mesh against primitives.

std::vector<Body> primitives() {
  std::vector<Body> out;
  out.push_back(primitiveBody("sphere", kinematics::Sphere{0.03}));
  out.push_back(primitiveBody("capsule", kinematics::Capsule{0.02, 0.06}));
  out.push_back(primitiveBody("box", kinematics::Box{{0.05, 0.03, 0.04}}));
  out.push_back(primitiveBody("cylinder", kinematics::Cylinder{0.025, 0.05}));
  return out;
}

// Brute-force distance from a mesh to a sphere or capsule (radius around a point or segment),
// or to a box (its 12 triangles), and how closely GJK is expected to meet it; nullopt for the
// cylinder (curved rim, no closed form here).
struct Reference {
  double distance;
  double tol;
};

// A box's surface as 12 triangles, written out independently of collision/.
TriangleMesh boxTriangles(const Vector3d& size) {
  TriangleMesh box;
  for (int i = 0; i < 8; ++i) {
    box.vertices.emplace_back(0.5 * size.x() * ((i & 1) ? 1 : -1),
                              0.5 * size.y() * ((i & 2) ? 1 : -1),
                              0.5 * size.z() * ((i & 4) ? 1 : -1));
  }
  box.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                   {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return box;
}

std::optional<Reference> analyticMeshPrimitiveDistance(const WorldMesh& mesh,
                                                       const Body& prim,
                                                       const Isometry3d& X_WG) {
  if (const auto* s = std::get_if<kinematics::Sphere>(&prim.primitive)) {
    return Reference{std::max(0.0, pointMeshDistance(X_WG.translation(), mesh) - s->radius),
                     kGjkCurvedTol};
  }
  if (const auto* c = std::get_if<kinematics::Capsule>(&prim.primitive)) {
    const Vector3d half = X_WG.linear().col(2) * (0.5 * c->length);
    const double axis =
        segmentMeshDistance(X_WG.translation() - half, X_WG.translation() + half, mesh);
    return Reference{std::max(0.0, axis - c->radius), kGjkCurvedTol};
  }
  if (const auto* b = std::get_if<kinematics::Box>(&prim.primitive)) {
    return Reference{meshMeshDistance(mesh, toWorld(boxTriangles(b->size), X_WG)), kGjkTol};
  }
  return std::nullopt;
}

// gap_min: how deep the slab placement may push the primitive into the mesh's extent (< 0).
void crossCheckMeshPrimitive(const Body& mesh, const Body& prim, unsigned seed, double gap_min) {
  std::mt19937 rng(seed);
  Coverage seen;
  int analytic_checked = 0;
  for (int i = 0; i < kPosesPerPair; ++i) {
    const PosePair poses = posesWithGap(mesh, prim, gap_min, 0.055, 0.02, rng);
    SCOPED_TRACE(mesh.name + " vs " + prim.name + ", pose " + std::to_string(i));
    const WorldMesh world = toWorld(*mesh.mesh, poses.X_Wa);
    const ShapeDistance exact =
        detail::exactShapeDistance(mesh.shape, poses.X_Wa, prim.shape, poses.X_Wb);
    const std::optional<Reference> ref = analyticMeshPrimitiveDistance(world, prim, poses.X_Wb);
    if (ref && ref->distance > kGjkTol) {
      EXPECT_TRUE(near(exact.distance, ref->distance, ref->tol, "exact vs brute-force reference"));
      EXPECT_GE(exact.distance, ref->distance - kExactTol) << "GJK below the true distance";
      ++analytic_checked;
    } else if (ref) {
      EXPECT_LE(exact.distance, kGjkTol)
          << "reference " << ref->distance << ", exact " << describe(exact);
    }
    if (exact.penetrating) ++seen.penetrating;
    for (std::size_t k = 0; k < kBounds.size(); ++k) {
      const double bound = kBounds[k];
      for (const bool witness : {false, true}) {
        // Both argument orders: the primitive first goes through the swapped branch.
        const ShapeDistance ab =
            detail::shapeDistance(mesh.shape, poses.X_Wa, prim.shape, poses.X_Wb, bound, witness);
        const ShapeDistance ba =
            detail::shapeDistance(prim.shape, poses.X_Wb, mesh.shape, poses.X_Wa, bound, witness);
        EXPECT_TRUE(boundedAgrees(ab, exact, bound, kSameTol)) << "mesh first, witness " << witness;
        EXPECT_TRUE(boundedAgrees(ba, exact, bound, kSameTol))
            << "primitive first, witness " << witness;
        if (witness && !ab.beyond && !ab.penetrating) {
          EXPECT_TRUE(witnessesConsistent(ab, world, std::nullopt, kGjkTol)) << "mesh first";
          ShapeDistance flipped = ba;
          std::swap(flipped.p_a, flipped.p_b);
          EXPECT_TRUE(witnessesConsistent(flipped, world, std::nullopt, kGjkTol))
              << "primitive first";
          ++seen.witnesses_checked;
        }
      }
      (exact.distance < bound ? seen.below : seen.beyond)[k]++;
    }
  }
  seen.expectBothSidesOfEveryFiniteBound(mesh.name + " vs " + prim.name);
  EXPECT_GT(seen.penetrating, 0) << "no overlapping pose: the contact path was not exercised";
  if (!std::holds_alternative<kinematics::Cylinder>(prim.primitive)) {
    EXPECT_GT(analytic_checked, kPosesPerPair / 4) << "too few separated poses for the reference";
  }
}

TEST(MeshPrimitiveDistance, LumpySphereMeshVsEachPrimitiveBoundedAgreesWithExactAndReference) {
  std::mt19937 rng(201);
  const Body mesh = meshBody("lumpy sphere", lumpySphere(0.06, 0.12, rng));
  unsigned seed = 20;
  for (const Body& prim : primitives()) crossCheckMeshPrimitive(mesh, prim, seed++, -0.01);
}

TEST(MeshPrimitiveDistance, OpenSheetVsEachPrimitiveBoundedAgreesWithExactAndReference) {
  std::mt19937 rng(202);
  const Body mesh = meshBody("open sheet", wavySheet(0.16, 10, 0.015, rng));
  unsigned seed = 30;
  // The sheet's waves are only ±15 mm: reaching through its extreme takes a deeper overlap.
  for (const Body& prim : primitives()) crossCheckMeshPrimitive(mesh, prim, seed++, -0.025);
}

// 3b. The box against a mesh has its own traversal (bounds in the box frame, the gap as the
// distance when a triangle lies over one face): the cases it shortcuts, against brute force.

// A flat square grid in z = 0, n × n cells, two triangles each: every triangle under a
// parallel box face is tied for the minimum.
TriangleMesh flatGrid(double size, int n) {
  TriangleMesh m;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      m.vertices.emplace_back(size * (i / static_cast<double>(n) - 0.5),
                              size * (j / static_cast<double>(n) - 0.5), 0.0);
    }
  }
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const int v00 = i * (n + 1) + j, v10 = v00 + n + 1;
      m.triangles.emplace_back(v00, v10, v10 + 1);
      m.triangles.emplace_back(v00, v10 + 1, v00 + 1);
    }
  }
  return m;
}

// Bounded box–mesh distance (both argument orders, witness points on) against the brute-force
// minimum over the box's 12 triangles × the mesh's triangles and against FCL's exact query.
void expectBoxMeshMatchesBruteForce(const Body& mesh,
                                    const Isometry3d& X_Wm,
                                    const Vector3d& box_size,
                                    const Isometry3d& X_Wb) {
  const Body box = primitiveBody("box", kinematics::Box{box_size});
  const WorldMesh world_mesh = toWorld(*mesh.mesh, X_Wm);
  const WorldMesh world_box = toWorld(boxTriangles(box_size), X_Wb);
  const double brute = meshMeshDistance(world_mesh, world_box);
  const ShapeDistance exact = detail::exactShapeDistance(box.shape, X_Wb, mesh.shape, X_Wm);
  EXPECT_TRUE(near(exact.distance, brute, kExactTol, "FCL's exact vs brute force"));
  for (const double bound : kBounds) {
    const ShapeDistance ab = detail::shapeDistance(box.shape, X_Wb, mesh.shape, X_Wm, bound, true);
    const ShapeDistance ba = detail::shapeDistance(mesh.shape, X_Wm, box.shape, X_Wb, bound, true);
    EXPECT_TRUE(boundedAgrees(ab, exact, bound, kSameTol)) << "box first";
    EXPECT_TRUE(boundedAgrees(ba, exact, bound, kSameTol)) << "mesh first";
    if (brute < bound) {
      EXPECT_TRUE(near(ab.distance, brute, kExactTol, "bounded vs brute force"));
      if (!ab.penetrating) {
        EXPECT_TRUE(witnessesConsistent(ab, world_box, world_mesh, kOnSurfaceTol));
        ShapeDistance flipped = ba;
        std::swap(flipped.p_a, flipped.p_b);
        EXPECT_TRUE(witnessesConsistent(flipped, world_box, world_mesh, kOnSurfaceTol));
      }
    }
  }
}

TEST(BoxMeshDistance, FaceOverAFlatGridMatchesBruteForceThroughTiesEdgesAndOverhangs) {
  const Body grid = meshBody("flat grid", flatGrid(0.2, 40));  // 3 200 triangles, 5 mm cells
  const Vector3d size(0.17, 0.07, 0.09);
  for (const double gap : {0.0, 0.0004, 0.003, 0.012, 0.031}) {
    for (const double tilt : {0.0, 1e-3, 0.07, 0.6}) {
      for (const double shift : {0.0, 0.06, 0.14}) {  // 0.14: the box overhangs the grid's edge
        SCOPED_TRACE("gap " + std::to_string(gap) + ", tilt " + std::to_string(tilt) + ", shift " +
                     std::to_string(shift));
        Isometry3d X_Wb = Isometry3d::Identity();
        X_Wb.linear() = Eigen::AngleAxisd(tilt, Vector3d(0.3, 1, 0).normalized()).matrix();
        // The lowest corner `gap` above the grid's plane (negative z extent of the box).
        const Vector3d half = 0.5 * size;
        double lowest = kInf;
        for (int i = 0; i < 8; ++i) {
          const Vector3d c((i & 1) ? half.x() : -half.x(), (i & 2) ? half.y() : -half.y(),
                           (i & 4) ? half.z() : -half.z());
          lowest = std::min(lowest, (X_Wb.linear() * c).z());
        }
        X_Wb.translation() = Vector3d(shift, 0.4 * shift, gap - lowest);
        expectBoxMeshMatchesBruteForce(grid, Isometry3d::Identity(), size, X_Wb);
      }
    }
  }
}

TEST(BoxMeshDistance, CurvedSheetUnderAFaceAtManyPosesMatchesBruteForce) {
  std::mt19937 rng(41);
  const Body sheet = meshBody("wavy sheet", wavySheet(0.2, 30, 0.02, rng));
  const Vector3d size(0.12, 0.05, 0.06);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 40; ++k) {
    SCOPED_TRACE("pose " + std::to_string(k));
    Isometry3d X_Wb = Isometry3d::Identity();
    X_Wb.linear() = Eigen::AngleAxisd(0.3 * u(rng), randomUnit(rng)).matrix();
    X_Wb.translation() = Vector3d(0.08 * u(rng), 0.08 * u(rng), 0.045 + 0.03 * u(rng));
    expectBoxMeshMatchesBruteForce(sheet, Isometry3d::Identity(), size, X_Wb);
  }
}

TEST(BoxMeshDistance, AMeshWhollyInsideTheBoxIsItsSurfaceDistanceNotContact) {
  // As for the polyhedron FCL measures: surfaces that do not cross are not in contact.
  std::mt19937 rng(42);
  const Body pebble = meshBody("pebble", lumpySphere(0.01, 0.1, rng));
  for (const Vector3d& at : {Vector3d(0, 0, 0), Vector3d(0.03, -0.01, 0.02)}) {
    Isometry3d X_Wm = Isometry3d::Identity();
    X_Wm.translation() = at;
    const Body box = primitiveBody("box", kinematics::Box{Vector3d(0.1, 0.08, 0.07)});
    const ShapeDistance d =
        detail::shapeDistance(box.shape, Isometry3d::Identity(), pebble.shape, X_Wm, kInf, false);
    EXPECT_FALSE(d.penetrating);
    EXPECT_GT(d.distance, 0.0);
    expectBoxMeshMatchesBruteForce(pebble, X_Wm, Vector3d(0.1, 0.08, 0.07), Isometry3d::Identity());
  }
}

// 4. Frame invariance (FCL's QueryWithVaryingWorldFrames): moving both bodies by the same world
// transform G changes nothing but the frame of the witness points.

// distance_tol: allowed change of the distance; witness_tol: allowed |G·p − p'| (negative: the
// witness points are not compared, only the distances).
void expectFrameInvariant(
    const Body& a, const Body& b, unsigned seed, double distance_tol, double witness_tol) {
  constexpr int kPoses = 60, kWorlds = 5;
  std::mt19937 rng(seed);
  for (int i = 0; i < kPoses; ++i) {
    const PosePair poses = posesWithGap(a, b, -0.01, 0.055, 0.02, rng);
    const ShapeDistance exact =
        detail::exactShapeDistance(a.shape, poses.X_Wa, b.shape, poses.X_Wb);
    const ShapeDistance bounded =
        detail::shapeDistance(a.shape, poses.X_Wa, b.shape, poses.X_Wb, 0.020, true);
    for (int g = 0; g < kWorlds; ++g) {
      SCOPED_TRACE(a.name + " vs " + b.name + ", pose " + std::to_string(i) + ", world " +
                   std::to_string(g));
      const Isometry3d G = randomPose(rng, 2.0);
      const Isometry3d X_Ga = G * poses.X_Wa, X_Gb = G * poses.X_Wb;
      const ShapeDistance exact_g = detail::exactShapeDistance(a.shape, X_Ga, b.shape, X_Gb);
      const ShapeDistance bounded_g =
          detail::shapeDistance(a.shape, X_Ga, b.shape, X_Gb, 0.020, true);
      EXPECT_TRUE(near(exact_g.distance, exact.distance, distance_tol, "exact distance, moved"));
      EXPECT_EQ(exact_g.penetrating, exact.penetrating)
          << describe(exact) << " became " << describe(exact_g);
      EXPECT_TRUE(
          near(bounded_g.distance, bounded.distance, distance_tol, "bounded distance, moved"));
      EXPECT_EQ(bounded_g.beyond, bounded.beyond)
          << describe(bounded) << " became " << describe(bounded_g);
      EXPECT_EQ(bounded_g.penetrating, bounded.penetrating)
          << describe(bounded) << " became " << describe(bounded_g);
      if (witness_tol >= 0.0 && !bounded.beyond && !bounded.penetrating) {
        EXPECT_TRUE(
            near((G * bounded.p_a - bounded_g.p_a).norm(), 0.0, witness_tol, "|G p_a - p_a'|"));
        EXPECT_TRUE(
            near((G * bounded.p_b - bounded_g.p_b).norm(), 0.0, witness_tol, "|G p_b - p_b'|"));
      }
    }
  }
}

TEST(ShapeDistanceFrameInvariance, MeshMeshDistancesAndWitnessesMoveWithTheWorldFrame) {
  std::mt19937 rng(301);
  const Body sphere = meshBody("lumpy sphere", lumpySphere(0.06, 0.12, rng));
  const Body box = meshBody("rounded box", roundedBox({0.07, 0.045, 0.03}, 0.002, rng));
  const Body sheet = meshBody("open sheet", wavySheet(0.16, 10, 0.015, rng));
  expectFrameInvariant(sphere, box, 1, kSameTol, kOnSurfaceTol);
  expectFrameInvariant(sheet, sphere, 2, kSameTol, kOnSurfaceTol);
}

TEST(ShapeDistanceFrameInvariance, MeshBoxExactlyAndCurvedPrimitivesWithinTheGjkError) {
  // A box is a polytope: its distance is a closed form in any frame. Against curved
  // supports where GJK stops depends on its world-fixed start direction, so the distance moves
  // within its error (kGjkCurvedTol; up to ~3e-5 m seen for the sphere) and the witness points
  // slide along the nearly flat neighbourhood of the closest pair: only distances compared.
  std::mt19937 rng(302);
  const Body mesh = meshBody("lumpy sphere", lumpySphere(0.06, 0.12, rng));
  unsigned seed = 10;
  for (const Body& prim : primitives()) {
    const bool box = std::holds_alternative<kinematics::Box>(prim.primitive);
    expectFrameInvariant(mesh, prim, seed++, box ? kSameTol : kGjkCurvedTol,
                         box ? kOnSurfaceTol : -1.0);
  }
}

// 5. Shared data (docs/design.md §10): Viper link meshes and the scanned bunny, none of them
// closed.

const fs::path kSharedData = SCANPLAN_SHARED_DATA_DIR;

// Through the product's own loader and makeCollisionShape (metres), plus the triangles again
// for the placement and the witness checks.
Body loadedMeshBody(std::string name, const fs::path& file) {
  kinematics::MeshLoadOptions options;
  options.units = kinematics::LengthUnit::kMetre;
  kinematics::Shape shape;
  shape.geometry = kinematics::MeshFile{file, options};
  Body body;
  body.name = std::move(name);
  body.shape = detail::makeCollisionShape(shape);
  body.mesh = kinematics::loadMesh(file, options).mesh;
  return body;
}

// Bounded against exact as in crossCheckMeshMesh; the brute force only for the first
// `brute_poses` poses (it is quadratic in the triangle count).
Coverage crossCheckLoadedMeshes(
    const Body& a, const Body& b, unsigned seed, int poses_count, int brute_poses) {
  std::mt19937 rng(seed);
  Coverage seen;
  for (int i = 0; i < poses_count; ++i) {
    const PosePair poses = posesWithGap(a, b, -0.012, 0.055, 0.03, rng);
    SCOPED_TRACE(a.name + " vs " + b.name + ", pose " + std::to_string(i));
    const std::optional<WorldMesh> world_a = toWorld(*a.mesh, poses.X_Wa);
    const std::optional<WorldMesh> world_b = toWorld(*b.mesh, poses.X_Wb);
    const ShapeDistance exact =
        detail::exactShapeDistance(a.shape, poses.X_Wa, b.shape, poses.X_Wb);
    if (i < brute_poses) {
      EXPECT_TRUE(near(exact.distance, meshMeshDistance(*world_a, *world_b), kExactTol,
                       "exactShapeDistance vs brute force"));
    }
    if (exact.penetrating) ++seen.penetrating;
    for (std::size_t k = 0; k < kBounds.size(); ++k) {
      const double bound = kBounds[k];
      for (const bool witness : {false, true}) {
        const ShapeDistance bounded =
            detail::shapeDistance(a.shape, poses.X_Wa, b.shape, poses.X_Wb, bound, witness);
        EXPECT_TRUE(boundedAgrees(bounded, exact, bound, kSameTol)) << "witness " << witness;
        if (witness && !bounded.beyond && !bounded.penetrating) {
          EXPECT_TRUE(witnessesConsistent(bounded, world_a, world_b, kOnSurfaceTol));
          ++seen.witnesses_checked;
        }
      }
      (exact.distance < bound ? seen.below : seen.beyond)[k]++;
    }
  }
  return seen;
}

TEST(SharedMeshDistance, ViperLinkMeshesBoundedAgreesWithExact) {
  const fs::path link2 = kSharedData / "robots/viper_s650/link2.stl";
  const fs::path link3 = kSharedData / "robots/viper_s650/link3.stl";
  if (!fs::exists(link2) || !fs::exists(link3))
    GTEST_SKIP() << "shared test data absent: " << link2;
  const Body a = loadedMeshBody("link2", link2);
  const Body b = loadedMeshBody("link3", link3);
  EXPECT_FALSE(a.mesh->isClosed() && b.mesh->isClosed()) << "premise: open CAD meshes";
  const Coverage seen = crossCheckLoadedMeshes(a, b, 41, kPosesPerPair, 8);
  seen.expectBothSidesOfEveryFiniteBound("link2 vs link3");
  EXPECT_GT(seen.penetrating, 0);
  EXPECT_GT(seen.witnesses_checked, 0);
}

TEST(SharedMeshDistance, StanfordBunnyVsViperLinkBoundedAgreesWithExact) {
  const fs::path bunny_file = kSharedData / "meshes/stlmodels_bunny.bin.stl";
  const fs::path link_file = kSharedData / "robots/viper_s650/link3.stl";
  if (!fs::exists(bunny_file) || !fs::exists(link_file))
    GTEST_SKIP() << "shared test data absent: " << bunny_file;
  const Body bunny = loadedMeshBody("bunny", bunny_file);
  const Body link = loadedMeshBody("link3", link_file);
  ASSERT_GT(bunny.mesh->triangles.size(), 60000u);
  EXPECT_FALSE(bunny.mesh->isClosed()) << "premise: the scan has holes";
  // 69k triangles: a handful of poses only, for speed.
  const Coverage seen = crossCheckLoadedMeshes(bunny, link, 42, 20, 0);
  EXPECT_GT(seen.below[k50mm], 0) << "no pose closer than 50 mm";
  EXPECT_GT(seen.beyond[k20mm], 0) << "no pose beyond 20 mm";
  EXPECT_GT(seen.witnesses_checked, 0);
}

// 6. Thread safety: geometry is built once and shared; queries on it must be safe from any
// number of threads (STYLE.md: const member functions must be thread safe).

struct Query {
  const Body* a;
  const Body* b;
  PosePair poses;
  double bound;
  bool witness;
};

bool bitIdentical(double x, double y) {
  return std::bit_cast<std::uint64_t>(x) == std::bit_cast<std::uint64_t>(y);
}

// Witness points are compared only where they are defined: requested, and below the bound.
bool bitIdentical(const ShapeDistance& x, const ShapeDistance& y, bool witness) {
  if (x.beyond != y.beyond || x.penetrating != y.penetrating ||
      !bitIdentical(x.distance, y.distance)) {
    return false;
  }
  if (!witness || x.beyond) return true;
  for (int k = 0; k < 3; ++k) {
    if (!bitIdentical(x.p_a[k], y.p_a[k]) || !bitIdentical(x.p_b[k], y.p_b[k])) return false;
  }
  return true;
}

TEST(ShapeDistanceThreads, FourThreadsOnSharedGeometryGiveBitIdenticalResults) {
  // shapeDistance, the query the maps and validation run on several threads. (The reference,
  // exactShapeDistance, calls fcl::distance on geometry and transforms, never constructing an
  // fcl::CollisionObject: FCL 0.7's constructor writes the shared geometry's AABB, a race.)
  std::mt19937 rng(601);
  std::vector<Body> bodies;
  bodies.push_back(meshBody("lumpy sphere", lumpySphere(0.06, 0.12, rng)));
  bodies.push_back(meshBody("rounded box", roundedBox({0.07, 0.045, 0.03}, 0.002, rng)));
  bodies.push_back(meshBody("open sheet", wavySheet(0.16, 10, 0.015, rng)));
  for (Body& prim : primitives()) bodies.push_back(std::move(prim));

  constexpr std::size_t kQueries = 200, kMeshes = 3;
  std::vector<Query> queries;
  std::uniform_int_distribution<std::size_t> mesh_index(0, kMeshes - 1),
      any_index(0, bodies.size() - 1);
  std::uniform_int_distribution<std::size_t> bound_index(0, kBounds.size() - 1);
  for (std::size_t i = 0; i < kQueries; ++i) {
    const Body* a = &bodies[mesh_index(rng)];
    const Body* b = &bodies[any_index(rng)];
    if (i % 2 == 1) std::swap(a, b);  // primitives first too
    const PosePair poses = posesWithGap(*a, *b, -0.01, 0.055, 0.02, rng);
    queries.push_back({a, b, poses, kBounds[bound_index(rng)], i % 3 != 0});
  }
  const auto run = [&](std::size_t start, std::vector<ShapeDistance>& out) {
    out.assign(kQueries, ShapeDistance{});
    for (std::size_t n = 0; n < kQueries; ++n) {
      const std::size_t i = (start + n) % kQueries;  // each thread in its own order
      const Query& q = queries[i];
      out[i] = detail::shapeDistance(q.a->shape, q.poses.X_Wa, q.b->shape, q.poses.X_Wb, q.bound,
                                     q.witness);
    }
  };
  std::vector<ShapeDistance> single;
  run(0, single);

  constexpr std::size_t kThreads = 4;
  std::array<std::vector<ShapeDistance>, kThreads> results;
  {
    std::vector<std::thread> threads;
    for (std::size_t t = 0; t < kThreads; ++t) {
      threads.emplace_back([&, t] { run(t * kQueries / kThreads, results[t]); });
    }
    for (std::thread& thread : threads) thread.join();
  }
  int below = 0;
  for (std::size_t i = 0; i < kQueries; ++i) {
    if (!single[i].beyond) ++below;
    for (std::size_t t = 0; t < kThreads; ++t) {
      EXPECT_TRUE(bitIdentical(results[t][i], single[i], queries[i].witness))
          << "query " << i << " (" << queries[i].a->name << " vs " << queries[i].b->name
          << "), thread " << t << ": " << describe(results[t][i]) << ", single thread "
          << describe(single[i]);
    }
  }
  EXPECT_GT(below, 20) << "too few queries below their bound to exercise the traversal";
}

}  // namespace
}  // namespace scanplan::collision
