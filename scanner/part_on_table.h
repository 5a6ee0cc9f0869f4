#pragma once
// The part resting on the table, seen in the table-top frame R (z up, the top at z = 0, the axis
// at x = y = 0): what the automatic scan planner casts rays against. The table is a body of
// revolution about R's z axis, so in R it does not move when the table turns: a scanner pose in R
// at table angle 0 stands for the same view at every angle (the table absorbs the azimuth).

#include <cstddef>
#include <optional>

#include <Eigen/Geometry>

#include <scanplan/kinematics/mesh.h>
#include <scanplan/scanner/raycaster.h>

namespace scanplan::scanner {

/// The table's top as an obstacle in R: a cylinder of `radius` from z = −height to 0, m.
struct TableTop {
  double radius = 0.25;
  double height = 0.1;
};

class PartOnTable {
 public:
  /// `part` in its own frame P (m), placed by X_RP. The table is tessellated within 0.1 mm.
  PartOnTable(const kinematics::TriangleMesh& part, const Eigen::Isometry3d& X_RP, TableTop table);

  /// The part mesh in R.
  const kinematics::TriangleMesh& part() const { return part_R_; }
  const Eigen::Isometry3d& X_RP() const { return X_RP_; }
  const TableTop& table() const { return table_; }

  /// Nearest hit on the part or the table along origin + s·d̂, s in [t_near, t_far] (R, m).
  std::optional<RayHit> cast(const Eigen::Vector3d& origin,
                             const Eigen::Vector3d& direction,
                             double t_near = 0.0,
                             double t_far = 1e30) const;
  /// The hit lies on the part (its triangle is a part triangle, RayHit::triangle indexes it).
  bool onPart(const RayHit& hit) const { return hit.triangle < part_triangles_; }
  /// Nothing (part or table) between `a` and `b`, leaving `margin` (m) free at both ends.
  bool clear(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double margin = 2e-5) const;

 private:
  kinematics::TriangleMesh part_R_;
  Eigen::Isometry3d X_RP_;
  TableTop table_;
  std::size_t part_triangles_ = 0;
  std::optional<Raycaster> raycaster_;
};

}  // namespace scanplan::scanner
