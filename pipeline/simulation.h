#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include <scanplan/kinematics/cell.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/trajectory.h>
#include <scanplan/pipeline/problem.h>
#include <scanplan/scanner/area_coverage.h>
#include <scanplan/scanner/coverage.h>
#include <scanplan/scanner/laser_model.h>
#include <scanplan/scanner/simulator.h>

namespace scanplan::pipeline {

/// One simulation run and the coverage of the part it gives.
struct SimulationRun {
  scanner::SimulatedCloud cloud;
  scanner::PartCoverage coverage;  ///< per triangle (hits, densities)
  scanner::AreaSampling sampling;  ///< the area samples (part frame) `area` covers
  scanner::AreaCoverage area;      ///< on area samples: the covered fraction of the area
  std::size_t area_samples = 0;
  double point_spacing = 0.0;  ///< m, the radius `area` was measured with
  /// Share of the area that faces the table or lies on it (scanner::facesTable() at the depth
  /// window's far end and the incidence limit): not scannable on this setup.
  double faces_table_fraction = 0.0;
  std::size_t frames = 0;  ///< profiles acquired (densified samples with scanning on)
  /// SimulationSettings::profile_images camera images, by profile index (ascending).
  std::vector<std::pair<std::uint32_t, scanner::ProfileImage>> profile_images;
  double seconds = 0.0;
};

/// m, the radius an area sample is covered within (SimulationRun::point_spacing): the settings'
/// point spacing, or the line's point pitch at the middle of the depth window.
double coverageSpacing(const SimulationSettings& settings, const scanner::LaserOptics& optics);

/// The scanner simulated along `trajectory`: a profile every 1/frame_rate_hz s while the path
/// scans, with the settings' fan, cameras, noise and real-table error; the coverage per triangle
/// and on area (the points on the part against area samples, scanner/area_coverage.h). Polls
/// `cancel` (when set) before each batch of profiles: throws Cancelled (pipeline/cancel.h).
SimulationRun simulateTrajectory(const kinematics::CellModel& cell,
                                 const kinematics::TriangleMesh& part,
                                 const scanner::LaserOptics& optics,
                                 const SimulationSettings& settings,
                                 const kinematics::Trajectory& trajectory,
                                 const std::atomic<bool>* cancel = nullptr);

}  // namespace scanplan::pipeline
