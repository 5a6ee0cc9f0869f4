#pragma once

#include <cstddef>
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include <scanplan/kinematics/mesh.h>
#include <scanplan/scanner/coverage.h>
#include <scanplan/scanner/simulator.h>

namespace scanplan::scanner {

/// The PLY writers below end every header line with "\r\n", which assimp, rply and line readers
/// all read right whatever the first data byte (after a bare '\n', assimp drops a first 0x0A).
///
/// Writes cloud.ply: PLY 1.0, binary little-endian, one `vertex` element per point with
///   float x, y, z                 part frame, mm
///   float nx, ny, nz              the hit surface's unit normal, part frame, towards the laser
///   float scalar_time             acquisition time, s
///   int scalar_profile            profile (frame) index
///   int scalar_ray                fan ray index within the profile
///   float scalar_range_mm         laser origin to the point along the ray, mm
///   float scalar_incidence_deg    angle between the ray and the surface normal, degrees
///   int scalar_part_triangle      the part mesh's hit triangle; −1: the point lies on another body
///   float quality                 the incidence again, degrees
/// The names and types are what viewers keep: CloudCompare loads the properties named
/// "scalar_…" as scalar fields (named without the prefix), MeshLab keeps only `quality`, Open3D's
/// tensor reader and PCL keep every property but refuse or drop uint ones (so: float and int).
/// The stream must be binary; the caller owns the file (write to a temporary name and rename).
void writeCloudPly(std::ostream& out, const std::vector<CloudPoint>& points);

/// Writes coverage.ply: the part mesh (part frame, mm), PLY 1.0 binary little-endian, coloured
/// by point density (densityColour). Each triangle gets its own three vertices, so per-vertex
/// values are the triangle's and any viewer shows them exactly: float x, y, z; uchar red,
/// green, blue; float scalar_density_per_mm2; int scalar_points (on the triangle); float quality
/// (the density again, for MeshLab). The `face` element has
/// only `vertex_indices` (list uchar int), which every reader takes. `max_per_mm2` ≤ 0 puts
/// the top of the colour scale at the coverage's p95 density.
void writeCoveragePly(std::ostream& out,
                      const kinematics::TriangleMesh& part,
                      const PartCoverage& coverage,
                      const CoverageSettings& settings = {},
                      double max_per_mm2 = 0.0);

/// Writes labelled surface samples (uncovered.ply): PLY 1.0, binary little-endian, one `vertex`
/// per sample with float x, y, z (mm), float nx, ny, nz (unit normal), uchar scalar_reason, the
/// index into `reasons`, whose names the header lists in a comment ("reason: … 1 = occluded"),
/// and float quality, the same index (for MeshLab).
/// Points in the caller's frame, m.
void writeLabelledSamplesPly(std::ostream& out,
                             const std::vector<Eigen::Vector3d>& points,
                             const std::vector<Eigen::Vector3d>& normals,
                             const std::vector<std::uint8_t>& labels,
                             const std::vector<std::string>& reasons);

}  // namespace scanplan::scanner
