// Scan paths and the scanner model: Eq. 5 (laser window) and Eq. 4 (triangulation) against hand
// values, Embree against a brute-force ray–triangle loop, the path generators (ring, raster,
// waypoints, file) against the geometry they promise, and the job-level errors of `scan`.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/config/job.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/scan_path.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/scanner/laser_model.h>
#include <scanplan/scanner/path_generators.h>
#include <scanplan/scanner/raycaster.h>
#include "tests/test_support.h"

extern char** environ;

namespace {

namespace fs = std::filesystem;
using namespace scanplan;
using kinematics::ScanPath;
using kinematics::ScanSample;
using kinematics::TriangleMesh;

// Hand values below carry 7–8 significant digits; the products are a few flops of O(0.1 m).
constexpr double kHandTol = 1e-9;  // m
// Embree stores vertices and rays in float: ~6e-8 relative on coordinates of ~0.5 m.
constexpr double kEmbreeTol = 1e-5;  // m
// A brute-force hit this close (in barycentric units) to a triangle edge may fall either way
// in float: such rays are skipped rather than compared.
constexpr double kEdgeMargin = 1e-5;

// ---------------------------------------------------------------------------------------------
// Meshes and a brute-force ray cast.

// A box [lo, hi] with every face split into n × n quads (2 triangles each), counter-clockwise
// seen from outside. Face corners are not welded (ray casting does not care).
void appendBox(TriangleMesh& mesh, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int n) {
  const Eigen::Vector3d d = hi - lo;
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX() * d.x(), Y = Eigen::Vector3d::UnitY() * d.y(),
                        Z = Eigen::Vector3d::UnitZ() * d.z();
  struct Face {
    Eigen::Vector3d corner, u, v;  // u × v points outward
  };
  const Face faces[] = {{lo, Z, Y},     {lo + X, Y, Z}, {lo, X, Z},
                        {lo + Y, Z, X}, {lo, Y, X},     {lo + Z, X, Y}};
  for (const Face& f : faces) {
    const int base = static_cast<int>(mesh.vertices.size());
    for (int j = 0; j <= n; ++j) {
      for (int i = 0; i <= n; ++i) {
        mesh.vertices.push_back(f.corner + f.u * (static_cast<double>(i) / n) +
                                f.v * (static_cast<double>(j) / n));
      }
    }
    const auto at = [&](int i, int j) { return base + j * (n + 1) + i; };
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        mesh.triangles.emplace_back(at(i, j), at(i + 1, j), at(i + 1, j + 1));
        mesh.triangles.emplace_back(at(i, j), at(i + 1, j + 1), at(i, j + 1));
      }
    }
  }
}

// A UV sphere: `rings` latitude bands × `segments` longitudes, outward counter-clockwise.
TriangleMesh sphereMesh(const Eigen::Vector3d& centre, double radius, int rings, int segments) {
  TriangleMesh mesh;
  for (int r = 0; r <= rings; ++r) {
    const double polar = std::numbers::pi * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double azimuth = 2.0 * std::numbers::pi * s / segments;
      mesh.vertices.push_back(centre + radius * Eigen::Vector3d(std::sin(polar) * std::cos(azimuth),
                                                                std::sin(polar) * std::sin(azimuth),
                                                                std::cos(polar)));
    }
  }
  const auto at = [&](int r, int s) { return r * segments + (s % segments); };
  for (int r = 0; r < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      if (r > 0) mesh.triangles.emplace_back(at(r, s), at(r + 1, s), at(r, s + 1));
      if (r + 1 < rings) mesh.triangles.emplace_back(at(r, s + 1), at(r + 1, s), at(r + 1, s + 1));
    }
  }
  return mesh;
}

struct BruteHit {
  double distance = 0.0;
  unsigned triangle = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // (v1 − v0) × (v2 − v0), unit
};

struct BruteResult {
  std::optional<BruteHit> hit;  // the nearest hit, edge grazes included
  bool ambiguous = false;       // the nearest hit is an edge graze float arithmetic may miss
};

// Möller–Trumbore over every triangle, in double, both faces.
BruteResult bruteCast(const TriangleMesh& mesh,
                      const Eigen::Vector3d& origin,
                      const Eigen::Vector3d& direction,
                      double t_near = 0.0,
                      double t_far = std::numeric_limits<double>::infinity()) {
  const Eigen::Vector3d d = direction.normalized();
  std::optional<BruteHit> clear, graze;
  for (std::size_t k = 0; k < mesh.triangles.size(); ++k) {
    const Eigen::Vector3i& tri = mesh.triangles[k];
    const Eigen::Vector3d& v0 = mesh.vertices[static_cast<std::size_t>(tri(0))];
    const Eigen::Vector3d& v1 = mesh.vertices[static_cast<std::size_t>(tri(1))];
    const Eigen::Vector3d& v2 = mesh.vertices[static_cast<std::size_t>(tri(2))];
    const Eigen::Vector3d e1 = v1 - v0, e2 = v2 - v0;
    const Eigen::Vector3d p = d.cross(e2);
    const double det = e1.dot(p);
    const Eigen::Vector3d n = e1.cross(e2).normalized();
    if (std::abs(n.dot(d)) < 1e-6) continue;  // edge-on
    const Eigen::Vector3d s = origin - v0;
    const double u = s.dot(p) / det;
    const Eigen::Vector3d q = s.cross(e1);
    const double v = d.dot(q) / det;
    const double t = e2.dot(q) / det;
    const double margin = std::min({u, v, 1.0 - u - v});
    if (margin < -kEdgeMargin || t < t_near - 1e-6 || t > t_far + 1e-6) continue;
    const bool grazing =
        margin < kEdgeMargin || std::abs(t - t_near) < 1e-6 || std::abs(t - t_far) < 1e-6;
    std::optional<BruteHit>& slot = grazing ? graze : clear;
    if (!slot || t < slot->distance) slot = BruteHit{t, static_cast<unsigned>(k), n};
  }
  BruteResult out;
  out.hit = clear;
  if (graze && (!clear || graze->distance < clear->distance - 1e-6)) {
    out.hit = graze;
    out.ambiguous = true;
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// A scratch folder per test.

class ScanJob : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("scanplan_test_scan_path_" + std::to_string(::getpid()) +
                                        "_" + info->test_suite_name() + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name, std::ios::binary | std::ios::trunc) << text;
    return dir_ / name;
  }
  // A job on the bundled robot and demo part (absolute paths) with `scan` given.
  fs::path writeJob(const std::string& rest) const {
    const fs::path src = test::sourceDir();
    return write("job.yaml", "robot: " + (src / "data/robots/viper_s650.yaml").string() +
                                 "\npart: {mesh: " +
                                 (src / "data/parts/demo_housing.stl").string() + "}\n" + rest);
  }

  fs::path dir_;
};

using test::throwsInputError;

// ---------------------------------------------------------------------------------------------
// Eq. 5 and Eq. 4.

