#include <scanplan/collision/primitive_distance.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include <boost/math/tools/toms748_solve.hpp>

namespace scanplan::collision::detail {
namespace {

constexpr double kTiny = 1e-300;

double clamp01(double v) { return std::clamp(v, 0.0, 1.0); }

Eigen::Vector3d toLocal(const Primitive& shape, const Eigen::Vector3d& p_W) {
  return shape.X_W.linear().transpose() * (p_W - shape.X_W.translation());
}

// Box-local point distance (the box centred, axis-aligned, half sides h).
double localPointBox(const Eigen::Vector3d& p, const Eigen::Vector3d& h) {
  const Eigen::Vector3d outside = (p.cwiseAbs() - h).cwiseMax(0.0);
  return outside.norm();
}

// Does the box-local segment a + s(b − a), s ∈ [0, 1], meet the box? (Slab clipping.)
// `enter`: where along it, from 0 at a to 1 at b, it first meets the box.
bool segmentMeetsBox(const Eigen::Vector3d& a,
                     const Eigen::Vector3d& b,
                     const Eigen::Vector3d& h,
                     double& enter) {
  return lineMeetsBox(a, b - a, h, 1.0, enter);
}

// The 12 edges of a box-local box: along axis i, at the four sign combinations of the others.
std::array<std::pair<Eigen::Vector3d, Eigen::Vector3d>, 12> localEdges(const Eigen::Vector3d& h) {
  std::array<std::pair<Eigen::Vector3d, Eigen::Vector3d>, 12> edges;
  std::size_t k = 0;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, l = (i + 2) % 3;
    for (int signs = 0; signs < 4; ++signs) {
      Eigen::Vector3d p = Eigen::Vector3d::Zero();
      p[j] = (signs & 1) ? h[j] : -h[j];
      p[l] = (signs & 2) ? h[l] : -h[l];
      Eigen::Vector3d q = p;
      p[i] = -h[i];
      q[i] = h[i];
      edges[k++] = {p, q};
    }
  }
  return edges;
}

// Where along the segment a + x·d, x ∈ [0, 1], the distance to a convex solid is least, from
// `slope(x)` = (p − π(p))·d (π: the solid's nearest point to p = a + x·d), the derivative of half
// the squared distance, which is convex and continuously differentiable: an end where the slope
// points outwards, else where the slope crosses zero (TOMS 748, Boost.Math).
template <class Slope>
double convexSegmentMin(const Eigen::Vector3d& d, Slope&& slope) {
  if (d.squaredNorm() <= kTiny) return 0.0;
  const double at_a = slope(0.0), at_b = slope(1.0);
  if (at_b <= 0.0) return 1.0;
  if (!(at_a < 0.0)) return 0.0;
  std::uintmax_t iterations = 100;
  const auto [lo, hi] = boost::math::tools::toms748_solve(
      slope, 0.0, 1.0, at_a, at_b, boost::math::tools::eps_tolerance<double>(50), iterations);
  return 0.5 * (lo + hi);
}

double localPointCylinderSq(const Eigen::Vector3d& p, double radius, double half_length) {
  const double dr = std::max(std::sqrt(p.x() * p.x() + p.y() * p.y()) - radius, 0.0);
  const double dz = std::max(std::abs(p.z()) - half_length, 0.0);
  return dr * dr + dz * dz;
}

// The closest points of a capsule-like pair from those of its axes: each moved out by its
// radius towards the other (0 when they overlap; the points then are the axes' closest).
Closest inflate(Closest c, double radius_a, double radius_b) {
  const double gap = c.distance - radius_a - radius_b;
  if (gap <= 0.0 || c.distance <= 0.0) return {0.0, c.p_a, c.p_b};
  const Eigen::Vector3d u = (c.p_b - c.p_a) / c.distance;
  return {gap, c.p_a + radius_a * u, c.p_b - radius_b * u};
}

Closest capsuleCapsule(const Primitive& a, const Primitive& b) {
  return inflate(segmentSegment(a.end(-1), a.end(1), b.end(-1), b.end(1)), a.radius(), b.radius());
}

Closest swapped(Closest c) {
  std::swap(c.p_a, c.p_b);
  return c;
}

// Ordered so that a.kind ≤ b.kind (capsule < cylinder < box).
// A cylinder lies in the slab between its caps' planes and in the infinite tube of its radius
// around its axis; the other shape's distance from either (the larger) bounds its distance from
// the cylinder from below. What the enclosing capsule misses on a flat cylinder, as a table
// top: a box above it is as far as the gap to the cap's plane. The other shape is taken whole
// when a box, else as its capsule.
double slabOrTubeGap(const Primitive& cylinder, const Primitive& other) {
  const Eigen::Vector3d u = cylinder.axis(), c = cylinder.X_W.translation();
  const double centre = (other.X_W.translation() - c).dot(u);
  double extent = 0.0;  // the other's half extent along u
  if (other.kind == Primitive::Kind::kBox) {
    extent = (other.X_W.linear().transpose() * u).cwiseAbs().dot(other.half);
  } else {
    extent = std::abs(other.axis().dot(u)) * other.halfLength() + other.radius();
  }
  const double slab = std::abs(centre) - extent - cylinder.halfLength();
  // The axis line's nearest points to the other shape lie within its extent along u.
  const Eigen::Vector3d lo = c + (centre - extent) * u, hi = c + (centre + extent) * u;
  const double line =
      other.kind == Primitive::Kind::kBox
          ? segmentBox(lo, hi, other)
          : std::sqrt(segmentSegmentSq(lo, hi, other.end(-1), other.end(1))) - other.radius();
  return std::max(slab, line - cylinder.radius());
}

PrimitiveDistance ordered(const Primitive& a, const Primitive& b) {
  using Kind = Primitive::Kind;
  if (a.kind == Kind::kCapsule) {
    switch (b.kind) {
      case Kind::kCapsule:
        return {capsuleCapsule(a, b), true};
      case Kind::kCylinder:
        return {inflate(segmentCylinderClosest(a.end(-1), a.end(1), b), a.radius(), 0.0), true};
      case Kind::kBox:
        return {inflate(segmentBoxClosest(a.end(-1), a.end(1), b), a.radius(), 0.0), true};
    }
  }
  if (a.kind == Kind::kCylinder) {  // lower bounds: the enclosing capsules, slabs and tubes
    if (b.kind == Kind::kCylinder) {
      const double one = segmentCylinder(a.end(-1), a.end(1), b) - a.radius();
      const double other = segmentCylinder(b.end(-1), b.end(1), a) - b.radius();
      return {{std::max({one, other, slabOrTubeGap(a, b), slabOrTubeGap(b, a)}), {}, {}}, false};
    }
    const double capsule = segmentBox(a.end(-1), a.end(1), b) - a.radius();
    return {{std::max(capsule, slabOrTubeGap(a, b)), {}, {}}, false};
  }
  return {boxBoxClosest(a, b), true};
}

}  // namespace

