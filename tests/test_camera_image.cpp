// The image-based scanner simulation's parts (scanner/camera_image.h, seed §5.3): the camera
// model and Eq. 4, sub-pixel stripe detection, and rendering on scenes with a known answer.
#include <scanplan/scanner/camera_image.h>

#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/shape.h>
#include <scanplan/scanner/laser_model.h>
#include <scanplan/scanner/raycaster.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <span>
#include <vector>

namespace scanplan::scanner {
namespace {

// Eq. 4 and the projection are closed forms of each other: only rounding separates them.
constexpr double kRoundTripTol = 1e-9;  // m (and pixels for the pixel round trip)
// The target of sub-pixel peak detection on an ideal (noise-free, unquantised) stripe.
constexpr double kSubPixelTol = 0.05;  // px

// The seed's head (docs/design.md §6 example): a 100 mm, b 100 mm, φ 60°, γ 10°: depth window
// 136.4 … 183.9 mm.
LaserOptics headOptics() { return {0.1, 0.1, std::numbers::pi / 3.0, std::numbers::pi / 18.0}; }

CameraModel headCamera(int side = 1, int rows = 256, int columns = 200) {
  CameraModel camera;
  camera.optics = headOptics();
  camera.rows = rows;
  camera.columns = columns;
  camera.side = side;
  return camera;
}

// Image settings for `camera`'s whole sensor and a 1 mm laser sheet.
ImageSettings sheetSettings(const CameraModel& camera) {
  ImageSettings settings;
  settings.rows = camera.rows;
  settings.columns = camera.columns;
  settings.thickness = 1e-3;
  return settings;
}

// A triangle mesh in the scanner frame as an ImageScene (one Embree ray per query): the
// reference the simulator's packet scene is compared against in test_scanner_sim.
class MeshScene final : public ImageScene {
 public:
  explicit MeshScene(const kinematics::TriangleMesh& mesh) : caster_(mesh) {}
  void nearest(std::span<const SceneRay> rays, std::span<SceneHit> hits) const override {
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const auto h = caster_.cast(rays[i].origin, rays[i].direction, 0.0, rays[i].t_far);
      hits[i] = SceneHit{};
      if (!h) continue;
      hits[i] = {h->distance, h->normal, static_cast<std::int32_t>(h->triangle), true};
    }
  }
  void occluded(std::span<const SceneRay> rays, std::span<char> blocked) const override {
    for (std::size_t i = 0; i < rays.size(); ++i) {
      blocked[i] = caster_.cast(rays[i].origin, rays[i].direction, 0.0, rays[i].t_far) ? 1 : 0;
    }
  }

