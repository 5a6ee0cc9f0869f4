#include <scanplan/collision/convex_hull.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <vector>

#include <scanplan/collision/fcl_geometry.h>
#include <scanplan/collision/mesh_distance.h>

// Last: qhull's C API defines short macros (its C++ headers do not compile as C++20).
extern "C" {
#include <libqhull_r/qhull_ra.h>
}

namespace scanplan::collision {
namespace {

// The vertices the triangles use, each once, in order of first use.
std::vector<Eigen::Vector3d> usedVertices(const kinematics::TriangleMesh& mesh) {
  std::vector<char> used(mesh.vertices.size(), 0);
  std::vector<Eigen::Vector3d> out;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const auto i = static_cast<std::size_t>(t[k]);
      if (!used[i]) {
        used[i] = 1;
        out.push_back(mesh.vertices[i]);
      }
    }
  }
  return out;
}

// One qhull run (reentrant C API), freed on every path. Messages go to a memory stream, not the
// terminal; a failure (no volume) comes back as a non-zero code, not an exception.
class QhullRun {
 public:
  QhullRun() : messages_(open_memstream(&text_, &size_)) { qh_zero(&qh_, messages_); }
  ~QhullRun() {
    int curlong = 0, totlong = 0;
    qh_freeqhull(&qh_, !qh_ALL);
    qh_memfreeshort(&qh_, &curlong, &totlong);
    if (messages_) std::fclose(messages_);
    std::free(text_);
  }
  QhullRun(const QhullRun&) = delete;
  QhullRun& operator=(const QhullRun&) = delete;

  // Qt: triangulated facets (merged coplanar facets split into triangles).
  bool run(std::vector<double>& coordinates) {
    char command[] = "qhull Qt";
    const int points = static_cast<int>(coordinates.size() / 3);
    return qh_new_qhull(&qh_, 3, points, coordinates.data(), False, command, nullptr, messages_) ==
           0;
  }
  qhT* get() { return &qh_; }

 private:
  qhT qh_{};
  char* text_ = nullptr;
  std::size_t size_ = 0;
  std::FILE* messages_;
};

// A triangle of a hull: its vertices (indices into the points given to qhull) counter-clockwise
// seen from outside, and its plane n·x + offset = 0 with n the unit outward normal.
struct HullFacet {
  std::array<std::size_t, 3> v{};
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  double offset = 0.0;
};

// The triangulated hull of points, or std::nullopt when they span no volume.
std::optional<std::vector<HullFacet>> hullFacets(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 4) return std::nullopt;
  std::vector<double> coordinates;
  coordinates.reserve(3 * points.size());
  for (const Eigen::Vector3d& p : points) {
    coordinates.insert(coordinates.end(), {p.x(), p.y(), p.z()});
  }
  QhullRun run;
  if (!run.run(coordinates)) return std::nullopt;  // no volume: flat or collinear points
  qhT* qh = run.get();
  std::vector<HullFacet> facets;
  facetT* facet;
  FORALLfacets {
    HullFacet f;
    int k = 0;
    vertexT *vertex, **vertexp;
    FOREACHvertex_(facet->vertices) {
      if (k < 3)
        f.v[static_cast<std::size_t>(k)] = static_cast<std::size_t>(qh_pointid(qh, vertex->point));
      ++k;
    }
    if (k != 3) continue;
    f.n = Eigen::Vector3d(facet->normal[0], facet->normal[1], facet->normal[2]);
    f.offset = facet->offset;
    const Eigen::Vector3d &a = points[f.v[0]], &b = points[f.v[1]], &c = points[f.v[2]];
    if ((b - a).cross(c - a).dot(f.n) < 0.0) std::swap(f.v[1], f.v[2]);
    facets.push_back(f);
  }
  if (facets.size() < 4) return std::nullopt;
  return facets;
}

// The mesh of a hull's facets, keeping only the points they use.
kinematics::TriangleMesh facetMesh(const std::vector<Eigen::Vector3d>& points,
                                   const std::vector<HullFacet>& facets) {
  kinematics::TriangleMesh hull;
  std::vector<int> index(points.size(), -1);
  for (const HullFacet& f : facets) {
    Eigen::Vector3i t;
    for (int k = 0; k < 3; ++k) {
      int& i = index[f.v[static_cast<std::size_t>(k)]];
      if (i < 0) {
        i = static_cast<int>(hull.vertices.size());
        hull.vertices.push_back(points[f.v[static_cast<std::size_t>(k)]]);
      }
      t[k] = i;
    }
    hull.triangles.push_back(t);
  }
  return hull;
}

