#include <scanplan/scanner/area_coverage.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <utility>

#include <tbb/parallel_for.h>
#include <nanoflann.hpp>

namespace scanplan::scanner {

namespace {

// nanoflann's view of the points.
struct PointSet {
  const std::vector<Eigen::Vector3d>& points;
  std::size_t kdtree_get_point_count() const { return points.size(); }
  double kdtree_get_pt(std::size_t i, std::size_t d) const {
    return points[i][static_cast<Eigen::Index>(d)];
  }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using PointTree = nanoflann::
    KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PointSet>, PointSet, 3>;

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
  const PointSet set{points};
  const PointTree tree(3, set, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  const double r2 = radius * radius;
  tbb::parallel_for(std::size_t{0}, sampling.samples.size(), [&](std::size_t i) {
    std::size_t nearest = 0;
    double d2 = 0.0;
    nanoflann::KNNResultSet<double> result(1);
    result.init(&nearest, &d2);
    tree.findNeighbors(result, sampling.samples[i].p.data(), nanoflann::SearchParams(10));
    out.covered[i] = d2 <= r2 ? 1 : 0;
  });
  if (times && times->size() == points.size()) {
    out.first_time.assign(sampling.samples.size(), std::numeric_limits<double>::infinity());
    tbb::parallel_for(std::size_t{0}, sampling.samples.size(), [&](std::size_t i) {
      if (!out.covered[i]) return;
      std::vector<std::pair<std::uint32_t, double>> near;
      tree.radiusSearch(sampling.samples[i].p.data(), r2, near, nanoflann::SearchParams(10));
      for (const auto& item : near)
        out.first_time[i] = std::min(out.first_time[i], (*times)[item.first]);
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
