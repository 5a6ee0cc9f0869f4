// Coverage on area (scanner/area_coverage.h): samples lie on the surface, each stands for the
// same area, and the covered fraction has known answers on a cube and a plate that do not depend
// on how the mesh is cut; the k-d tree agrees with a brute-force nearest point.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "geometry_support.h"

#include <scanplan/scanner/area_coverage.h>

namespace {

using Eigen::Vector3d;
using scanplan::kinematics::TriangleMesh;
using scanplan::scanner::areaCoverage;
using scanplan::scanner::AreaSampling;
using scanplan::scanner::sampleArea;

constexpr double kMm = 1e-3;
constexpr double kPi = 3.141592653589793;

// The square [0, a]² at z = 0 cut into n × n cells of two triangles each.
TriangleMesh plate(double a, int n) {
  TriangleMesh m;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) m.vertices.emplace_back(a * i / n, a * j / n, 0.0);
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int v = j * (n + 1) + i;
      m.triangles.emplace_back(v, v + 1, v + n + 2);
      m.triangles.emplace_back(v, v + n + 2, v + n + 1);
    }
  }
  return m;
}

// Points on a grid of pitch `h` over [x0, x1] × [y0, y1] at height z.
std::vector<Vector3d> grid(double x0, double x1, double y0, double y1, double z, double h) {
  std::vector<Vector3d> p;
  for (double y = y0; y <= y1 + 1e-12; y += h) {
    for (double x = x0; x <= x1 + 1e-12; x += h) p.emplace_back(x, y, z);
  }
  return p;
}

// Barycentric test: the sample lies in its triangle's plane and inside it (1 nm slack).
bool onTriangle(const TriangleMesh& m, const scanplan::scanner::AreaSample& s) {
  const auto& f = m.triangles[static_cast<std::size_t>(s.triangle)];
  const Vector3d a = m.vertices[static_cast<std::size_t>(f[0])];
  const Vector3d u = m.vertices[static_cast<std::size_t>(f[1])] - a;
  const Vector3d v = m.vertices[static_cast<std::size_t>(f[2])] - a;
  const Vector3d n = u.cross(v).normalized();
  const Vector3d w = s.p - a;
  if (std::abs(w.dot(n)) > 1e-9) return false;
  const double uu = u.dot(u), uv = u.dot(v), vv = v.dot(v), wu = w.dot(u), wv = w.dot(v);
  const double d = uu * vv - uv * uv;
  const double beta = (vv * wu - uv * wv) / d, gamma = (uu * wv - uv * wu) / d;
  return beta >= -1e-9 && gamma >= -1e-9 && beta + gamma <= 1.0 + 1e-9;
}

TEST(AreaSampling, SamplesLieOnTheirTrianglesAndSplitTheAreaEvenly) {
  const TriangleMesh m = scanplan::test::centredCube(10 * kMm);  // 600 mm²
  const AreaSampling s = sampleArea(m, 0.5 * kMm);
  EXPECT_NEAR(s.total_area, 600e-6, 1e-12);
  ASSERT_EQ(s.samples.size(), 2400u);  // 600 mm² / 0.25 mm²
  EXPECT_NEAR(s.area_per_sample * static_cast<double>(s.samples.size()), s.total_area, 1e-15);
  std::vector<int> per_triangle(m.triangles.size());
  for (const auto& a : s.samples) {
    ASSERT_TRUE(onTriangle(m, a));
    EXPECT_NEAR(a.n.norm(), 1.0, 1e-12);
    ++per_triangle[static_cast<std::size_t>(a.triangle)];
  }
  // Each triangle is 50 mm² = 200 samples; systematic sampling is off by at most one.
  for (const int n : per_triangle) EXPECT_NEAR(n, 200, 1);
}