// a = 100 mm, b = 100 mm, φ = 60°, γ = 10° (the demo optics):
//   z_min  = a / tan(φ + γ) + b = 100 / tan 70° + 100 = 100 / 2.7474774 + 100 = 136.39702 mm
//   z_max  = a / tan(φ − γ) + b = 100 / tan 50° + 100 = 100 / 1.1917536 + 100 = 183.90996 mm
//   y_near = a · tan γ / sin(φ + γ) = 100 · 0.17632698 / 0.93969262 = 18.764325 mm
//   y_far  = a · tan γ / sin(φ − γ) = 100 · 0.17632698 / 0.76604444 = 23.017853 mm
// The centre pixel row (p_y = 0) looks along the camera axis: z = a / tan φ + b = 157.73503 mm.
TEST(LaserModel, Eq5WindowMatchesHandValuesForTheDemoOptics) {
  const scanner::LaserOptics optics{mm(100.0), mm(100.0), deg(60.0), deg(10.0)};
  const scanner::LaserWindow w = scanner::laserWindow(optics);
  EXPECT_NEAR(w.z_min, mm(136.39702342662025), kHandTol);
  EXPECT_NEAR(w.z_max, mm(183.909963117728), kHandTol);
  EXPECT_NEAR(w.y_near, mm(18.764325355773742), kHandTol);
  EXPECT_NEAR(w.y_far, mm(23.017852592278228), kHandTol);
  // The defaults of LaserOptics are these optics.
  const scanner::LaserWindow d = scanner::laserWindow(scanner::LaserOptics{});
  EXPECT_NEAR(d.z_min, w.z_min, 1e-15);
  EXPECT_NEAR(d.z_max, w.z_max, 1e-15);

  // The trapezoid: half-width linear in depth, ends at y_near / y_far.
  EXPECT_NEAR(w.halfWidth(w.z_min), w.y_near, 1e-15);
  EXPECT_NEAR(w.halfWidth(w.z_max), w.y_far, 1e-15);
  EXPECT_NEAR(w.halfWidth(0.5 * (w.z_min + w.z_max)), 0.5 * (w.y_near + w.y_far), 1e-15);
  EXPECT_TRUE(w.contains(0.0, w.z_min));
  EXPECT_TRUE(w.contains(w.y_far - 1e-9, w.z_max));
  EXPECT_FALSE(w.contains(w.y_far - 1e-9, w.z_min));  // wider than the near line
  EXPECT_FALSE(w.contains(0.0, w.z_min - 1e-6));
  EXPECT_FALSE(w.contains(0.0, w.z_max + 1e-6));
  EXPECT_FALSE(w.contains(-w.y_near - 1e-6, w.z_min));
}

// With f = H / (2 tan γ), the image edge p_y = ±H/2 has atan(p_y / f) = atan(±tan γ) = ±γ, so
// the ray angle is φ ∓ γ: p_y = +H/2 → z = a / tan(φ − γ) + b = z_max (far), p_y = −H/2 →
// z_min (near). At p_x = ±H/2 (square pixels, a square image) y = a · (H/2) / (f sin(φ ∓ γ))
// = a tan γ / sin(φ ∓ γ): the trapezoid's corners y_far and y_near.
TEST(LaserModel, TriangulationMapsImageEdgesToTheWindowAndTheCentreToTheAxis) {
  const scanner::LaserOptics optics{mm(100.0), mm(100.0), deg(60.0), deg(10.0)};
  const scanner::LaserWindow w = scanner::laserWindow(optics);
  const double H = 1024.0;
  double y = 0.0, z = 0.0;
  scanner::triangulate(optics, H, 0.0, +H / 2, y, z);
  EXPECT_NEAR(z, w.z_max, kHandTol);
  EXPECT_NEAR(y, 0.0, 1e-15);
  scanner::triangulate(optics, H, 0.0, -H / 2, y, z);
  EXPECT_NEAR(z, w.z_min, kHandTol);
  scanner::triangulate(optics, H, 0.0, 0.0, y, z);
  EXPECT_NEAR(z, mm(157.7350269189626), kHandTol);
  EXPECT_NEAR(y, 0.0, 1e-15);

  scanner::triangulate(optics, H, +H / 2, +H / 2, y, z);
  EXPECT_NEAR(y, w.y_far, kHandTol);
  scanner::triangulate(optics, H, -H / 2, -H / 2, y, z);
  EXPECT_NEAR(y, -w.y_near, kHandTol);
  EXPECT_NEAR(z, w.z_min, kHandTol);

  // Depth grows monotonically from the near edge to the far edge, and every pixel of the
  // image lands inside the trapezoid.
  double last = -1.0;
  for (int row = 0; row <= 64; ++row) {
    const double p_y = -H / 2 + H * row / 64.0;
    for (double p_x : {-H / 2, 0.0, H / 2}) {
      scanner::triangulate(optics, H, p_x, p_y, y, z);
      EXPECT_TRUE(w.contains(y * (1.0 - 1e-12), z)) << "p_x " << p_x << " p_y " << p_y;
    }
    EXPECT_GT(z, last);
    last = z;
  }
}

// ---------------------------------------------------------------------------------------------
// Embree against brute force.

struct RayCase {
  Eigen::Vector3d origin, direction;
};

std::vector<RayCase> randomRays(const Eigen::AlignedBox3d& box, int count, std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> fraction(0.0, 1.0);
  const Eigen::Vector3d c = box.center(), half = 0.5 * box.sizes();
  std::vector<RayCase> rays;
  for (int i = 0; i < count; ++i) {
    RayCase r;
    r.origin = c + 3.0 * half.cwiseProduct(Eigen::Vector3d(unit(rng), unit(rng), unit(rng)));
    if (i % 5 == 0) {
      r.direction = Eigen::Vector3d(unit(rng), unit(rng), unit(rng));  // anywhere
    } else {
      const Eigen::Vector3d target = box.min() + box.sizes().cwiseProduct(Eigen::Vector3d(
                                                     fraction(rng), fraction(rng), fraction(rng)));
      r.direction = target - r.origin;
    }
    if (r.direction.norm() < 1e-3) r.direction = Eigen::Vector3d::UnitZ();
    rays.push_back(r);
  }
  return rays;
}

