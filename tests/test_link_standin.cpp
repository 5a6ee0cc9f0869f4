// Convex pieces standing in for a link mesh: on an L-shaped block, whose distance is known in
// closed form (the nearer of two boxes), the pieces hold the block, points of their surfaces lie
// within the certified margin of it, and distances to them sit between the block's distance
// minus that margin and the block's distance; the cache gives back the same pieces to the bit,
// and refuses another mesh's or a damaged file.

#include <scanplan/collision/link_standin.h>

#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

#include <scanplan/collision/fcl_geometry.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/shape.h>
#include "geometry_support.h"

namespace scanplan::collision {
namespace {

namespace fs = std::filesystem;
using Eigen::Isometry3d;
using Eigen::Vector3d;
using kinematics::TriangleMesh;

constexpr double kArm = 0.10, kThick = 0.03, kHeight = 0.05;  // m

// The L profile (arms kArm long, kThick thick) extruded kHeight up: closed, outward.
TriangleMesh lBlock() {
  const std::vector<Eigen::Vector2d> profile = {{0, 0},           {kArm, 0},      {kArm, kThick},
                                                {kThick, kThick}, {kThick, kArm}, {0, kArm}};
  TriangleMesh mesh;
  const int n = static_cast<int>(profile.size());
  for (double z : {0.0, kHeight}) {
    for (const auto& p : profile) mesh.vertices.emplace_back(p.x(), p.y(), z);
  }
  for (int i = 1; i + 1 < n; ++i) {  // a fan from the corner at the origin sees every vertex
    mesh.triangles.emplace_back(0, i + 1, i);          // bottom, facing down
    mesh.triangles.emplace_back(n, n + i, n + i + 1);  // top, facing up
  }
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    mesh.triangles.emplace_back(i, j, n + j);
    mesh.triangles.emplace_back(i, n + j, n + i);
  }
  return mesh;
}

double boxDistance(const Vector3d& p, const Vector3d& lo, const Vector3d& hi) {
  return (lo - p).cwiseMax(p - hi).cwiseMax(0.0).norm();
}

// Distance from a point to the L block's solid, in closed form (0 inside).
double lDistance(const Vector3d& p) {
  return std::min(boxDistance(p, Vector3d::Zero(), Vector3d(kArm, kThick, kHeight)),
                  boxDistance(p, Vector3d::Zero(), Vector3d(kThick, kArm, kHeight)));
}

// A uniformly random point of a random triangle of the mesh.
Vector3d randomSurfacePoint(const TriangleMesh& mesh, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Eigen::Vector3i& t = mesh.triangles[rng() % mesh.triangles.size()];
  double a = u(rng), b = u(rng);
  if (a + b > 1.0) a = 1.0 - a, b = 1.0 - b;
  const Vector3d& p = mesh.vertices[static_cast<std::size_t>(t[0])];
  return p + a * (mesh.vertices[static_cast<std::size_t>(t[1])] - p) +
         b * (mesh.vertices[static_cast<std::size_t>(t[2])] - p);
}

TEST(LinkStandIn, ALooseMarginTakesTheHullAndNeverUnderstatesIt) {
  const TriangleMesh mesh = lBlock();
  EXPECT_TRUE(mesh.isClosed());
  EXPECT_NEAR(mesh.signedVolume(), (2 * kArm * kThick - kThick * kThick) * kHeight, 1e-15);
  // The hull's margin is known: the midpoint of its face across the inner corner lies
  // (kArm - kThick) / 2 from both arms. A 50 mm margin takes the hull, its bound at or above that.
  StandInOptions loose;
  loose.margin = 0.05;
  const StandIn hull = fitStandIn(mesh, loose);
  EXPECT_TRUE(hull.fits);
  EXPECT_EQ(hull.pieces.size(), 1u);
  EXPECT_GE(hull.margin, 0.5 * (kArm - kThick) - 1e-9);
  EXPECT_LE(hull.margin, loose.margin);
}

TEST(LinkStandIn, OverTheBudgetItSaysSo) {
  StandInOptions one;
  one.max_pieces = 1;
  const StandIn s = fitStandIn(lBlock(), one);
  EXPECT_FALSE(s.fits);
  EXPECT_GT(s.pieces.size(), 1u) << "an L needs two";
}

TEST(LinkStandIn, PiecesHoldTheBlockWithinTheMargin) {
  const TriangleMesh mesh = lBlock();
  StandInOptions options;
  const StandIn s = fitStandIn(mesh, options);
  ASSERT_TRUE(s.fits);
  EXPECT_GE(s.pieces.size(), 2u);
  EXPECT_LE(s.pieces.size(), 8u) << "an L is two boxes";
  EXPECT_LE(s.margin, options.margin);
  std::mt19937 rng(3);
  double worst = 0.0;
  for (const TriangleMesh& piece : s.pieces) {
    EXPECT_TRUE(piece.isClosed());
    EXPECT_GT(piece.signedVolume(), 0.0) << "outward";
    for (int k = 0; k < 200; ++k) {
      const Vector3d p = randomSurfacePoint(piece, rng);
      worst = std::max(worst, lDistance(p));
    }
  }
  EXPECT_LE(worst, s.margin + 1e-12);
  // Points all over the block's surface lie in some piece (the pieces hold its surface).
  const auto held = [&](const Vector3d& v) {
    for (const TriangleMesh& piece : s.pieces) {
      bool inside = true;
      for (const Eigen::Vector3i& t : piece.triangles) {
        const Vector3d& a = piece.vertices[static_cast<std::size_t>(t[0])];
        const Vector3d n = (piece.vertices[static_cast<std::size_t>(t[1])] - a)
                               .cross(piece.vertices[static_cast<std::size_t>(t[2])] - a);
        inside = inside && n.dot(v - a) <= 1e-9 * n.norm();
      }
      if (inside) return true;
    }
    return false;
  };
  for (int k = 0; k < 2000; ++k) {
    const Vector3d p = randomSurfacePoint(mesh, rng);
    ASSERT_TRUE(held(p)) << p.transpose();
  }
}

// The distance sandwich against boxes and capsules placed at random around the block:
// d(B, pieces) ≤ d(B, block) ≤ d(B, pieces) + margin.
TEST(LinkStandIn, DistancesSitWithinTheMarginBelowTheBlocks) {
  const TriangleMesh mesh = lBlock();
  const StandIn s = fitStandIn(mesh, {});
  ASSERT_TRUE(s.fits);
  detail::CollisionShape exact;
  exact.geometry = detail::makeMeshModel(mesh);
  std::vector<detail::CollisionShape> pieces;
  for (const TriangleMesh& piece : s.pieces) pieces.push_back(detail::makeHullShape(exact, piece));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int near = 0;
  for (int i = 0; i < 300; ++i) {
    kinematics::Shape probe;
    if (i % 2 == 0) {
      probe.geometry = kinematics::Box{Vector3d(0.01 + 0.02 * std::abs(u(rng)), 0.015, 0.02)};
    } else {
      probe.geometry = kinematics::Capsule{0.004 + 0.01 * std::abs(u(rng)), 0.02};
    }
    const detail::CollisionShape other = detail::makeCollisionShape(probe);
    Isometry3d X = Isometry3d::Identity();
    X.linear() = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
    X.translation() =
        Vector3d(0.05, 0.05, 0.025) + Vector3d(0.09 * u(rng), 0.09 * u(rng), 0.06 * u(rng));
    const double d_mesh =
        detail::exactShapeDistance(exact, Isometry3d::Identity(), other, X).distance;
    double d_pieces = std::numeric_limits<double>::infinity();
    for (const auto& p : pieces) {
      d_pieces =
          std::min(d_pieces,
                   detail::shapeDistance(p, Isometry3d::Identity(), other, X, 1e9, false).distance);
    }
    EXPECT_LE(d_pieces, d_mesh + 1e-6) << "probe " << i;
    if (d_mesh > 0.0) {
      EXPECT_LE(d_mesh, d_pieces + s.margin + 1e-6) << "probe " << i;
    }
    if (d_mesh > 0.0 && d_mesh < 0.02) ++near;
  }
  EXPECT_GT(near, 20) << "premise: probes near the block, outside it";
}

// Whether p lies inside the convex piece (on the inner side of every face, as its centroid).
bool insideConvex(const TriangleMesh& piece, const Vector3d& p) {
  Vector3d centroid = Vector3d::Zero();
  for (const Vector3d& v : piece.vertices) centroid += v;
  centroid /= static_cast<double>(piece.vertices.size());
  for (const Eigen::Vector3i& t : piece.triangles) {
    const Vector3d& a = piece.vertices[static_cast<std::size_t>(t[0])];
    const Vector3d n = (piece.vertices[static_cast<std::size_t>(t[1])] - a)
                           .cross(piece.vertices[static_cast<std::size_t>(t[2])] - a);
    if (n.dot(p - a) * n.dot(centroid - a) < 0.0) return false;
  }
  return true;
}

// A probe about the L block: a box or a capsule at a world pose.
struct Probe {
  detail::CollisionShape shape;
  Isometry3d X = Isometry3d::Identity();
  bool box = false;
};

// `count` probes for each piece of the L block's stand-in, alternately capsules and boxes; each
// `aligned` with the block's faces (unturned, or turned a quarter about x) or turned at random.
// Calls visit(hull, distance to the piece's triangles with witness points, probe, index) for the
// probes outside the piece (centre outside it, more than `least` from its triangles); returns
// how many.
template <class Visit>
int probesOutsideThePieces(unsigned seed, int count, bool aligned, double least, Visit&& visit) {
  const TriangleMesh mesh = lBlock();
  const StandIn s = fitStandIn(mesh, {});
  EXPECT_TRUE(s.fits);
  detail::CollisionShape exact;
  exact.geometry = detail::makeMeshModel(mesh);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int visited = 0;
  for (const TriangleMesh& piece : s.pieces) {
    const detail::CollisionShape hull = detail::makeHullShape(exact, piece);
    detail::CollisionShape triangles;
    triangles.geometry = detail::makeMeshModel(piece);
    for (int i = 0; i < count; ++i) {
      Probe probe;
      probe.box = i % 2 == 1;
      kinematics::Shape shape;
      if (probe.box) {
        shape.geometry = kinematics::Box{Vector3d(0.01 + 0.03 * std::abs(u(rng)), 0.012, 0.02)};
      } else {
        shape.geometry = kinematics::Capsule{0.002 + 0.006 * std::abs(u(rng)), 0.03};
      }
      probe.shape = detail::makeCollisionShape(shape);
      if (!aligned) {
        probe.X.linear() = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
      } else if (i % 4 == 3) {
        probe.X.linear() = Eigen::AngleAxisd(0.5 * M_PI, Vector3d::UnitX()).matrix();
      }
      probe.X.translation() =
          Vector3d(0.05, 0.05, 0.025) + Vector3d(0.09 * u(rng), 0.09 * u(rng), 0.06 * u(rng));
      if (insideConvex(piece, probe.X.translation())) continue;  // the solid reads 0, its skin more
      const detail::ShapeDistance d =
          detail::exactShapeDistance(triangles, Isometry3d::Identity(), probe.shape, probe.X);
      if (!(d.distance > least)) continue;
      visit(hull, d, probe, i);
      ++visited;
    }
  }
  return visited;
}

// A piece's distance (GJK on its convex hull: FCL's where it certifies itself, else the shorter
// of FCL's and libccd's) is the distance to its own triangles: never farther, and no shorter
// than libccd's tolerance; asked with a bound below it, beyond, with a lower bound no more than
// the distance. Boxes with faces parallel to the pieces' (where FCL's GJK alone can stop short)
// and capsules along the block's edges.
TEST(LinkStandIn, PieceDistancesMatchTheirTrianglesOnAlignedProbes) {
  const int measured = probesOutsideThePieces(
      11, 150, true, 0.0,
      [](const detail::CollisionShape& hull, const detail::ShapeDistance& d, const Probe& probe,
         int i) {
        const double d_hull =
            detail::shapeDistance(hull, Isometry3d::Identity(), probe.shape, probe.X, 1e9, false)
                .distance;
        EXPECT_LE(d_hull, d.distance + 1e-9) << "probe " << i;
        EXPECT_GE(d_hull, d.distance - 2e-5) << "probe " << i;
        // Bounded below the distance: beyond, with a lower bound between the two.
        const double bound = 0.5 * d.distance;
        const detail::ShapeDistance beyond =
            detail::shapeDistance(hull, Isometry3d::Identity(), probe.shape, probe.X, bound, false);
        EXPECT_TRUE(beyond.beyond) << "probe " << i;
        EXPECT_GE(beyond.lower, bound) << "probe " << i;
        EXPECT_LE(beyond.lower, d.distance + 1e-9) << "probe " << i;
      });
  EXPECT_GT(measured, 200) << "premise: probes outside the pieces";
}

// The separation along any direction is a lower bound on the distance, and along the direction
// of the nearest points it is the distance: the certificate GJK's convex answers are checked
// against. On the L block's pieces, boxes and capsules at random poses, by the distance to the
// pieces' triangles.
TEST(LinkStandIn, SeparationBoundsTheDistanceAndMeetsItAlongTheNearestPoints) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int measured = probesOutsideThePieces(
      13, 100, false, 1e-4,
      [&](const detail::CollisionShape& hull, const detail::ShapeDistance& d, const Probe& probe,
          int i) {
        const auto along = [&](const Vector3d& n) {
          return detail::separationAlong(hull, Isometry3d::Identity(), probe.shape, probe.X, n);
        };
        for (int k = 0; k < 5; ++k)
          EXPECT_LE(along(Vector3d(u(rng), u(rng), u(rng))), d.distance + 1e-9) << "probe " << i;
        // Equal along the nearest points where the reference is exact: boxes, walked in the
        // box's frame (for capsules it is libccd's GJK at the triangles: its witnesses stray).
        if (probe.box) {
          EXPECT_NEAR(along(d.p_b - d.p_a), d.distance, 1e-7) << "probe " << i;
        }
      });
  EXPECT_GT(measured, 100) << "premise: probes outside the pieces";
  detail::CollisionShape mesh;
  mesh.geometry = detail::makeMeshModel(lBlock());
  EXPECT_THROW(detail::separationAlong(mesh, Isometry3d::Identity(), mesh, Isometry3d::Identity(),
                                       Vector3d::UnitX()),
               std::invalid_argument);
}

