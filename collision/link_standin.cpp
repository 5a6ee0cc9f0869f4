#include <scanplan/collision/link_standin.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <system_error>
#include <utility>

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <Eigen/Eigenvalues>

#include <scanplan/collision/convex_hull.h>
#include <scanplan/collision/fcl_geometry.h>
#include <scanplan/collision/mesh_distance.h>

namespace scanplan::collision {
namespace {

// Raised whenever the fitting changes what it gives: old cache files then miss.
constexpr int kMethodVersion = 1;
// A flat cluster's sliver depth, inward (where the solid is): m.
constexpr double kSliverDepth = 1e-4;
// At most this many surface pieces to cluster: bounds the memory a huge mesh takes.
constexpr std::size_t kMaxFineTriangles = 400000;
// Branch-and-bound evaluations per piece.
constexpr std::size_t kMaxQueries = 400000;

// A small triangle of the mesh's surface: the unit the clusters are made of.
struct Fine {
  Eigen::Vector3d a, b, c;
  Eigen::Vector3d normal;  // area-weighted (length = 2 × area)
};

// The mesh's triangles, each bisected at its longest edge until no edge exceeds max_edge.
std::vector<Fine> fineTriangles(const kinematics::TriangleMesh& mesh, double max_edge) {
  std::vector<Fine> out;
  std::vector<Fine> stack;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d& a = mesh.vertices[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d& b = mesh.vertices[static_cast<std::size_t>(t[1])];
    const Eigen::Vector3d& c = mesh.vertices[static_cast<std::size_t>(t[2])];
    stack.assign(1, Fine{a, b, c, (b - a).cross(c - a)});
    while (!stack.empty()) {
      Fine f = stack.back();
      stack.pop_back();
      const double ab = (f.b - f.a).norm(), bc = (f.c - f.b).norm(), ca = (f.a - f.c).norm();
      if (std::max({ab, bc, ca}) <= max_edge || out.size() + stack.size() >= kMaxFineTriangles) {
        out.push_back(f);
        continue;
      }
      // Rotate so that ab is the longest edge, then cut it at its midpoint.
      if (bc >= ab && bc >= ca)
        f = Fine{f.b, f.c, f.a, f.normal};
      else if (ca >= ab && ca >= bc)
        f = Fine{f.c, f.a, f.b, f.normal};
      const Eigen::Vector3d m = 0.5 * (f.a + f.b);
      stack.push_back(Fine{f.a, m, f.c, 0.5 * f.normal});
      stack.push_back(Fine{m, f.b, f.c, 0.5 * f.normal});
    }
  }
  return out;
}

using Cluster = std::vector<std::size_t>;  // indices into the fine triangles

// The convex hull of a cluster's corners; a flat cluster gets a sliver inward (against its
// triangles' outward normals, into the solid). std::nullopt for degenerate triangles only.
std::optional<kinematics::TriangleMesh> clusterHull(const std::vector<Fine>& fine,
                                                    const Cluster& ids) {
  std::vector<Eigen::Vector3d> points;
  points.reserve(3 * ids.size());
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  for (std::size_t i : ids) {
    points.insert(points.end(), {fine[i].a, fine[i].b, fine[i].c});
    normal += fine[i].normal;
  }
  if (auto hull = convexHullOf(points)) return hull;
  if (normal.norm() <= 0.0) return std::nullopt;
  const std::size_t n = points.size();
  for (std::size_t i = 0; i < n; ++i)
    points.push_back(points[i] - kSliverDepth * normal.normalized());
  return convexHullOf(points);
}

double hullVolume(const std::vector<Fine>& fine, const Cluster& ids) {
  const auto hull = clusterHull(fine, ids);
  return hull ? std::abs(hull->signedVolume()) : 0.0;
}

// Splits a cluster in two by a plane across one of its principal axes (at a quartile or the
// median of its triangles' centroids along it): the plane that leaves the least hull volume.
std::pair<Cluster, Cluster> splitCluster(const std::vector<Fine>& fine,
                                         const Cluster& ids,
                                         const Eigen::Vector3d& worst) {
  std::vector<Eigen::Vector3d> centre(ids.size());
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < ids.size(); ++k) {
    centre[k] = (fine[ids[k]].a + fine[ids[k]].b + fine[ids[k]].c) / 3.0;
    mean += centre[k];
  }
  mean /= static_cast<double>(ids.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& c : centre) covariance += (c - mean) * (c - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> axes(covariance);
  std::pair<Cluster, Cluster> best;
  double best_cost = std::numeric_limits<double>::infinity();
  std::vector<double> along(ids.size());
  for (int axis = 2; axis >= 0; --axis) {
    const Eigen::Vector3d u = axes.eigenvectors().col(axis);
    for (std::size_t k = 0; k < ids.size(); ++k) along[k] = u.dot(centre[k]);
    std::vector<double> sorted = along;
    std::sort(sorted.begin(), sorted.end());
    for (double q : {-1.0, 0.5, 0.375, 0.625, 0.25, 0.75, 0.125, 0.875}) {
      const double cut =
          q < 0.0 ? u.dot(worst)
                  : sorted[static_cast<std::size_t>(q * static_cast<double>(ids.size() - 1))];
      std::pair<Cluster, Cluster> halves;
      for (std::size_t k = 0; k < ids.size(); ++k) {
        (along[k] <= cut ? halves.first : halves.second).push_back(ids[k]);
      }
      if (halves.first.empty() || halves.second.empty()) continue;
      const double cost = hullVolume(fine, halves.first) + hullVolume(fine, halves.second);
      if (cost < best_cost) {
        best_cost = cost;
        best = std::move(halves);
      }
    }
  }
  if (best.first.empty()) {  // every centroid at one point: halve by order
    const auto middle = ids.begin() + static_cast<std::ptrdiff_t>(ids.size() / 2);
    best = {Cluster(ids.begin(), middle), Cluster(middle, ids.end())};
  }
  return best;
}

// One cluster's hull and how far it stands outside the solid (an upper bound; evaluation
// stops early once it is certainly above `give_up`).
struct Candidate {
  std::optional<kinematics::TriangleMesh> hull;
  HullMargin margin;
};

Candidate measure(const std::vector<Fine>& fine,
                  const Cluster& ids,
                  const detail::MeshModel& solid,
                  double tolerance,
                  double give_up) {
  Candidate out;
  out.hull = clusterHull(fine, ids);
  if (!out.hull) return out;
  detail::PointSolidDistance distance(solid);
  out.margin = detail::surfaceBound(*out.hull, distance, tolerance, kMaxQueries, give_up, give_up);
  return out;
}

// A cluster with its hull and how far that stands outside the solid (an upper bound).
struct Part {
  Cluster ids;
  kinematics::TriangleMesh hull;
  double margin = 0.0;
  double volume = 0.0;
  Eigen::AlignedBox3d box;
};

Part makePart(Cluster ids, Candidate c) {
  Part p{std::move(ids), std::move(*c.hull), c.margin.margin, 0.0, {}};
  p.volume = std::abs(p.hull.signedVolume());
  p.box = p.hull.bounds();
  return p;
}

// Top down: each round measures every open cluster in parallel, keeps those within the margin
// and splits the rest in two, while the parts stay within `cap`; past it, the open clusters
// are kept as they are, each measured in full.
std::vector<Part> splitPhase(const std::vector<Fine>& fine,
                             const detail::MeshModel& solid,
                             const StandInOptions& options,
                             std::size_t cap) {
  Cluster all(fine.size());
  for (std::size_t i = 0; i < fine.size(); ++i) all[i] = i;
  std::vector<Cluster> round{std::move(all)};
  std::vector<Part> parts;
  while (!round.empty()) {
    std::vector<Candidate> measured(round.size());
    tbb::parallel_for(std::size_t{0}, round.size(), [&](std::size_t i) {
      measured[i] = measure(fine, round[i], solid, options.tolerance, options.margin);
    });
    std::vector<std::size_t> open;
    for (std::size_t i = 0; i < round.size(); ++i) {
      if (!measured[i].hull) continue;
      if (measured[i].margin.margin <= options.margin || round[i].size() < 2) {
        parts.push_back(makePart(std::move(round[i]), std::move(measured[i])));
      } else {
        open.push_back(i);
      }
    }
    if (parts.size() + 2 * open.size() > cap) {
      for (std::size_t i : open) {
        parts.push_back(
            makePart(std::move(round[i]), measure(fine, round[i], solid, options.tolerance,
                                                  std::numeric_limits<double>::infinity())));
      }
      break;
    }
    std::vector<std::pair<Cluster, Cluster>> halves(open.size());
    tbb::parallel_for(std::size_t{0}, open.size(), [&](std::size_t k) {
      halves[k] = splitCluster(fine, round[open[k]], measured[open[k]].margin.where);
    });
    std::vector<Cluster> next;
    for (auto& h : halves) {
      next.push_back(std::move(h.first));
      next.push_back(std::move(h.second));
    }
    round = std::move(next);
  }
  return parts;
}

Cluster joined(const Cluster& a, const Cluster& b) {
  Cluster out(a);
  out.insert(out.end(), b.begin(), b.end());
  return out;
}

// Bottom up: each round ranks the pairs of touching parts by the hull volume their merge
// adds, takes the best disjoint pairs in that order, and merges those whose joint hull still
// stands within the margin. Stops when a round merges none.
void mergePhase(const std::vector<Fine>& fine,
                const detail::MeshModel& solid,
                const StandInOptions& options,
                std::vector<Part>& parts) {
  for (;;) {
    std::vector<std::pair<std::size_t, std::size_t>> pairs;
    for (std::size_t i = 0; i < parts.size(); ++i) {
      for (std::size_t j = i + 1; j < parts.size(); ++j) {
        Eigen::AlignedBox3d grown = parts[i].box;
        grown.extend(grown.min() - Eigen::Vector3d::Constant(options.margin));
        grown.extend(grown.max() + Eigen::Vector3d::Constant(options.margin));
        if (grown.intersects(parts[j].box)) pairs.emplace_back(i, j);
      }
    }
    std::vector<double> cost(pairs.size());
    tbb::parallel_for(std::size_t{0}, pairs.size(), [&](std::size_t k) {
      const auto [i, j] = pairs[k];
      cost[k] =
          hullVolume(fine, joined(parts[i].ids, parts[j].ids)) - parts[i].volume - parts[j].volume;
    });
    std::vector<std::size_t> order(pairs.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t x, std::size_t y) { return cost[x] < cost[y]; });
    std::vector<char> taken(parts.size(), 0);
    std::vector<std::size_t> tried;
    for (std::size_t k : order) {
      const auto [i, j] = pairs[k];
      if (taken[i] || taken[j]) continue;
      taken[i] = taken[j] = 1;
      tried.push_back(k);
    }
    std::vector<Candidate> merged(tried.size());
    tbb::parallel_for(std::size_t{0}, tried.size(), [&](std::size_t t) {
      const auto [i, j] = pairs[tried[t]];
      merged[t] = measure(fine, joined(parts[i].ids, parts[j].ids), solid, options.tolerance,
                          options.margin);
    });
    std::vector<char> gone(parts.size(), 0);
    std::vector<Part> next;
    for (std::size_t t = 0; t < tried.size(); ++t) {
      if (!merged[t].hull || merged[t].margin.margin > options.margin) continue;
      const auto [i, j] = pairs[tried[t]];
      gone[i] = gone[j] = 1;
      next.push_back(makePart(joined(parts[i].ids, parts[j].ids), std::move(merged[t])));
    }
    if (next.empty()) return;
    for (std::size_t i = 0; i < parts.size(); ++i) {
      if (!gone[i]) next.push_back(std::move(parts[i]));
    }
    parts = std::move(next);
  }
}

}  // namespace

