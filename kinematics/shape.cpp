#include <scanplan/kinematics/shape.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace scanplan::kinematics {
namespace {

// Segments around a circle of radius r so that each chord's sagitta r·(1 − cos(π/n)) stays
// within the tolerance.
int segmentsFor(double radius, const TessellationOptions& options) {
  int n = options.min_segments;
  if (radius > options.chord_tolerance && options.chord_tolerance > 0.0) {
    const double half_angle = std::acos(1.0 - options.chord_tolerance / radius);
    // Clamped as a double: a tiny tolerance asks for more segments than an int holds.
    n = static_cast<int>(std::min(std::ceil(std::numbers::pi / half_angle), 1e6));
  } else if (options.chord_tolerance <= 0.0) {
    n = options.max_segments;
  }
  return std::clamp(n, std::max(3, options.min_segments), std::max(3, options.max_segments));
}

TriangleMesh boxSurface(const Eigen::Vector3d& size) {
  TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) {  // vertex i: bit 0 = +x, bit 1 = +y, bit 2 = +z
    mesh.vertices.push_back(0.5 * Eigen::Vector3d((i & 1) ? size.x() : -size.x(),
                                                  (i & 2) ? size.y() : -size.y(),
                                                  (i & 4) ? size.z() : -size.z()));
  }
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    mesh.triangles.emplace_back(f[0], f[1], f[2]);
    mesh.triangles.emplace_back(f[0], f[2], f[3]);
  }
  return mesh;
}

TriangleMesh cylinderSurface(double radius, double length, const TessellationOptions& options) {
  const int n = segmentsFor(radius, options);
  const double h = 0.5 * length;
  TriangleMesh mesh;
  for (int i = 0; i < n; ++i) {  // 2i: bottom ring, 2i + 1: top ring
    const double a = 2.0 * std::numbers::pi * i / n;
    mesh.vertices.emplace_back(radius * std::cos(a), radius * std::sin(a), -h);
    mesh.vertices.emplace_back(radius * std::cos(a), radius * std::sin(a), h);
  }
  const int bottom = 2 * n, top = 2 * n + 1;
  mesh.vertices.emplace_back(0.0, 0.0, -h);
  mesh.vertices.emplace_back(0.0, 0.0, h);
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    mesh.triangles.emplace_back(2 * i, 2 * j, 2 * j + 1);
    mesh.triangles.emplace_back(2 * i, 2 * j + 1, 2 * i + 1);
    mesh.triangles.emplace_back(bottom, 2 * j, 2 * i);
    mesh.triangles.emplace_back(top, 2 * i + 1, 2 * j + 1);
  }
  return mesh;
}

// A UV sphere of the radius, its upper half lifted by +half_length and its lower half lowered
// by −half_length along z: a sphere for 0, a capsule otherwise (the two equator rings then
// bound the cylindrical band).
TriangleMesh roundSurface(double radius, double half_length, const TessellationOptions& options) {
  const int n = segmentsFor(radius, options);
  const int half_rings = std::max(1, (n + 3) / 4);  // latitude steps per hemisphere
  struct Ring {
    double polar;
    double z_offset;
  };
  std::vector<Ring> rings;
  for (int k = 1; k <= half_rings; ++k) {
    rings.push_back({0.5 * std::numbers::pi * k / half_rings, half_length});
  }
  for (int k = half_length > 0.0 ? 0 : 1; k < half_rings; ++k) {
    rings.push_back(
        {0.5 * std::numbers::pi * (1.0 + static_cast<double>(k) / half_rings), -half_length});
  }
  TriangleMesh mesh;
  mesh.vertices.emplace_back(0.0, 0.0, radius + half_length);
  for (const Ring& ring : rings) {
    for (int i = 0; i < n; ++i) {
      const double a = 2.0 * std::numbers::pi * i / n;
      mesh.vertices.emplace_back(radius * std::sin(ring.polar) * std::cos(a),
                                 radius * std::sin(ring.polar) * std::sin(a),
                                 radius * std::cos(ring.polar) + ring.z_offset);
    }
  }
  const int south = static_cast<int>(mesh.vertices.size());
  mesh.vertices.emplace_back(0.0, 0.0, -radius - half_length);
  const auto at = [n](int ring, int i) { return 1 + ring * n + (i % n); };
  const int last = static_cast<int>(rings.size()) - 1;
  for (int i = 0; i < n; ++i) {
    mesh.triangles.emplace_back(0, at(0, i), at(0, i + 1));
    for (int r = 0; r < last; ++r) {
      mesh.triangles.emplace_back(at(r, i), at(r + 1, i), at(r + 1, i + 1));
      mesh.triangles.emplace_back(at(r, i), at(r + 1, i + 1), at(r, i + 1));
    }
    mesh.triangles.emplace_back(south, at(last, i + 1), at(last, i));
  }
  return mesh;
}

}  // namespace

std::string shapeKindName(const ShapeGeometry& geometry) {
  struct Namer {
    std::string operator()(const Box&) const { return "box"; }
    std::string operator()(const Sphere&) const { return "sphere"; }
    std::string operator()(const Cylinder&) const { return "cylinder"; }
    std::string operator()(const Capsule&) const { return "capsule"; }
    std::string operator()(const MeshFile&) const { return "mesh"; }
  };
  return std::visit(Namer{}, geometry);
}

TriangleMesh shapeSurface(const Shape& shape, const TessellationOptions& options) {
  struct Tessellator {
    const TessellationOptions& options;
    TriangleMesh operator()(const Box& b) const { return boxSurface(b.size); }
    TriangleMesh operator()(const Sphere& s) const { return roundSurface(s.radius, 0.0, options); }
    TriangleMesh operator()(const Cylinder& c) const {
      return cylinderSurface(c.radius, c.length, options);
    }
    TriangleMesh operator()(const Capsule& c) const {
      return roundSurface(c.radius, 0.5 * c.length, options);
    }
    TriangleMesh operator()(const MeshFile& m) const { return loadMesh(m.path, m.options).mesh; }
  };
  TriangleMesh mesh = std::visit(Tessellator{options}, shape.geometry);
  for (Eigen::Vector3d& v : mesh.vertices) v = shape.X_BG * v;
  return mesh;
}

}  // namespace scanplan::kinematics
