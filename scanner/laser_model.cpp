#include <scanplan/scanner/laser_model.h>

#include <cmath>

namespace scanplan::scanner {

LaserWindow laserWindow(const LaserOptics& o) {
  LaserWindow w;
  w.z_min = o.a / std::tan(o.phi + o.gamma) + o.b;
  w.z_max = o.a / std::tan(o.phi - o.gamma) + o.b;
  w.y_near = o.a * std::tan(o.gamma) / std::sin(o.phi + o.gamma);
  w.y_far = o.a * std::tan(o.gamma) / std::sin(o.phi - o.gamma);
  return w;
}

void triangulate(
    const LaserOptics& o, double image_height_px, double p_x, double p_y, double& y, double& z) {
  const double f = image_height_px / (2.0 * std::tan(o.gamma));
  const double angle = o.phi - std::atan(p_y / f);
  y = o.a * p_x / (f * std::sin(angle));
  z = o.a / std::tan(angle) + o.b;
}

}  // namespace scanplan::scanner
