#include <scanplan/scanner/area_coverage.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <utility>

#include <tbb/parallel_for.h>
#include <nanoflann.hpp>

namespace scanplan::scanner {

namespace {

// nanoflann's view of some of the points (`index` into `points`).
struct PointSet {
  const std::vector<Eigen::Vector3d>& points;
  std::vector<std::uint32_t> index;
  std::size_t kdtree_get_point_count() const { return index.size(); }
  double kdtree_get_pt(std::size_t i, std::size_t d) const {
    return points[index[i]][static_cast<Eigen::Index>(d)];
  }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using PointTree = nanoflann::
    KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PointSet>, PointSet, 3>;

// Points per slab at least: fewer points get one tree.
constexpr std::size_t kSlabPoints = 100000;
constexpr std::size_t kMaxSlabs = 16;

// The points split into slabs along the axis they spread most along, about equal in count, each
// with its own k-d tree over the points within it or within `radius` of it: every point within
// `radius` of a query is in the tree of the slab the query falls in, so a search there finds
// what one tree over all points finds. The trees are built in parallel; the slabs depend on the
// points alone, not on the threads.
class SlabTrees {
 public:
  SlabTrees(const std::vector<Eigen::Vector3d>& points, double radius) {
    Eigen::AlignedBox3d box;
    for (const Eigen::Vector3d& p : points) box.extend(p);
    box.sizes().maxCoeff(&axis_);
    const std::size_t slabs =
        std::clamp<std::size_t>(points.size() / kSlabPoints, std::size_t{1}, kMaxSlabs);
    bounds_ = splitAt(points, box, slabs);
    std::vector<std::vector<std::uint32_t>> members = slabMembers(points, radius, slabs);
    sets_.reserve(slabs);
    for (auto& m : members)
      sets_.push_back(std::make_unique<PointSet>(PointSet{points, std::move(m)}));
    trees_.resize(slabs);
    tbb::parallel_for(std::size_t{0}, slabs, [&](std::size_t k) {
      trees_[k] =
          std::make_unique<PointTree>(3, *sets_[k], nanoflann::KDTreeSingleIndexAdaptorParams(16));
    });
  }
  // The tree to search around `q`, and the point indices its results refer to.
  const PointTree& tree(const Eigen::Vector3d& q) const { return *trees_[slabOf(q[axis_])]; }
  const std::vector<std::uint32_t>& index(const Eigen::Vector3d& q) const {
    return sets_[slabOf(q[axis_])]->index;
  }

 private:
  // Each slab's points (within `radius` of it), ascending: chunks of the points sorted in
  // parallel, then each slab's pieces joined in the chunks' order.
  std::vector<std::vector<std::uint32_t>> slabMembers(const std::vector<Eigen::Vector3d>& points,
                                                      double radius,
                                                      std::size_t slabs) const {
    constexpr std::size_t kChunk = 1 << 16;
    const std::size_t chunks = (points.size() + kChunk - 1) / kChunk;
    std::vector<std::vector<std::vector<std::uint32_t>>> pieces(
        chunks, std::vector<std::vector<std::uint32_t>>(slabs));
    tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
      for (std::size_t i = c * kChunk; i < std::min(points.size(), (c + 1) * kChunk); ++i) {
        const double x = points[i][axis_];
        for (std::size_t k = slabOf(x - radius), last = slabOf(x + radius); k <= last; ++k)
          pieces[c][k].push_back(static_cast<std::uint32_t>(i));
      }
    });
    std::vector<std::vector<std::uint32_t>> members(slabs);
    tbb::parallel_for(std::size_t{0}, slabs, [&](std::size_t k) {
      std::size_t count = 0;
      for (const auto& piece : pieces) count += piece[k].size();
      members[k].reserve(count);
      for (const auto& piece : pieces)
        members[k].insert(members[k].end(), piece[k].begin(), piece[k].end());
    });
    return members;
  }

  // Slab boundaries at equal counts, from a histogram of the points along the axis.
  std::vector<double> splitAt(const std::vector<Eigen::Vector3d>& points,
                              const Eigen::AlignedBox3d& box,
                              std::size_t slabs) const {
    constexpr std::size_t kBins = 4096;
    const double lo = box.min()[axis_], width = std::max(box.sizes()[axis_], 1e-12);
    std::vector<std::size_t> bins(kBins, 0);
    const auto bin = [&](double x) {
      return std::min(kBins - 1, static_cast<std::size_t>((x - lo) / width * kBins));
    };
    for (const Eigen::Vector3d& p : points) ++bins[bin(p[axis_])];
    std::vector<double> bounds;
    std::size_t below = 0;
    for (std::size_t b = 0; b < kBins && bounds.size() + 1 < slabs; ++b) {
      below += bins[b];
      if (below * slabs >= (bounds.size() + 1) * points.size())
        bounds.push_back(lo + width * static_cast<double>(b + 1) / kBins);
    }
    return bounds;
  }
  std::size_t slabOf(double x) const {
    return static_cast<std::size_t>(std::upper_bound(bounds_.begin(), bounds_.end(), x) -
                                    bounds_.begin());
  }

