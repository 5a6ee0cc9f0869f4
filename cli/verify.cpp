#include "cli/verify.h"

#include <algorithm>
#include <chrono>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "cli/plot/figure.h"
#include "cli/plot/image_io.h"
#include "cli/programs/programs.h"
#include "kinematics/error.h"
#include "kinematics/units.h"
#include "scanner/cloud_io.h"

namespace scanplan::cli {

namespace {

scanner::CameraRule cameraRule(const std::string& name) {
  if (name == "negative") return scanner::CameraRule::kNegative;
  if (name == "both") return scanner::CameraRule::kBoth;
  if (name == "either") return scanner::CameraRule::kEither;
  return scanner::CameraRule::kPositive;
}

std::string readWhole(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) {
    throw InputError(fmt::format("{}: file does not exist", file.string()));
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(fmt::format("{}: cannot be read", file.string()));
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

Rgb toRgb(const std::array<std::uint8_t, 3>& c) { return {c[0], c[1], c[2]}; }

}  // namespace

planner::ValidationSettings validationSettings(const JobSpec& job) {
  planner::ValidationSettings s;
  s.sample_dt = 1.0 / job.scanner.frame_rate_hz;
  s.table_omega_max = deg(job.table.max_speed_deg_s);
  s.table_alpha_max = deg(job.table.max_accel_deg_s2);
  s.collision_resolution = job.validation.collision_resolution_mm * kMmToM;
  return s;
}

kinematics::Trajectory loadTrajectoryFile(const std::filesystem::path& file) {
  const std::string text = readWhole(file);
  const bool vplus = text.rfind(".PROGRAM", 0) == 0 || text.find("\n.PROGRAM") != std::string::npos;
  return vplus ? readVplusProgram(text, file.string())
               : kinematics::parseTrajectoryCsv(text, file.string());
}

std::string writePrograms(const std::filesystem::path& dir,
                          const std::string& shown_as,
                          const JobSpec& job,
                          const kinematics::CellModel& cell,
                          const kinematics::Trajectory& trajectory,
                          const std::vector<std::string>& formats) {
  ProgramOptions options;
  options.name = job.outputs.program_name;
  options.job = job.name;
  options.table_max_speed = deg(job.table.max_speed_deg_s);
  std::vector<std::string> written;
  double max_percent = 0.0;
  std::size_t over = 0;
  for (const std::string& name : formats) {
    const auto format = parseProgramFormat(name);
    if (!format)
      throw InputError(fmt::format("program format '{}': expected one of {}", name,
                                   fmt::join(programFormatNames(), ", ")));
    const ProgramFiles files = writeProgram(trajectory, cell.robot, *format, options);
    for (const auto& [file, content] : files.files) {
      writeFileAtomically(dir / file, content);
      written.push_back(file);
    }
    max_percent = std::max(max_percent, files.max_speed_percent);
    over = std::max(over, files.over_speed_segments);
  }
  if (written.empty()) return "programs   none (outputs.programs is empty)\n";
  return fmt::format(
      "programs   {}: {}; fastest step {:.0f}% of an axis's max speed (joints, table){}\n",
      shown_as, fmt::join(written, ", "), max_percent,
      over == 0
          ? std::string()
          : fmt::format(", {} step(s) need more than 100% (marked WARNING, run slower)", over));
}

std::string validationSummary(const planner::ValidationReport& r, std::size_t max_lines) {
  std::string s =
      fmt::format("validation {}: {} poses, {} clearance evaluations in {:.2f} s; ",
                  r.valid ? "valid" : fmt::format("INVALID, {} violation(s)", r.violations.size()),
                  r.samples, r.poses_checked, r.seconds);
  s += std::isfinite(r.min_distance)
           ? fmt::format("min distance {:.1f} mm ({} at t = {:.2f} s); ", toMm(r.min_distance),
                         r.min_distance_pair, r.min_distance_t)
           : std::string("every pair beyond its d_high; ");
  s += std::isfinite(r.proven_clearance)
           ? fmt::format("proven clearance over the whole motion {:.1f} mm\n",
                         toMm(r.proven_clearance))
           : std::string("no pairs\n");
  for (std::size_t i = 0; i < r.violations.size() && i < max_lines; ++i) {
    s += "  " + planner::describe(r.violations[i]) + "\n";
  }
  if (r.violations.size() > max_lines) {
    s += fmt::format("  … and {} more (report.json lists all)\n", r.violations.size() - max_lines);
  }
  if (r.first_collision) {
    const Eigen::Vector3d p = r.first_collision->p_W * kMToMm;
    s += fmt::format(
        "  first collision: {} at t = {:.3f} s, contact at ({:.1f}, {:.1f}, {:.1f}) mm "
        "(world)\n",
        r.first_collision->what, r.first_collision->t, p.x(), p.y(), p.z());
  }
  return s;
}

void writeValidationJson(JsonWriter& json,
                         const std::string& key,
                         const planner::ValidationReport& r) {
  json.beginObject(key);
  json.value("valid", r.valid);
  json.value("poses", static_cast<int>(r.samples));
  json.value("clearance_evaluations", static_cast<int>(r.poses_checked));
  json.value("seconds", r.seconds);
  json.value("min_distance_mm", toMm(r.min_distance));
  json.value("min_distance_pair", r.min_distance_pair);
  json.value("min_distance_time_s", r.min_distance_t);
  json.value("proven_clearance_mm", toMm(r.proven_clearance));
  json.beginArray("violations");
  const auto user = [](const planner::Violation& v, double x) {
    switch (v.kind) {
      case planner::Violation::Kind::kCollision:
        return toMm(x);
      default:
        return toDeg(x);  // rad, rad/s, rad/s² → deg, deg/s, deg/s²
    }
  };
  for (const planner::Violation& v : r.violations) {
    json.beginObject();
    json.value("kind", planner::kindName(v.kind));
    json.value("what", v.what);
    json.value("time_s", v.t);
    json.value("start_s", v.t_start);
    json.value("end_s", v.t_end);
    json.value("value", user(v, v.value));
    json.value("limit", user(v, v.limit));
    json.value("unit", v.kind == planner::Violation::Kind::kCollision ? "mm"
                       : v.kind == planner::Violation::Kind::kJointSpeed ||
                               v.kind == planner::Violation::Kind::kTableSpeed
                           ? "deg/s"
                       : v.kind == planner::Violation::Kind::kTableAccel ? "deg/s^2"
                                                                         : "deg");
    if (v.kind == planner::Violation::Kind::kCollision) {
      json.beginArray("contact_mm");
      for (int i = 0; i < 3; ++i) json.element(toMm(v.p_W(i)));
      json.endArray();
    }
    json.endObject();
  }
  json.endArray();
  json.endObject();
}

SimulationRun simulateTrajectory(const JobSpec& job,
                                 const kinematics::CellModel& cell,
                                 const kinematics::TriangleMesh& part,
                                 const kinematics::Trajectory& trajectory) {
  const auto start = std::chrono::steady_clock::now();
  const kinematics::Trajectory dense =
      planner::densify(trajectory, 1.0 / job.scanner.frame_rate_hz);
  std::vector<scanner::ScanFrame> frames;
  for (const auto& s : dense.samples) {
    if (s.scanning) frames.push_back({s.t, s.theta, s.q});
  }
  scanner::SimulationSettings settings;
  settings.rays_per_profile = job.scanner.rays_per_profile;
  settings.cameras = cameraRule(job.scanner.cameras);
  settings.sigma_longitudinal = job.scanner.noise.longitudinal_mm * kMmToM;
  settings.sigma_orthogonal = job.scanner.noise.orthogonal_mm * kMmToM;
  settings.seed = static_cast<std::uint64_t>(job.scanner.noise.seed);
  const auto& e = job.simulation.extra_eccentricity_mm;
  const auto& t = job.simulation.extra_tilt_deg;
  if (e[0] != 0.0 || e[1] != 0.0 || t[0] != 0.0 || t[1] != 0.0) {
    kinematics::RotaryTableModel real = cell.table;
    real.eccentricity += Eigen::Vector2d(e[0], e[1]) * kMmToM;
    real.tilt += Eigen::Vector2d(deg(t[0]), deg(t[1]));
    settings.simulated_table = real;
  }
  const scanner::ScanSimulator simulator(cell, part);
  SimulationRun run;
  run.frames = frames.size();
  run.cloud = simulator.simulate(frames, laserOptics(job), settings);
  scanner::CoverageSettings coverage;
  coverage.min_points = static_cast<std::uint32_t>(job.simulation.coverage_min_points);
  run.coverage = scanner::computeCoverage(part, run.cloud.points, coverage);
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return run;
}

void writeSimulationOutputs(const std::filesystem::path& dir,
                            const JobSpec& job,
                            const kinematics::TriangleMesh& part,
                            const SimulationRun& run) {
  {
    std::ostringstream cloud(std::ios::binary);
    scanner::writeCloudPly(cloud, run.cloud.points);
    writeFileAtomically(dir / "cloud.ply", cloud.str());
  }
  scanner::CoverageSettings coverage_settings;
  coverage_settings.min_points = static_cast<std::uint32_t>(job.simulation.coverage_min_points);
  {
    std::ostringstream coverage(std::ios::binary);
    scanner::writeCoveragePly(coverage, part, run.coverage, coverage_settings);
    writeFileAtomically(dir / "coverage.ply", coverage.str());
  }

  // cloud.png: top row the points (coloured by acquisition time), bottom row the part coloured
  // by density; iso, top and front views, captioned, each row with its colour scale.
  constexpr int kView = 480;
  const double t_end = run.cloud.points.empty() ? 1.0 : run.cloud.points.back().t;
  std::vector<Rgb> triangle_colours;
  const double max_density = run.coverage.density_p95_per_mm2;
  for (std::size_t i = 0; i < part.triangles.size(); ++i) {
    const bool covered = run.coverage.hits[i] >= coverage_settings.min_points;
    triangle_colours.push_back(toRgb(scanner::densityColour(
        scanner::triangleDensityPerMm2(part, run.coverage, i), max_density, covered)));
  }
  ViewGrid grid;
  grid.rows.resize(2);  // both rows first: references into the vector stay valid
  ViewRow& cloud = grid.rows[0];
  cloud.title =
      fmt::format("Simulated cloud, {} points, by acquisition time:", run.cloud.points.size());
  ViewRow& density = grid.rows[1];
  density.title = fmt::format("Coverage, {:.1f}% of the area, point density:",
                              100.0 * run.coverage.covered_fraction);
  for (int i = 0; i < 64; ++i) {
    const double u = i / 63.0;
    cloud.scale.push_back(toRgb(scanner::densityColour(u, 1.0, true)));
    density.scale.push_back(toRgb(scanner::densityColour(u * max_density, max_density, true)));
  }
  cloud.scale_from = "0 s";
  cloud.scale_to = fmt::format("{:.0f} s", t_end);
  density.scale_from = "0";
  density.scale_to = fmt::format("{:.1f} points/mm² (95%)", max_density);
  for (const NamedView& view : partViews()) {
    grid.captions.push_back(view.name);
    RenderRequest points;
    points.width = points.height = kView;
    points.R_view = view.R_view;
    // Fit both rows to the part's box: invisible corner markers would show, so use the part.
    points.vertices = part.vertices;
    points.triangles = {};
    for (const auto& p : run.cloud.points) {
      points.dots.push_back(p.p_P);
      const double u = t_end > 0.0 ? p.t / t_end : 0.0;
      points.dot_colours.push_back(toRgb(scanner::densityColour(u, 1.0, true)));
    }
    cloud.views.push_back(renderScene(points));
    RenderRequest mesh;
    mesh.width = mesh.height = kView;
    mesh.R_view = view.R_view;
    mesh.vertices = part.vertices;
    mesh.triangles = part.triangles;
    mesh.triangle_colours = triangle_colours;
    density.views.push_back(renderScene(mesh));
  }
  grid.legend = {{toRgb(scanner::densityColour(0.0, 1.0, false)),
                  coverage_settings.min_points > 1
                      ? fmt::format("not covered (fewer than {} points on the triangle)",
                                    coverage_settings.min_points)
                      : std::string("not covered (no point on the triangle)")}};
  const RgbImage out = drawViewGrid(grid);
  writePng(dir / "cloud.png", out);
}

std::string simulationSummary(const SimulationRun& run) {
  const scanner::SimulationStats& s = run.cloud.stats;
  std::string text = fmt::format(
      "simulation {} profiles, {} laser + {} occlusion rays in {:.1f} s: {} points ({} outside "
      "the window, {} hidden from the camera)\n",
      s.profiles, s.laser_rays, s.occlusion_rays, run.seconds, s.points, s.outside_window,
      s.occluded);
  text += fmt::format(
      "coverage   {:.1f}% of the part's area ({} of {} triangles); density {:.2f} points/mm² "
      "(median {:.2f}, 5% {:.2f}, 95% {:.2f})\n",
      100.0 * run.coverage.covered_fraction, run.coverage.covered_triangles,
      run.coverage.hits.size(), run.coverage.density_mean_per_mm2,
      run.coverage.density_median_per_mm2, run.coverage.density_p5_per_mm2,
      run.coverage.density_p95_per_mm2);
  return text;
}

void writeSimulationJson(JsonWriter& json, const std::string& key, const SimulationRun& run) {
  const scanner::SimulationStats& s = run.cloud.stats;
  json.beginObject(key);
  json.value("profiles", static_cast<int>(s.profiles));
  json.value("laser_rays", static_cast<double>(s.laser_rays));
  json.value("occlusion_rays", static_cast<double>(s.occlusion_rays));
  json.value("points", static_cast<double>(s.points));
  json.value("outside_window", static_cast<double>(s.outside_window));
  json.value("occluded", static_cast<double>(s.occluded));
  json.value("seconds", run.seconds);
  json.beginObject("coverage");
  json.value("covered_fraction", run.coverage.covered_fraction);
  json.value("covered_area_mm2", run.coverage.covered_area * 1e6);
  json.value("total_area_mm2", run.coverage.total_area * 1e6);
  json.value("covered_triangles", static_cast<double>(run.coverage.covered_triangles));
  json.value("triangles", static_cast<double>(run.coverage.hits.size()));
  json.value("points_on_part", static_cast<double>(run.coverage.part_points));
  json.value("density_mean_per_mm2", run.coverage.density_mean_per_mm2);
  json.value("density_median_per_mm2", run.coverage.density_median_per_mm2);
  json.value("density_p5_per_mm2", run.coverage.density_p5_per_mm2);
  json.value("density_p95_per_mm2", run.coverage.density_p95_per_mm2);
  json.endObject();
  json.endObject();
}

}  // namespace scanplan::cli
