#pragma once
// Synthetic parts with known hard spots for the automatic scan's tests and benchmarks, written as
// ASCII STL in mm with outward winding: boxes, a block with a square hole (blind or through),
// thin fins on a plate, and a block with a grid of blind cavities.
#include <array>
#include <filesystem>
#include <fstream>
#include <vector>

#include <Eigen/Core>

namespace scanplan::test {

struct Quad {
  Eigen::Vector3d a, b, c, d;  // counter-clockwise seen from outside
};

inline void writeStl(const std::filesystem::path& file, const std::vector<Quad>& quads) {
  std::ofstream out(file);
  out << "solid part\n";
  for (const Quad& q : quads) {
    for (const auto& t : {std::array<Eigen::Vector3d, 3>{q.a, q.b, q.c},
                          std::array<Eigen::Vector3d, 3>{q.a, q.c, q.d}}) {
      out << "facet normal 0 0 0\nouter loop\n";
      for (const auto& v : t) out << "vertex " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
      out << "endloop\nendfacet\n";
    }
  }
  out << "endsolid part\n";
}

// An axis-aligned box [lo, hi] as six outward quads.
inline void addBox(std::vector<Quad>& q, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const auto P = [&](int x, int y, int z) {
    return Eigen::Vector3d(x ? hi.x() : lo.x(), y ? hi.y() : lo.y(), z ? hi.z() : lo.z());
  };
  q.push_back({P(0, 0, 0), P(0, 1, 0), P(1, 1, 0), P(1, 0, 0)});
  q.push_back({P(0, 0, 1), P(1, 0, 1), P(1, 1, 1), P(0, 1, 1)});
  q.push_back({P(0, 0, 0), P(1, 0, 0), P(1, 0, 1), P(0, 0, 1)});
  q.push_back({P(0, 1, 0), P(0, 1, 1), P(1, 1, 1), P(1, 1, 0)});
  q.push_back({P(0, 0, 0), P(0, 0, 1), P(0, 1, 1), P(0, 1, 0)});
  q.push_back({P(1, 0, 0), P(1, 1, 0), P(1, 1, 1), P(1, 0, 1)});
}

// A block with a square hole of side h from the top down to `depth` (through when depth = z):
// the top as four quads around the hole, the hole's walls facing in, a floor for a blind hole.
inline std::vector<Quad> blockWithHole(double x, double y, double z, double h, double depth) {
  std::vector<Quad> q;
  const double x0 = 0.5 * (x - h), x1 = 0.5 * (x + h), y0 = 0.5 * (y - h), y1 = 0.5 * (y + h);
  const double zb = z - depth;
  const auto V = [](double a, double b, double c) { return Eigen::Vector3d(a, b, c); };
  // Sides.
  q.push_back({V(0, 0, 0), V(x, 0, 0), V(x, 0, z), V(0, 0, z)});
  q.push_back({V(0, y, 0), V(0, y, z), V(x, y, z), V(x, y, 0)});
  q.push_back({V(0, 0, 0), V(0, 0, z), V(0, y, z), V(0, y, 0)});
  q.push_back({V(x, 0, 0), V(x, y, 0), V(x, y, z), V(x, 0, z)});
  // Top around the hole (+z).
  q.push_back({V(0, 0, z), V(x, 0, z), V(x, y0, z), V(0, y0, z)});
  q.push_back({V(0, y1, z), V(x, y1, z), V(x, y, z), V(0, y, z)});
  q.push_back({V(0, y0, z), V(x0, y0, z), V(x0, y1, z), V(0, y1, z)});
  q.push_back({V(x1, y0, z), V(x, y0, z), V(x, y1, z), V(x1, y1, z)});
  // Hole walls, normals into the hole.
  q.push_back({V(x0, y0, zb), V(x0, y0, z), V(x1, y0, z), V(x1, y0, zb)});  // +y facing
  q.push_back({V(x0, y1, zb), V(x1, y1, zb), V(x1, y1, z), V(x0, y1, z)});  // −y facing
  q.push_back({V(x0, y0, zb), V(x0, y1, zb), V(x0, y1, z), V(x0, y0, z)});  // +x facing
  q.push_back({V(x1, y0, zb), V(x1, y0, z), V(x1, y1, z), V(x1, y1, zb)});  // −x facing
  if (depth < z) {
    q.push_back({V(x0, y0, zb), V(x1, y0, zb), V(x1, y1, zb), V(x0, y1, zb)});  // floor, up
    q.push_back({V(0, 0, 0), V(0, y, 0), V(x, y, 0), V(x, 0, 0)});              // bottom
  } else {
    // Bottom around the through hole (−z).
    q.push_back({V(0, 0, 0), V(0, y0, 0), V(x, y0, 0), V(x, 0, 0)});
    q.push_back({V(0, y1, 0), V(0, y, 0), V(x, y, 0), V(x, y1, 0)});
    q.push_back({V(0, y0, 0), V(0, y1, 0), V(x0, y1, 0), V(x0, y0, 0)});
    q.push_back({V(x1, y0, 0), V(x1, y1, 0), V(x, y1, 0), V(x, y0, 0)});
  }
  return q;
}

// A base plate with three thin upright fins (2 mm walls, 60 mm tall, 12 mm apart): boxes that
// touch, fine for ray casting (no interior faces are seen).
inline std::vector<Quad> thinWalls() {
  std::vector<Quad> q;
  addBox(q, {0, 0, 0}, {120, 80, 10});
  for (int k = 0; k < 3; ++k) {
    const double x = 40.0 + 14.0 * k;
    addBox(q, {x, 10, 10}, {x + 2, 70, 70});
  }
  return q;
}

// A block x × y × z with an n × n grid of square blind cavities (side h, `depth` deep) in its
// top: many pockets close together, each seen from few directions.
inline std::vector<Quad> blockWithCavities(double x, double y, double z, int n, double h,
                                          double depth) {
  std::vector<Quad> q;
  const auto V = [](double a, double b, double c) { return Eigen::Vector3d(a, b, c); };
  q.push_back({V(0, 0, 0), V(x, 0, 0), V(x, 0, z), V(0, 0, z)});
  q.push_back({V(0, y, 0), V(0, y, z), V(x, y, z), V(x, y, 0)});
  q.push_back({V(0, 0, 0), V(0, 0, z), V(0, y, z), V(0, y, 0)});
  q.push_back({V(x, 0, 0), V(x, y, 0), V(x, y, z), V(x, 0, z)});
  q.push_back({V(0, 0, 0), V(0, y, 0), V(x, y, 0), V(x, 0, 0)});
  // The top: a grid of cells, each a cavity in the middle of its square of the top.
  const double cx = x / n, cy = y / n, zb = z - depth;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double x0 = i * cx, y0 = j * cy, x1 = x0 + cx, y1 = y0 + cy;
      const double a0 = x0 + 0.5 * (cx - h), a1 = a0 + h, b0 = y0 + 0.5 * (cy - h), b1 = b0 + h;
      q.push_back({V(x0, y0, z), V(x1, y0, z), V(x1, b0, z), V(x0, b0, z)});
      q.push_back({V(x0, b1, z), V(x1, b1, z), V(x1, y1, z), V(x0, y1, z)});
      q.push_back({V(x0, b0, z), V(a0, b0, z), V(a0, b1, z), V(x0, b1, z)});
      q.push_back({V(a1, b0, z), V(x1, b0, z), V(x1, b1, z), V(a1, b1, z)});
      q.push_back({V(a0, b0, zb), V(a0, b0, z), V(a1, b0, z), V(a1, b0, zb)});
      q.push_back({V(a0, b1, zb), V(a1, b1, zb), V(a1, b1, z), V(a0, b1, z)});
      q.push_back({V(a0, b0, zb), V(a0, b1, zb), V(a0, b1, z), V(a0, b0, z)});
      q.push_back({V(a1, b0, zb), V(a1, b0, z), V(a1, b1, z), V(a1, b1, zb)});
      q.push_back({V(a0, b0, zb), V(a1, b0, zb), V(a1, b1, zb), V(a0, b1, zb)});
    }
  }
  return q;
}

}  // namespace scanplan::test