TEST(AreaSampling, IsDeterministicAndHonoursTheCap) {
  const TriangleMesh m = scanplan::test::centredCube(10 * kMm);
  const AreaSampling a = sampleArea(m, 0.5 * kMm, 2'000'000, 7);
  const AreaSampling b = sampleArea(m, 0.5 * kMm, 2'000'000, 7);
  ASSERT_EQ(a.samples.size(), b.samples.size());
  for (std::size_t i = 0; i < a.samples.size(); ++i) ASSERT_EQ(a.samples[i].p, b.samples[i].p);
  const AreaSampling capped = sampleArea(m, 0.01 * kMm, 1000);  // 6 M wanted
  EXPECT_EQ(capped.samples.size(), 1000u);
  EXPECT_NEAR(capped.area_per_sample, 600e-6 / 1000, 1e-15);
  EXPECT_THROW(sampleArea(m, 0.0), std::invalid_argument);
  EXPECT_THROW(sampleArea(m, std::nan("")), std::invalid_argument);
}

TEST(AreaCoverage, TopFaceCoveredGivesItsAreaPlusTheRimWithinTheRadius) {
  // Points densely on the top face of a 10 mm cube, radius 0.5 mm: the top (100 mm²) and a
  // 0.5 mm strip at the top of each side (4 × 5 mm²) are covered: 120 / 600 = 0.2.
  const TriangleMesh m = scanplan::test::centredCube(10 * kMm);
  const AreaSampling s = sampleArea(m, 0.2 * kMm);
  const auto points = grid(-5 * kMm, 5 * kMm, -5 * kMm, 5 * kMm, 5 * kMm, 0.02 * kMm);
  const auto c = areaCoverage(s, points, 0.5 * kMm);
  // Sampling noise: 15 000 samples, binomial σ ≈ 0.0033; the grid pitch shifts the rim by < 2 %.
  EXPECT_NEAR(c.covered_fraction, 0.2, 0.012);
  // Every covered sample is on the top face or within the radius of it.
  for (std::size_t i = 0; i < s.samples.size(); ++i) {
    if (c.covered[i]) {
      EXPECT_GE(s.samples[i].p.z(), 4.5 * kMm - 1e-9);
    }
  }
}

TEST(AreaCoverage, NearestPointAgreesWithBruteForce) {
  const TriangleMesh m = scanplan::test::centredCube(10 * kMm);
  const AreaSampling s = sampleArea(m, 0.5 * kMm);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-6 * kMm, 6 * kMm);
  std::vector<Vector3d> points(3000);
  for (auto& p : points) p = Vector3d(u(rng), u(rng), u(rng));
  const double r = 1.0 * kMm;
  const auto c = areaCoverage(s, points, r);
  std::size_t covered = 0;
  for (std::size_t i = 0; i < s.samples.size(); ++i) {
    bool any = false;
    for (const auto& p : points) any = any || (p - s.samples[i].p).squaredNorm() <= r * r;
    ASSERT_EQ(c.covered[i] != 0, any) << "sample " << i;
    covered += any ? 1 : 0;
  }
  EXPECT_EQ(c.covered_samples, covered);
}

TEST(AreaCoverage, ALargeCloudSplitIntoSlabsFindsWhatBruteForceFinds) {
  // 350 000 points (several slabs, each with its own tree) scattered through the cube's box, a
  // radius they cover about half the samples with: which samples are covered and when, against
  // every point checked.
  const TriangleMesh m = scanplan::test::centredCube(10 * kMm);
  const AreaSampling s = sampleArea(m, 1.0 * kMm);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-6 * kMm, 6 * kMm), t(0.0, 100.0);
  std::vector<Vector3d> points(350000);
  std::vector<double> times(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    points[i] = Vector3d(u(rng), u(rng), u(rng));
    times[i] = t(rng);
  }
  const double r = 0.1 * kMm;
  const auto c = areaCoverage(s, points, r, &times);
  std::size_t covered = 0;
  for (std::size_t i = 0; i < s.samples.size(); ++i) {
    double first = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < points.size(); ++k)
      if ((points[k] - s.samples[i].p).squaredNorm() <= r * r) first = std::min(first, times[k]);
    const bool any = std::isfinite(first);
    ASSERT_EQ(c.covered[i] != 0, any) << "sample " << i;
    if (any) {
      ASSERT_EQ(c.first_time[i], first) << "sample " << i;
    }
    covered += any ? 1 : 0;
  }
  EXPECT_EQ(c.covered_samples, covered);
  EXPECT_GT(covered, s.samples.size() / 4);
  EXPECT_LT(covered, 3 * s.samples.size() / 4);
}

