#include "kinematics/placement.h"

#include <algorithm>
#include <limits>

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

}  // namespace scanplan::kinematics