StandIn fitStandIn(const kinematics::TriangleMesh& mesh, const StandInOptions& options) {
  StandIn out;
  if (mesh.triangles.empty()) return out;
  const auto solid = detail::makeMeshModel(mesh);
  const double diagonal = mesh.bounds().diagonal().norm();
  const std::vector<Fine> fine =
      fineTriangles(mesh, std::max(5.0 * options.margin, diagonal / 50.0));
  // The split may overshoot the budget for the merge to win back, within a bound: the merge
  // ranks every touching pair.
  std::vector<Part> parts =
      splitPhase(fine, *solid, options, std::min<std::size_t>(8 * options.max_pieces, 4096));
  mergePhase(fine, *solid, options, parts);
  for (Part& p : parts) {
    out.margin = std::max(out.margin, p.margin);
    out.vertices += p.hull.vertices.size();
    out.pieces.push_back(std::move(p.hull));
  }
  out.fits = out.margin <= options.margin && out.pieces.size() <= options.max_pieces;
  return out;
}

std::optional<AxisCylinder> axisCylinder(const kinematics::TriangleMesh& mesh,
                                         const Eigen::Vector3d& o,
                                         const Eigen::Vector3d& u,
                                         double tolerance,
                                         double give_up) {
  if (mesh.triangles.empty() || mesh.vertices.empty()) return std::nullopt;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, radius = 0.0;
  for (const Eigen::Vector3d& v : mesh.vertices) {
    const double t = (v - o).dot(u);
    lo = std::min(lo, t);
    hi = std::max(hi, t);
    radius = std::max(radius, (v - o - t * u).norm());
  }
  if (!(hi > lo) || !(radius > 0.0)) return std::nullopt;
  AxisCylinder out;
  out.radius = radius;
  out.length = hi - lo;
  out.X_MC.translation() = o + 0.5 * (lo + hi) * u;
  out.X_MC.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), u).matrix();
  // The prism's faces touch the circle: its corners lie 1/cos(π/n) out.
  const double corner = radius / std::cos(std::numbers::pi / kCylinderSides);
  std::vector<Eigen::Vector3d> corners;
  for (int i = 0; i < kCylinderSides; ++i) {
    const double a = 2.0 * std::numbers::pi * i / kCylinderSides;
    for (const double z : {-0.5 * out.length, 0.5 * out.length})
      corners.push_back(out.X_MC * Eigen::Vector3d(corner * std::cos(a), corner * std::sin(a), z));
  }
  auto prism = convexHullOf(corners);
  if (!prism) return std::nullopt;
  out.prism = std::move(*prism);
  const auto solid = detail::makeMeshModel(mesh);
  detail::PointSolidDistance distance(*solid);
  out.margin =
      detail::surfaceBound(out.prism, distance, tolerance, kMaxQueries, give_up, give_up).margin;
  return out;
}