// A plane n·x ≤ h (n unit).
struct Plane {
  Eigen::Vector3d n;
  double h;
};

// The vertices of the intersection of half-spaces n·x ≤ h around an interior point c, by the
// dual: each plane is the point n / (h − n·c), and each facet a·p + o = 0 of their hull is the
// vertex c − a/o. std::nullopt when the planes do not bound a volume.
std::optional<std::vector<Eigen::Vector3d>> planeVertices(const std::vector<Plane>& planes,
                                                          const Eigen::Vector3d& c) {
  std::vector<Eigen::Vector3d> dual;
  for (const Plane& p : planes) dual.push_back(p.n / (p.h - p.n.dot(c)));
  const auto facets = hullFacets(dual);
  if (!facets) return std::nullopt;
  std::vector<Eigen::Vector3d> vertices;
  for (const HullFacet& f : *facets) {
    if (!(f.offset < 0.0)) return std::nullopt;  // c not inside: unbounded
    vertices.push_back(c - f.n / f.offset);
  }
  return vertices;
}

// The hull of points as a mesh.
std::optional<kinematics::TriangleMesh> hullOf(const std::vector<Eigen::Vector3d>& points) {
  const auto facets = hullFacets(points);
  if (!facets) return std::nullopt;
  return facetMesh(points, *facets);
}

}  // namespace

std::optional<kinematics::TriangleMesh> convexHull(const kinematics::TriangleMesh& mesh) {
  return hullOf(usedVertices(mesh));
}

std::optional<kinematics::TriangleMesh> convexHullOf(const std::vector<Eigen::Vector3d>& points) {
  return hullOf(points);
}

std::optional<kinematics::TriangleMesh> simplifiedHull(const kinematics::TriangleMesh& hull,
                                                       std::size_t max_vertices) {
  if (hull.vertices.size() <= max_vertices) return hull;
  // The hull's planes (slivers from triangulating merged facets left out) and an interior point.
  std::vector<Plane> faces;
  for (const Eigen::Vector3i& t : hull.triangles) {
    const Eigen::Vector3d& a = hull.vertices[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d n = (hull.vertices[static_cast<std::size_t>(t[1])] - a)
                                  .cross(hull.vertices[static_cast<std::size_t>(t[2])] - a);
    if (n.norm() > 1e-12) faces.push_back({n.normalized(), n.normalized().dot(a)});
  }
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& v : hull.vertices) c += v;
  c /= static_cast<double>(hull.vertices.size());
  // Start from the bounding box; then cut the vertex farthest outside the hull with the hull
  // plane it is farthest beyond, while the vertices stay within the budget.
  const Eigen::AlignedBox3d box = hull.bounds();
  std::vector<Plane> planes;
  for (int i = 0; i < 3; ++i) {
    planes.push_back({Eigen::Vector3d::Unit(i), box.max()[i]});
    planes.push_back({-Eigen::Vector3d::Unit(i), -box.min()[i]});
  }
  const auto vertices = planeVertices(planes, c);
  std::optional<kinematics::TriangleMesh> kept = vertices ? hullOf(*vertices) : std::nullopt;
  if (!kept) return std::nullopt;
  for (std::size_t round = 0; round < faces.size(); ++round) {
    double worst = 1e-9;  // m: nearer than this, the vertex is on the hull
    const Plane* cut = nullptr;
    for (const Eigen::Vector3d& x : kept->vertices) {
      for (const Plane& f : faces) {
        if (f.n.dot(x) - f.h > worst) {
          worst = f.n.dot(x) - f.h;
          cut = &f;
        }
      }
    }
    if (!cut) break;  // every vertex on the hull: it is the hull
    planes.push_back(*cut);
    const auto next_vertices = planeVertices(planes, c);
    auto next = next_vertices ? hullOf(*next_vertices) : std::nullopt;
    if (!next || next->vertices.size() > max_vertices) break;
    kept = std::move(next);
  }
  return kept;
}

HullMargin hullMargin(const kinematics::TriangleMesh& hull,
                      const kinematics::TriangleMesh& mesh,
                      double tolerance,
                      std::size_t max_queries) {
  if (hull.triangles.empty() || mesh.triangles.empty()) return {};
  const auto model = detail::makeMeshModel(mesh);
  detail::PointMeshDistance distance(*model);
  return detail::surfaceBound(hull, distance, tolerance, max_queries);
}

}  // namespace scanplan::collision
