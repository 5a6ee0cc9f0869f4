#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/scanner/laser_model.h>

namespace scanplan::scanner {

/// The camera of a profile scanner (seed §5.3, Eq. 4–5; docs/design.md §6) in the scanner frame S:
/// the laser plane is X = 0, the camera centre C = (s·a, 0, b) with s = +1 (camera C+) or −1
/// (C−), its optical axis in the XZ plane at the angle φ to +Z, looking back at the plane.
///
/// The image has `rows` × `columns` pixels (H × W). Image-plane coordinates (p_x, p_y) are in
/// pixels of the focal length f = H / (2 tan γ) (Eq. 4), from the image centre: p_y across the
/// rows (increasing with depth z), p_x across the columns (along +Y). The columns span the same
/// view angle as the rows (Eq. 5's square field, p_x in [−H/2, H/2]), so one column is H / W
/// row pixels wide. Row index r (0 at the near edge z_min) and column index c have their pixel
/// centres at p_y = r + ½ − H/2 and p_x = (c + ½ − W/2)·H/W.
///
/// The projection is the one Eq. 4 inverts exactly: a point Q with r = Q − C maps to
/// p_y = f·tan(φ − ψ), ψ = atan2(s·(−r_x), r_z) the ray's angle to +Z in the XZ plane, and
/// p_x = f·r_y / |r_XZ|. (A pinhole would have p_x = f·r_y / (r·axis), which differs from Eq. 4's
/// P_Y by cos(atan(p_y/f)), up to 1.5 % at γ = 10°; Eq. 4 is the paper's sensor model.)
struct CameraModel {
  LaserOptics optics;
  int rows = 256;     ///< H, pixels
  int columns = 200;  ///< W, pixels
  int side = 1;       ///< +1: camera C+ at (+a, 0, b); −1: C− at (−a, 0, b)

  /// f = H / (2 tan γ), pixels.
  double focal() const;
  /// The camera centre C, scanner frame, m.
  Eigen::Vector3d centre() const;
  /// Image-plane coordinates (p_x, p_y), pixels, of a (sub-)pixel position (column, row).
  Eigen::Vector2d imagePlane(double column, double row) const;
  /// The inverse of imagePlane(): (column, row).
  Eigen::Vector2d pixel(double p_x, double p_y) const;
  /// Unit direction (scanner frame) of the camera ray through image-plane point (p_x, p_y).
  Eigen::Vector3d rayDirection(double p_x, double p_y) const;
  /// Image-plane coordinates of point p_S (scanner frame, m); none when it lies behind the
  /// camera (not within ±90° of the optical axis in the XZ plane).
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p_S) const;
  /// Eq. 4 (docs/design.md §6 form): the laser-plane point (0, P_Y, P_Z) seen at (p_x, p_y), m.
  Eigen::Vector3d triangulate(double p_x, double p_y) const;
};

/// Surface reflectance of the simulated cell, as grey levels of an 8-bit camera for unit laser
/// irradiance: intensity = 255 · E · (lambert · cos θ_i + specular · (n·h)^shininess), θ_i the
/// laser's incidence angle, h the half vector between the directions to the laser and to the
/// camera (Blinn–Phong).
struct Reflectance {
  double lambert = 0.8;
  double specular = 0.0;
  double shininess = 20.0;
};

/// Sub-pixel peak detection of the stripe in one column.
enum class StripeMethod {
  kCentreOfGravity,  ///< centroid of (I − threshold) over the run above threshold at the peak
  kGaussian,  ///< 3-point Gaussian fit (log-parabola) at the peak; centroid when a side is dark
};

