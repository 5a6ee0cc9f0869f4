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

namespace {

scanner::CameraRule cameraRule(const std::string& name) {
  if (name == "negative") return scanner::CameraRule::kNegative;
  if (name == "both") return scanner::CameraRule::kBoth;
  if (name == "either") return scanner::CameraRule::kEither;
  return scanner::CameraRule::kPositive;
}

// The arm can reach the part at some table angle: an error when none of it is within reach, a
// warning when some of it is not (kinematics::partReach is a necessary condition only).
void checkInReach(const JobSpec& job,
                  const kinematics::CellModel& cell,
                  const kinematics::TriangleMesh& mesh) {
  const scanner::LaserWindow window = scanner::laserWindow(laserOptics(job));
  const double lever = cell.robot.definition().opw.c4 + cell.scanner.X_FS.translation().norm() +
                       std::hypot(window.z_max, window.y_far);
  const kinematics::PartReach reach = kinematics::partReach(cell, mesh, lever);
  const double mount = cell.scanner.X_FS.translation().norm();
  if (mount > reach.arm_reach - lever) {  // the arm's own stretch, shoulder to flange
    throw InputError(fmt::format(
        "{}: scanner.mount: the laser frame sits {:.0f} mm from the flange, more than the arm's "
        "whole stretch of {:.0f} mm: expected the scanner's offset on the flange (xyz_mm, mm)",
        job.source.string(), toMm(mount), toMm(reach.arm_reach - lever)));
  }
  if (reach.nearest_excess > 0.0) {
    throw InputError(fmt::format(
        "{}: part: no point of the part ({:.0f} mm across) is within the arm's reach at any "
        "table angle: the nearest stays {:.0f} mm beyond the {:.0f} mm the arm, the scanner "
        "and its depth window can stretch from the shoulder; expected the table (table.axis) "
        "within reach of the robot and the part's size as meant (part.units, part.scale)",
        job.source.string(), toMm(mesh.bounds().diagonal().norm()), toMm(reach.nearest_excess),
        toMm(reach.arm_reach)));
  }
  if (reach.beyond_fraction > 0.0) {
    spdlog::warn(
        "{}: part: {:.1f} % of the part's vertices are beyond the arm's reach at every "
        "table angle; they cannot be scanned",
        job.source.filename().string(), 100.0 * reach.beyond_fraction);
  }
}

// The part on the table top: none of it below (beyond a rounding hair), and a warning when it
// overhangs the table.
void checkOnTable(const JobSpec& job,
                  const kinematics::CellModel& cell,
                  const kinematics::TriangleMesh& mesh) {
  constexpr double kSunkTolerance = 1e-5;  // m: 0.01 mm, far above the float rounding of a mesh
  const auto [lowest, widest] = kinematics::partExtent(mesh, cell.part.X_RP);
  if (lowest < -kSunkTolerance) {
    throw InputError(fmt::format(
        "{}: part.pose: the part reaches {:.2f} mm below the table top (its lowest point is at "
        "z = {:.2f} mm on the table): expected it to rest on the table; raise pose.xyz_mm z by "
        "{:.2f}, or set part.place: table",
        job.source.string(), toMm(-lowest), toMm(lowest), toMm(-lowest)));
  }
  if (widest > cell.table.radius) {
    spdlog::warn(
        "{}: part: the part reaches {:.1f} mm from the table axis, beyond the table's "
        "radius of {:.1f} mm",
        job.source.filename().string(), toMm(widest), toMm(cell.table.radius));
  }
  checkInReach(job, cell, mesh);
}

}  // namespace

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

kinematics::LoadedMesh loadPart(const JobSpec& job, const kinematics::CellModel& cell) {
  kinematics::LoadedMesh part = loadPartMesh(job, cell.part);
  for (const std::string& w : part.report.warnings) {
    spdlog::warn("{}: part.mesh: {}", job.source.filename().string(), w);
  }
  // Inside out, every surface would face away from the scanner: say so, not "nothing seen".
  if (part.mesh.isClosed() && part.mesh.signedVolume() < 0.0) {
    throw InputError(fmt::format(
        "{}: part.mesh: {} is closed but inside out: its triangles' winding puts their normals "
        "into the part (volume {:.0f} mm³ by the winding): expected outward normals; reverse "
        "the winding of every face in a mesh tool",
        job.source.string(), job.part.mesh.as_written, part.mesh.signedVolume() * 1e9));
  }
  checkOnTable(job, cell, part.mesh);
  return part;
}

scanner::PathRequest placedPathRequest(const JobSpec& job, const kinematics::CellModel& cell) {
  scanner::PathRequest request = pathRequest(job);
  if (job.part.place != "table") return request;
  const double table_top_P = -cell.part.X_RP.translation().z();  // for a part turned about z
  for (scanner::PathElement& e : request.elements) {
    if (auto* ring = std::get_if<scanner::RingSpec>(&e)) ring->height += table_top_P;
  }
  return request;
}