bool lineMeetsBox(const Eigen::Vector3d& p,
                  const Eigen::Vector3d& d,
                  const Eigen::Vector3d& h,
                  double s_max,
                  double& enter) {
  double lo = 0.0, hi = s_max;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < kTiny) {
      if (std::abs(p[i]) > h[i]) return false;
      continue;
    }
    double t1 = (-h[i] - p[i]) / d[i], t2 = (h[i] - p[i]) / d[i];
    if (t1 > t2) std::swap(t1, t2);
    lo = std::max(lo, t1);
    hi = std::min(hi, t2);
    if (lo > hi) return false;
  }
  enter = lo;
  return true;
}

Closest segmentSegment(const Eigen::Vector3d& p0,
                       const Eigen::Vector3d& p1,
                       const Eigen::Vector3d& q0,
                       const Eigen::Vector3d& q1) {
  // Ericson, Real-Time Collision Detection §5.1.9, with its degenerate cases.
  const Eigen::Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0.0, t = 0.0;
  if (a <= kTiny && e <= kTiny) return {r.norm(), p0, q0};
  if (a <= kTiny) {
    t = clamp01(f / e);
  } else {
    const double c = d1.dot(r);
    if (e <= kTiny) {
      s = clamp01(-c / a);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 0.0 ? clamp01((b * f - c * e) / denom) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = clamp01(-c / a);
      } else if (t > 1.0) {
        t = 1.0;
        s = clamp01((b - c) / a);
      }
    }
  }
  const Eigen::Vector3d pa = p0 + s * d1, pb = q0 + t * d2;
  return {(pa - pb).norm(), pa, pb};
}

double segmentSegmentSq(const Eigen::Vector3d& p0,
                        const Eigen::Vector3d& p1,
                        const Eigen::Vector3d& q0,
                        const Eigen::Vector3d& q1) {
  const double d = segmentSegment(p0, p1, q0, q1).distance;
  return d * d;
}

Closest pointBoxClosest(const Eigen::Vector3d& p, const Primitive& box) {
  const Eigen::Vector3d local = toLocal(box, p);
  const Eigen::Vector3d on = local.cwiseMax(-box.half).cwiseMin(box.half);
  return {localPointBox(local, box.half), p, box.X_W * on};
}

double pointBox(const Eigen::Vector3d& p, const Primitive& box) {
  return localPointBox(toLocal(box, p), box.half);
}

Closest segmentBoxClosest(const Eigen::Vector3d& a_W,
                          const Eigen::Vector3d& b_W,
                          const Primitive& box) {
  const Eigen::Vector3d a = toLocal(box, a_W), b = toLocal(box, b_W);
  double enter = 0.0;
  if (segmentMeetsBox(a, b, box.half, enter)) {
    const Eigen::Vector3d p = box.X_W * (a + enter * (b - a));
    return {0.0, p, p};
  }
  const Eigen::Vector3d d = b - a;
  const double s = convexSegmentMin(d, [&](double x) {
    const Eigen::Vector3d p = a + x * d;
    return (p - p.cwiseMax(-box.half).cwiseMin(box.half)).dot(d);
  });
  return pointBoxClosest(a_W + s * (b_W - a_W), box);
}