/// How a profile image is made and read.
struct ImageSettings {
  /// H × W, pixels (rows ≥ 2, columns ≥ 1): the simulator builds its CameraModel from them;
  /// renderProfileImage() itself renders the camera's own rows and columns.
  int rows = 256;
  int columns = 200;
  /// Laser sheet thickness, m: its irradiance across the sheet is Gaussian,
  /// E(x) = exp(−2x²/w²) with w = thickness / 2 (the 1/e² half width); a point with |x| > w is
  /// not lit.
  double thickness = 0.5e-3;
  Reflectance reflectance;
  /// Ambient light from the camera's side, grey levels on a surface facing the camera (shows
  /// the part around the stripe; keep it below the threshold).
  double ambient = 12.0;
  double noise = 0.0;       ///< σ of Gaussian sensor noise, grey levels (then clamped, rounded)
  double threshold = 40.0;  ///< grey levels a stripe peak must exceed
  StripeMethod method = StripeMethod::kCentreOfGravity;
};

/// The nearest surface a ray meets.
struct SceneHit {
  double t = 0.0;                                  ///< along the unit ray, m
  Eigen::Vector3d n_S = Eigen::Vector3d::UnitZ();  ///< unit geometric normal, scanner frame
  std::int32_t part_triangle = -1;                 ///< part mesh triangle; −1 on another body
  bool hit = false;
};

/// A ray in the scanner frame: origin + t·direction (unit), t in [0, t_far].
struct SceneRay {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
  double t_far = 0.0;
};

/// The scene a profile image is rendered from (the simulator's posed cell, or a test mesh), in
/// the scanner frame. Batched so that an implementation can cast packets.
class ImageScene {
 public:
  virtual ~ImageScene() = default;
  /// The nearest hit of each ray; hits.size() == rays.size().
  virtual void nearest(std::span<const SceneRay> rays, std::span<SceneHit> hits) const = 0;
  /// blocked[i] = 1 when something lies on rays[i] within [0, t_far], else 0.
  virtual void occluded(std::span<const SceneRay> rays, std::span<char> blocked) const = 0;
};

/// A grey image, row-major (row 0 = the near edge of the depth window), with what each pixel
/// saw.
struct ProfileImage {
  int rows = 0;
  int columns = 0;
  std::vector<float> grey;     ///< grey levels 0…255, rows × columns
  std::vector<SceneHit> hit;   ///< per pixel, the surface its ray met
  std::size_t lit = 0;         ///< pixels the laser lit (before noise)
  std::size_t laser_rays = 0;  ///< laser-reach rays cast

  float at(int row, int column) const {
    return grey[static_cast<std::size_t>(row) * static_cast<std::size_t>(columns) +
                static_cast<std::size_t>(column)];
  }
};

/// Per-thread buffers for renderProfileImage (reused profile after profile).
struct RenderScratch {
  std::vector<SceneRay> rays;
  std::vector<std::uint32_t> candidates;
  std::vector<Eigen::Vector3d> points;
  std::vector<char> blocked;
};

/// Renders what `camera` sees (docs/design.md §6, seed §5.3 "ray tracing simulation"): each pixel's
/// ray (through its centre) meets the scene's nearest surface; the pixel is lit when that point
/// lies within the laser sheet (|x| ≤ thickness/2, z > 0), faces the laser, and the segment
/// from the laser origin to it is clear. Intensity per Reflectance (plus the ambient term),
/// then Gaussian noise seeded by `noise_seed` (only when settings.noise > 0), clamped to
/// [0, 255] and rounded to integer grey levels. Rays reach twice the distance to the laser
/// plane. Deterministic for a given scene, settings and seed.
void renderProfileImage(const CameraModel& camera,
                        const ImageSettings& settings,
                        const ImageScene& scene,
                        std::uint64_t noise_seed,
                        ProfileImage& image,
                        RenderScratch& scratch);

/// The stripe's sub-pixel row in each column (row index units, pixel centres at integers),
/// none where no pixel exceeds `threshold`. The strongest peak of the column is taken.
std::vector<std::optional<double>> detectStripe(const ProfileImage& image,
                                                double threshold,
                                                StripeMethod method);

/// One column's stripe (see detectStripe) from `rows` samples spaced `stride` apart.
std::optional<double> detectPeak(
    const float* column, int rows, std::size_t stride, double threshold, StripeMethod method);

}  // namespace scanplan::scanner
