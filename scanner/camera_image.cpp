#include <scanplan/scanner/camera_image.h>

#include <scanplan/scanner/detail/random.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>
#include <random>

namespace scanplan::scanner {
namespace {

// Laser-reach rays stop this far short of the lit point, so that Embree's float arithmetic
// cannot report the lit surface itself (as the geometric mode's occlusion rays, simulator.cpp).
constexpr double kReachOffset = 1e-5;  // m
constexpr double kFullScale = 255.0;   // grey levels of an 8-bit camera

}  // namespace

double CameraModel::focal() const { return rows / (2.0 * std::tan(optics.gamma)); }

Eigen::Vector3d CameraModel::centre() const { return {side * optics.a, 0.0, optics.b}; }

Eigen::Vector2d CameraModel::imagePlane(double column, double row) const {
  return {(column + 0.5 - 0.5 * columns) * rows / columns, row + 0.5 - 0.5 * rows};
}

Eigen::Vector2d CameraModel::pixel(double p_x, double p_y) const {
  return {p_x * columns / rows + 0.5 * columns - 0.5, p_y + 0.5 * rows - 0.5};
}

Eigen::Vector3d CameraModel::rayDirection(double p_x, double p_y) const {
  const double f = focal();
  const double psi = optics.phi - std::atan(p_y / f);
  return Eigen::Vector3d(-side * std::sin(psi), p_x / f, std::cos(psi)).normalized();
}

std::optional<Eigen::Vector2d> CameraModel::project(const Eigen::Vector3d& p_S) const {
  const Eigen::Vector3d r = p_S - centre();
  const double psi = std::atan2(-side * r.x(), r.z());
  const double off_axis = optics.phi - psi;
  const double xz = std::hypot(r.x(), r.z());
  if (!(std::abs(off_axis) < 0.5 * std::numbers::pi) || !(xz > 0.0)) return std::nullopt;
  const double f = focal();
  return Eigen::Vector2d(f * r.y() / xz, f * std::tan(off_axis));
}

Eigen::Vector3d CameraModel::triangulate(double p_x, double p_y) const {
  double y = 0.0, z = 0.0;
  scanner::triangulate(optics, rows, p_x, p_y, y, z);
  return {0.0, y, z};
}

namespace {

// One camera ray per pixel, row by row (neighbours in a packet are neighbouring pixels), each
// reaching twice as far as the laser plane x = 0 (at t = |C_x| / |d_x|) to show the surfaces
// around and behind the stripe.
void cameraRays(const CameraModel& camera, std::vector<SceneRay>& rays) {
  const std::size_t rows = static_cast<std::size_t>(camera.rows);
  const std::size_t columns = static_cast<std::size_t>(camera.columns);
  const Eigen::Vector3d c = camera.centre();
  rays.resize(rows * columns);
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t k = 0; k < columns; ++k) {
      const Eigen::Vector2d p = camera.imagePlane(static_cast<double>(k), static_cast<double>(r));
      SceneRay& ray = rays[r * columns + k];
      ray.origin = c;
      ray.direction = camera.rayDirection(p.x(), p.y());
      ray.t_far = 2.0 * camera.optics.a / std::abs(ray.direction.x());
    }
  }
}

// Ambient shading of every pixel that sees the scene; the pixels whose point lies in the laser
// sheet, on the side the laser lights, become candidates, their camera rays replaced by the
// laser's ray to the point (for the reach test), compacted to the front of scratch.rays.
void shadeAndCollectSheetPoints(const Eigen::Vector3d& c,
                                const ImageSettings& settings,
                                ProfileImage& image,
                                RenderScratch& scratch) {
  const double w = 0.5 * settings.thickness;
  scratch.candidates.clear();
  scratch.points.clear();
  for (std::size_t i = 0; i < image.hit.size(); ++i) {
    SceneHit& h = image.hit[i];
    if (!h.hit) continue;
    const Eigen::Vector3d& d = scratch.rays[i].direction;
    if (h.n_S.dot(d) > 0.0) h.n_S = -h.n_S;  // the side the camera sees
    image.grey[i] = static_cast<float>(settings.ambient * -h.n_S.dot(d));
    const Eigen::Vector3d p = c + h.t * d;
    if (!(std::abs(p.x()) <= w) || !(p.z() > 0.0)) continue;
    const double range = p.norm();
    if (!(h.n_S.dot(p) < 0.0)) continue;  // the laser lights the other side
    scratch.candidates.push_back(static_cast<std::uint32_t>(i));
    scratch.points.push_back(p);
    SceneRay& reach = scratch.rays[i];  // the camera ray is no longer needed
    reach.origin = Eigen::Vector3d::Zero();
    reach.direction = p / range;
    reach.t_far = std::max(0.0, range - kReachOffset);
  }
  // Compact the laser rays to the front (candidates are increasing: i ≥ j always).
  for (std::size_t j = 0; j < scratch.candidates.size(); ++j)
    scratch.rays[j] = scratch.rays[scratch.candidates[j]];
}