::testing::AssertionResult sameHit(const std::optional<scanner::RayHit>& embree,
                                   const BruteResult& brute) {
  if (embree.has_value() != brute.hit.has_value()) {
    return ::testing::AssertionFailure()
           << "Embree "
           << (embree ? "hits at " + std::to_string(embree->distance) : std::string("misses"))
           << ", brute force "
           << (brute.hit ? "hits at " + std::to_string(brute.hit->distance)
                         : std::string("misses"));
  }
  if (!embree) return ::testing::AssertionSuccess();
  if (std::abs(embree->distance - brute.hit->distance) > kEmbreeTol) {
    return ::testing::AssertionFailure() << "distance: Embree " << embree->distance
                                         << " m, brute force " << brute.hit->distance << " m";
  }
  // The normal is the hit triangle's plane normal (either sign: the header promises a unit
  // geometric normal, not an orientation).
  const double alignment = std::abs(embree->normal.dot(brute.hit->normal));
  if (std::abs(embree->normal.norm() - 1.0) > 1e-6 || alignment < 1.0 - 1e-5) {
    return ::testing::AssertionFailure() << "normal " << embree->normal.transpose()
                                         << " vs triangle normal " << brute.hit->normal.transpose();
  }
  return ::testing::AssertionSuccess();
}

void compareOnMesh(const TriangleMesh& mesh, std::uint32_t seed, int rays_count) {
  const scanner::Raycaster raycaster(mesh);
  std::mt19937 rng(seed);
  int compared = 0, hits = 0, skipped = 0;
  for (const RayCase& r : randomRays(mesh.bounds(), rays_count, rng)) {
    const BruteResult brute = bruteCast(mesh, r.origin, r.direction);
    if (brute.ambiguous) {
      ++skipped;
      continue;
    }
    ++compared;
    hits += brute.hit ? 1 : 0;
    EXPECT_TRUE(sameHit(raycaster.cast(r.origin, r.direction), brute))
        << "ray from " << r.origin.transpose() << " along " << r.direction.transpose();
  }
  EXPECT_LT(skipped, rays_count / 50) << "too many edge grazes to be a meaningful comparison";
  EXPECT_GT(hits, compared / 3);
  EXPECT_GT(compared - hits, compared / 20);
}

TEST(Raycaster, MatchesBruteForceOnASubdividedBox) {
  TriangleMesh box;
  appendBox(box, Eigen::Vector3d(-0.06, -0.04, 0.0), Eigen::Vector3d(0.05, 0.03, 0.08), 5);
  ASSERT_EQ(box.triangles.size(), 300u);
  compareOnMesh(box, 11, 3000);
}

TEST(Raycaster, MatchesBruteForceOnASphere) {
  const TriangleMesh sphere = sphereMesh(Eigen::Vector3d(0.1, -0.2, 0.3), 0.07, 14, 24);
  ASSERT_GT(sphere.triangles.size(), 500u);
  compareOnMesh(sphere, 12, 3000);
}

// Ray ranges: [t_near, t_far] selects which surface is reported; from inside, the back face.
TEST(Raycaster, RespectsTheRayRangeAndHitsBackFacesFromInside) {
  TriangleMesh box;
  appendBox(box, Eigen::Vector3d(-0.05, -0.05, -0.05), Eigen::Vector3d(0.05, 0.05, 0.05), 3);
  const scanner::Raycaster raycaster(box);
  // Along +x from x = −0.2 through y = z = 0.0123 (off the subdivision lines): the faces
  // x = −0.05 and x = +0.05 are 0.15 m and 0.25 m away.
  const Eigen::Vector3d o(-0.2, 0.0123, 0.0123), d(2.0, 0.0, 0.0);  // not unit on purpose
  auto hit = raycaster.cast(o, d);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->distance, 0.15, kEmbreeTol);
  EXPECT_NEAR(std::abs(hit->normal.x()), 1.0, 1e-6);
  hit = raycaster.cast(o, d, 0.16);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->distance, 0.25, kEmbreeTol);
  EXPECT_FALSE(raycaster.cast(o, d, 0.0, 0.14));
  EXPECT_FALSE(raycaster.cast(o, d, 0.26));
  hit = raycaster.cast(Eigen::Vector3d(0.0, 0.0123, 0.0123), Eigen::Vector3d(0.0, 0.0, -1.0));
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->distance, 0.05 + 0.0123, kEmbreeTol);
  EXPECT_FALSE(raycaster.cast(o, -d));
}

