// The scan section of a job file: hand-written path elements and the automatic scan; their
// YAML keys (describe) and the path request in SI (pathRequest).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <regex>
#include <set>
#include <sstream>
#include <type_traits>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <scanplan/config/detail/job_sections.h>
#include <scanplan/config/robot_urdf.h>
#include <scanplan/config/text.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/placement.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/programs/programs.h>

namespace scanplan::config {
namespace {

inline const std::vector<std::string> kPathTypes = {"ring", "raster", "waypoints", "file"};

template <class A>
void describeWaypoint(A& a, WaypointSpec& s) {
  a.require("xyz_mm");
  a.field("xyz_mm", s.xyz_mm);
  a.field("rpy_deg", s.rpy_deg);
  a.field("speed_mm_s", s.speed_mm_s, Expect::positive());
  a.field("rotation_speed_deg_s", s.rotation_speed_deg_s, Expect::positive());
  a.field("scanning", s.scanning);
}

template <class A>
void describePathElement(A& a, PathElementSpec& s) {
  a.require("type");
  a.field("type", s.type, Expect::oneOf(kPathTypes));
  if (s.type == "ring") {
    a.require("height_mm");
    a.field("height_mm", s.height_mm);
    a.field("tilt_deg", s.tilt_deg, Expect::range(-80.0, 80.0));
    a.field("start_deg", s.start_deg);
    a.field("extent_deg", s.extent_deg, Expect::range(-3600.0, 3600.0));
    a.field("speed_deg_s", s.speed_deg_s, Expect::positive());
    if (A::kReading || s.distance_mm > 0.0)
      a.field("distance_mm", s.distance_mm, Expect::positive());
    if constexpr (A::kReading) {
      s.has_axis = a.has("axis_xy_mm");
      if (s.extent_deg == 0.0) a.fail("extent_deg", "0", "a non-zero angle");
    }
    if (s.has_axis) a.field("axis_xy_mm", s.axis_xy_mm);
  } else if (s.type == "raster") {
    a.field("view", s.view);
    a.field("pass_direction", s.pass_direction);
    a.field("overlap", s.overlap, Expect{0.0, 0.95, false, false, {}});
    a.field("lead_mm", s.lead_mm, Expect::nonNegative());
    a.field("speed_mm_s", s.speed_mm_s, Expect::positive());
    if constexpr (A::kReading) {
      if (Eigen::Vector3d(s.view.data()).norm() < 1e-9)
        a.fail("view", "[0, 0, 0]", "a non-zero direction");
    }
  } else if (s.type == "waypoints") {
    a.require("points");
    a.list("points", s.points, 2, 100000);
  } else {
    a.require("file");
    a.field("file", s.file);
  }
}

template <class A>
void describeAuto(A& a, AutoSpec& s) {
  a.field("max_incidence_deg", s.max_incidence_deg, Expect{1.0, 89.0, false, false, {}});
  a.field("point_spacing_mm", s.point_spacing_mm, Expect{0.0, 100.0, false, false, {}});
  if constexpr (A::kReading) {
    // Finer than any line scanner resolves: the passes, at spacing × frame rate, would crawl.
    constexpr double kFinest = 0.001;
    if (s.point_spacing_mm > 0.0 && s.point_spacing_mm < kFinest) {
      a.fail("point_spacing_mm", formatNumber(s.point_spacing_mm),
             fmt::format("0 (the line's point pitch at mid depth) or at least {} mm: the passes "
                         "scan at the spacing times the frame rate, and finer than a micrometre "
                         "no line scanner resolves",
                         kFinest));
    }
  }
  a.field("target_coverage", s.target_coverage, Expect{0.01, 1.0, false, false, {}});
  a.field("max_passes", s.max_passes, Expect::range(1, 1000));
  a.field("time_budget_s", s.time_budget_s, Expect{0.1, 86400.0, false, false, {}});
  a.field("max_program_s", s.max_program_s, Expect{0.0, 86400.0, false, false, {}});
  a.field("sample_spacing_mm", s.sample_spacing_mm, Expect{0.2, 100.0, false, false, {}});
}

template <class A>
void describeScan(A& a, ScanSpec& s) {
  a.field("dt_s", s.dt_s, Expect{0.001, 10.0, false, false, {}});
  a.field("transfer_speed_mm_s", s.transfer_speed_mm_s, Expect::positive());
  a.field("retreat_mm", s.retreat_mm, Expect::nonNegative());
  a.list("paths", s.paths, 0, 1000);
  // Present means enabled; a job without it writes none (jobToYaml reads back the same job).
  if constexpr (A::kReading) s.auto_scan.enabled = a.has("auto");
  if (s.auto_scan.enabled) a.section("auto", s.auto_scan);
}

}  // namespace

void describe(YamlIn& a, WaypointSpec& s) { describeWaypoint(a, s); }
void describe(YamlOut& a, WaypointSpec& s) { describeWaypoint(a, s); }
void describe(SchemaOut& a, WaypointSpec& s) { describeWaypoint(a, s); }
void describe(YamlIn& a, PathElementSpec& s) { describePathElement(a, s); }
void describe(YamlOut& a, PathElementSpec& s) { describePathElement(a, s); }
void describe(SchemaOut& a, PathElementSpec& s) { describePathElement(a, s); }
void describe(YamlIn& a, AutoSpec& s) { describeAuto(a, s); }
void describe(YamlOut& a, AutoSpec& s) { describeAuto(a, s); }
void describe(SchemaOut& a, AutoSpec& s) { describeAuto(a, s); }
void describe(YamlIn& a, ScanSpec& s) { describeScan(a, s); }
void describe(YamlOut& a, ScanSpec& s) { describeScan(a, s); }
void describe(SchemaOut& a, ScanSpec& s) { describeScan(a, s); }

template <>
std::vector<PathElementSpec> schemaVariants<PathElementSpec>() {
  std::vector<PathElementSpec> out;
  for (const std::string& type : kPathTypes) {
    PathElementSpec s;
    s.type = type;
    out.push_back(s);
  }
  return out;
}

scanner::PathRequest pathRequest(const JobSpec& job) {
  scanner::PathRequest request;
  request.dt = job.scan.dt_s;
  request.transfer_speed = mm(job.scan.transfer_speed_mm_s);
  request.retreat = mm(job.scan.retreat_mm);
  for (const PathElementSpec& e : job.scan.paths) {
    if (e.type == "ring") {
      scanner::RingSpec ring;
      ring.height = mm(e.height_mm);
      ring.tilt = deg(e.tilt_deg);
      ring.start = deg(e.start_deg);
      ring.extent = deg(e.extent_deg);
      ring.speed = deg(e.speed_deg_s);
      if (e.distance_mm > 0.0) ring.distance = mm(e.distance_mm);
      if (e.has_axis) ring.axis_xy = Eigen::Vector2d(e.axis_xy_mm[0], e.axis_xy_mm[1]) * kMmToM;
      request.elements.emplace_back(ring);
    } else if (e.type == "raster") {
      scanner::RasterSpec raster;
      raster.view = Eigen::Vector3d(e.view.data());
      raster.pass_direction = Eigen::Vector3d(e.pass_direction.data());
      raster.overlap = e.overlap;
      raster.lead = mm(e.lead_mm);
      raster.speed = mm(e.speed_mm_s);
      request.elements.emplace_back(raster);
    } else if (e.type == "waypoints") {
      scanner::WaypointSpec points;
      for (const WaypointSpec& w : e.points) {
        scanner::Waypoint p;
        p.X_PS = toIsometry({w.xyz_mm, w.rpy_deg});
        p.speed = mm(w.speed_mm_s);
        p.rotation_speed = deg(w.rotation_speed_deg_s);
        p.scanning = w.scanning;
        points.points.push_back(p);
      }
      request.elements.emplace_back(points);
    } else {
      std::ifstream in(e.file.resolved, std::ios::binary);
      std::ostringstream text;
      text << in.rdbuf();
      request.elements.emplace_back(scanner::parsePathCsv(text.str(), e.file.resolved.string()));
    }
  }
  return request;
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

}  // namespace scanplan::config