TEST(AreaCoverage, DoesNotDependOnHowTheMeshIsCut) {
  // Points over the left half of a 10 mm plate (radius 0.1 mm): half the area is covered,
  // whether the plate is 2 triangles or 800. A per-triangle count says 100 % on the 2-triangle
  // plate (both triangles have points).
  const auto points = grid(0.0, 5 * kMm, 0.0, 10 * kMm, 0.0, 0.05 * kMm);
  for (const int n : {1, 20}) {
    const TriangleMesh m = plate(10 * kMm, n);
    const auto c = areaCoverage(sampleArea(m, 0.1 * kMm), points, 0.1 * kMm);
    EXPECT_NEAR(c.covered_fraction, 0.51, 0.01) << n << " x " << n << " cells";  // 5.1 of 10 mm
  }
}

TEST(AreaCoverage, NoPointsCoverNothing) {
  const AreaSampling s = sampleArea(scanplan::test::centredCube(10 * kMm), 1 * kMm);
  const auto c = areaCoverage(s, {}, 1 * kMm);
  EXPECT_EQ(c.covered_samples, 0u);
  EXPECT_EQ(c.covered_fraction, 0.0);
  EXPECT_EQ(c.covered.size(), s.samples.size());
}

// The cube resting on the table (its centre 5 mm up): exactly the samples of its bottom face
// (triangles 0 and 1: the vertices with z < 0) face the table; the sides and the top do not.
TEST(FacesTable, ACubeOnTheTableFacesItWithExactlyItsBottom) {
  const TriangleMesh m = scanplan::test::centredCube(10 * kMm);
  const AreaSampling s = sampleArea(m, 0.5 * kMm);
  const Eigen::Isometry3d X_RP(Eigen::Translation3d(0.0, 0.0, 5 * kMm));
  const auto faces = scanplan::scanner::facesTable(s, X_RP, 60.0 * kPi / 180.0, 0.2);
  std::size_t flagged = 0;
  for (std::size_t i = 0; i < s.samples.size(); ++i) {
    const bool bottom = s.samples[i].triangle <= 1;
    ASSERT_EQ(faces[i] != 0, bottom) << "sample " << i << " on triangle " << s.samples[i].triangle;
    flagged += faces[i];
  }
  EXPECT_NEAR(static_cast<double>(flagged), 400.0, 2.0);  // the bottom's 100 of 600 mm²
}

// A face looking 70° below the horizon (n_z = −sin 70°) is seen from at most 10° below it with a
// 60° incidence limit: from 196 mm away the scanner is 34 mm lower than the face. At 100 mm above
// the table that is fine; at 20 mm the scanner would be under the table top.
TEST(FacesTable, ADownwardFaceIsReachableOnlyHighEnoughAboveTheTable) {
  const double tilt = 70.0 * kPi / 180.0;
  // A 1 mm square at the origin with normal (cos 70°, 0, −sin 70°) (rotated about y).
  TriangleMesh m = plate(1 * kMm, 1);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(kPi - (kPi / 2 - tilt), Eigen::Vector3d::UnitY()).toRotationMatrix();
  for (auto& v : m.vertices) v = R * v;
  const AreaSampling s = sampleArea(m, 0.1 * kMm);
  ASSERT_NEAR(s.samples.front().n.z(), -std::sin(tilt), 1e-12);
  const auto at = [&](double z_mm) {
    const Eigen::Isometry3d X_RP(Eigen::Translation3d(0.0, 0.0, z_mm * kMm));
    const auto f = scanplan::scanner::facesTable(s, X_RP, 60.0 * kPi / 180.0, 0.196);
    return std::count(f.begin(), f.end(), 1);
  };
  EXPECT_EQ(at(100.0), 0);                                   // 100 − 34 > 0
  EXPECT_EQ(at(20.0), static_cast<long>(s.samples.size()));  // 20 − 34 < 0
}

}  // namespace