// Frame invariance: moving mesh and rays by the same rigid transform changes nothing.
TEST(Raycaster, DistancesDoNotDependOnTheMeshFrame) {
  const TriangleMesh sphere = sphereMesh(Eigen::Vector3d::Zero(), 0.05, 10, 16);
  const scanner::Raycaster here(sphere);
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const auto rays = randomRays(sphere.bounds(), 400, rng);
  for (int pose = 0; pose < 3; ++pose) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = Eigen::Quaterniond(unit(rng), unit(rng), unit(rng), unit(rng))
                     .normalized()
                     .toRotationMatrix();
    X.translation() = Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
    TriangleMesh moved = sphere;
    for (auto& v : moved.vertices) v = X * v;
    const scanner::Raycaster there(moved);
    for (const RayCase& r : rays) {
      if (bruteCast(sphere, r.origin, r.direction).ambiguous) continue;
      const auto a = here.cast(r.origin, r.direction);
      const auto b = there.cast(X * r.origin, X.linear() * r.direction);
      ASSERT_EQ(a.has_value(), b.has_value()) << "pose " << pose;
      if (a) {
        EXPECT_NEAR(a->distance, b->distance, kEmbreeTol);
        EXPECT_NEAR((X.linear() * a->normal).dot(b->normal), 1.0, 1e-5);
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Ring on the demo part.

struct DemoPath {
  config::JobSpec job;
  kinematics::LoadedMesh part;
  scanner::LaserWindow window;
  scanner::GeneratedPath generated;
};

const DemoPath& demoPath() {
  static const DemoPath demo = [] {
    DemoPath d;
    // The two rings and the head these tests were written for, whatever the demo uses today.
    d.job = config::loadJob(
        test::sourceDir() / "data/jobs/demo_rings.yaml",
        {"scanner.optics={a_mm: 100, b_mm: 100, phi_deg: 60, gamma_deg: 10}",
         "scan.paths=[{type: ring, height_mm: 50, tilt_deg: 20, speed_deg_s: 20}, {type: ring, "
         "height_mm: 100, tilt_deg: 50, speed_deg_s: 20}]"});
    const kinematics::CellModel cell = config::buildCell(d.job);
    d.part = kinematics::loadMesh(cell.part.mesh.path, cell.part.mesh.options);
    d.window = scanner::laserWindow(config::laserOptics(d.job));
    const scanner::Raycaster raycaster(d.part.mesh);
    d.generated =
        scanner::generatePath(config::pathRequest(d.job), d.part.mesh, raycaster, d.window);
    return d;
  }();
  return demo;
}

// Samples of element `e` (inside its time span).
std::vector<std::size_t> elementSamples(const scanner::GeneratedPath& g, std::size_t e) {
  const auto& r = g.elements[e];
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < g.path.samples.size(); ++i) {
    const double t = g.path.samples[i].t;
    if (t >= r.start_time - 1e-9 && t <= r.start_time + r.duration + 1e-9) out.push_back(i);
  }
  return out;
}

TEST(RingPath, DemoRingsKeepTheCentralRayInTheDepthWindowAsOftenAsReported) {
  const DemoPath& demo = demoPath();
  const auto& g = demo.generated;
  ASSERT_EQ(g.elements.size(), 2u);
  const double tol = 1e-4;  // m: the ring is sampled between 1° keys (chord sag ~0.03 mm)
  for (std::size_t e = 0; e < g.elements.size(); ++e) {
    const auto& report = g.elements[e];
    EXPECT_EQ(report.kind, "ring");
    EXPECT_NEAR(report.duration, 360.0 / 20.0, 1e-9);  // extent / speed
    int hits = 0, inside = 0;
    for (std::size_t i : elementSamples(g, e)) {
      const ScanSample& s = g.path.samples[i];
      EXPECT_TRUE(s.scanning) << "t = " << s.t;
      const BruteResult ray =
          bruteCast(demo.part.mesh, s.X_PS.translation(), s.X_PS.linear().col(2));
      if (!ray.hit) continue;
      ++hits;
      const double z = ray.hit->distance;
      inside += (z >= demo.window.z_min - tol && z <= demo.window.z_max + tol) ? 1 : 0;
      EXPECT_GE(z, report.depth_min - tol) << "t = " << s.t;
      EXPECT_LE(z, report.depth_max + tol) << "t = " << s.t;
    }
    ASSERT_GT(hits, 0);
    const double fraction = static_cast<double>(inside) / hits;
    // The report counts 3 probes across the line every 2°; the central rays alone must do at
    // least as well (one sample of slack for the different sampling).
    EXPECT_GE(fraction, report.coverage_in_window - 1.0 / hits)
        << "ring " << e << ": " << inside << " of " << hits
        << " central rays in the window, report says " << report.coverage_in_window;
    EXPECT_GT(report.coverage_in_window, 0.9) << "ring " << e;
  }
}

TEST(RingPath, DemoRingsLookAtTheAxisAndMovePerpendicularToTheLaserPlane) {
  const DemoPath& demo = demoPath();
  const auto& g = demo.generated;
  const Eigen::Vector2d axis = demo.part.mesh.bounds().center().head<2>();
  const double dt = demo.job.scan.dt_s;
  ASSERT_FALSE(g.path.samples.empty());
  EXPECT_DOUBLE_EQ(g.path.dt, dt);
  for (std::size_t i = 0; i < g.path.samples.size(); ++i) {
    EXPECT_NEAR(g.path.samples[i].t, static_cast<double>(i) * dt, 1e-9);
  }
  for (std::size_t e = 0; e < g.elements.size(); ++e) {
    const auto& spec = demo.job.scan.paths[e];
    const double tilt = deg(spec.tilt_deg);
    const Eigen::Vector3d aim(axis.x(), axis.y(), mm(spec.height_mm));
    const auto samples = elementSamples(g, e);
    ASSERT_GT(samples.size(), 100u);
    const double L = (g.path.samples[samples.front()].X_PS.translation() - aim).norm();
    for (std::size_t k = 0; k < samples.size(); ++k) {
      const Eigen::Isometry3d& X = g.path.samples[samples[k]].X_PS;
      const Eigen::Vector3d p = X.translation(), z = X.linear().col(2);
      const Eigen::Vector2d radial = (p.head<2>() - axis).normalized();
      // z_S = −cos(tilt) · radial − sin(tilt) · ẑ: inward and down by the tilt.
      EXPECT_NEAR(z.head<2>().dot(radial), -std::cos(tilt), 1e-6)
          << "ring " << e << " sample " << k;
      EXPECT_NEAR(z.z(), -std::sin(tilt), 1e-6);
      EXPECT_NEAR(z.head<2>().x() * radial.y() - z.head<2>().y() * radial.x(), 0.0, 1e-6);
      // The central ray passes through the aim point on the axis, at the same standoff.
      const Eigen::Vector3d to_aim = aim - p;
      EXPECT_LT((to_aim - to_aim.dot(z) * z).norm(), 1e-4);
      EXPECT_NEAR(to_aim.norm(), L, 1e-4);
      EXPECT_NEAR(X.linear().determinant(), 1.0, 1e-9);
      if (k + 1 == samples.size()) break;
      // Between samples the scanner moves along ±x_S (the laser plane's normal): the chord
      // between two ring samples is along the mean of their x_S axes.
      const Eigen::Isometry3d& Y = g.path.samples[samples[k + 1]].X_PS;
      const Eigen::Vector3d step = Y.translation() - p;
      const Eigen::Vector3d x_mid = (X.linear().col(0) + Y.linear().col(0)).normalized();
      ASSERT_GT(step.norm(), 1e-4);
      EXPECT_GT(std::abs(step.normalized().dot(x_mid)), std::cos(deg(0.5)))
          << "ring " << e << " sample " << k << ": step " << step.transpose() << ", x_S "
          << x_mid.transpose();
      // |step| = 2 L cos(tilt) sin(Δφ / 2) with Δφ = speed · dt.
      const double expected = 2.0 * L * std::cos(tilt) * std::sin(0.5 * deg(spec.speed_deg_s) * dt);
      EXPECT_NEAR(step.norm(), expected, 1e-4);
    }
  }
}

// A clockwise ring (negative extent) with an explicit standoff and axis: the scanner starts at
// the start angle, keeps the given distance to the aim point, and still moves along +x_S.
TEST(RingPath, ClockwiseRingWithExplicitDistanceAndAxis) {
  const DemoPath& demo = demoPath();
  const scanner::Raycaster raycaster(demo.part.mesh);
  scanner::RingSpec ring;
  ring.height = 0.05;
  ring.tilt = deg(30.0);
  ring.start = deg(90.0);
  ring.extent = deg(-60.0);
  ring.speed = deg(30.0);
  ring.distance = 0.2;
  ring.axis_xy = Eigen::Vector2d(0.01, -0.005);
  scanner::PathRequest request;
  request.elements.emplace_back(ring);
  request.dt = 0.1;
  const auto g = scanner::generatePath(request, demo.part.mesh, raycaster, demo.window);
  EXPECT_NEAR(g.elements.front().duration, 2.0, 1e-9);  // 60° at 30°/s
  ASSERT_EQ(g.path.samples.size(), 21u);
  const Eigen::Vector3d aim(0.01, -0.005, 0.05);
  // Start: at φ = 90°, L cos(tilt) out along +y from the axis, L sin(tilt) above the aim.
  EXPECT_LT((g.path.samples.front().X_PS.translation() -
             (aim + Eigen::Vector3d(0.0, 0.2 * std::cos(deg(30.0)), 0.2 * std::sin(deg(30.0)))))
                .norm(),
            1e-12);
  for (std::size_t i = 0; i < g.path.samples.size(); ++i) {
    const Eigen::Isometry3d& X = g.path.samples[i].X_PS;
    EXPECT_NEAR((X.translation() - aim).norm(), 0.2, 1e-4) << i;
    const Eigen::Vector3d to_aim = (aim - X.translation()).normalized();
    EXPECT_GT(to_aim.dot(X.linear().col(2)), 1.0 - 1e-8) << i << ": z_S looks at the aim point";
    if (i + 1 == g.path.samples.size()) break;
    const Eigen::Vector3d step = g.path.samples[i + 1].X_PS.translation() - X.translation();
    EXPECT_GT(step.normalized().dot(X.linear().col(0)), std::cos(deg(2.0)))
        << i << ": moving along +x_S";
    // Clockwise seen from above: the angle around the axis decreases.
    const Eigen::Vector2d r0 = X.translation().head<2>() - aim.head<2>();
    const Eigen::Vector2d r1 = g.path.samples[i + 1].X_PS.translation().head<2>() - aim.head<2>();
    EXPECT_LT(r0.x() * r1.y() - r0.y() * r1.x(), 0.0) << i;
  }
  // End: φ = 30°.
  const Eigen::Vector3d end = g.path.samples.back().X_PS.translation() - aim;
  EXPECT_NEAR(std::atan2(end.y(), end.x()), deg(30.0), 1e-9);
}

// ---------------------------------------------------------------------------------------------
// Raster on a generated part: a 100 × 80 × 30 mm box with a 15 mm step on its +x end.

struct RasterFixture {
  TriangleMesh part;
  scanner::LaserWindow window = scanner::laserWindow(scanner::LaserOptics{});
  scanner::RasterSpec spec;
  scanner::GeneratedPath generated;
};

// The box spans x in [−half_length, half_length], y in [−40, 40] mm, z in [0, 30] mm; the step
// x in [15 mm, half_length], z up to 45 mm.
RasterFixture rasterOnSteppedBox(double half_length = 0.05) {
  RasterFixture r;
  appendBox(r.part, Eigen::Vector3d(-half_length, -0.04, 0.0),
            Eigen::Vector3d(half_length, 0.04, 0.03), 4);
  appendBox(r.part, Eigen::Vector3d(0.015, -0.04, 0.03), Eigen::Vector3d(half_length, 0.04, 0.045),
            4);
  const scanner::Raycaster raycaster(r.part);
  scanner::PathRequest request;
  request.elements.emplace_back(r.spec);
  request.dt = 0.02;  // 0.6 mm between samples at 30 mm/s
  r.generated = scanner::generatePath(request, r.part, raycaster, r.window);
  return r;
}

TEST(RasterPath, CentralRayStaysInTheDepthWindowWhileScanning) {
  const RasterFixture r = rasterOnSteppedBox();
  const double tol = 1e-6;
  int checked = 0;
  for (const ScanSample& s : r.generated.path.samples) {
    const Eigen::Vector3d z = s.X_PS.linear().col(2);
    EXPECT_NEAR(z.dot(-Eigen::Vector3d::UnitZ()), 1.0, 1e-9)
        << "t = " << s.t << ": z_S is the view";
    if (!s.scanning) continue;
    const BruteResult ray = bruteCast(r.part, s.X_PS.translation(), z);
    const double x = s.X_PS.translation().x();
    if (!ray.hit) {
      EXPECT_TRUE(x < -0.05 + 1e-3 || x > 0.05 - 1e-3)
          << "t = " << s.t << ": no surface under a pass at x = " << x;
      continue;
    }
    ++checked;
    EXPECT_GE(ray.hit->distance, r.window.z_min - tol) << "t = " << s.t << ", x = " << x;
    EXPECT_LE(ray.hit->distance, r.window.z_max + tol) << "t = " << s.t << ", x = " << x;
  }
  EXPECT_GT(checked, 300);
  EXPECT_NEAR(r.generated.elements.front().coverage_in_window, 1.0, 1e-12);
}

// Passes run along +x, −x, +x … at constant y; there are ⌈width / spacing⌉ of them with
// spacing = near line length × (1 − overlap) = 2 · 18.764 · 0.8 = 30.02 mm, spread evenly over
// the 80 mm width: 3 passes at y = +26.67, 0, −26.67 mm (w = view × pass direction = −y).
TEST(RasterPath, PassesAreSpacedByTheNearLineAndCoverTheWidth) {
  const RasterFixture r = rasterOnSteppedBox();
  const double documented = 2.0 * r.window.y_near * (1.0 - r.spec.overlap);
  EXPECT_NEAR(documented, mm(30.02292), 1e-6);
  const int passes = static_cast<int>(std::ceil(0.08 / documented));
  ASSERT_EQ(passes, 3);
  // The y of every scanning run.
  std::vector<double> pass_y;
  bool in_run = false;
  for (const ScanSample& s : r.generated.path.samples) {
    if (s.scanning && !in_run) pass_y.push_back(s.X_PS.translation().y());
    if (s.scanning) {
      EXPECT_NEAR(s.X_PS.translation().y(), pass_y.back(), 1e-9)
          << "t = " << s.t << ": a pass is straight";
    }
    in_run = s.scanning;
  }
  ASSERT_EQ(pass_y.size(), 3u);
  const double actual = 0.08 / passes;
  EXPECT_LE(actual, documented + 1e-12) << "passes farther apart than the near line allows";
  for (int k = 0; k < passes; ++k) {
    EXPECT_NEAR(pass_y[static_cast<std::size_t>(k)], 0.04 - actual * (k + 0.5), 1e-9);
  }
  // Every point of the width is within half a near line of some pass.
  for (double y = -0.04; y <= 0.04; y += 0.001) {
    double nearest = 1.0;
    for (double p : pass_y) nearest = std::min(nearest, std::abs(p - y));
    EXPECT_LE(nearest, r.window.y_near) << "y = " << y;
  }
  // Motion along ±x_S, alternating.
  std::vector<double> direction;
  for (std::size_t i = 0; i + 1 < r.generated.path.samples.size(); ++i) {
    const ScanSample& a = r.generated.path.samples[i];
    const ScanSample& b = r.generated.path.samples[i + 1];
    if (!b.scanning || !a.scanning) continue;
    const Eigen::Vector3d step = b.X_PS.translation() - a.X_PS.translation();
    const Eigen::Vector3d x_s = b.X_PS.linear().col(0);
    EXPECT_NEAR(std::abs(x_s.x()), 1.0, 1e-9);
    EXPECT_NEAR(step.y(), 0.0, 1e-12);
    if (std::abs(step.x()) > 1e-6) {
      EXPECT_GT(step.x() * x_s.x(), 0.0) << "t = " << b.t << ": moving along +x_S";
    }
  }
  EXPECT_NE(r.generated.elements.front().note.find("3 passes"), std::string::npos)
      << r.generated.elements.front().note;
}

// `scanning` is false on the lead-in / lead-out beyond the part and on transfers between passes,
// and true wherever a pass is over the part (x in [−half_length, half_length]).
void checkScanningFlags(double half_length) {
  const RasterFixture r = rasterOnSteppedBox(half_length);
  const auto& samples = r.generated.path.samples;
  ASSERT_FALSE(samples.front().scanning);
  EXPECT_NEAR(samples.front().X_PS.translation().x(), -half_length - r.spec.lead, 1e-9)
      << "the lead-in starts the path";
  const double key_spacing =
      0.01;  // keys every 10 mm: the motion arriving at a key on the part scans
  std::vector<double> pass_y;
  for (const ScanSample& s : samples) {
    if (s.scanning &&
        (pass_y.empty() || std::abs(pass_y.back() - s.X_PS.translation().y()) > 1e-9)) {
      pass_y.push_back(s.X_PS.translation().y());
    }
  }
  int over_part = 0;
  for (const ScanSample& s : samples) {
    const Eigen::Vector3d p = s.X_PS.translation();
    const bool on_pass_line = std::any_of(pass_y.begin(), pass_y.end(),
                                          [&](double y) { return std::abs(p.y() - y) < 1e-9; });
    if (!on_pass_line) {
      EXPECT_FALSE(s.scanning) << "t = " << s.t << ": scanning during a transfer at y = " << p.y();
      continue;
    }
    if (p.x() < -half_length - key_spacing - 1e-9 || p.x() > half_length + key_spacing + 1e-9) {
      EXPECT_FALSE(s.scanning) << "t = " << s.t << ": scanning on a lead at x = " << p.x();
    }
    // On the pass line, over the part, at the scanning height (not a transfer's back-off).
    const BruteResult ray = bruteCast(r.part, p, s.X_PS.linear().col(2));
    if (p.x() >= -half_length && p.x() <= half_length && ray.hit &&
        ray.hit->distance <= r.window.z_max) {
      ++over_part;
      EXPECT_TRUE(s.scanning) << "t = " << s.t
                              << ": not scanning over the part at x = " << p.x() * 1e3
                              << " mm, y = " << p.y() * 1e3 << " mm";
    }
  }
  EXPECT_GT(over_part, 300);
}

TEST(RasterPath, ScanningFlagIsOffOnLeadsAndTransfersAndOnOverThePart) { checkScanningFlags(0.05); }

// Keys are 10 mm apart from u_min − lead; a move acquires whenever it overlaps the part, so a
// part whose length is not a multiple of 10 mm (this 95 mm box) is scanned to its very ends.
TEST(RasterPath, ScanningCoversAPartWhoseLengthIsNotAMultipleOfTheKeySpacing) {
  checkScanningFlags(0.0475);
}

// ---------------------------------------------------------------------------------------------
// Waypoints.

Eigen::Isometry3d pose(const Eigen::Vector3d& p, const Eigen::Matrix3d& R) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = R;
  X.translation() = p;
  return X;
}

Eigen::Matrix3d rotZ(double a) {
  return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}
Eigen::Matrix3d rotX(double a) {
  return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).toRotationMatrix();
}

