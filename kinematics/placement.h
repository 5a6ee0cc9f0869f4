#pragma once
// A part on the rotary table: where it rests and how far it reaches (table-top frame R: z up,
// the top at z = 0, the axis at x = y = 0).

#include <Eigen/Geometry>

#include <scanplan/kinematics/cell.h>
#include <scanplan/kinematics/mesh.h>

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

/// How much of the part placed in `cell` the arm could reach at some table angle.
struct PartReach {
  double beyond_fraction = 0.0;  ///< share of the (sampled) vertices beyond reach at every angle
  /// The least, over the sampled vertices, of how far beyond reach they stay at their best
  /// table angle, m: above 0, no vertex of the part is within reach.
  double nearest_excess = 0.0;
  double arm_reach = 0.0;  ///< the bound used: the arm's longest stretch plus `lever`, m
};

/// A necessary condition for reach. A scanned point lies within `lever` (m: wrist centre to
/// flange, flange to laser, laser to the far end of its window) of the wrist centre, and the
/// wrist centre within c2 + √(a2² + c3²) + |b| of the shoulder circle (radius |a1| at height c1
/// about J1). A vertex beyond that sum at every table angle (every 2°) is beyond reach; one
/// within it may still be out of reach (joint limits, orientation). At most 4 096 vertices are
/// sampled, evenly by index.
PartReach partReach(const CellModel& cell, const TriangleMesh& mesh, double lever);

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