 private:
  Raycaster caster_;
};

// A rectangle (two triangles) with corners c ± u ± v.
void addQuad(kinematics::TriangleMesh& mesh,
             const Eigen::Vector3d& c,
             const Eigen::Vector3d& u,
             const Eigen::Vector3d& v) {
  const int base = static_cast<int>(mesh.vertices.size());
  mesh.vertices.insert(mesh.vertices.end(), {c - u - v, c + u - v, c + u + v, c - u + v});
  mesh.triangles.emplace_back(base, base + 1, base + 2);
  mesh.triangles.emplace_back(base, base + 2, base + 3);
}

// A plate facing the scanner at depth z0, tilted by `tilt` about the scanner's Y axis (the
// laser line's direction), 200 mm square.
kinematics::TriangleMesh plate(double z0, double tilt) {
  kinematics::TriangleMesh mesh;
  const Eigen::Vector3d u(0.1 * std::cos(tilt), 0.0, 0.1 * std::sin(tilt));
  addQuad(mesh, {0.0, 0.0, z0}, u, {0.0, 0.1, 0.0});
  return mesh;
}

// The depth (m) one row spans at image-plane row p_y on the laser plane: |dP_Z/dp_y| of Eq. 4,
// by central difference (the derivative is smooth; the step is far above rounding).
double rowFootprint(const CameraModel& camera, double p_y) {
  return std::abs(camera.triangulate(0.0, p_y + 0.5).z() - camera.triangulate(0.0, p_y - 0.5).z());
}

// ---------------------------------------------------------------------------------------------
// Camera model and Eq. 4.

// Eq. 4 inverts the camera's projection exactly: a laser-plane point in the field, projected
// to the image plane and triangulated back, is the point again; and so is the pixel position
// through pixel() and imagePlane(). Seeded samples over the whole field, both cameras.
TEST(CameraModel, Eq4InvertsTheProjectionOfEveryLaserPlanePoint) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const LaserWindow window = laserWindow(headOptics());
  for (const int side : {1, -1}) {
    const CameraModel camera = headCamera(side);
    double worst = 0.0;
    for (int i = 0; i < 2000; ++i) {
      const double z = window.z_min + unit(rng) * (window.z_max - window.z_min);
      const double y = (2.0 * unit(rng) - 1.0) * window.halfWidth(z);
      const Eigen::Vector3d p(0.0, y, z);
      const auto image = camera.project(p);
      ASSERT_TRUE(image);
      const Eigen::Vector3d back = camera.triangulate(image->x(), image->y());
      worst = std::max(worst, (back - p).norm());
      const Eigen::Vector2d px = camera.pixel(image->x(), image->y());
      EXPECT_LT((camera.imagePlane(px.x(), px.y()) - *image).norm(), kRoundTripTol);
      // The ray through that image point passes through p.
      const Eigen::Vector3d d = camera.rayDirection(image->x(), image->y());
      const Eigen::Vector3d r = p - camera.centre();
      EXPECT_LT((r - r.dot(d) * d).norm(), kRoundTripTol);
    }
    EXPECT_LT(worst, kRoundTripTol) << "side " << side;
  }
}

// At the image edges Eq. 4 gives Eq. 5: rows at p_y = ∓H/2 look along φ ± γ, the depth
// window's ends z_min and z_max; the corner columns p_x = ±H/2 reach the line's ends there.
TEST(CameraModel, ImageEdgesTriangulateToTheEq5Window) {
  const LaserWindow w = laserWindow(headOptics());
  for (const int rows : {64, 256, 1024}) {
    const CameraModel camera = headCamera(1, rows, 173);
    const double h = 0.5 * rows;
    EXPECT_NEAR(camera.triangulate(0.0, -h).z(), w.z_min, 1e-12);
    EXPECT_NEAR(camera.triangulate(0.0, h).z(), w.z_max, 1e-12);
    for (const double s : {-1.0, 1.0}) {
      EXPECT_NEAR(camera.triangulate(s * h, -h).y(), s * w.y_near, 1e-12);
      EXPECT_NEAR(camera.triangulate(s * h, h).y(), s * w.y_far, 1e-12);
    }
    // The outer pixel edges are the image edges.
    EXPECT_NEAR(camera.imagePlane(-0.5, -0.5).y(), -h, 1e-12);
    EXPECT_NEAR(camera.imagePlane(172.5, rows - 0.5).x(), h, 1e-12);
  }
}

// ---------------------------------------------------------------------------------------------
// Stripe detection.