TEST(LinkStandIn, ConvexMeshIsOnePiece) {
  const StandIn s = fitStandIn(test::centredCube(0.1), {});
  EXPECT_TRUE(s.fits);
  EXPECT_EQ(s.pieces.size(), 1u);
  EXPECT_EQ(s.vertices, 8u);
}

// A round mesh (a disk tessellated within 0.1 mm, tilted off the axes) stands in as the
// cylinder about its own axis: it holds every vertex, and its margin is certified within the
// 2 mm asked and no less than its prism's corners stand out; about an axis 10 mm off, or for a
// cube, it stands farther out than that.
TEST(LinkStandIn, ARoundMeshStandsInAsACylinderAboutItsAxis) {
  kinematics::Shape disk;
  disk.geometry = kinematics::Cylinder{0.03, 0.02};
  disk.X_BG = Isometry3d(Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()));
  disk.X_BG.translation() = Vector3d(0.01, -0.02, 0.05);
  const TriangleMesh mesh = kinematics::shapeSurface(disk);
  const Vector3d o = disk.X_BG.translation(), u = disk.X_BG.linear().col(2);
  const auto c = axisCylinder(mesh, o, u, 2.5e-4, 0.002);
  ASSERT_TRUE(c);
  EXPECT_NEAR(c->radius, 0.03, 1e-9);
  EXPECT_NEAR(c->length, 0.02, 1e-9);
  for (const Vector3d& v : mesh.vertices) {
    const Vector3d local = c->X_MC.inverse() * v;
    EXPECT_LE(local.head<2>().norm(), c->radius + 1e-12);
    EXPECT_LE(std::abs(local.z()), 0.5 * c->length + 1e-12);
  }
  // The prism's corners lie this far outside the circle, so outside the disk's solid.
  const double corners = 0.03 / std::cos(std::numbers::pi / kCylinderSides) - 0.03;
  EXPECT_GE(c->margin, corners - 1e-12);
  EXPECT_LE(c->margin, 0.002);
  const Vector3d off = u.unitOrthogonal();
  const auto shifted = axisCylinder(mesh, o + 0.01 * off, u, 2.5e-4, 0.002);
  ASSERT_TRUE(shifted);
  EXPECT_GT(shifted->margin, 0.002);
  const auto cube =
      axisCylinder(test::centredCube(0.04), Vector3d::Zero(), Vector3d::UnitZ(), 2.5e-4, 0.002);
  ASSERT_TRUE(cube);
  EXPECT_NEAR(cube->radius, 0.02 * std::sqrt(2.0), 1e-12);
  EXPECT_GT(cube->margin, 0.002);  // its rim stands 8.3 mm out beside the faces
}

