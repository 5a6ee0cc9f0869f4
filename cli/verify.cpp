#include "cli/verify.h"

#include <algorithm>
#include <chrono>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "cli/plot/figure.h"
#include "cli/plot/image_io.h"
#include "cli/programs/programs.h"
#include "kinematics/error.h"
#include "kinematics/units.h"
#include "scanner/cloud_io.h"

namespace scanplan::cli {

namespace {

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

// The summary's word on the formats against the robot's controller: a warning for another
// vendor's language (its joint values are this robot's, not that vendor's), a note when the
// robot file names no controller.
std::string controllerNote(const RobotSpec& robot, const std::vector<std::string>& formats) {
  const std::vector<std::string> foreign = foreignPrograms(robot, formats);
  if (!foreign.empty()) {
    const std::string warning =
        fmt::format("{} {} not the language of robot '{}' (controller {}, writes {})",
                    fmt::join(foreign, ", "), foreign.size() == 1 ? "is" : "are", robot.name,
                    robot.controller, controllerProgramFormat(robot.controller));
    spdlog::warn("programs: {}", warning);
    return "; WARNING: " + warning;
  }
  if (controllerProgramFormat(robot.controller).empty()) {
    return fmt::format("; robot '{}' names no controller (controller: none)", robot.name);
  }
  return "";
}

}  // namespace

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
      "programs   {}: {}; fastest step {:.0f}% of an axis's max speed (joints, table){}{}\n",
      shown_as, fmt::join(written, ", "), max_percent,
      over == 0
          ? std::string()
          : fmt::format(", {} step(s) need more than 100% (marked WARNING, run slower)", over),
      controllerNote(job.robot, formats));
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

namespace {

// The unit a violation's value and limit are given in, as validationJson() converts them.
const char* violationUnit(planner::Violation::Kind kind) {
  using Kind = planner::Violation::Kind;
  if (kind == Kind::kCollision) return "mm";
  if (kind == Kind::kJointSpeed || kind == Kind::kTableSpeed) return "deg/s";
  if (kind == Kind::kTableAccel) return "deg/s^2";
  return "deg";
}

Json violationJson(const planner::Violation& v) {
  const bool collision = v.kind == planner::Violation::Kind::kCollision;
  // rad, rad/s, rad/s² → deg, deg/s, deg/s²; m → mm
  const auto user = [&](double x) { return collision ? toMm(x) : toDeg(x); };
  Json json = {{"kind", planner::kindName(v.kind)},
               {"what", v.what},
               {"time_s", v.t},
               {"start_s", v.t_start},
               {"end_s", v.t_end},
               {"value", user(v.value)},
               {"limit", user(v.limit)},
               {"unit", violationUnit(v.kind)}};
  if (collision) json["contact_mm"] = {toMm(v.p_W(0)), toMm(v.p_W(1)), toMm(v.p_W(2))};
  return json;
}

}  // namespace

Json validationJson(const planner::ValidationReport& r) {
  Json violations = Json::array();
  for (const planner::Violation& v : r.violations) violations.push_back(violationJson(v));
  return {{"valid", r.valid},
          {"poses", r.samples},
          {"clearance_evaluations", r.poses_checked},
          {"seconds", r.seconds},
          {"min_distance_mm", toMm(r.min_distance)},
          {"min_distance_pair", r.min_distance_pair},
          {"min_distance_time_s", r.min_distance_t},
          {"proven_clearance_mm", toMm(r.proven_clearance)},
          {"violations", std::move(violations)}};
}

SimulationRun simulateTrajectory(const JobSpec& job,
                                 const kinematics::CellModel& cell,
                                 const kinematics::TriangleMesh& part,
                                 const kinematics::Trajectory& trajectory) {
  return pipeline::simulateTrajectory(cell, part, laserOptics(job), simulationSettings(job, cell),
                                      trajectory);
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

Json simulationJson(const SimulationRun& run) {
  const scanner::SimulationStats& s = run.cloud.stats;
  const scanner::PartCoverage& c = run.coverage;
  return {{"profiles", s.profiles},
          {"laser_rays", s.laser_rays},
          {"occlusion_rays", s.occlusion_rays},
          {"points", s.points},
          {"outside_window", s.outside_window},
          {"occluded", s.occluded},
          {"seconds", run.seconds},
          {"coverage",
           {{"covered_fraction", c.covered_fraction},
            {"covered_area_mm2", c.covered_area * 1e6},
            {"total_area_mm2", c.total_area * 1e6},
            {"covered_triangles", c.covered_triangles},
            {"triangles", c.hits.size()},
            {"points_on_part", c.part_points},
            {"density_mean_per_mm2", c.density_mean_per_mm2},
            {"density_median_per_mm2", c.density_median_per_mm2},
            {"density_p5_per_mm2", c.density_p5_per_mm2},
            {"density_p95_per_mm2", c.density_p95_per_mm2}}}};
}

}  // namespace scanplan::cli