// A sampled Gaussian stripe I(r) = A·exp(−(r − c)²/(2σ²)) at seeded sub-pixel centres: the
// 3-point Gaussian fit is exact for it (the log of a Gaussian is a parabola); the centre of
// gravity over the run above the threshold, with (I − threshold) weights, is within 0.05 px for
// stripes at least a pixel wide (σ ≥ 1).
TEST(StripeDetection, RecoversASyntheticGaussianStripeCentre) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> centre(20.0, 40.0);
  for (const double sigma : {1.0, 1.5, 2.5}) {
    for (int i = 0; i < 200; ++i) {
      const double c = centre(rng);
      std::vector<float> column(64);
      for (int r = 0; r < 64; ++r) {
        column[static_cast<std::size_t>(r)] =
            static_cast<float>(12.0 + 200.0 * std::exp(-(r - c) * (r - c) / (2 * sigma * sigma)));
      }
      // The Gaussian fit sees the ambient 12 grey levels as part of the stripe: without it, it
      // is exact; the centroid subtracts the threshold.
      std::vector<float> clean = column;
      for (float& v : clean) v -= 12.0f;
      const auto gauss = detectPeak(clean.data(), 64, 1, 10.0, StripeMethod::kGaussian);
      const auto cog = detectPeak(column.data(), 64, 1, 40.0, StripeMethod::kCentreOfGravity);
      ASSERT_TRUE(gauss && cog);
      EXPECT_NEAR(*gauss, c, 1e-4) << "sigma " << sigma;
      EXPECT_NEAR(*cog, c, kSubPixelTol) << "sigma " << sigma;
    }
  }
}

TEST(StripeDetection, ColumnsBelowTheThresholdHaveNoStripeAndTheStrongestPeakWins) {
  ProfileImage image;
  image.rows = 10;
  image.columns = 2;
  image.grey.assign(20, 5.0f);
  // Column 1: a weak peak at row 2, a strong one at row 7.
  image.grey[2 * 2 + 1] = 60.0f;
  image.grey[7 * 2 + 1] = 200.0f;
  const auto rows = detectStripe(image, 40.0, StripeMethod::kCentreOfGravity);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_FALSE(rows[0]);
  ASSERT_TRUE(rows[1]);
  EXPECT_DOUBLE_EQ(*rows[1], 7.0);
}

// ---------------------------------------------------------------------------------------------
// Rendering on known scenes.

struct Measured {
  std::vector<Eigen::Vector3d> points;  // scanner frame
  ProfileImage image;
};

Measured measure(const CameraModel& camera,
                 const ImageSettings& settings,
                 const ImageScene& scene,
                 std::uint64_t seed = 1) {
  Measured m;
  RenderScratch scratch;
  renderProfileImage(camera, settings, scene, seed, m.image, scratch);
  const auto rows = detectStripe(m.image, settings.threshold, settings.method);
  for (int k = 0; k < camera.columns; ++k) {
    if (const auto& r = rows[static_cast<std::size_t>(k)]) {
      const Eigen::Vector2d p = camera.imagePlane(k, *r);
      m.points.push_back(camera.triangulate(p.x(), p.y()));
    }
  }
  return m;
}

// The accuracy a stripe read to `px` pixels gives at depth z: px row footprints, plus the
// depth error a column's lateral pitch allows on a surface sloped by `slope` (dz/dy).
double depthTolerance(const CameraModel& camera, double z, double px) {
  const Eigen::Vector2d image = *camera.project({0.0, 0.0, z});
  return px * rowFootprint(camera, image.y());
}

