#include <scanplan/collision/mesh_distance.h>

#include <array>
#include <cmath>
#include <limits>

#include <fcl/narrowphase/detail/primitive_shape_algorithm/sphere_triangle.h>

#include <scanplan/collision/primitive_distance.h>

namespace scanplan::collision::detail {

double PointMeshDistance::operator()(const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  stack_.clear();
  stack_.push_back({0, gap(0, p)});
  while (!stack_.empty()) {
    const Entry e = stack_.back();
    stack_.pop_back();
    if (e.gap >= best) continue;
    const auto& node = mesh_.getBV(e.node);
    if (node.isLeaf()) {
      best = std::min(best, triangle(node.primitiveId(), p));
      if (best <= 0.0) return 0.0;
      continue;
    }
    const int l = node.leftChild(), r = node.rightChild();
    const double gl = gap(l, p), gr = gap(r, p);
    stack_.push_back(gl <= gr ? Entry{r, gr} : Entry{l, gl});
    stack_.push_back(gl <= gr ? Entry{l, gl} : Entry{r, gr});
  }
  return best;
}

double PointMeshDistance::gap(int id, const Eigen::Vector3d& p) const {
  const fcl::OBBd& obb = mesh_.getBV(id).bv.obb;
  const Eigen::Vector3d local = obb.axis.transpose() * (p - obb.To);
  return (local.cwiseAbs() - obb.extent).cwiseMax(0.0).norm();
}

double PointMeshDistance::triangle(int primitive, const Eigen::Vector3d& p) const {
  static const fcl::Sphered point(0.0);
  const fcl::Triangle& t = mesh_.tri_indices[primitive];
  fcl::Transform3d at = fcl::Transform3d::Identity();
  at.translation() = p;
  double d = 0.0;
  // false: the point lies on the triangle (within its radius 0).
  if (!fcl::detail::sphereTriangleDistance(point, at, mesh_.vertices[t[0]], mesh_.vertices[t[1]],
                                           mesh_.vertices[t[2]], &d)) {
    return 0.0;
  }
  return std::max(d, 0.0);
}

namespace {

// Whether the ray p + s·u (s > 0) crosses the triangle abc (Möller–Trumbore).
bool rayCrossesTriangle(const Eigen::Vector3d& p,
                        const Eigen::Vector3d& u,
                        const Eigen::Vector3d& a,
                        const Eigen::Vector3d& b,
                        const Eigen::Vector3d& c) {
  const Eigen::Vector3d e1 = b - a, e2 = c - a, h = u.cross(e2);
  const double det = e1.dot(h);
  if (std::abs(det) < 1e-300) return false;  // parallel to the plane
  const Eigen::Vector3d s = p - a;
  const double v = s.dot(h) / det;
  if (v < 0.0 || v > 1.0) return false;
  const Eigen::Vector3d q = s.cross(e1);
  const double w = u.dot(q) / det;
  if (w < 0.0 || v + w > 1.0) return false;
  return e2.dot(q) / det > 0.0;
}

}  // namespace

int PointInside::crossings(const Eigen::Vector3d& p, const Eigen::Vector3d& u) {
  int count = 0;
  stack_.assign(1, 0);
  while (!stack_.empty()) {
    const int id = stack_.back();
    stack_.pop_back();
    const auto& node = mesh_.getBV(id);
    const fcl::OBBd& obb = node.bv.obb;
    double enter = 0.0;
    if (!lineMeetsBox(obb.axis.transpose() * (p - obb.To), obb.axis.transpose() * u, obb.extent,
                      std::numeric_limits<double>::infinity(), enter)) {
      continue;
    }
    if (node.isLeaf()) {
      const fcl::Triangle& t = mesh_.tri_indices[node.primitiveId()];
      count += rayCrossesTriangle(p, u, mesh_.vertices[t[0]], mesh_.vertices[t[1]],
                                  mesh_.vertices[t[2]]);
      continue;
    }
    stack_.push_back(node.leftChild());
    stack_.push_back(node.rightChild());
  }
  return count;
}

bool PointInside::operator()(const Eigen::Vector3d& p) {
  // Directions no mesh axis or facet of ordinary CAD is likely to line up with.
  static const std::array<Eigen::Vector3d, 3> directions = {
      Eigen::Vector3d(0.5773, 0.3341, 0.7451).normalized(),
      Eigen::Vector3d(-0.6154, 0.7123, -0.3372).normalized(),
      Eigen::Vector3d(0.2719, -0.8562, -0.4393).normalized()};
  int odd = 0;
  for (const Eigen::Vector3d& u : directions) odd += crossings(p, u) % 2;
  return odd >= 2;
}

}  // namespace scanplan::collision::detail