double angleBetween(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B) {
  return Eigen::AngleAxisd(A.transpose() * B).angle();
}

TEST(WaypointPath, TimingIsDistanceOverSpeedOrRotationOverRotationSpeed) {
  TriangleMesh part;
  appendBox(part, Eigen::Vector3d(-0.01, -0.01, 0.0), Eigen::Vector3d(0.01, 0.01, 0.02), 1);
  const scanner::Raycaster raycaster(part);
  scanner::WaypointSpec spec;
  // 1: 100 mm at 50 mm/s = 2 s; the 30° turn at 0.5 rad/s would need only 1.05 s.
  // 2: 10 mm at 50 mm/s = 0.2 s, but a 90° turn at 0.5 rad/s needs π s: rotation governs.
  spec.points.push_back({pose({0.1, 0.0, 0.2}, Eigen::Matrix3d::Identity()), 0.05, 0.5, false});
  spec.points.push_back({pose({0.1, 0.1, 0.2}, rotZ(deg(30.0))), 0.05, 0.5, true});
  spec.points.push_back(
      {pose({0.11, 0.1, 0.2}, rotZ(deg(30.0)) * rotX(deg(90.0))), 0.05, 0.5, false});
  scanner::PathRequest request;
  request.elements.emplace_back(spec);
  request.dt = 0.05;
  const auto g =
      scanner::generatePath(request, part, raycaster, scanner::laserWindow(scanner::LaserOptics{}));
  const double t1 = 2.0, t2 = 2.0 + std::numbers::pi;
  EXPECT_NEAR(g.elements.front().duration, t2, 1e-9);
  ASSERT_EQ(g.path.samples.size(), static_cast<std::size_t>(std::floor(t2 / 0.05)) + 1);
  EXPECT_EQ(g.elements.front().kind, "waypoints");
  for (const ScanSample& s : g.path.samples) {
    if (s.t <= t1 + 1e-9) {
      const double u = s.t / t1;  // fraction of segment 1
      EXPECT_NEAR((s.X_PS.translation() - Eigen::Vector3d(0.1, 0.1 * u, 0.2)).norm(), 0.0, 1e-12)
          << "t = " << s.t;
      EXPECT_NEAR(angleBetween(s.X_PS.linear(), rotZ(deg(30.0) * u)), 0.0, 1e-9) << "t = " << s.t;
      EXPECT_EQ(s.scanning, s.t > 0.0)
          << "t = " << s.t << ": segment 1 scans, the start point does not";
    } else {
      const double u = (s.t - t1) / (t2 - t1);
      EXPECT_NEAR((s.X_PS.translation() - Eigen::Vector3d(0.1 + 0.01 * u, 0.1, 0.2)).norm(), 0.0,
                  1e-12);
      EXPECT_NEAR(angleBetween(s.X_PS.linear(), rotZ(deg(30.0)) * rotX(deg(90.0) * u)), 0.0, 1e-9)
          << "t = " << s.t;
      EXPECT_FALSE(s.scanning) << "t = " << s.t;
    }
  }
  // Midway through segment 1 (t = 1 s): halfway along, orientation slerped halfway (Rz 15°).
  const ScanSample& mid = g.path.samples[20];
  ASSERT_NEAR(mid.t, 1.0, 1e-12);
  EXPECT_NEAR((mid.X_PS.translation() - Eigen::Vector3d(0.1, 0.05, 0.2)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(angleBetween(mid.X_PS.linear(), rotZ(deg(15.0))), 0.0, 1e-12);
}

TEST(WaypointPath, InterpolationSlerpsTheShortWayAndIsLinearInPosition) {
  const Eigen::Isometry3d a = pose({0.0, 0.0, 0.0}, rotZ(deg(170.0)));
  const Eigen::Isometry3d b = pose({0.2, -0.4, 0.6}, rotZ(deg(-170.0)));
  const Eigen::Isometry3d m = kinematics::interpolatePose(a, b, 0.5);
  EXPECT_NEAR(angleBetween(m.linear(), rotZ(deg(180.0))), 0.0, 1e-12)
      << "20° the short way, not 340°";
  EXPECT_NEAR((m.translation() - Eigen::Vector3d(0.1, -0.2, 0.3)).norm(), 0.0, 1e-15);
  const Eigen::Isometry3d q = kinematics::interpolatePose(a, b, 0.25);
  EXPECT_NEAR(angleBetween(q.linear(), rotZ(deg(175.0))), 0.0, 1e-12);
  EXPECT_NEAR(angleBetween(kinematics::interpolatePose(a, b, 0.0).linear(), a.linear()), 0.0,
              1e-12);
  EXPECT_NEAR(angleBetween(kinematics::interpolatePose(a, b, 1.0).linear(), b.linear()), 0.0,
              1e-12);
}

// Two elements: a transfer backs off along −z_S, crosses and approaches, without scanning.
TEST(WaypointPath, TransfersBetweenElementsRetreatAndDoNotScan) {
  TriangleMesh part;
  appendBox(part, Eigen::Vector3d(-0.01, -0.01, 0.0), Eigen::Vector3d(0.01, 0.01, 0.02), 1);
  const scanner::Raycaster raycaster(part);
  const Eigen::Matrix3d down = rotX(deg(180.0));  // z_S = −z
  scanner::WaypointSpec first, second;
  first.points = {{pose({0.0, 0.0, 0.2}, down), 0.05, 0.5, true},
                  {pose({0.05, 0.0, 0.2}, down), 0.05, 0.5, true}};
  second.points = {{pose({0.05, 0.1, 0.2}, down), 0.05, 0.5, true},
                   {pose({0.0, 0.1, 0.2}, down), 0.05, 0.5, true}};
  scanner::PathRequest request;
  request.elements = {first, second};
  request.dt = 0.05;
  request.transfer_speed = 0.1;
  request.retreat = 0.05;
  const auto g =
      scanner::generatePath(request, part, raycaster, scanner::laserWindow(scanner::LaserOptics{}));
  ASSERT_EQ(g.elements.size(), 2u);
  // Element 1: 1 s. Transfer: 50 mm up, 100 mm across, 50 mm down at 100 mm/s = 2 s.
  EXPECT_NEAR(g.elements[0].duration, 1.0, 1e-12);
  EXPECT_NEAR(g.elements[1].start_time, 3.0, 1e-12);
  EXPECT_NEAR(g.path.duration(), 4.0, 1e-9);
  double highest = 0.0;
  for (const ScanSample& s : g.path.samples) {
    const bool transfer = s.t > 1.0 + 1e-9 && s.t <= 3.0 + 1e-9;
    EXPECT_EQ(s.scanning, !transfer) << "t = " << s.t;
    highest = std::max(highest, s.X_PS.translation().z());
  }
  EXPECT_NEAR(highest, 0.25, 1e-12) << "backed off by `retreat` along −z_S";
}

// ---------------------------------------------------------------------------------------------
// Path files.

TEST(PathFile, CsvRoundTripsWithinThePrintedPrecision) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  ScanPath path;
  path.dt = 0.1;
  for (int i = 0; i < 200; ++i) {
    ScanSample s;
    s.t = 0.1 * i;
    s.X_PS.translation() = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * 0.4;
    s.X_PS.linear() = Eigen::Quaterniond(unit(rng), unit(rng), unit(rng), unit(rng))
                          .normalized()
                          .toRotationMatrix();
    s.scanning = i % 3 != 0;
    path.samples.push_back(s);
  }
  const std::string csv = scanner::pathToCsv(path);
  EXPECT_EQ(csv.substr(0, csv.find('\n')), "t_s,x_mm,y_mm,z_mm,qw,qx,qy,qz,scanning");
  const scanner::FileSpec back = scanner::parsePathCsv(csv, "roundtrip.csv");
  ASSERT_EQ(back.samples.size(), path.samples.size());
  // 10 significant digits: ≤ 5e-8 mm on coordinates below 400 mm, 5e-11 on quaternion terms.
  for (std::size_t i = 0; i < path.samples.size(); ++i) {
    const ScanSample& a = path.samples[i];
    const ScanSample& b = back.samples[i];
    EXPECT_NEAR(a.t, b.t, 1e-9);
    EXPECT_LT((a.X_PS.translation() - b.X_PS.translation()).norm(), 1e-10) << "row " << i;
    EXPECT_LT(angleBetween(a.X_PS.linear(), b.X_PS.linear()), 1e-9) << "row " << i;
    EXPECT_EQ(a.scanning, b.scanning) << "row " << i;
  }
}

TEST(PathFile, EightColumnsScanAndFileTimesAreShiftedAndResampled) {
  const std::string csv =
      "# written by hand\n"
      "t_s,x_mm,y_mm,z_mm,qw,qx,qy,qz\n"
      "5.0, 100, 0, 200, 1, 0, 0, 0\n"
      "6.0, 200, 0, 200, 1, 0, 0, 0\r\n"
      "\n"
      "7.0, 200, 100, 200, 0, 0, 0, 1\n";
  const scanner::FileSpec spec = scanner::parsePathCsv(csv, "hand.csv");
  ASSERT_EQ(spec.samples.size(), 3u);
  EXPECT_TRUE(spec.samples[0].scanning);
  EXPECT_NEAR(spec.samples[1].X_PS.translation().x(), 0.2, 1e-15);
  TriangleMesh part;
  appendBox(part, Eigen::Vector3d(-0.01, -0.01, 0.0), Eigen::Vector3d(0.01, 0.01, 0.02), 1);
  const scanner::Raycaster raycaster(part);
  scanner::PathRequest request;
  request.elements.emplace_back(spec);
  request.dt = 0.25;
  const auto g =
      scanner::generatePath(request, part, raycaster, scanner::laserWindow(scanner::LaserOptics{}));
  ASSERT_EQ(g.path.samples.size(), 9u);  // 0 … 2 s every 0.25 s
  EXPECT_NEAR((g.path.samples[2].X_PS.translation() - Eigen::Vector3d(0.15, 0.0, 0.2)).norm(), 0.0,
              1e-12);
  EXPECT_NEAR(angleBetween(g.path.samples[6].X_PS.linear(), rotZ(deg(90.0))), 0.0, 1e-9);
  EXPECT_EQ(g.elements.front().kind, "file");
}

TEST(PathFile, BadRowsNameTheSourceAndTheLine) {
  const std::string header = "t_s,x_mm,y_mm,z_mm,qw,qx,qy,qz,scanning\n";
  const std::string good = "0,1,2,3,1,0,0,0,1\n";
  const auto parse = [](const std::string& text) {
    return [text] { scanner::parsePathCsv(text, "bad.csv"); };
  };
  EXPECT_TRUE(throwsInputError(parse(header + good + "0.1,1,abc,3,1,0,0,0,1\n"),
                               {"bad.csv:3", "'abc'", "not a finite number"}));
  EXPECT_TRUE(
      throwsInputError(parse(header + good + "0.1,1,nan,3,1,0,0,0,1\n"), {"bad.csv:3", "'nan'"}));
  EXPECT_TRUE(throwsInputError(parse(header + good + "0.1,1,,3,1,0,0,0,1\n"), {"bad.csv:3"}));
  EXPECT_TRUE(throwsInputError(parse(header + good + "0.1,1,2,3,1,0,0\n"),
                               {"bad.csv:3", "7 columns", "expected 8 or 9"}));
  EXPECT_TRUE(throwsInputError(parse(header + good + "0.1,1,2,3,1,0,0,0,1,1\n"),
                               {"bad.csv:3", "10 columns"}));
  EXPECT_TRUE(throwsInputError(parse(header + good + "0,1,2,3,1,0,0,0,1\n"),
                               {"bad.csv:3", "does not increase"}));
  EXPECT_TRUE(throwsInputError(parse(header + good + "-1,1,2,3,1,0,0,0,1\n"),
                               {"bad.csv:3", "does not increase"}));
  EXPECT_TRUE(throwsInputError(parse(header + good + "0.1,1,2,3,1,1,0,0,1\n"),
                               {"bad.csv:3", "quaternion norm", "unit quaternion"}));
  EXPECT_TRUE(throwsInputError(parse(header + "# comment\n\n" + good + "0.2,1,2,3,0,0,0,0\n"),
                               {"bad.csv:5", "quaternion"}));
  // Unit within the tolerance of printed digits is fine.
  EXPECT_NO_THROW(
      scanner::parsePathCsv(header + good + "0.1,1,2,3,0.70710678,0.70710678,0,0,0\n", "ok.csv"));
}

// ---------------------------------------------------------------------------------------------
// Job-level errors of `scan`.

TEST_F(ScanJob, BadScanDefinitionsAreRejectedWithTheFieldPath) {
  const auto load = [](const fs::path& job) { return [job] { config::loadJob(job); }; };
  EXPECT_TRUE(
      throwsInputError(load(writeJob("scan:\n  paths:\n    - {type: spiral}\n")),
                       {"scan.paths[0].type", "'spiral'", "ring, raster, waypoints, file"}));
  EXPECT_TRUE(throwsInputError(load(writeJob("scan:\n  paths:\n    - {type: ring, height_mm: 50}\n "
                                             "   - {type: ring, height_mm: 50, extent_deg: 0}\n")),
                               {"scan.paths[1].extent_deg", "non-zero"}));
  EXPECT_TRUE(
      throwsInputError(load(writeJob("scan:\n  paths:\n    - {type: raster, view: [0, 0, 0]}\n")),
                       {"scan.paths[0].view", "non-zero direction"}));
  EXPECT_TRUE(throwsInputError(load(writeJob("scan:\n  paths:\n    - type: waypoints\n      "
                                             "points:\n        - {xyz_mm: [0, 0, 300]}\n")),
                               {"scan.paths[0].points", "2"}));
  EXPECT_TRUE(
      throwsInputError(load(writeJob("scan:\n  paths:\n    - {type: file, file: nowhere.csv}\n")),
                       {"scan.paths[0].file", "nowhere.csv", "does not exist"}));
  EXPECT_TRUE(throwsInputError(load(writeJob("scanner:\n  optics: {phi_deg: 30, gamma_deg: 30}\n")),
                               {"scanner.optics.gamma_deg", "30", "phi_deg"}));
  EXPECT_TRUE(throwsInputError(load(writeJob("scanner:\n  optics: {phi_deg: 30, gamma_deg: 40}\n")),
                               {"scanner.optics.gamma_deg"}));
  EXPECT_TRUE(throwsInputError(load(writeJob("scanner:\n  optics: {phi_deg: 50, gamma_deg: 40}\n")),
                               {"scanner.optics.gamma_deg", "phi_deg + gamma_deg < 90"}));
  EXPECT_TRUE(throwsInputError(
      load(writeJob("scan:\n  paths:\n    - {type: ring, height_mm: 50, view: [0, 0, -1]}\n")),
      {"scan.paths[0].view", "unknown key"}));
  EXPECT_TRUE(throwsInputError(load(writeJob("scan:\n  paths:\n    - {type: ring}\n")),
                               {"scan.paths[0].height_mm", "required"}));
}

TEST_F(ScanJob, ABadPathFileIsReportedWithItsNameAndLine) {
  write("path.csv", "t_s,x_mm,y_mm,z_mm,qw,qx,qy,qz\n0,0,0,300,1,0,0,0\n0,0,0,300,1,0,0,0\n");
  const config::JobSpec job =
      config::loadJob(writeJob("scan:\n  paths:\n    - {type: file, file: path.csv}\n"));
  EXPECT_TRUE(throwsInputError([&] { config::pathRequest(job); },
                               {(dir_ / "path.csv").string() + ":3", "does not increase"}));
}

// A ring far above the part (tilt 0: horizontal rays) never sees it: the error names the element.
TEST_F(ScanJob, ARingThatNeverSeesThePartNamesItsElement) {
  const fs::path file = writeJob(
      "scan:\n  paths:\n    - {type: ring, height_mm: 50, tilt_deg: 20}\n"
      "    - {type: ring, height_mm: 2000, tilt_deg: 0}\n");
  const config::JobSpec job = config::loadJob(file);
  const kinematics::CellModel cell = config::buildCell(job);
  const auto part = kinematics::loadMesh(cell.part.mesh.path, cell.part.mesh.options);
  const scanner::Raycaster raycaster(part.mesh);
  const scanner::PathRequest request = config::pathRequest(job);
  EXPECT_TRUE(throwsInputError(
      [&] {
        scanner::generatePath(request, part.mesh, raycaster,
                              scanner::laserWindow(config::laserOptics(job)));
      },
      {"scan.paths[1]", "never sees the part", "2000"}));

  // Through the CLI: input-error exit code, the job file and the element on stderr.
  const fs::path err = dir_ / "stderr.txt";
  std::vector<std::string> args{SCANPLAN_BINARY, "path", file.string(), "-o",
                                (dir_ / "out").string()};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 4);
  std::ifstream in(err);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("scanplan: error: " + file.string() + ": scan.paths[1]"), std::string::npos)
      << text;
}

}  // namespace

namespace scanplan::scanner {
namespace {

TEST(RaycasterThreads, AliveRaycasterDoesNotThrottleOurParallelLoops) {
  // Embree's TBB back end, given "threads=N", installs a process-wide tbb::global_control for
  // the device's lifetime: the maps then ran on one thread while a Raycaster was alive.
  const std::size_t before =
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
  kinematics::TriangleMesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.triangles = {{0, 1, 2}};
  const Raycaster raycaster(mesh);
  EXPECT_EQ(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism),
            before);
}

}  // namespace
}  // namespace scanplan::scanner
