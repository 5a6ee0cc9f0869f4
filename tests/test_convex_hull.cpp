// Convex hulls of link meshes for the configuration maps: the hull contains the
// mesh and is convex (checked face by face against every vertex), its margin is an upper bound
// on how far the hull's surface reaches outside the mesh (checked against a brute-force distance
// over sampled hull points, and against a part with a known answer), and distances to the hull
// sit between the mesh's distance minus that margin and the mesh's distance.

#include <scanplan/collision/convex_hull.h>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <random>
#include <vector>

#include <scanplan/collision/fcl_geometry.h>
#include <scanplan/collision/scene.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/shape.h>
#include "geometry_support.h"

namespace scanplan::collision {
namespace {

namespace fs = std::filesystem;
using Eigen::Isometry3d;
using Eigen::Vector3d;
using kinematics::TriangleMesh;

const fs::path kSharedData = SCANPLAN_SHARED_DATA_DIR;

// Brute-force distance from a point to a mesh's surface.
double bruteDistance(const Vector3d& p, const TriangleMesh& mesh) {
  double best = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3i& t : mesh.triangles) {
    best =
        std::min(best, test::pointTriangleDistance(p, mesh.vertices[static_cast<std::size_t>(t[0])],
                                                   mesh.vertices[static_cast<std::size_t>(t[1])],
                                                   mesh.vertices[static_cast<std::size_t>(t[2])]));
  }
  return best;
}

TriangleMesh moved(TriangleMesh mesh, const Vector3d& by) {
  for (Vector3d& v : mesh.vertices) v += by;
  return mesh;
}

TriangleMesh joined(const TriangleMesh& a, const TriangleMesh& b) {
  TriangleMesh out = a;
  const int n = static_cast<int>(a.vertices.size());
  out.vertices.insert(out.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (const Eigen::Vector3i& t : b.triangles)
    out.triangles.push_back(t + Eigen::Vector3i::Constant(n));
  return out;
}

// Two cubes of edge a, 2a apart along x: the hull is the 4a × a × a box around both, and the
// points of its surface farthest from the cubes are those midway, a from either cube.
TriangleMesh twoCubes(double a) {
  const TriangleMesh cube = test::centredCube(a);
  return joined(moved(cube, Vector3d(0.5, 0.5, 0.5) * a), moved(cube, Vector3d(3.5, 0.5, 0.5) * a));
}

// The hull is closed and outward, convex, holds every mesh vertex, and uses mesh vertices only.
void expectHullOf(const TriangleMesh& hull, const TriangleMesh& mesh) {
  EXPECT_TRUE(hull.isClosed());
  for (const Eigen::Vector3i& t : hull.triangles) {
    const Vector3d& a = hull.vertices[static_cast<std::size_t>(t[0])];
    const Vector3d n = (hull.vertices[static_cast<std::size_t>(t[1])] - a)
                           .cross(hull.vertices[static_cast<std::size_t>(t[2])] - a);
    if (n.norm() < 1e-15) continue;  // a sliver from triangulating a merged facet
    const Vector3d u = n.normalized();
    for (const Vector3d& v : mesh.vertices) ASSERT_LE(u.dot(v - a), 1e-9);
  }
  for (const Vector3d& h : hull.vertices) {
    const bool found = std::any_of(mesh.vertices.begin(), mesh.vertices.end(),
                                   [&](const Vector3d& v) { return (v - h).norm() == 0.0; });
    ASSERT_TRUE(found) << "hull vertex not a mesh vertex: " << h.transpose();
  }
}

// A random point on a random hull triangle (area-uniform within the triangle).
Vector3d randomSurfacePoint(const TriangleMesh& hull, std::mt19937& rng) {
  std::uniform_int_distribution<std::size_t> pick(0, hull.triangles.size() - 1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Eigen::Vector3i& t = hull.triangles[pick(rng)];
  double r1 = u(rng), r2 = u(rng);
  if (r1 + r2 > 1.0) {
    r1 = 1.0 - r1;
    r2 = 1.0 - r2;
  }
  const Vector3d& a = hull.vertices[static_cast<std::size_t>(t[0])];
  return a + r1 * (hull.vertices[static_cast<std::size_t>(t[1])] - a) +
         r2 * (hull.vertices[static_cast<std::size_t>(t[2])] - a);
}

TEST(ConvexHull, CubeIsItsOwnHullWithNoMargin) {
  const TriangleMesh cube = test::centredCube(0.2);
  const auto hull = convexHull(cube);
  ASSERT_TRUE(hull);
  EXPECT_EQ(hull->vertices.size(), 8u);
  EXPECT_EQ(hull->triangles.size(), 12u);
  expectHullOf(*hull, cube);
  // Convex: every point of the hull is on the mesh, so the bound comes down to the tolerance
  // (pieces no larger than it); FCL's point–triangle distance rounds to a few nm.
  const HullMargin m = hullMargin(*hull, cube, 1e-2);
  EXPECT_LE(m.margin, 1e-2 + 1e-8);
  EXPECT_LT(m.found, 1e-8);
}

TEST(ConvexHull, TwoCubesHaveTheKnownMargin) {
  const TriangleMesh mesh = twoCubes(0.1);
  const auto hull = convexHull(mesh);
  ASSERT_TRUE(hull);
  EXPECT_EQ(hull->vertices.size(), 8u);
  expectHullOf(*hull, mesh);
  const HullMargin m = hullMargin(*hull, mesh, 1e-4);
  EXPECT_GE(m.margin, 0.1 - 1e-12);  // never below the truth
  EXPECT_LE(m.margin, 0.1 + 1e-4 + 1e-12);
  EXPECT_GE(m.found, 0.1 - 1e-4);
  EXPECT_LE(m.found, 0.1 + 1e-12);
}

TEST(ConvexHull, FlatOrTinyMeshesHaveNone) {
  TriangleMesh flat;
  flat.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  flat.triangles = {{0, 1, 2}, {1, 3, 2}};
  EXPECT_FALSE(convexHull(flat));
  TriangleMesh one;
  one.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 5, 5}};  // the last is unused
  one.triangles = {{0, 1, 2}};
  EXPECT_FALSE(convexHull(one));
}

TEST(ConvexHull, MarginRunsOutOfQueriesStillBoundsTheTruth) {
  const TriangleMesh mesh = twoCubes(0.1);
  const auto hull = convexHull(mesh);
  ASSERT_TRUE(hull);
  const HullMargin m = hullMargin(*hull, mesh, 1e-6, 40);
  EXPECT_LE(m.queries, 40u);
  EXPECT_GE(m.margin, 0.1);
}

// The hull's margin against a brute-force distance at random points of its surface, and the
// distance sandwich d(B, hull) ≤ d(B, mesh) ≤ d(B, hull) + margin against boxes and capsules.
void checkMeshHull(const TriangleMesh& mesh, unsigned seed) {
  const auto hull = convexHull(mesh);
  ASSERT_TRUE(hull);
  expectHullOf(*hull, mesh);
  const HullMargin m = hullMargin(*hull, mesh, 5e-4);
  std::mt19937 rng(seed);
  double worst = 0.0;
  for (int i = 0; i < 300; ++i) {
    worst = std::max(worst, bruteDistance(randomSurfacePoint(*hull, rng), mesh));
  }
  EXPECT_LE(worst, m.margin + 1e-12);
  EXPECT_LE(m.found, m.margin);

  const detail::CollisionShape exact = [&] {
    detail::CollisionShape s;
    s.geometry = detail::makeMeshModel(mesh);
    const auto box = mesh.bounds();
    s.centre_G = box.center();
    s.radius = 0.5 * box.sizes().norm();
    s.bounding_box =
        detail::Primitive{detail::Primitive::Kind::kBox, Isometry3d::Identity(), 0.5 * box.sizes()};
    s.bounding_box->X_W.translation() = box.center();
    return s;
  }();
  const detail::CollisionShape convex = detail::makeHullShape(exact, *hull);
  const double size = mesh.bounds().sizes().norm();
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int near = 0;
  for (int i = 0; i < 200; ++i) {
    kinematics::Shape probe;
    if (i % 2 == 0) {
      probe.geometry = kinematics::Box{Vector3d(0.02 + 0.05 * std::abs(u(rng)), 0.03, 0.04)};
    } else {
      probe.geometry = kinematics::Capsule{0.01 + 0.02 * std::abs(u(rng)), 0.05};
    }
    const detail::CollisionShape other = detail::makeCollisionShape(probe);
    Isometry3d X = Isometry3d::Identity();
    X.linear() = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
    X.translation() = mesh.bounds().center() + 0.8 * size * Vector3d(u(rng), u(rng), u(rng));
    const double d_mesh =
        detail::exactShapeDistance(exact, Isometry3d::Identity(), other, X).distance;
    const double d_hull =
        detail::shapeDistance(convex, Isometry3d::Identity(), other, X, 1e9, false).distance;
    EXPECT_LE(d_hull, d_mesh + 1e-6) << "probe " << i;
    if (d_hull > 0.0) {
      EXPECT_LE(d_mesh, d_hull + m.margin + 1e-6) << "probe " << i;
    }
    if (d_mesh < 0.05) ++near;
  }
  EXPECT_GT(near, 5) << "premise: probes near the mesh";
}

TEST(ConvexHull, TwoCubesDistancesSandwich) { checkMeshHull(twoCubes(0.1), 1); }

TEST(ConvexHull, ViperLinkMeshesDistancesSandwich) {
  for (int k : {2, 3}) {
    const fs::path file = kSharedData / ("robots/viper_s650/link" + std::to_string(k) + ".stl");
    if (!fs::exists(file)) GTEST_SKIP() << "shared test data absent: " << file;
    kinematics::MeshLoadOptions options;
    options.units = kinematics::LengthUnit::kMetre;
    checkMeshHull(kinematics::loadMesh(file, options).mesh, 10u + static_cast<unsigned>(k));
  }
}

}  // namespace
}  // namespace scanplan::collision
