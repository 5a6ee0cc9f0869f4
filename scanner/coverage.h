#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <scanplan/kinematics/mesh.h>
#include <scanplan/scanner/simulator.h>

namespace scanplan::scanner {

struct CoverageSettings {
  /// A part triangle counts as covered when at least this many points landed on it.
  std::uint32_t min_points = 1;
};

/// How a simulated cloud covers the part mesh (its triangles, as the cloud's part_triangle).
///
/// Covered area: the area of the triangles with at least `min_points` points over the mesh
/// area. This is exact only when the triangles are small against the point spacing; a large
/// triangle hit once counts whole, so on coarse meshes the fraction is an upper bound (compare
/// the densities). Densities are per triangle, hits / area, in points/mm²; the statistics are
/// over the covered triangles: the mean is covered points / covered area, the quantiles are
/// area-weighted (a quantile q is the density below which a fraction q of the covered area
/// lies), so sliver triangles with one point do not skew them.
struct PartCoverage {
  std::vector<std::uint32_t> hits;  ///< points per part triangle
  std::size_t part_points = 0;      ///< points on the part (part_triangle ≥ 0)
  std::size_t covered_triangles = 0;
  double total_area = 0.0;    ///< m²
  double covered_area = 0.0;  ///< m²
  double covered_fraction = 0.0;
  double density_mean_per_mm2 = 0.0;
  double density_median_per_mm2 = 0.0;
  double density_p5_per_mm2 = 0.0;
  double density_p95_per_mm2 = 0.0;
};

/// The points of a cloud on the part (part_triangle ≥ 0) that the laser met within
/// `max_incidence` (rad) of the normal, the ones that count toward the area coverage, in the
/// cloud's order: positions (part frame) and times.
struct PartPoints {
  std::vector<Eigen::Vector3d> p;
  std::vector<double> t;
};
PartPoints pointsOnPart(const std::vector<CloudPoint>& points, double max_incidence);

/// Counts the points per part triangle and derives the statistics. Points whose part_triangle
/// is out of the mesh's range are ignored.
PartCoverage computeCoverage(const kinematics::TriangleMesh& part,
                             const std::vector<CloudPoint>& points,
                             const CoverageSettings& settings = {});

/// Points per mm² on triangle `triangle` (0 for a zero-area triangle).
double triangleDensityPerMm2(const kinematics::TriangleMesh& part,
                             const PartCoverage& coverage,
                             std::size_t triangle);

/// The colour scale of coverage.ply: uncovered triangles (fewer than min_points) red-orange
/// (220, 70, 40), clear against the ramp and a grey part; covered ones on a viridis ramp from dark
/// violet (68, 1, 84) at density 0 through blue, teal and green to yellow (253, 231, 37) at
/// `max_per_mm2` and above.
std::array<std::uint8_t, 3> densityColour(double density_per_mm2, double max_per_mm2, bool covered);

}  // namespace scanplan::scanner