// A flat plate across the window at several depths and tilts (none near grazing for the
// camera: at −0.4 rad its line of sight from C+ runs within 2° of the plate, the stripe shrinks
// below a pixel and columns lose it — a real effect, not this test's): every column finds it,
// and each triangulated point lies on the plate within 0.25 of a row's depth footprint (the
// stripe is 2–4 px wide; the centroid of 8-bit samples is good to ~0.1 px, with margin).
TEST(ImageRendering, FlatPlatePointsLieOnThePlateWithinAPixelFraction) {
  const CameraModel camera = headCamera();
  ImageSettings settings = sheetSettings(camera);
  for (const auto method : {StripeMethod::kCentreOfGravity, StripeMethod::kGaussian}) {
    settings.method = method;
    for (const double z0 : {0.145, 0.16, 0.175}) {
      for (const double tilt : {0.0, 0.3, -0.2}) {
        const MeshScene scene(plate(z0, tilt));
        const Measured m = measure(camera, settings, scene);
        // The plate's line in the laser plane: z = z0 + x·tan(tilt) at x = 0 → z = z0.
        EXPECT_EQ(m.points.size(), static_cast<std::size_t>(camera.columns))
            << "z0 " << z0 << " tilt " << tilt;
        const double tol = depthTolerance(camera, z0, 0.25);
        double worst = 0.0;
        for (const Eigen::Vector3d& p : m.points) worst = std::max(worst, std::abs(p.z() - z0));
        EXPECT_LT(worst, tol) << "z0 " << z0 << " tilt " << tilt << " method "
                              << static_cast<int>(method);
        // The line spans the field at that depth: its ends within a column pitch of it.
        const double half =
            std::tan(camera.optics.gamma) * std::hypot(camera.optics.a, z0 - camera.optics.b);
        const double pitch = 2.0 * half / camera.columns;
        double lo = 1.0, hi = -1.0;
        for (const Eigen::Vector3d& p : m.points) {
          lo = std::min(lo, p.y());
          hi = std::max(hi, p.y());
        }
        EXPECT_NEAR(lo, -half + 0.5 * pitch, pitch);
        EXPECT_NEAR(hi, half - 0.5 * pitch, pitch);
      }
    }
  }
}

// A cylinder of radius 40 mm, axis along the scanner's X (across the laser plane), its top
// at depth 150 mm: the laser line follows the circle y² + (z − z_c)² = R² in the plane. The
// points lie on the tessellated cylinder within the row-footprint tolerance plus the
// tessellation's sagitta.
TEST(ImageRendering, CylinderPointsLieOnTheCylinder) {
  const CameraModel camera = headCamera();
  ImageSettings settings = sheetSettings(camera);
  const double radius = 0.04, z_c = 0.19;
  kinematics::Shape shape;
  shape.geometry = kinematics::Cylinder{radius, 0.2};
  shape.X_BG.linear() = Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitY()).matrix();
  shape.X_BG.translation() << 0.0, 0.0, z_c;
  kinematics::TessellationOptions tessellation;
  tessellation.chord_tolerance = 1e-6;
  tessellation.max_segments = 720;
  const kinematics::TriangleMesh mesh = kinematics::shapeSurface(shape, tessellation);
  std::size_t segments = 0;  // vertices on the circle at one end
  for (const Eigen::Vector3d& v : mesh.vertices) {
    if (std::abs(v.x() - 0.1) < 1e-9 && std::abs(std::hypot(v.y(), v.z() - z_c) - radius) < 1e-9)
      ++segments;
  }
  ASSERT_GE(segments, 12u);
  const MeshScene scene(mesh);
  const Measured m = measure(camera, settings, scene);
  ASSERT_GT(m.points.size(), static_cast<std::size_t>(camera.columns) * 9 / 10);
  const double sagitta =
      radius * (1.0 - std::cos(std::numbers::pi / static_cast<double>(segments)));
  double worst = 0.0;
  for (const Eigen::Vector3d& p : m.points) {
    const double off = std::abs(std::hypot(p.y(), p.z() - z_c) - radius);
    // The circle's slope stretches a depth error along its normal by at most 1.
    const double tol = depthTolerance(camera, p.z(), 0.25) + sagitta;
    EXPECT_LT(off, tol) << "at y " << p.y();
    worst = std::max(worst, off);
  }
  RecordProperty("worst_mm", std::to_string(worst * 1e3));
}

