// The closed-form primitive distances (collision/primitive_distance) against plain
// fcl::distance on randomized pairs: every pair kind, separated, close and overlapping. Exact
// forms agree to 1e-9 m; the cylinder pairs that are only bounded never exceed FCL's distance.
#include <scanplan/collision/primitive_distance.h>

#include <gtest/gtest.h>

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/narrowphase/distance.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>

namespace scanplan::collision::detail {
namespace {

using Kind = Primitive::Kind;

// FCL's GJK runs here to 1e-12 m (its default, 1e-6 m, is what the clearance query uses); its
// closed forms (capsule–capsule) are exact. 1e-9 m is the agreement bound.
constexpr double kAgree = 1e-9;

std::shared_ptr<fcl::CollisionGeometryd> fclShape(const Primitive& p) {
  switch (p.kind) {
    case Kind::kCapsule:
      return std::make_shared<fcl::Capsuled>(p.radius(), 2.0 * p.halfLength());
    case Kind::kCylinder:
      return std::make_shared<fcl::Cylinderd>(p.radius(), 2.0 * p.halfLength());
    case Kind::kBox:
      return std::make_shared<fcl::Boxd>(2.0 * p.half);
  }
  return nullptr;
}

double fclDistance(const Primitive& a,
                   const Primitive& b,
                   fcl::GJKSolverType solver,
                   double tolerance = 1e-12) {
  fcl::DistanceRequestd request;
  request.distance_tolerance = tolerance;
  request.gjk_solver_type = solver;
  fcl::DistanceResultd result;
  const auto ga = fclShape(a), gb = fclShape(b);
  fcl::distance(ga.get(), fcl::Transform3d(a.X_W.matrix()), gb.get(),
                fcl::Transform3d(b.X_W.matrix()), request, result);
  return std::max(result.min_distance, 0.0);
}

// GJK's answer is the distance of witness points, never below the true distance; either of
// FCL's two solvers stops early on some pairs (libccd ~1e-8 m on capsule–box, FCL's own GJK
// by up to 0.4 mm on box–box), so the reference is the better of the two.
double fclDistance(const Primitive& a, const Primitive& b) {
  return std::min(fclDistance(a, b, fcl::GST_LIBCCD), fclDistance(a, b, fcl::GST_INDEP));
}

Primitive randomPrimitive(Kind kind, std::mt19937& rng, double spread) {
  std::uniform_real_distribution<double> size(0.01, 0.15), pos(-spread, spread), unit(-1, 1);
  Primitive p;
  p.kind = kind;
  Eigen::Quaterniond q(unit(rng), unit(rng), unit(rng), unit(rng));
  p.X_W.linear() = q.normalized().toRotationMatrix();
  p.X_W.translation() = Eigen::Vector3d(pos(rng), pos(rng), pos(rng));
  if (kind == Kind::kBox) {
    p.half = Eigen::Vector3d(size(rng), size(rng), size(rng));
  } else {
    const double r = size(rng) * 0.6;
    // One in five capsules is a sphere (zero length), as scanplan builds spheres.
    const double h = kind == Kind::kCapsule && rng() % 5 == 0 ? 0.0 : size(rng);
    p.half = Eigen::Vector3d(r, r, h);
  }
  return p;
}

// How far p lies outside the solid primitive (0 on or inside it).
double onShape(const Primitive& p, const Eigen::Vector3d& x) {
  switch (p.kind) {
    case Kind::kCapsule:
      return std::max(0.0, std::sqrt(segmentSegmentSq(p.end(-1), p.end(1), x, x)) - p.radius());
    case Kind::kCylinder:
      return pointCylinder(x, p);
    case Kind::kBox:
      return pointBox(x, p);
  }
  return 0.0;
}

void checkPairs(Kind ka, Kind kb) {
  std::mt19937 rng(static_cast<unsigned>(31 * static_cast<int>(ka) + static_cast<int>(kb)));
  int separated = 0, touching = 0;
  for (int k = 0; k < 3000; ++k) {
    const double spread = k % 3 == 0 ? 0.1 : 0.4;  // a third close enough to overlap often
    const Primitive a = randomPrimitive(ka, rng, spread), b = randomPrimitive(kb, rng, spread);
    const PrimitiveDistance d = primitiveDistance(a, b), swapped = primitiveDistance(b, a);
    const double reference = fclDistance(a, b);
    ASSERT_EQ(d.exact, swapped.exact);
    ASSERT_NEAR(d.distance, swapped.distance, 1e-12);
    if (d.exact) {
      ASSERT_NEAR(d.distance, reference, kAgree) << "pair " << k;
      // The witness points lie on their shapes and are the distance apart.
      ASSERT_NEAR((d.p_a - d.p_b).norm(), d.distance, reference > 0.0 ? 1e-12 : 1e9);
      ASSERT_LE(onShape(a, d.p_a), 1e-12);
      ASSERT_LE(onShape(b, d.p_b), 1e-12);
    } else {
      ASSERT_LE(d.distance, reference + kAgree) << "pair " << k;
    }
    (reference > 0.0 ? separated : touching)++;
  }
  EXPECT_GT(separated, 1000);  // both regimes are exercised
  EXPECT_GT(touching, 100);
}

TEST(PrimitiveDistance, CapsulesAndSpheresAgreeWithFcl) {
  checkPairs(Kind::kCapsule, Kind::kCapsule);
}
TEST(PrimitiveDistance, CapsuleAndBoxAgreeWithFcl) { checkPairs(Kind::kCapsule, Kind::kBox); }
TEST(PrimitiveDistance, CapsuleAndCylinderAgreeWithFcl) {
  checkPairs(Kind::kCapsule, Kind::kCylinder);
}
TEST(PrimitiveDistance, BoxesAgreeWithFcl) { checkPairs(Kind::kBox, Kind::kBox); }
TEST(PrimitiveDistance, CylinderAndBoxBoundFclFromBelow) {
  checkPairs(Kind::kCylinder, Kind::kBox);
}
TEST(PrimitiveDistance, CylindersBoundFclFromBelow) {
  checkPairs(Kind::kCylinder, Kind::kCylinder);
}

// A flat cylinder, as a rotary table's top, under boxes and tilted cylinders: its enclosing
// capsule would bulge its radius above the cap, so the bound would be 0; the cap's plane gives
// the exact gap (the lowest corner's height above the cap, the shapes being within the rim),
// and the bound never exceeds FCL's distance.
TEST(PrimitiveDistance, AFlatCylinderIsBoundedByItsCapNotItsCapsule) {
  Primitive table;
  table.kind = Kind::kCylinder;
  table.half = {0.25, 0.25, 0.01};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> xy(-0.08, 0.08), z(0.08, 0.2);
  for (int k = 0; k < 500; ++k) {
    Primitive box = randomPrimitive(Kind::kBox, rng, 0.0);
    box.half = box.half.cwiseMin(0.05);
    box.X_W.translation() = Eigen::Vector3d(xy(rng), xy(rng), z(rng));
    double lowest = 1e9;
    for (int i = 0; i < 8; ++i) {
      const Eigen::Vector3d s((i & 1) ? 1.0 : -1.0, (i & 2) ? 1.0 : -1.0, (i & 4) ? 1.0 : -1.0);
      lowest = std::min(lowest, (box.X_W * s.cwiseProduct(box.half)).z());
    }
    const PrimitiveDistance d = primitiveDistance(table, box);
    ASSERT_FALSE(d.exact);
    ASSERT_NEAR(d.distance, std::max(lowest - 0.01, 0.0), 1e-12) << "box " << k;
    ASSERT_LE(d.distance, fclDistance(table, box) + kAgree);
    Primitive tilted = randomPrimitive(Kind::kCylinder, rng, 0.0);
    tilted.half = tilted.half.cwiseMin(0.04);
    tilted.X_W.translation() = box.X_W.translation();
    ASSERT_LE(primitiveDistance(table, tilted).distance, fclDistance(table, tilted) + kAgree);
  }
}

// Known answers, independent of FCL: a sphere beside a cylinder's side, over its cap and off
// its rim; a segment parallel to a box face; two boxes corner to corner.
TEST(PrimitiveDistance, KnownAnswers) {
  Primitive cyl;
  cyl.kind = Kind::kCylinder;
  cyl.half = {0.1, 0.1, 0.2};
  EXPECT_NEAR(pointCylinder({0.3, 0, 0}, cyl), 0.2, 1e-15);
  EXPECT_NEAR(pointCylinder({0.05, 0, 0.5}, cyl), 0.3, 1e-15);
  EXPECT_NEAR(pointCylinder({0.4, 0, 0.6}, cyl), 0.5, 1e-15);  // 3-4-5 off the rim
  EXPECT_NEAR(segmentCylinder({0.3, -1, 0.1}, {0.3, 1, 0.1}, cyl), 0.2, 1e-12);
  EXPECT_NEAR(segmentCylinder({-1, 0, 0}, {1, 0, 0}, cyl), 0.0, 1e-12);  // through it
  Primitive box;
  box.kind = Kind::kBox;
  box.half = {0.1, 0.2, 0.3};
  EXPECT_NEAR(segmentBox({-1, 0, 0.35}, {1, 0, 0.35}, box), 0.05, 1e-15);
  Primitive other = box;
  other.X_W.translation() = Eigen::Vector3d(0.2 + 0.03, 0.4 + 0.04, 0.6);
  EXPECT_NEAR(boxBox(box, other), 0.05, 1e-15);
}

// FCL 0.7's libccd GJK at its default tolerance (1e-6 m) puts this capsule (link 4 of the
// bundled Viper) 39.5 mm from this cylinder (its flange); both are 2.9 mm apart, as a dense
// walk along the capsule's axis confirms. The closed form gets it right; so does FCL's own GJK
// solver, and libccd at a 1e-12 m tolerance. Found by the map benchmark's old-path comparison.
TEST(PrimitiveDistance, APoseWhereLibccdIsWrongByCentimetres) {
  Eigen::Matrix4d A, B;
  A << 0.4097345014060102, -0.89637734380254896, 0.16919011754548496, 0.50263166920203717,
      -0.070337047182894769, 0.15387655984147247, 0.98558343336571208, -0.086284233597523144,
      -0.90948905334322716, -0.41572786994480015, 6.123233995736766e-17, 0.36273644630419494, 0, 0,
      0, 1;
  B << -0.74314482547739424, -0.66913060635885813, -2.1168469813005917e-16, 0.50263166920203717,
      -0.66913060635885813, 0.74314482547739424, 1.4361630669508566e-16, -0.08628423359752313,
      6.9596780082808331e-18, 2.0659756026588462e-16, -1, 0.28273644630419492, 0, 0, 0, 1;
  Primitive capsule;  // from (0, 90, 0) to (0, 40, 0) mm in link 4's frame, radius 42 mm
  capsule.half = {0.042, 0.042, 0.025};
  capsule.X_W = Eigen::Isometry3d(A);
  capsule.X_W.translate(Eigen::Vector3d(0, 0.065, 0));
  capsule.X_W.rotate(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()));
  Primitive cylinder;  // from (0, 0, -16) to (0, 0, 0) mm in the flange frame, radius 32 mm
  cylinder.kind = Kind::kCylinder;
  cylinder.half = {0.032, 0.032, 0.008};
  cylinder.X_W = Eigen::Isometry3d(B);
  cylinder.X_W.translate(Eigen::Vector3d(0, 0, -0.008));
  double walk = 1e9;
  for (int i = 0; i <= 200000; ++i) {
    const double s = i / 200000.0;
    walk = std::min(walk, pointCylinder((1 - s) * capsule.end(-1) + s * capsule.end(1), cylinder));
  }
  const double closed = primitiveDistance(capsule, cylinder).distance;
  EXPECT_NEAR(closed, walk - 0.042, 1e-9);
  EXPECT_NEAR(closed, 0.002904, 1e-6);
  EXPECT_NEAR(fclDistance(capsule, cylinder, fcl::GST_INDEP), closed, 1e-7);
  // The bug, as of FCL 0.7, at the default tolerance scanplan's clearance query used (1e-6 m):
  EXPECT_GT(
      fclDistance(capsule, cylinder, fcl::GST_LIBCCD, fcl::DistanceRequestd().distance_tolerance),
      0.03);
}

}  // namespace
}  // namespace scanplan::collision::detail