pipeline::MapSettings mapSettings(const JobSpec& job) {
  pipeline::MapSettings s;
  s.angle_step = deg(job.map.angle_step_deg);
  if (job.map.branch != "auto") s.branches = {*parseBranch(job.map.branch)};
  s.memory_limit_bytes = static_cast<std::size_t>(job.map.memory_limit_mb * 1024.0 * 1024.0);
  return s;
}

pipeline::PlanSettings planSettings(const JobSpec& job) {
  pipeline::PlanSettings s;
  s.method = job.planner.method;
  s.objective = plannerSettings(job);
  s.continuous = job.table.continuous;
  s.start_theta = startAngle(job);
  s.planners.ray.rays = job.planner.ray.rays;
  s.planners.ray.horizon = job.planner.ray.horizon;
  s.planners.ray.starts = job.planner.ray.starts;
  s.planners.ray.blocked_penalty = job.planner.ray.blocked_penalty_s;
  s.planners.ray.cost_to_go = job.planner.ray.cost_to_go;
  s.planners.ray.dp_fallback = job.planner.ray.dp_fallback;
  s.planners.dp_subdivisions = job.planner.dp.angle_subdivisions;
  s.planners.ompl.seed = static_cast<std::uint32_t>(job.planner.ompl.seed);
  s.termination.time_limit_s = job.planner.ompl.time_limit_s;
  s.termination.max_iterations = static_cast<std::size_t>(job.planner.ompl.max_iterations);
  s.refine = job.planner.refine.enabled;
  s.refine_settings.time_limit_s = job.planner.refine.time_limit_s;
  s.dp_gap = job.planner.dp_gap;
  return s;
}

planner::ValidationSettings validationSettings(const JobSpec& job) {
  planner::ValidationSettings s;
  s.sample_dt = 1.0 / job.scanner.frame_rate_hz;
  s.table_omega_max = deg(job.table.max_speed_deg_s);
  s.table_alpha_max = deg(job.table.max_accel_deg_s2);
  s.collision_resolution = job.validation.collision_resolution_mm * kMmToM;
  return s;
}

pipeline::SimulationSettings simulationSettings(const JobSpec& job,
                                                const kinematics::CellModel& cell) {
  pipeline::SimulationSettings s;
  s.frame_rate_hz = job.scanner.frame_rate_hz;
  s.scanner.rays_per_profile = job.scanner.rays_per_profile;
  s.scanner.cameras = cameraRule(job.scanner.cameras);
  s.scanner.sigma_longitudinal = job.scanner.noise.longitudinal_mm * kMmToM;
  s.scanner.sigma_orthogonal = job.scanner.noise.orthogonal_mm * kMmToM;
  s.scanner.seed = static_cast<std::uint64_t>(job.scanner.noise.seed);
  s.scanner.mode = job.simulation.mode == "image" ? scanner::SimulationMode::kImage
                                                  : scanner::SimulationMode::kGeometric;
  const CameraSpec& camera = job.scanner.camera;
  scanner::ImageSettings& image = s.scanner.image;
  image.rows = camera.rows;
  image.columns = camera.columns > 0 ? camera.columns : job.scanner.rays_per_profile;
  image.thickness = job.scanner.laser.thickness_mm * kMmToM;
  image.reflectance = {job.simulation.reflectance.lambert, job.simulation.reflectance.specular,
                       job.simulation.reflectance.shininess};
  image.ambient = camera.ambient_grey;
  image.noise = camera.noise_grey;
  image.threshold = camera.threshold_grey;
  image.method = camera.detection == "gauss" ? scanner::StripeMethod::kGaussian
                                             : scanner::StripeMethod::kCentreOfGravity;
  if (s.scanner.mode == scanner::SimulationMode::kImage)
    s.profile_images = static_cast<std::size_t>(job.simulation.profile_images);
  const auto& e = job.simulation.extra_eccentricity_mm;
  const auto& t = job.simulation.extra_tilt_deg;
  if (e[0] != 0.0 || e[1] != 0.0 || t[0] != 0.0 || t[1] != 0.0) {
    kinematics::RotaryTableModel real = cell.table;
    real.eccentricity += Eigen::Vector2d(e[0], e[1]) * kMmToM;
    real.tilt += Eigen::Vector2d(deg(t[0]), deg(t[1]));
    s.scanner.simulated_table = real;
  }
  s.coverage.min_points = static_cast<std::uint32_t>(job.simulation.coverage_min_points);
  return s;
}

pipeline::AutoScanSettings autoScanSettings(const JobSpec& job) {
  const AutoSpec& a = job.scan.auto_scan;
  pipeline::AutoScanSettings s;
  s.max_incidence = deg(a.max_incidence_deg);
  s.point_spacing = a.point_spacing_mm * kMmToM;
  s.target_coverage = a.target_coverage;
  s.max_passes = static_cast<std::size_t>(a.max_passes);
  s.time_budget = a.time_budget_s;
  s.max_program = a.max_program_s;
  s.sample_spacing = a.sample_spacing_mm * kMmToM;
  return s;
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