TEST(LinkStandIn, TheCacheGivesBackTheSamePiecesAndRefusesOthers) {
  const TriangleMesh mesh = lBlock();
  const StandInOptions options;
  const StandIn fitted = fitStandIn(mesh, options);
  const std::string key = standInKey(mesh, options);
  const fs::path dir = fs::temp_directory_path() / ("scanplan_standin_" + std::to_string(getpid()));
  fs::remove_all(dir);
  const fs::path file = dir / "cache" / (key + ".pieces");
  EXPECT_FALSE(loadStandIn(file, key)) << "absent";
  ASSERT_TRUE(saveStandIn(file, key, fitted));
  const auto loaded = loadStandIn(file, key);
  ASSERT_TRUE(loaded);
  EXPECT_EQ(loaded->margin, fitted.margin);
  EXPECT_EQ(loaded->fits, fitted.fits);
  ASSERT_EQ(loaded->pieces.size(), fitted.pieces.size());
  for (std::size_t i = 0; i < fitted.pieces.size(); ++i) {
    EXPECT_EQ(loaded->pieces[i].vertices, fitted.pieces[i].vertices) << "piece " << i;
    EXPECT_EQ(loaded->pieces[i].triangles, fitted.pieces[i].triangles) << "piece " << i;
  }
  // Another mesh (one vertex moved), other settings: other keys, so the file is not theirs.
  TriangleMesh changed = mesh;
  changed.vertices[1].x() += 1e-6;
  EXPECT_NE(standInKey(changed, options), key);
  StandInOptions looser;
  looser.margin = 0.005;
  EXPECT_NE(standInKey(mesh, looser), key);
  EXPECT_FALSE(loadStandIn(file, standInKey(changed, options)));
  // A damaged file is refused, whatever the damage.
  std::string text;
  {
    std::ifstream in(file);
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  for (const std::string& damaged :
       {text.substr(0, text.size() / 2), text + "1 2 3\n", std::string("garbage"),
        text.substr(0, text.find('\n') + 1) + "nan 1 1\n"}) {
    std::ofstream(file, std::ios::trunc) << damaged;
    EXPECT_FALSE(loadStandIn(file, key)) << damaged.substr(0, 60);
  }
  fs::remove_all(dir);
}

TEST(LinkStandIn, FittingIsDeterministic) {
  const StandIn a = fitStandIn(lBlock(), {});
  const StandIn b = fitStandIn(lBlock(), {});
  ASSERT_EQ(a.pieces.size(), b.pieces.size());
  for (std::size_t i = 0; i < a.pieces.size(); ++i)
    EXPECT_EQ(a.pieces[i].vertices, b.pieces[i].vertices);
  EXPECT_EQ(a.margin, b.margin);
}

}  // namespace
}  // namespace scanplan::collision
