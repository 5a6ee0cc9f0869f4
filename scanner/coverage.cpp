#include <scanplan/scanner/coverage.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include <tbb/parallel_for.h>

#include <scanplan/kinematics/units.h>
#include <scanplan/scanner/detail/large_buffer.h>

namespace scanplan::scanner {
namespace {

double triangleArea(const kinematics::TriangleMesh& mesh, std::size_t triangle) {
  const Eigen::Vector3i& f = mesh.triangles[triangle];
  const Eigen::Vector3d& v0 = mesh.vertices[static_cast<std::size_t>(f(0))];
  const Eigen::Vector3d& v1 = mesh.vertices[static_cast<std::size_t>(f(1))];
  const Eigen::Vector3d& v2 = mesh.vertices[static_cast<std::size_t>(f(2))];
  return 0.5 * (v1 - v0).cross(v2 - v0).norm();
}

constexpr double kMm2PerM2 = kMToMm * kMToMm;

}  // namespace

PartCoverage computeCoverage(const kinematics::TriangleMesh& part,
                             const std::vector<CloudPoint>& points,
                             const CoverageSettings& settings) {
  PartCoverage c;
  const std::size_t n = part.triangles.size();
  c.hits.assign(n, 0);
  for (const CloudPoint& p : points) {
    if (p.part_triangle < 0 || static_cast<std::size_t>(p.part_triangle) >= n) continue;
    ++c.hits[static_cast<std::size_t>(p.part_triangle)];
    ++c.part_points;
  }
  std::vector<std::pair<double, double>> covered;  // (density per mm², area m²)
  std::size_t covered_points = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double area = triangleArea(part, i);
    c.total_area += area;
    if (c.hits[i] < std::max<std::uint32_t>(settings.min_points, 1)) continue;
    ++c.covered_triangles;
    c.covered_area += area;
    covered_points += c.hits[i];
    if (area > 0.0) covered.emplace_back(c.hits[i] / (area * kMm2PerM2), area);
  }
  if (c.total_area > 0.0) c.covered_fraction = c.covered_area / c.total_area;
  if (c.covered_area > 0.0) {
    c.density_mean_per_mm2 = static_cast<double>(covered_points) / (c.covered_area * kMm2PerM2);
  }
  if (!covered.empty()) {
    std::sort(covered.begin(), covered.end());
    double weight = 0.0;
    for (const auto& [density, area] : covered) weight += area;
    const auto quantile = [&](double q) {
      double below = 0.0;
      for (const auto& [density, area] : covered) {
        below += area;
        if (below >= q * weight) return density;
      }
      return covered.back().first;
    };
    c.density_p5_per_mm2 = quantile(0.05);
    c.density_median_per_mm2 = quantile(0.5);
    c.density_p95_per_mm2 = quantile(0.95);
  }
  return c;
}

PartPoints pointsOnPart(const std::vector<CloudPoint>& points, double max_incidence) {
  // Chunks counted in parallel, then each copied in parallel to its place.
  constexpr std::size_t kChunk = 1 << 16;
  const std::size_t chunks = (points.size() + kChunk - 1) / kChunk;
  const auto counts = [&](const CloudPoint& p) {
    return p.part_triangle >= 0 && p.incidence <= max_incidence;
  };
  std::vector<std::size_t> offset(chunks + 1, 0);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
    const auto end =
        points.begin() + static_cast<std::ptrdiff_t>(std::min(points.size(), (c + 1) * kChunk));
    offset[c + 1] = static_cast<std::size_t>(
        std::count_if(points.begin() + static_cast<std::ptrdiff_t>(c * kChunk), end, counts));
  });
  for (std::size_t c = 0; c < chunks; ++c) offset[c + 1] += offset[c];
  PartPoints out;
  detail::reserveLarge(out.p, offset.back());
  detail::reserveLarge(out.t, offset.back());
  out.p.resize(offset.back());
  out.t.resize(offset.back());
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
    std::size_t at = offset[c];
    for (std::size_t i = c * kChunk; i < std::min(points.size(), (c + 1) * kChunk); ++i) {
      if (!counts(points[i])) continue;
      out.p[at] = points[i].p_P;
      out.t[at] = points[i].t;
      ++at;
    }
  });
  return out;
}

double triangleDensityPerMm2(const kinematics::TriangleMesh& part,
                             const PartCoverage& coverage,
                             std::size_t triangle) {
  const double area = triangleArea(part, triangle);
  return area > 0.0 ? coverage.hits[triangle] / (area * kMm2PerM2) : 0.0;
}

std::array<std::uint8_t, 3> densityColour(double density_per_mm2,
                                          double max_per_mm2,
                                          bool covered) {
  if (!covered) return {220, 70, 40};
  // Viridis at five stops, linear in between.
  static constexpr double kStops[5][3] = {
      {68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};
  double s = max_per_mm2 > 0.0 ? density_per_mm2 / max_per_mm2 : 1.0;
  s = std::clamp(std::isfinite(s) ? s : 1.0, 0.0, 1.0) * 4.0;
  const int i = std::min(3, static_cast<int>(s));
  const double f = s - i;
  std::array<std::uint8_t, 3> rgb{};
  for (std::size_t k = 0; k < 3; ++k) {
    const double v = kStops[i][k] + f * (kStops[i + 1][k] - kStops[i][k]);
    rgb[k] = static_cast<std::uint8_t>(std::lround(v));
  }
  return rgb;
}

}  // namespace scanplan::scanner
