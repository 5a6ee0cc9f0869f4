#include "cli/report/verify_report.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include <fmt/format.h>

#include <scanplan/kinematics/units.h>

namespace scanplan::cli {

std::string validationSummary(const planner::ValidationReport& r, std::size_t max_lines) {
  std::string s =
      fmt::format("validation {}: {} poses, {} clearance evaluations in {:.2f} s; ",
                  r.valid ? "valid" : fmt::format("INVALID, {} violation(s)", r.violations.size()),
                  r.samples, r.poses_checked, r.seconds);
  // What limits the scan (the cell's bodies) first, the robot's own pairs apart.
  const auto closest = [](const char* what, double d, const std::string& pair, double t) {
    return std::isfinite(d)
               ? fmt::format("{} {:.1f} mm ({} at t = {:.2f} s); ", what, toMm(d), pair, t)
               : fmt::format("{}: every pair beyond its d_high; ", what);
  };
  s += closest("min distance to the cell", r.min_cell_distance, r.min_cell_distance_pair,
               r.min_cell_distance_t);
  s += closest("within the robot", r.min_self_distance, r.min_self_distance_pair,
               r.min_self_distance_t);
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
  if (kind == Kind::kSensor) return "";
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
  if (v.kind == planner::Violation::Kind::kSensor) json["note"] = v.note;
  return json;
}

// A closest approach: its distance (mm), pair and time; all three null when no pair came within
// its d_high (nothing was measured closer: there is no "where").
void closest(
    Json& json, const std::string& key, double distance, const std::string& pair, double t) {
  const bool measured = std::isfinite(distance);
  json[key + "_mm"] = measured ? Json(toMm(distance)) : Json(nullptr);
  json[key + "_pair"] = measured ? Json(pair) : Json(nullptr);
  json[key + "_time_s"] = measured ? Json(t) : Json(nullptr);
}

}  // namespace

Json validationJson(const planner::ValidationReport& r) {
  Json violations = Json::array();
  for (const planner::Violation& v : r.violations) violations.push_back(violationJson(v));
  Json json = {{"valid", r.valid},
               {"poses", r.samples},
               {"clearance_evaluations", r.poses_checked},
               {"seconds", r.seconds}};
  closest(json, "min_distance", r.min_distance, r.min_distance_pair, r.min_distance_t);
  closest(json, "min_cell_distance", r.min_cell_distance, r.min_cell_distance_pair,
          r.min_cell_distance_t);
  closest(json, "min_self_distance", r.min_self_distance, r.min_self_distance_pair,
          r.min_self_distance_t);
  json["proven_clearance_mm"] = toMm(r.proven_clearance);
  json["violations"] = std::move(violations);
  return json;
}

std::string simulationSummary(const pipeline::SimulationRun& run) {
  const scanner::SimulationStats& s = run.cloud.stats;
  std::string text =
      s.pixel_rays > 0
          ? fmt::format(
                "simulation {} profiles (camera images), {} pixel + {} laser rays in {:.1f} s: "
                "{} lit pixels, {} points ({:.1f} per profile)\n",
                s.profiles, s.pixel_rays, s.occlusion_rays, run.seconds, s.lit_pixels, s.points,
                static_cast<double>(s.points) /
                    static_cast<double>(std::max<std::size_t>(1, s.profiles)))
          : fmt::format(
                "simulation {} profiles, {} laser + {} occlusion rays in {:.1f} s: {} points ({} "
                "outside the window, {} hidden from the camera)\n",
                s.profiles, s.laser_rays, s.occlusion_rays, run.seconds, s.points, s.outside_window,
                s.occluded);
  text += fmt::format(
      "coverage   {:.1f}% of the part's area within {:.2f} mm of a point ({} area samples); "
      "{:.1f}% faces or lies on the table\n",
      100.0 * run.area.covered_fraction, toMm(run.point_spacing), run.area_samples,
      100.0 * run.faces_table_fraction);
  text += fmt::format(
      "triangles  {:.1f}% of the area on triangles with a point ({} of {} triangles); density "
      "{:.2f} points/mm² (median {:.2f}, 5% {:.2f}, 95% {:.2f})\n",
      100.0 * run.coverage.covered_fraction, run.coverage.covered_triangles,
      run.coverage.hits.size(), run.coverage.density_mean_per_mm2,
      run.coverage.density_median_per_mm2, run.coverage.density_p5_per_mm2,
      run.coverage.density_p95_per_mm2);
  return text;
}

std::string certificateSummary(const pipeline::Certificate& c, bool suggest_setups) {
  std::string text = fmt::format(
      "certificate {:.1f}% of the area scannable, {:.1f}% of that covered; not scannable: {:.1f}% "
      "faces the table, {:.1f}% occluded, {:.1f}% no standoff fits the housing, {:.1f}% out of "
      "the arm's reach\n",
      100.0 * c.scannable_fraction, 100.0 * c.covered_of_scannable, 100.0 * c.fraction[2],
      100.0 * c.fraction[3], 100.0 * c.fraction[4], 100.0 * c.fraction[5]);
  if (!suggest_setups) return text;
  if (c.fraction[5] >= 0.01) {
    text += fmt::format(
        "note       {:.1f}% of the area is seen only by passes out of the arm's reach: the table "
        "closer to the robot, another part.pose or plan --setups 2 may reach it\n",
        100.0 * c.fraction[5]);
  }
  if (c.fraction[2] >= 0.05) {
    text += fmt::format(
        "note       {:.1f}% of the area faces the table: plan --setups 2 turns the part over for "
        "it\n",
        100.0 * c.fraction[2]);
  }
  return text;
}

Json certificateJson(const pipeline::SimulationRun& run, const pipeline::Certificate& c) {
  Json by_reason = Json::object();
  for (std::size_t k = 0; k < pipeline::kCoverageClasses; ++k)
    by_reason[pipeline::coverageClassName(static_cast<pipeline::CoverageClass>(k))] = c.fraction[k];
  return {{"area_fraction", run.area.covered_fraction},
          {"point_spacing_mm", toMm(run.point_spacing)},
          {"area_samples", run.area_samples},
          {"scannable_fraction", c.scannable_fraction},
          {"covered_of_scannable", c.covered_of_scannable},
          {"by_reason", by_reason}};
}

Json simulationJson(const pipeline::SimulationRun& run) {
  const scanner::SimulationStats& s = run.cloud.stats;
  const scanner::PartCoverage& c = run.coverage;
  return {{"profiles", s.profiles},
          {"laser_rays", s.laser_rays},
          {"occlusion_rays", s.occlusion_rays},
          {"points", s.points},
          {"outside_window", s.outside_window},
          {"occluded", s.occluded},
          {"pixel_rays", s.pixel_rays},
          {"lit_pixels", s.lit_pixels},
          {"seconds", run.seconds},
          {"coverage",
           {{"area_fraction", run.area.covered_fraction},
            {"point_spacing_mm", toMm(run.point_spacing)},
            {"area_samples", run.area_samples},
            {"faces_table_fraction", run.faces_table_fraction},
            {"covered_fraction", c.covered_fraction},
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