// The laser's light on each candidate it reaches (not blocked): a Gaussian sheet across x,
// Lambert plus Phong-like specular reflection towards the camera at c.
void addLaserLight(const Eigen::Vector3d& c,
                   const ImageSettings& settings,
                   ProfileImage& image,
                   const RenderScratch& scratch) {
  const double w = 0.5 * settings.thickness;
  const Reflectance& refl = settings.reflectance;
  for (std::size_t j = 0; j < scratch.candidates.size(); ++j) {
    if (scratch.blocked[j]) continue;
    const std::size_t i = scratch.candidates[j];
    const SceneHit& h = image.hit[i];
    const Eigen::Vector3d& p = scratch.points[j];
    const Eigen::Vector3d& l = scratch.rays[j].direction;  // laser → point
    const Eigen::Vector3d to_camera = (c - p).normalized();
    const double x = p.x();
    const double irradiance = std::exp(-2.0 * x * x / (w * w));
    const double cos_i = -h.n_S.dot(l);
    double value = refl.lambert * cos_i;
    if (refl.specular > 0.0) {
      const Eigen::Vector3d half = (to_camera - l).normalized();
      value += refl.specular * std::pow(std::max(0.0, h.n_S.dot(half)), refl.shininess);
    }
    image.grey[i] += static_cast<float>(kFullScale * irradiance * value);
    ++image.lit;
  }
}

// Sensor noise (Gaussian, seeded per profile) and quantisation to whole grey levels.
void addNoiseAndQuantise(double noise, std::uint64_t noise_seed, std::vector<float>& grey) {
  std::optional<std::mt19937_64> rng;
  if (noise > 0.0) rng.emplace(detail::mix(noise_seed));
  const std::size_t n = grey.size();
  for (std::size_t i = 0; i < n; i += 2) {
    double e0 = 0.0, e1 = 0.0;
    if (rng) {
      const auto [g0, g1] = detail::gaussianPair(*rng);
      e0 = noise * g0;
      e1 = noise * g1;
    }
    grey[i] = static_cast<float>(
        std::round(std::clamp(static_cast<double>(grey[i]) + e0, 0.0, kFullScale)));
    if (i + 1 < n) {
      grey[i + 1] = static_cast<float>(
          std::round(std::clamp(static_cast<double>(grey[i + 1]) + e1, 0.0, kFullScale)));
    }
  }
}

}  // namespace

void renderProfileImage(const CameraModel& camera,
                        const ImageSettings& settings,
                        const ImageScene& scene,
                        std::uint64_t noise_seed,
                        ProfileImage& image,
                        RenderScratch& scratch) {
  const std::size_t n =
      static_cast<std::size_t>(camera.rows) * static_cast<std::size_t>(camera.columns);
  image.rows = camera.rows;
  image.columns = camera.columns;
  image.grey.assign(n, 0.0f);
  image.hit.resize(n);
  image.lit = 0;
  image.laser_rays = 0;

  cameraRays(camera, scratch.rays);
  scene.nearest(scratch.rays, image.hit);
  const Eigen::Vector3d c = camera.centre();
  shadeAndCollectSheetPoints(c, settings, image, scratch);
  const std::size_t m = scratch.candidates.size();
  scratch.blocked.assign(m, 0);
  scene.occluded(std::span<const SceneRay>(scratch.rays.data(), m), scratch.blocked);
  image.laser_rays = m;
  addLaserLight(c, settings, image, scratch);
  addNoiseAndQuantise(settings.noise, noise_seed, image.grey);
}

std::optional<double> detectPeak(
    const float* column, int rows, std::size_t stride, double threshold, StripeMethod method) {
  const auto at = [&](int r) {
    return static_cast<double>(column[static_cast<std::size_t>(r) * stride]);
  };
  int peak = -1;
  double best = threshold;
  for (int r = 0; r < rows; ++r) {
    if (at(r) > best) {
      best = at(r);
      peak = r;
    }
  }
  if (peak < 0) return std::nullopt;
  if (method == StripeMethod::kGaussian && peak > 0 && peak + 1 < rows && best < kFullScale) {
    const double a = at(peak - 1), c = at(peak + 1);
    if (a > 0.0 && c > 0.0) {
      const double la = std::log(a), lb = std::log(best), lc = std::log(c);
      const double den = la - 2.0 * lb + lc;
      if (den < 0.0) return peak + 0.5 * (la - lc) / den;
    }
  }
  // Centre of gravity of the run above the threshold around the peak.
  int lo = peak, hi = peak;
  while (lo > 0 && at(lo - 1) > threshold) --lo;
  while (hi + 1 < rows && at(hi + 1) > threshold) ++hi;
  double sum = 0.0, moment = 0.0;
  for (int r = lo; r <= hi; ++r) {
    const double weight = at(r) - threshold;
    sum += weight;
    moment += weight * r;
  }
  return moment / sum;
}

std::vector<std::optional<double>> detectStripe(const ProfileImage& image,
                                                double threshold,
                                                StripeMethod method) {
  std::vector<std::optional<double>> rows(static_cast<std::size_t>(image.columns));
  for (int k = 0; k < image.columns; ++k) {
    rows[static_cast<std::size_t>(k)] =
        detectPeak(image.grey.data() + k, image.rows, static_cast<std::size_t>(image.columns),
                   threshold, method);
  }
  return rows;
}

}  // namespace scanplan::scanner
