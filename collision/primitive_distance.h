#pragma once
// Internal to collision/: closed-form distances between convex primitives (spheres, capsules,
// cylinders, boxes), tried before FCL/libccd's GJK. Every query here is exact up to rounding
// except where a result says it is only a lower bound (cylinder against a box or a cylinder:
// the cylinder's enclosing capsule), in which case a caller that needs the value asks FCL.

#include <Eigen/Geometry>

namespace scanplan::collision::detail {

/// A convex primitive at a world pose, m. A sphere is a capsule of zero length.
struct Primitive {
  enum class Kind { kCapsule, kCylinder, kBox };
  Kind kind = Kind::kCapsule;
  Eigen::Isometry3d X_W = Eigen::Isometry3d::Identity();  ///< centre; axis along local z
  Eigen::Vector3d half = Eigen::Vector3d::Zero();  ///< box: half sides; else (r, r, half length)

  double radius() const { return half.x(); }
  double halfLength() const { return half.z(); }
  Eigen::Vector3d axis() const { return X_W.linear().col(2); }
  /// The axis segment's ends (capsules, cylinders).
  Eigen::Vector3d end(double sign) const { return X_W.translation() + sign * half.z() * axis(); }
};

/// A distance and where it is: p_a on the first, p_b on the second (world, m). When the
/// shapes overlap the distance is 0 and the points are some points inside.
struct Closest {
  double distance = 0.0;
  Eigen::Vector3d p_a = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_b = Eigen::Vector3d::Zero();
};

/// Closest points of segments [p0, p1] and [q0, q1] (either may be a point).
Closest segmentSegment(const Eigen::Vector3d& p0,
                       const Eigen::Vector3d& p1,
                       const Eigen::Vector3d& q0,
                       const Eigen::Vector3d& q1);
/// Closest points of a point and a solid box, of a segment and a box, of two boxes, of a point
/// and a solid cylinder, of a segment and a cylinder (as the distances below).
Closest pointBoxClosest(const Eigen::Vector3d& p, const Primitive& box);
Closest segmentBoxClosest(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Primitive& box);
Closest boxBoxClosest(const Primitive& a, const Primitive& b);
Closest pointCylinderClosest(const Eigen::Vector3d& p, const Primitive& cylinder);
Closest segmentCylinderClosest(const Eigen::Vector3d& a,
                               const Eigen::Vector3d& b,
                               const Primitive& cylinder);

/// Squared distance between segments [p0, p1] and [q0, q1] (either may be a point).
double segmentSegmentSq(const Eigen::Vector3d& p0,
                        const Eigen::Vector3d& p1,
                        const Eigen::Vector3d& q0,
                        const Eigen::Vector3d& q1);

/// Distance from a point to a solid box (0 inside).
double pointBox(const Eigen::Vector3d& p, const Primitive& box);

/// Does the line p + s·d, s ∈ [0, s_max] (s_max may be +∞: a ray), meet the axis-aligned box of
/// half sides h centred at the origin? (Slab clipping.) `enter`: the first s where it does.
bool lineMeetsBox(const Eigen::Vector3d& p,
                  const Eigen::Vector3d& d,
                  const Eigen::Vector3d& h,
                  double s_max,
                  double& enter);
/// Distance from a segment to a solid box (0 when it meets the box).
double segmentBox(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Primitive& box);
/// The widest gap between two boxes along any of the 15 separating axes: a lower bound on their
/// distance, and ≤ 0 exactly when they overlap or touch (separating-axis theorem).
double boxGap(const Primitive& a, const Primitive& b);
/// Distance between two solid boxes: 0 when they overlap (separating axes), else the least of
/// the vertex–box and edge–edge distances.
double boxBox(const Primitive& a, const Primitive& b);
/// Distance from a point to a solid cylinder (0 inside).
double pointCylinder(const Eigen::Vector3d& p, const Primitive& cylinder);
/// Distance from a segment to a solid cylinder: the squared point–cylinder distance is convex
/// and smooth along the segment; its slope's zero found by TOMS 748 (Boost.Math).
double segmentCylinder(const Eigen::Vector3d& a,
                       const Eigen::Vector3d& b,
                       const Primitive& cylinder);

/// The distance between two primitives (0 when they touch or overlap) with its witness points,
/// or only a lower bound on it (no points) where `exact` is false.
struct PrimitiveDistance : Closest {
  bool exact = true;
};
PrimitiveDistance primitiveDistance(const Primitive& a, const Primitive& b);

/// A lower bound on the distance, cheaper than primitiveDistance where that searches: two
/// boxes by their separating-axis gap, capsules and cylinders as capsules (segment–segment).
double quickLowerBound(const Primitive& a, const Primitive& b);

}  // namespace scanplan::collision::detail
