#include <scanplan/pipeline/replay.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include <scanplan/collision/scene.h>
#include <scanplan/kinematics/shape.h>
#include <scanplan/scanner/coverage.h>

namespace scanplan::pipeline {

namespace {

using kinematics::TriangleMesh;

// `m` appended to `out` (same frame).
void append(TriangleMesh& out, const TriangleMesh& m) {
  const int base = static_cast<int>(out.vertices.size());
  out.vertices.insert(out.vertices.end(), m.vertices.begin(), m.vertices.end());
  for (const Eigen::Vector3i& t : m.triangles)
    out.triangles.push_back(t + Eigen::Vector3i::Constant(base));
}

// The shapes' surfaces merged into one mesh in their body frame.
TriangleMesh surfaces(const std::vector<kinematics::Shape>& shapes,
                      const kinematics::TessellationOptions& options) {
  TriangleMesh out;
  for (const kinematics::Shape& shape : shapes)
    append(out, kinematics::shapeSurface(shape, options));
  return out;
}

void addBodies(const kinematics::CellModel& cell,
               const TriangleMesh& part,
               const kinematics::TessellationOptions& tess,
               ReplayScene& scene) {
  const auto& robot = cell.robot.definition();
  for (int k = 0; k <= kinematics::kNumJoints; ++k) {
    const auto& link = robot.links[static_cast<std::size_t>(k)];
    const std::string fallback = k == 0 ? std::string("base") : "link" + std::to_string(k);
    scene.bodies.push_back(
        {link.name.empty() ? fallback : link.name, k, surfaces(link.shapes, tess), {}, {}});
  }
  scene.bodies.push_back(
      {"scanner", kReplayScannerFrame, surfaces(cell.scanner.body, tess), {}, {}});
  kinematics::Shape table;
  table.geometry = kinematics::Cylinder{cell.table.radius, cell.table.height};
  table.X_BG.translation() << 0.0, 0.0, -0.5 * cell.table.height;
  scene.bodies.push_back({"table", kReplayTableFrame, surfaces({table}, tess), {}, {}});
  TriangleMesh part_R = part;
  for (Eigen::Vector3d& v : part_R.vertices) v = cell.part.X_RP * v;
  scene.bodies.push_back({"part", kReplayTableFrame, std::move(part_R), {}, {}});
  for (const kinematics::Obstacle& o : cell.obstacles) {
    const int frame = o.carrier == kinematics::Carrier::kTable ? kReplayTableFrame : kReplayWorld;
    scene.bodies.push_back({o.name, frame, surfaces(o.shapes, tess), {}, {}});
  }
}

// The maps' stand-ins for the robot's mesh links (hulls or convex pieces), one body per link,
// each piece in a colour of its own.
void addStandIns(const collision::Scene& collision_scene, ReplayScene& scene) {
  static constexpr std::array<std::array<std::uint8_t, 3>, 6> kPieceColours = {
      {{0, 114, 178}, {0, 158, 115}, {204, 121, 167}, {86, 180, 233}, {230, 159, 0}, {213, 94, 0}}};
  for (const collision::MapHull& h : collision_scene.mapHulls()) {
    if (!h.used || h.standin.empty()) continue;
    const collision::BodyInfo& info = collision_scene.bodies()[static_cast<std::size_t>(h.body)];
    if (info.link < 0 || info.motion != collision::BodyMotion::kRobotLink) continue;
    ReplayBody body{info.name + " stand-in", info.link, {}, {}, {}, true};
    for (std::size_t k = 0; k < h.standin.size(); ++k) {
      append(body.mesh, h.standin[k]);
      body.colours.resize(body.mesh.triangles.size(), kPieceColours[k % kPieceColours.size()]);
    }
    scene.bodies.push_back(std::move(body));
  }
}

// The carriers' world poses at a trajectory sample.
ReplayFrame frameAt(const kinematics::CellModel& cell, const kinematics::TrajectorySample& s) {
  ReplayFrame f;
  f.t = s.t;
  f.scanning = s.scanning;
  const auto links = cell.robot.linkFrames(s.q);
  for (int k = 0; k <= kinematics::kNumJoints; ++k) {
    f.poses[static_cast<std::size_t>(k)] = cell.X_WB * links[static_cast<std::size_t>(k)];
  }
  f.poses[kReplayScannerFrame] = f.poses[kinematics::kNumJoints] * cell.scanner.X_FS;
  f.poses[kReplayTableFrame] = cell.table.X_WR(s.theta);
  return f;
}

// The part's triangles coloured as coverage.ply colours them, but uncovered ones a clear
// red-orange rather than grey (grey reads as "no data" on a grey part).
std::vector<std::array<std::uint8_t, 3>> coverageColours(const TriangleMesh& part,
                                                         const SimulationRun& run) {
  std::vector<std::array<std::uint8_t, 3>> out(part.triangles.size(), {220, 70, 40});
  const double top = run.coverage.density_p95_per_mm2;
  for (std::size_t t = 0; t < part.triangles.size() && t < run.coverage.hits.size(); ++t) {
    if (run.coverage.hits[t] == 0) continue;
    out[t] =
        scanner::densityColour(scanner::triangleDensityPerMm2(part, run.coverage, t), top, true);
  }
  return out;
}

// Per part triangle: the time of the first point on it (+inf: none).
std::vector<float> coveredTimes(const TriangleMesh& part, const SimulationRun& run) {
  std::vector<float> out(part.triangles.size(), std::numeric_limits<float>::infinity());
  for (const scanner::CloudPoint& p : run.cloud.points) {
    if (p.part_triangle < 0 || static_cast<std::size_t>(p.part_triangle) >= out.size()) continue;
    float& t = out[static_cast<std::size_t>(p.part_triangle)];
    t = std::min(t, static_cast<float>(p.t));
  }
  return out;
}

void addCloud(const SimulationRun& run, const ReplayOptions& options, ReplayScene& scene) {
  const auto& points = run.cloud.points;
  scene.cloud_total = points.size();
  const std::size_t max_points = std::max<std::size_t>(1, options.max_points);
  const std::size_t stride =
      std::max<std::size_t>(1, (points.size() + max_points - 1) / max_points);
  for (std::size_t i = 0; i < points.size(); i += stride) {
    scene.cloud.push_back(points[i].p_P.cast<float>());
    scene.cloud_t.push_back(static_cast<float>(points[i].t));
  }
}

}  // namespace

ReplayScene replayScene(const kinematics::CellModel& cell,
                        const TriangleMesh& part,
                        const ScanPlan& plan,
                        const ReplayOptions& options) {
  ReplayScene scene;
  kinematics::TessellationOptions tess;
  tess.chord_tolerance = options.chord_tolerance;
  tess.max_segments = 48;
  addBodies(cell, part, tess, scene);
  if (plan.prepared && plan.prepared->scene) addStandIns(*plan.prepared->scene, scene);
  scene.X_RP = cell.part.X_RP;
  const auto& samples = plan.trajectory->trajectory.samples;
  const std::size_t n = samples.size();
  const std::size_t frames = std::min(n, std::max<std::size_t>(2, options.max_frames));
  for (std::size_t i = 0; i < frames; ++i) {
    const std::size_t k = frames == 1 ? 0 : i * (n - 1) / (frames - 1);
    scene.frames.push_back(frameAt(cell, samples[k]));
  }
  const scanner::LaserWindow& w = plan.prepared->window;
  scene.fan = {Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, -w.y_near, w.z_min),
               Eigen::Vector3d(0.0, w.y_near, w.z_min), Eigen::Vector3d(0.0, w.y_far, w.z_max),
               Eigen::Vector3d(0.0, -w.y_far, w.z_max)};
  if (plan.simulation) {
    for (ReplayBody& body : scene.bodies) {
      if (body.name != "part") continue;
      body.colours = coverageColours(part, *plan.simulation);
      body.covered_t = coveredTimes(part, *plan.simulation);
      scene.density_top_per_mm2 = plan.simulation->coverage.density_p95_per_mm2;
    }
    addCloud(*plan.simulation, options, scene);
    if (plan.certificate) {
      const auto& samples_area = plan.simulation->sampling.samples;
      for (std::size_t i = 0; i < samples_area.size() && i < plan.certificate->classes.size();
           ++i) {
        const CoverageClass c = plan.certificate->classes[i];
        if (c == CoverageClass::kCovered) continue;
        scene.uncovered.push_back(samples_area[i].p.cast<float>());
        scene.uncovered_class.push_back(static_cast<std::uint8_t>(c));
      }
    }
  }
  if (plan.validation) {
    const auto& v = *plan.validation;
    const auto add = [&](const std::string& pair, double t, double d) {
      const auto dash = pair.find(" - ");
      if (dash == std::string::npos || !std::isfinite(d)) return;
      scene.closest.push_back({pair.substr(0, dash), pair.substr(dash + 3), t, d});
    };
    add(v.min_cell_distance_pair, v.min_cell_distance_t, v.min_cell_distance);
    add(v.min_distance_pair, v.min_distance_t, v.min_distance);
  }
  return scene;
}

}  // namespace scanplan::pipeline