double segmentBox(const Eigen::Vector3d& a_W, const Eigen::Vector3d& b_W, const Primitive& box) {
  return segmentBoxClosest(a_W, b_W, box).distance;
}

double boxGap(const Primitive& a, const Primitive& b) {
  const Eigen::Matrix3d& A = a.X_W.linear();
  const Eigen::Matrix3d& B = b.X_W.linear();
  const Eigen::Vector3d T = b.X_W.translation() - a.X_W.translation();
  double gap = -std::numeric_limits<double>::infinity();
  const auto along = [&](const Eigen::Vector3d& axis) {
    const double n = axis.norm();
    if (n < 1e-9) return;  // parallel edges: the face axes decide
    const double ra = a.half.dot((A.transpose() * axis).cwiseAbs());
    const double rb = b.half.dot((B.transpose() * axis).cwiseAbs());
    gap = std::max(gap, (std::abs(T.dot(axis)) - ra - rb) / n);
  };
  for (int i = 0; i < 3; ++i) {
    along(A.col(i));
    along(B.col(i));
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) along(A.col(i).cross(B.col(j)));
  }
  return gap;
}

Closest boxBoxClosest(const Primitive& a, const Primitive& b) {
  if (boxGap(a, b) <= 0.0) {  // overlapping: the witness points are arbitrary (the centres')
    return {0.0, a.X_W.translation(), b.X_W.translation()};
  }
  const auto edges_a = localEdges(a.half), edges_b = localEdges(b.half);
  Closest best{std::numeric_limits<double>::infinity(), {}, {}};
  const auto keep = [&](const Closest& c) {
    if (c.distance < best.distance) best = c;
  };
  for (const auto& [p, q] : edges_a) {  // a's vertices are its edges' ends
    keep(pointBoxClosest(a.X_W * p, b));
    keep(pointBoxClosest(a.X_W * q, b));
  }
  for (const auto& [p, q] : edges_b) {
    keep(swapped(pointBoxClosest(b.X_W * p, a)));
    keep(swapped(pointBoxClosest(b.X_W * q, a)));
  }
  for (const auto& [pa, qa] : edges_a) {
    const Eigen::Vector3d p = a.X_W * pa, q = a.X_W * qa;
    for (const auto& [pb, qb] : edges_b) keep(segmentSegment(p, q, b.X_W * pb, b.X_W * qb));
  }
  return best;
}

double boxBox(const Primitive& a, const Primitive& b) { return boxBoxClosest(a, b).distance; }

Closest pointCylinderClosest(const Eigen::Vector3d& p, const Primitive& cylinder) {
  const Eigen::Vector3d local = toLocal(cylinder, p);
  const double r = cylinder.radius(), h = cylinder.halfLength();
  Eigen::Vector3d on = local;
  const double rho = std::sqrt(local.x() * local.x() + local.y() * local.y());
  if (rho > r) on.head<2>() *= r / rho;
  on.z() = std::clamp(local.z(), -h, h);
  return {std::sqrt(localPointCylinderSq(local, r, h)), p, cylinder.X_W * on};
}

double pointCylinder(const Eigen::Vector3d& p, const Primitive& cylinder) {
  return std::sqrt(
      localPointCylinderSq(toLocal(cylinder, p), cylinder.radius(), cylinder.halfLength()));
}

Closest segmentCylinderClosest(const Eigen::Vector3d& a_W,
                               const Eigen::Vector3d& b_W,
                               const Primitive& cylinder) {
  const Eigen::Vector3d a = toLocal(cylinder, a_W), d = toLocal(cylinder, b_W) - a;
  const double r = cylinder.radius(), h = cylinder.halfLength();
  const double s = convexSegmentMin(d, [&](double x) {
    const Eigen::Vector3d p = a + x * d;
    Eigen::Vector3d on = p;
    const double rho = std::sqrt(p.x() * p.x() + p.y() * p.y());
    if (rho > r) on.head<2>() *= r / rho;
    on.z() = std::clamp(p.z(), -h, h);
    return (p - on).dot(d);
  });
  return pointCylinderClosest(a_W + s * (b_W - a_W), cylinder);
}

double segmentCylinder(const Eigen::Vector3d& a_W,
                       const Eigen::Vector3d& b_W,
                       const Primitive& cylinder) {
  return segmentCylinderClosest(a_W, b_W, cylinder).distance;
}

double quickLowerBound(const Primitive& a, const Primitive& b) {
  using Kind = Primitive::Kind;
  if (a.kind == Kind::kBox && b.kind == Kind::kBox) return boxGap(a, b);
  if (a.kind == Kind::kBox || b.kind == Kind::kBox) return primitiveDistance(a, b).distance;
  // Capsules and cylinders: each within its axis segment's radius, a cylinder in its capsule.
  return capsuleCapsule(a, b).distance;
}

PrimitiveDistance primitiveDistance(const Primitive& a, const Primitive& b) {
  PrimitiveDistance d = a.kind <= b.kind ? ordered(a, b) : ordered(b, a);
  if (a.kind > b.kind) std::swap(d.p_a, d.p_b);
  d.distance = std::max(d.distance, 0.0);
  return d;
}

}  // namespace scanplan::collision::detail
