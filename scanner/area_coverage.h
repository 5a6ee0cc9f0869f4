#pragma once
// Coverage measured on area, not triangles (docs/design.md §11): the part's surface sampled
// area-uniformly, a sample covered when a measured point lies within the point spacing of it.
// Per-triangle counts overstate coverage on coarse meshes (one point on a large triangle counts
// the whole triangle); area samples do not depend on how the mesh is cut.

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <scanplan/kinematics/mesh.h>

namespace scanplan::scanner {

/// One area sample: a point on the surface with the normal of its triangle.
struct AreaSample {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();   ///< mesh frame, m
  Eigen::Vector3d n = Eigen::Vector3d::UnitZ();  ///< unit outward normal (the winding's)
  std::int32_t triangle = -1;
};

/// An area-uniform sampling of a mesh's surface: every sample stands for the same area.
struct AreaSampling {
  std::vector<AreaSample> samples;
  double total_area = 0.0;       ///< m², the mesh's
  double area_per_sample = 0.0;  ///< m²
};

/// Samples of the surface, about one per `spacing`² of area (systematic in the running area, so a
/// triangle gets ⌊area/spacing²⌋ or one more; uniform inside each triangle from a seeded
/// generator). At most `max_samples`: a larger count coarsens the spacing to fit. Deterministic.
/// Throws std::invalid_argument for spacing ≤ 0 or non-finite, or max_samples 0.
AreaSampling sampleArea(const kinematics::TriangleMesh& mesh,
                        double spacing,
                        std::size_t max_samples = 2'000'000,
                        std::uint64_t seed = 1);

/// Which samples have a point within `radius` (m) of them, and the covered fraction of the area.
struct AreaCoverage {
  std::vector<std::uint8_t> covered;  ///< 1 per covered sample, in sampling order
  std::size_t covered_samples = 0;
  double covered_fraction = 0.0;  ///< covered samples / samples (each stands for equal area)
  double radius = 0.0;            ///< m, as asked
  /// With point times: per sample, the earliest time (s) of a point within the radius; +inf
  /// where none. Empty without times.
  std::vector<double> first_time;
};

/// The coverage of `sampling` by `points` (same frame): k-d trees over the points (nanoflann; a
/// large cloud split into slabs along its longest side, one tree each, built in parallel, each
/// holding the points within `radius` of its slab too), the nearest point of every sample. With
/// `times` (one per point, s), also when each sample was first covered (every point within the
/// radius searched). Deterministic, the same on any number of threads; parallel over samples.
AreaCoverage areaCoverage(const AreaSampling& sampling,
                          const std::vector<Eigen::Vector3d>& points,
                          double radius,
                          const std::vector<double>* times = nullptr);

/// Which samples face the table or lie on it (the first class of the scannability certificate,
/// docs/design.md §11): no laser ray from a scanner above the table top can reach them within the
/// incidence limit. With the part on the table by X_RP (R: table top frame, z up, the top at
/// z = 0), a sample at height z with normal n (elevation ε = asin n_z) is seen at most from the
/// elevation ε + `max_incidence`; from `max_standoff` away the scanner is then at height
/// z + max_standoff · sin(min(ε + max_incidence, 90°)), which must be above the top. 1 where it is
/// not (the sample faces the table), in sampling order. Other bodies are not considered: a
/// sample this says 0 for may still be occluded.
std::vector<std::uint8_t> facesTable(const AreaSampling& sampling,
                                     const Eigen::Isometry3d& X_RP,
                                     double max_incidence,
                                     double max_standoff);

}  // namespace scanplan::scanner
