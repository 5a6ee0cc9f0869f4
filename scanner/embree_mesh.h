#pragma once
// Private to scanner/: a triangle mesh as an Embree geometry. Not installed.

#include <cmath>

#include <embree3/rtcore.h>

#include <scanplan/kinematics/mesh.h>

namespace scanplan::scanner {

// A committed triangle geometry of `mesh` on `device`; the caller attaches and releases it.
// Vertices are stored 16 bytes apart with w = 0: Embree reads each vertex with a 16-byte load,
// and with a 12-byte stride the last vertex's w came from the buffer's uninitialised padding
// (valgrind reported branches on it inside the BVH build).
RTCGeometry embreeTriangles(RTCDevice device, const kinematics::TriangleMesh& mesh);

// A ray direction component as Embree must get it. Embree replaces a component under ~1e-18 by
// a fixed positive one before taking its reciprocal, losing its sign: a fan in a link's x = 0
// plane (x = −1e-19 of rounding noise) then culled the BVH nodes on its own side, and whole
// 4-ray packets went through the link's box. Such a component keeps its sign at 1e-15 (a bend
// of 1e-15 rad, to the side the brute-force backend takes too).
inline float embreeDirection(double v) noexcept {
  constexpr double kSmallest = 1e-15;
  if (v != 0.0 && std::abs(v) < kSmallest) return static_cast<float>(std::copysign(kSmallest, v));
  return static_cast<float>(v);
}

}  // namespace scanplan::scanner
