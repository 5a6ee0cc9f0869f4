#pragma once
// Internal to collision/: point queries against a triangle mesh through FCL's BVH of it, and the
// branch and bound that bounds a distance function over a surface. Nothing outside collision/
// includes this.

#include <algorithm>
#include <cstddef>
#include <limits>
#include <queue>
#include <vector>

#include <Eigen/Core>

#include <scanplan/collision/convex_hull.h>
#include <scanplan/collision/fcl_geometry.h>
#include <scanplan/kinematics/mesh.h>

namespace scanplan::collision::detail {

/// Distance from a point to a mesh's surface: a depth-first walk of FCL's BVH of the mesh, the
/// nearer child first, nodes pruned by the gap to their OBB, leaves by FCL's point–triangle
/// distance. Not thread-safe (it keeps its stack); one per thread.
class PointMeshDistance {
 public:
  explicit PointMeshDistance(const MeshModel& mesh) : mesh_(mesh) {}
  double operator()(const Eigen::Vector3d& p);

 private:
  struct Entry {
    int node;
    double gap;
  };
  double gap(int id, const Eigen::Vector3d& p) const;
  double triangle(int primitive, const Eigen::Vector3d& p) const;

  const MeshModel& mesh_;
  std::vector<Entry> stack_;
};

/// Whether a point lies inside the solid a closed mesh bounds: the parity of the surface
/// crossings of three rays in fixed, unrelated directions, by majority (one ray grazing an edge
/// or slipping through a crack does not decide). The walk skips BVH nodes the ray misses.
class PointInside {
 public:
  explicit PointInside(const MeshModel& mesh) : mesh_(mesh) {}
  bool operator()(const Eigen::Vector3d& p);

 private:
  int crossings(const Eigen::Vector3d& p, const Eigen::Vector3d& direction);
  const MeshModel& mesh_;
  std::vector<int> stack_;
};

/// Distance from a point to the solid a closed mesh bounds: 0 inside, else to its surface.
class PointSolidDistance {
 public:
  explicit PointSolidDistance(const MeshModel& mesh) : surface_(mesh), inside_(mesh) {}
  double operator()(const Eigen::Vector3d& p) { return inside_(p) ? 0.0 : surface_(p); }

 private:
  PointMeshDistance surface_;
  PointInside inside_;
};

/// An upper bound on max over the surface of `distance` (any 1-Lipschitz function of the point),
/// within `tolerance` of the largest value measured: branch and bound over the surface's
/// triangles, each split in four while its bound (the value at its centroid plus its reach from
/// there) is the largest and above the largest value found plus the tolerance. After
/// `max_queries` evaluations, or once a value above `give_up` is found, it stops: the bound is
/// then only looser, never lower than the truth. It also stops once the bound is within
/// `enough`, when only that matters.
template <class Distance>
HullMargin surfaceBound(const kinematics::TriangleMesh& surface,
                        Distance& distance,
                        double tolerance,
                        std::size_t max_queries,
                        double give_up = std::numeric_limits<double>::infinity(),
                        double enough = 0.0) {
  struct Piece {
    Eigen::Vector3d a, b, c;
    double upper = 0.0;
  };
  HullMargin out;
  const auto make = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                        const Eigen::Vector3d& c) {
    const Eigen::Vector3d g = (a + b + c) / 3.0;
    const double d = distance(g);
    if (d > out.found) {
      out.found = d;
      out.where = g;
    }
    ++out.queries;
    const double reach = std::max({(a - g).norm(), (b - g).norm(), (c - g).norm()});
    return Piece{a, b, c, d + reach};
  };
  const auto lower = [](const Piece& x, const Piece& y) { return x.upper < y.upper; };
  std::priority_queue<Piece, std::vector<Piece>, decltype(lower)> pieces(lower);
  for (const Eigen::Vector3i& t : surface.triangles) {
    pieces.push(make(surface.vertices[static_cast<std::size_t>(t[0])],
                     surface.vertices[static_cast<std::size_t>(t[1])],
                     surface.vertices[static_cast<std::size_t>(t[2])]));
  }
  if (pieces.empty()) return out;
  while (pieces.top().upper > std::max(out.found + tolerance, enough) &&
         out.queries + 4 <= max_queries && out.found <= give_up) {
    const Piece p = pieces.top();
    pieces.pop();
    const Eigen::Vector3d ab = 0.5 * (p.a + p.b), bc = 0.5 * (p.b + p.c), ca = 0.5 * (p.c + p.a);
    pieces.push(make(p.a, ab, ca));
    pieces.push(make(ab, p.b, bc));
    pieces.push(make(ca, bc, p.c));
    pieces.push(make(ab, bc, ca));
  }
  out.margin = std::max(pieces.top().upper, out.found);
  return out;
}

}  // namespace scanplan::collision::detail
