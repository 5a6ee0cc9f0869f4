#pragma once
// A part on the rotary table: where it rests and how far it reaches (table-top frame R: z up,
// the top at z = 0, the axis at x = y = 0).

#include <Eigen/Geometry>

#include "kinematics/mesh.h"

namespace scanplan::kinematics {

/// X_RP that rests `mesh` (part frame P, m) on the table top: its lowest point at z = 0 and its
/// bounding box centred on the axis, after `pose`'s rotation; `pose`'s translation is an offset
/// from there.
Eigen::Isometry3d placedOnTable(const TriangleMesh& mesh, const Eigen::Isometry3d& pose);

/// How the part placed by X_RP sits on the table, m.
struct PartExtent {
  double lowest = 0.0;  ///< z of its lowest point (below 0: it reaches into the table)
  double widest = 0.0;  ///< largest distance of a vertex from the table axis
};
PartExtent partExtent(const TriangleMesh& mesh, const Eigen::Isometry3d& X_RP);

/// The centre of mass of the solid a closed, outward-wound mesh bounds (uniform density), in the
/// mesh's frame, m: the volume-weighted centroids of the tetrahedra from the origin to each
/// triangle. The area centroid when the volume is (near) zero.
Eigen::Vector3d solidCentroid(const TriangleMesh& mesh);

/// The part placed by X_RP rests stably on the table top: its centre of mass lies over the
/// convex hull of the points it touches the top with (vertices within `contact` of the lowest,
/// m), at least `margin` inside it. A part touching at fewer than 3 non-collinear points does
/// not rest stably.
bool restsStably(const TriangleMesh& mesh,
                 const Eigen::Isometry3d& X_RP,
                 double contact = 5e-4,
                 double margin = 2e-3);

}  // namespace scanplan::kinematics
