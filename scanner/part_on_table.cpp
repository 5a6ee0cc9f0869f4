#include <scanplan/scanner/part_on_table.h>

#include <scanplan/kinematics/shape.h>

namespace scanplan::scanner {

namespace {

kinematics::TriangleMesh partAndTable(const kinematics::TriangleMesh& part_R, TableTop table) {
  kinematics::Shape top{kinematics::Cylinder{table.radius, table.height}};  // X_BG: identity
  top.X_BG.translation() = Eigen::Vector3d(0.0, 0.0, -0.5 * table.height);
  const kinematics::TriangleMesh cylinder = kinematics::shapeSurface(top);
  kinematics::TriangleMesh all = part_R;
  const int offset = static_cast<int>(all.vertices.size());
  all.vertices.insert(all.vertices.end(), cylinder.vertices.begin(), cylinder.vertices.end());
  for (const Eigen::Vector3i& t : cylinder.triangles)
    all.triangles.push_back(t + Eigen::Vector3i::Constant(offset));
  return all;
}

}  // namespace

PartOnTable::PartOnTable(const kinematics::TriangleMesh& part,
                         const Eigen::Isometry3d& X_RP,
                         TableTop table)
    : X_RP_(X_RP), table_(table), part_triangles_(part.triangles.size()) {
  part_R_.triangles = part.triangles;
  part_R_.vertices.reserve(part.vertices.size());
  for (const Eigen::Vector3d& v : part.vertices) part_R_.vertices.push_back(X_RP * v);
  raycaster_.emplace(partAndTable(part_R_, table));
}

std::optional<RayHit> PartOnTable::cast(const Eigen::Vector3d& origin,
                                        const Eigen::Vector3d& direction,
                                        double t_near,
                                        double t_far) const {
  return raycaster_->cast(origin, direction, t_near, t_far);
}

bool PartOnTable::clear(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double margin) const {
  const Eigen::Vector3d d = b - a;
  const double length = d.norm();
  if (length <= 2.0 * margin) return true;
  return !raycaster_->cast(a, d, margin, length - margin).has_value();
}

}  // namespace scanplan::scanner