// Occlusion: a small plate 4 mm wide, between the laser and a plate at 160 mm, but outside the
// camera's view of it: it shadows the plate at |y| < 2 mm · 160/120 along the line. Columns in
// the shadow see no stripe; those well outside it do.
TEST(ImageRendering, PointsTheLaserCannotReachAreNotLit) {
  const CameraModel camera = headCamera();
  ImageSettings settings = sheetSettings(camera);
  kinematics::TriangleMesh mesh = plate(0.16, 0.0);
  const double z_block = 0.12, half_width = 0.002;
  addQuad(mesh, {0.0, 0.0, z_block}, {0.003, 0.0, 0.0}, {0.0, half_width, 0.0});
  const MeshScene scene(mesh);
  const Measured m = measure(camera, settings, scene);
  const double shadow = half_width * 0.16 / z_block;
  std::size_t inside = 0, outside = 0;
  for (const Eigen::Vector3d& p : m.points) {
    EXPECT_GT(std::abs(p.y()), shadow - 2e-4) << "a point in the shadow at y " << p.y();
    if (std::abs(p.y()) > shadow + 1e-3) ++outside;
    if (std::abs(p.y()) < shadow) ++inside;
  }
  EXPECT_EQ(inside, 0u);
  EXPECT_GT(outside, static_cast<std::size_t>(camera.columns) * 3 / 4);
  // The same scene without the blocker lights those columns (the shadow is the blocker's).
  const MeshScene open(plate(0.16, 0.0));
  const Measured lit = measure(camera, settings, open);
  EXPECT_EQ(lit.points.size(), static_cast<std::size_t>(camera.columns));
}

// A surface whose lit side faces away from the camera is not seen lit: the plate seen edge-on
// from behind (tilted past the camera's line of sight) gives no stripe.
TEST(ImageRendering, SheetOutsideTheSurfaceGivesNoStripe) {
  const CameraModel camera = headCamera();
  ImageSettings settings;
  settings.rows = camera.rows;
  settings.columns = camera.columns;
  // A plate in the plane x = 5 mm, parallel to the laser sheet: never within its thickness.
  kinematics::TriangleMesh mesh;
  addQuad(mesh, {0.005, 0.0, 0.16}, {0.0, 0.0, 0.05}, {0.0, 0.05, 0.0});
  const MeshScene scene(mesh);
  const Measured m = measure(camera, settings, scene);
  EXPECT_TRUE(m.points.empty());
  EXPECT_EQ(m.image.lit, 0u);
}

// Sensor noise is seeded: the same seed gives the same image bit for bit, another seed another.
TEST(ImageRendering, NoiseIsDeterministicPerSeed) {
  const CameraModel camera = headCamera(1, 64, 48);
  ImageSettings settings;
  settings.rows = camera.rows;
  settings.columns = camera.columns;
  settings.noise = 4.0;
  const MeshScene scene(plate(0.16, 0.2));
  const Measured a = measure(camera, settings, scene, 7);
  const Measured b = measure(camera, settings, scene, 7);
  const Measured c = measure(camera, settings, scene, 8);
  EXPECT_EQ(a.image.grey, b.image.grey);
  EXPECT_NE(a.image.grey, c.image.grey);
  for (const float v : a.image.grey) {
    EXPECT_EQ(v, std::round(v));
    EXPECT_GE(v, 0.0f);
    EXPECT_LE(v, 255.0f);
  }
}

// The specular term brightens the stripe where the half vector meets the normal, never darkens.
TEST(ImageRendering, SpecularTermAddsLight) {
  const CameraModel camera = headCamera(1, 128, 64);
  ImageSettings matte;
  matte.rows = camera.rows;
  matte.columns = camera.columns;
  matte.reflectance.lambert = 0.3;
  ImageSettings shiny = matte;
  shiny.reflectance.specular = 0.5;
  shiny.reflectance.shininess = 5.0;
  const MeshScene scene(plate(0.16, 0.5));
  const Measured a = measure(camera, matte, scene);
  const Measured b = measure(camera, shiny, scene);
  double sum_a = 0.0, sum_b = 0.0;
  for (std::size_t i = 0; i < a.image.grey.size(); ++i) {
    EXPECT_GE(b.image.grey[i], a.image.grey[i]);
    sum_a += a.image.grey[i];
    sum_b += b.image.grey[i];
  }
  EXPECT_GT(sum_b, sum_a);
}

}  // namespace
}  // namespace scanplan::scanner