namespace {

// FNV-1a, 64 bits, over raw bytes.
struct Hash {
  std::uint64_t h = 1469598103934665603ull;
  void bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  }
  template <class T>
  void value(const T& v) {
    bytes(&v, sizeof v);
  }
};

}  // namespace

std::string standInKey(const kinematics::TriangleMesh& mesh, const StandInOptions& options) {
  Hash hash;
  hash.value(kMethodVersion);
  hash.value(options.margin);
  hash.value(options.max_pieces);
  hash.value(options.tolerance);
  for (const Eigen::Vector3d& v : mesh.vertices) hash.bytes(v.data(), 3 * sizeof(double));
  for (const Eigen::Vector3i& t : mesh.triangles) hash.bytes(t.data(), 3 * sizeof(int));
  return fmt::format("{:016x}", hash.h);
}

namespace {

constexpr const char* kMagic = "scanplan-standin";
constexpr std::size_t kMaxCachedPieces = 100000;
constexpr std::size_t kMaxCachedVertices = 10000000;

// A closed, outward polytope: every vertex on or behind every face's plane.
bool isConvexPolytope(const kinematics::TriangleMesh& piece) {
  if (!piece.isClosed() || !(piece.signedVolume() > 0.0)) return false;
  const double slack = 1e-9 * (1.0 + piece.bounds().diagonal().norm());
  for (const Eigen::Vector3i& t : piece.triangles) {
    const Eigen::Vector3d& a = piece.vertices[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d n = (piece.vertices[static_cast<std::size_t>(t[1])] - a)
                                  .cross(piece.vertices[static_cast<std::size_t>(t[2])] - a);
    if (!(n.norm() > 0.0)) continue;
    for (const Eigen::Vector3d& v : piece.vertices) {
      if (n.normalized().dot(v - a) > slack) return false;
    }
  }
  return true;
}

bool readPieces(std::istream& in, std::size_t count, StandIn& out) {
  for (std::size_t p = 0; p < count; ++p) {
    std::size_t n = 0, m = 0;
    if (!(in >> n >> m) || n < 4 || m < 4 || out.vertices + n > kMaxCachedVertices || m > 2 * n) {
      return false;
    }
    kinematics::TriangleMesh piece;
    piece.vertices.resize(n);
    for (Eigen::Vector3d& v : piece.vertices) {
      if (!(in >> v.x() >> v.y() >> v.z()) || !v.allFinite()) return false;
    }
    piece.triangles.resize(m);
    for (Eigen::Vector3i& t : piece.triangles) {
      if (!(in >> t[0] >> t[1] >> t[2])) return false;
      for (int k = 0; k < 3; ++k) {
        if (t[k] < 0 || static_cast<std::size_t>(t[k]) >= n) return false;
      }
    }
    if (!isConvexPolytope(piece)) return false;
    out.vertices += n;
    out.pieces.push_back(std::move(piece));
  }
  return true;
}

}  // namespace

std::optional<StandIn> loadStandIn(const std::filesystem::path& file, const std::string& key) {
  std::ifstream in(file);
  if (!in) return std::nullopt;
  std::string magic, file_key;
  int version = 0, fits = 0;
  std::size_t count = 0;
  StandIn out;
  if (!(in >> magic >> version >> file_key >> out.margin >> fits >> count)) return std::nullopt;
  if (magic != kMagic || version != kMethodVersion || file_key != key) return std::nullopt;
  if (!std::isfinite(out.margin) || out.margin < 0.0 || count > kMaxCachedPieces)
    return std::nullopt;
  out.fits = fits == 1;
  if (!readPieces(in, count, out)) return std::nullopt;
  std::string rest;
  if (in >> rest) return std::nullopt;  // trailing content: not ours
  return out;
}

bool saveStandIn(const std::filesystem::path& file,
                 const std::string& key,
                 const StandIn& standin) {
  std::ostringstream text;
  text << kMagic << ' ' << kMethodVersion << ' ' << key << '\n'
       << fmt::format("{:.17g} {} {}\n", standin.margin, standin.fits ? 1 : 0,
                      standin.pieces.size());
  for (const auto& piece : standin.pieces) {
    text << piece.vertices.size() << ' ' << piece.triangles.size() << '\n';
    for (const Eigen::Vector3d& v : piece.vertices) {
      text << fmt::format("{:.17g} {:.17g} {:.17g}\n", v.x(), v.y(), v.z());
    }
    for (const Eigen::Vector3i& t : piece.triangles)
      text << fmt::format("{} {} {}\n", t[0], t[1], t[2]);
  }
  std::error_code ec;
  std::filesystem::create_directories(file.parent_path(), ec);
  const std::filesystem::path tmp = fmt::format("{}.{}.tmp", file.string(), getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) return false;
    out << text.str();
    if (!out.flush()) {
      std::filesystem::remove(tmp, ec);
      return false;
    }
  }
  std::filesystem::rename(tmp, file, ec);
  if (ec) std::filesystem::remove(tmp, ec);
  return !ec;
}

}  // namespace scanplan::collision
