// The job as the library's problem: every section's SI conversion (job_*.cpp) put together, and
// the check of the simulated scanner's resolution against the spacing coverage is measured at.
#include <scanplan/config/to_problem.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <variant>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/placement.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/pipeline/auto_scan.h>

namespace scanplan::config {

// One ray has no line width to measure with (coverage would count the whole line's width around
// each point); rays farther apart than the spacing leave their tracks only.
std::string checkScannerResolution(const JobSpec& job, const pipeline::ScanProblem& p) {
  if (!p.simulation) return {};
  // The line's width at mid depth: the pitch of two rays (pipeline::autoPointSpacing).
  const double width = pipeline::autoPointSpacing({}, p.optics, 2);
  const int rays = job.scanner.rays_per_profile;
  if (rays < 2) {
    throw InputError(fmt::format(
        "{}: scanner.rays_per_profile: {}: one ray per profile has no line width, and coverage "
        "would be measured over the whole {:.1f} mm line around each point: expected at least 2 "
        "(the scanner's points per line; {} gives a {:.2f} mm pitch at mid depth)",
        job.source.string(), rays, toMm(width), 200, toMm(width / 199.0)));
  }
  const double pitch = width / static_cast<double>(rays - 1);
  const double spacing = p.simulation->point_spacing;
  if (!(spacing > 0.0 && pitch > spacing * (1.0 + 1e-9))) return {};
  return fmt::format(
      "{}: scanner.rays_per_profile: {} rays put points {:.2f} mm apart across the line at "
      "mid depth, coarser than the {:.2f} mm coverage is measured at: only the rays' tracks "
      "count as covered; {} rays match the spacing",
      job.source.filename().string(), rays, toMm(pitch), toMm(spacing),
      static_cast<long long>(std::ceil(width / spacing - 1e-9)) + 1);
}

pipeline::ScanProblem toProblem(const JobSpec& job,
                                kinematics::CellModel cell,
                                kinematics::TriangleMesh part) {
  pipeline::ScanProblem p(std::move(cell));
  p.name = job.name;
  p.optics = laserOptics(job);
  p.path = placedPathRequest(job, p.cell);
  p.clearance = clearanceConfig(job);
  p.constraints = constraintSettings(job);
  p.map = mapSettings(job);
  p.planning = planSettings(job);
  if (job.validation.enabled) p.validation = validationSettings(job);
  if (job.simulation.enabled) p.simulation = simulationSettings(job, p.cell);
  if (job.scan.auto_scan.enabled) {
    p.auto_scan = autoScanSettings(job);
    if (p.simulation) {  // coverage is measured the way the passes were chosen
      p.simulation->point_spacing = p.auto_scan->point_spacing;
      p.simulation->max_incidence = p.auto_scan->max_incidence;
    }
  }
  if (const std::string w = checkScannerResolution(job, p); !w.empty()) spdlog::warn("{}", w);
  p.part = std::move(part);
  return p;
}

pipeline::ScanProblem toProblem(const JobSpec& job) {
  kinematics::CellModel cell = buildCell(job);
  kinematics::LoadedMesh part = loadPart(job, cell);
  return toProblem(job, std::move(cell), std::move(part.mesh));
}

}  // namespace scanplan::config