  Eigen::Index axis_ = 0;
  std::vector<double> bounds_;  // slab k holds x in [bounds_[k − 1], bounds_[k])
  std::vector<std::unique_ptr<PointSet>> sets_;
  std::vector<std::unique_ptr<PointTree>> trees_;
};

double triangleArea(const kinematics::TriangleMesh& mesh, std::size_t t, Eigen::Vector3d& n) {
  const Eigen::Vector3i& f = mesh.triangles[t];
  const Eigen::Vector3d& a = mesh.vertices[static_cast<std::size_t>(f[0])];
  const Eigen::Vector3d cross = (mesh.vertices[static_cast<std::size_t>(f[1])] - a)
                                    .cross(mesh.vertices[static_cast<std::size_t>(f[2])] - a);
  const double twice = cross.norm();
  n = twice > 0.0 ? Eigen::Vector3d(cross / twice) : Eigen::Vector3d::UnitZ();
  return 0.5 * twice;
}

// A uniform point of triangle t from two uniform numbers (the square folded onto it).
Eigen::Vector3d pointIn(const kinematics::TriangleMesh& mesh, std::size_t t, double u, double v) {
  if (u + v > 1.0) {
    u = 1.0 - u;
    v = 1.0 - v;
  }
  const Eigen::Vector3i& f = mesh.triangles[t];
  const Eigen::Vector3d& a = mesh.vertices[static_cast<std::size_t>(f[0])];
  return a + u * (mesh.vertices[static_cast<std::size_t>(f[1])] - a) +
         v * (mesh.vertices[static_cast<std::size_t>(f[2])] - a);
}

}  // namespace

AreaSampling sampleArea(const kinematics::TriangleMesh& mesh,
                        double spacing,
                        std::size_t max_samples,
                        std::uint64_t seed) {
  if (!(spacing > 0.0) || !std::isfinite(spacing) || max_samples == 0) {
    throw std::invalid_argument("sampleArea: spacing must be finite and > 0, max_samples > 0");
  }
  AreaSampling out;
  Eigen::Vector3d n;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    out.total_area += triangleArea(mesh, t, n);
  if (!(out.total_area > 0.0)) return out;
  const double wanted = out.total_area / (spacing * spacing);
  // ceil, forgiving the rounding of an area that is a whole number of spacing² cells.
  const double count =
      std::min(std::max(1.0, std::ceil(wanted * (1.0 - 1e-12))), static_cast<double>(max_samples));
  out.area_per_sample = out.total_area / count;
  out.samples.reserve(static_cast<std::size_t>(count));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  // Systematic: sample k sits where the running area passes (k + 0.5) area_per_sample.
  double before = 0.0, next = 0.5 * out.area_per_sample;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const double area = triangleArea(mesh, t, n);
    const double after = before + area;
    while (next < after && out.samples.size() < static_cast<std::size_t>(count)) {
      const double u = uniform(rng), v = uniform(rng);
      out.samples.push_back({pointIn(mesh, t, u, v), n, static_cast<std::int32_t>(t)});
      next += out.area_per_sample;
    }
    before = after;
  }
  return out;
}

AreaCoverage areaCoverage(const AreaSampling& sampling,
                          const std::vector<Eigen::Vector3d>& points,
                          double radius,
                          const std::vector<double>* times) {
  AreaCoverage out;
  out.radius = radius;
  out.covered.assign(sampling.samples.size(), 0);
  if (points.empty() || sampling.samples.empty() || !(radius >= 0.0)) return out;
  const SlabTrees trees(points, radius);
  const double r2 = radius * radius;
  tbb::parallel_for(std::size_t{0}, sampling.samples.size(), [&](std::size_t i) {
    const Eigen::Vector3d& q = sampling.samples[i].p;
    std::size_t nearest = 0;
    double d2 = std::numeric_limits<double>::infinity();
    nanoflann::KNNResultSet<double> result(1);
    result.init(&nearest, &d2);
    trees.tree(q).findNeighbors(result, q.data(), nanoflann::SearchParams(10));
    out.covered[i] = d2 <= r2 ? 1 : 0;
  });
  if (times && times->size() == points.size()) {
    out.first_time.assign(sampling.samples.size(), std::numeric_limits<double>::infinity());
    tbb::parallel_for(std::size_t{0}, sampling.samples.size(), [&](std::size_t i) {
      if (!out.covered[i]) return;
      const Eigen::Vector3d& q = sampling.samples[i].p;
      const std::vector<std::uint32_t>& index = trees.index(q);
      std::vector<std::pair<std::uint32_t, double>> near;
      trees.tree(q).radiusSearch(q.data(), r2, near, nanoflann::SearchParams(10));
      for (const auto& item : near)
        out.first_time[i] = std::min(out.first_time[i], (*times)[index[item.first]]);
    });
  }
  for (const std::uint8_t c : out.covered) out.covered_samples += c;
  out.covered_fraction =
      static_cast<double>(out.covered_samples) / static_cast<double>(sampling.samples.size());
  return out;
}

std::vector<std::uint8_t> facesTable(const AreaSampling& sampling,
                                     const Eigen::Isometry3d& X_RP,
                                     double max_incidence,
                                     double max_standoff) {
  constexpr double kHalfPi = 1.5707963267948966;
  std::vector<std::uint8_t> out(sampling.samples.size(), 0);
  for (std::size_t i = 0; i < sampling.samples.size(); ++i) {
    const AreaSample& s = sampling.samples[i];
    const double z = (X_RP * s.p).z();
    const double n_z = std::clamp((X_RP.linear() * s.n).z(), -1.0, 1.0);
    const double best = std::min(std::asin(n_z) + max_incidence, kHalfPi);
    // A hair of tolerance: a sample on the table top seen exactly edge-on is not scannable.
    out[i] = z + max_standoff * std::sin(best) <= 1e-9 ? 1 : 0;
  }
  return out;
}

}  // namespace scanplan::scanner
