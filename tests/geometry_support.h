#pragma once

// Brute-force geometry for checking simulated points against meshes (test_scanner_sim,
// test_cli_verify), and small meshes with known answers.
#include <Eigen/Core>

#include <scanplan/kinematics/mesh.h>

namespace scanplan::test {

/// An axis-aligned cube of edge `a` centred at the origin, outward winding, 12 triangles.
inline kinematics::TriangleMesh centredCube(double a) {
  kinematics::TriangleMesh box;
  for (int i = 0; i < 8; ++i) {
    box.vertices.emplace_back(0.5 * a * ((i & 1) ? 1 : -1), 0.5 * a * ((i & 2) ? 1 : -1),
                              0.5 * a * ((i & 4) ? 1 : -1));
  }
  box.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                   {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return box;
}

/// Closest distance from p to the triangle abc (Ericson, Real-Time Collision Detection, 5.1.5),
/// in the units of its arguments.
inline double pointTriangleDistance(const Eigen::Vector3d& p,
                                    const Eigen::Vector3d& a,
                                    const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return (p - a).norm();
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return (p - b).norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return (p - c).norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
  }
  const double denom = 1.0 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

}  // namespace scanplan::test
