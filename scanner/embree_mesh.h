#pragma once
// Private to scanner/: a triangle mesh as an Embree geometry. Not installed.

#include <embree3/rtcore.h>

#include "kinematics/mesh.h"

namespace scanplan::scanner {

// A committed triangle geometry of `mesh` on `device`; the caller attaches and releases it.
// Vertices are stored 16 bytes apart with w = 0: Embree reads each vertex with a 16-byte load,
// and with a 12-byte stride the last vertex's w came from the buffer's uninitialised padding
// (valgrind reported branches on it inside the BVH build).
RTCGeometry embreeTriangles(RTCDevice device, const kinematics::TriangleMesh& mesh);

}  // namespace scanplan::scanner
