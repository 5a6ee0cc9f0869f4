#include <scanplan/kinematics/placement.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

namespace scanplan::kinematics {

Eigen::Isometry3d placedOnTable(const TriangleMesh& mesh, const Eigen::Isometry3d& pose) {
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& v : mesh.vertices) box.extend(pose.linear() * v);
  Eigen::Isometry3d X_RP = pose;
  if (box.isEmpty()) return X_RP;
  X_RP.translation() += Eigen::Vector3d(-box.center().x(), -box.center().y(), -box.min().z());
  return X_RP;
}

PartExtent partExtent(const TriangleMesh& mesh, const Eigen::Isometry3d& X_RP) {
  PartExtent e;
  e.lowest = mesh.vertices.empty() ? 0.0 : std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& v : mesh.vertices) {
    const Eigen::Vector3d p_R = X_RP * v;
    e.lowest = std::min(e.lowest, p_R.z());
    e.widest = std::max(e.widest, p_R.head<2>().norm());
  }
  return e;
}

namespace {

// Distance of p (robot base frame) from the circle the shoulder sweeps about J1.
double fromShoulderCircle(const OpwParameters& opw, const Eigen::Vector3d& p) {
  const double radial = p.head<2>().norm() - std::abs(opw.a1);
  return std::hypot(radial, p.z() - opw.c1);
}

}  // namespace

PartReach partReach(const CellModel& cell, const TriangleMesh& mesh, double lever) {
  const OpwParameters& opw = cell.robot.definition().opw;
  PartReach r;
  r.arm_reach = opw.c2 + std::hypot(opw.a2, opw.c3) + std::abs(opw.b) + lever;
  constexpr std::size_t kMaxVertices = 4096;
  constexpr int kAngles = 180;  // every 2°
  const std::size_t n = mesh.vertices.size();
  const std::size_t stride = std::max<std::size_t>(1, (n + kMaxVertices - 1) / kMaxVertices);
  std::vector<Eigen::Isometry3d> X_BR(kAngles);
  for (int k = 0; k < kAngles; ++k) {
    X_BR[static_cast<std::size_t>(k)] = cell.X_WB.inverse() *
                                        cell.table.X_WR(2.0 * std::numbers::pi * k / kAngles) *
                                        cell.part.X_RP;
  }
  std::size_t sampled = 0, beyond = 0;
  r.nearest_excess = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; i += stride, ++sampled) {
    double best = std::numeric_limits<double>::infinity();
    for (const Eigen::Isometry3d& X : X_BR) {
      best = std::min(best, fromShoulderCircle(opw, X * mesh.vertices[i]));
    }
    const double excess = best - r.arm_reach;
    r.nearest_excess = std::min(r.nearest_excess, excess);
    if (excess > 0.0) ++beyond;
  }
  if (sampled == 0) r.nearest_excess = -r.arm_reach;
  r.beyond_fraction = sampled ? static_cast<double>(beyond) / static_cast<double>(sampled) : 0.0;
  return r;
}

Eigen::Vector3d solidCentroid(const TriangleMesh& mesh) {
  double volume = 0.0, area = 0.0;
  Eigen::Vector3d moment = Eigen::Vector3d::Zero(), area_moment = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d& a = mesh.vertices[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d& b = mesh.vertices[static_cast<std::size_t>(t[1])];
    const Eigen::Vector3d& c = mesh.vertices[static_cast<std::size_t>(t[2])];
    const double v = a.dot(b.cross(c)) / 6.0;  // signed tetrahedron (origin, a, b, c)
    volume += v;
    moment += v * (a + b + c) / 4.0;
    const double s = 0.5 * (b - a).cross(c - a).norm();
    area += s;
    area_moment += s * (a + b + c) / 3.0;
  }
  if (std::abs(volume) > 1e-12) return moment / volume;
  return area > 0.0 ? Eigen::Vector3d(area_moment / area) : Eigen::Vector3d::Zero();
}

namespace {

// Andrew's monotone chain: the convex hull of 2-D points, counter-clockwise.
std::vector<Eigen::Vector2d> hull2d(std::vector<Eigen::Vector2d> p) {
  std::sort(p.begin(), p.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  if (p.size() < 3) return p;
  const auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a,
                        const Eigen::Vector2d& b) {
    return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
  };
  std::vector<Eigen::Vector2d> h(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0.0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && cross(h[k - 2], h[k - 1], p[i]) <= 0.0) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);
  return h;
}

}  // namespace

bool restsStably(const TriangleMesh& mesh,
                 const Eigen::Isometry3d& X_RP,
                 double contact,
                 double margin) {
  const double lowest = partExtent(mesh, X_RP).lowest;
  std::vector<Eigen::Vector2d> touching;
  for (const Eigen::Vector3d& v : mesh.vertices) {
    const Eigen::Vector3d p = X_RP * v;
    if (p.z() <= lowest + contact) touching.push_back(p.head<2>());
  }
  const std::vector<Eigen::Vector2d> h = hull2d(std::move(touching));
  if (h.size() < 3) return false;
  const Eigen::Vector2d c = (X_RP * solidCentroid(mesh)).head<2>();
  // Inside a counter-clockwise polygon by `margin`: left of every edge by at least that much.
  for (std::size_t i = 0; i < h.size(); ++i) {
    const Eigen::Vector2d e = h[(i + 1) % h.size()] - h[i];
    const double left = (e.x() * (c - h[i]).y() - e.y() * (c - h[i]).x()) / e.norm();
    if (left < margin) return false;
  }
  return true;
}

}  // namespace scanplan::kinematics
