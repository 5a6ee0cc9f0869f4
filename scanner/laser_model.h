#pragma once

#include <cmath>

namespace scanplan::scanner {

/// Profile scanner optics (seed §5.3, Eq. 4–5): camera baseline a and offset b (m), camera
/// axis angle φ to the laser plane and half view angle γ (rad). Valid when a > 0 and
/// 0 < γ < φ < π/2 − γ.
struct LaserOptics {
  double a = 0.1;
  double b = 0.1;
  double phi = 1.0471975511965976;     // 60°
  double gamma = 0.17453292519943295;  // 10°
};

/// The measured trapezoid in the laser plane (YZ of the scanner frame), Eq. 5, m:
/// depth z in [z_min, z_max]; half-width y_near at z_min, y_far at z_max.
struct LaserWindow {
  double z_min = 0.0;
  double z_max = 0.0;
  double y_near = 0.0;
  double y_far = 0.0;

  /// Half-width of the measured line at depth z (linear between near and far).
  double halfWidth(double z) const {
    const double s = (z - z_min) / (z_max - z_min);
    return y_near + s * (y_far - y_near);
  }
  /// Inside the trapezoid? (Inline: the scanner simulation asks once per fan-ray hit.)
  bool contains(double y, double z) const {
    return z >= z_min && z <= z_max && std::abs(y) <= halfWidth(z);
  }
};

/// Eq. 5. Precondition: the optics are valid (see LaserOptics).
LaserWindow laserWindow(const LaserOptics& optics);

/// Eq. 4 in the consistent form of docs/design.md §6: pixel (p_x, p_y) → laser-plane point (y, z),
/// f = H / (2 tan γ) in pixels for an image H pixels high.
void triangulate(const LaserOptics& optics,
                 double image_height_px,
                 double p_x,
                 double p_y,
                 double& y,
                 double& z);

}  // namespace scanplan::scanner
