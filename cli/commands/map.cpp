#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <numbers>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <scanplan/collision/scene.h>
#include <scanplan/config/text.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/planner/config_map.h>
#include <scanplan/scanner/path_generators.h>
#include <scanplan/scanner/raycaster.h>
#include "cli/commands/commands.h"
#include "cli/io/json.h"
#include "cli/io/output.h"
#include "cli/plot/image_io.h"
#include "cli/plot/map_figures.h"
#include "cli/report/plan_summary.h"

namespace scanplan::cli {

// A progress line on stderr, only on a terminal (scripts and CI logs stay clean).
Progress::Progress(std::string label)
    : label_(std::move(label)), enabled_(isatty(STDERR_FILENO) != 0) {}

void Progress::operator()(std::size_t done, std::size_t total) {
  if (!enabled_) return;
  const std::lock_guard<std::mutex> lock(mutex_);
  const int percent = static_cast<int>(100 * done / std::max<std::size_t>(total, 1));
  if (percent == last_ && done != total) return;
  last_ = percent;
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::string eta;
  if (elapsed > 3.0 && done > 0 && done < total) {
    const double left = elapsed * static_cast<double>(total - done) / static_cast<double>(done);
    eta = left < 90.0 ? fmt::format(", {:.0f} s left  ", left)
                      : fmt::format(", {:.0f} min left  ", left / 60.0);
  }
  std::fprintf(stderr, "\r%s %3d%% (%zu / %zu)%s%s", label_.c_str(), percent, done, total,
               eta.c_str(), done == total ? "\n" : "");
  std::fflush(stderr);
}

void warnSlowLinkMeshes(const config::JobSpec& job, const kinematics::CellModel& cell) {
  const auto& clearance = job.constraints.clearance;
  if (clearance.link_meshes == "hull") return;
  bool meshes = false;
  for (const kinematics::Link& link : cell.robot.definition().links) {
    for (const kinematics::Shape& shape : link.shapes) {
      meshes = meshes || std::holds_alternative<kinematics::MeshFile>(shape.geometry);
    }
  }
  if (!meshes) return;
  const collision::Scene scene(cell, config::clearanceConfig(job));
  std::size_t total = 0;
  std::string each;
  for (std::size_t i = 0; i < scene.bodies().size(); ++i) {
    const collision::BodyInfo& body = scene.bodies()[i];
    if (body.motion != collision::BodyMotion::kRobotLink || body.triangles == 0) continue;
    const auto& hulls = scene.mapHulls();
    const auto hull = std::find_if(hulls.begin(), hulls.end(), [i](const collision::MapHull& h) {
      return h.body == static_cast<int>(i);
    });
    if (hull != hulls.end() && hull->used) continue;
    total += body.triangles;
    each += fmt::format("{}{} {}", each.empty() ? "" : ", ", body.name, body.triangles);
    if (hull != hulls.end()) {
      each += hull->pieces > 0
                  ? fmt::format(" ({} pieces {:.1f} mm out)", hull->pieces, toMm(hull->margin))
                  : fmt::format(" (hull {:.1f} mm out)", toMm(hull->hull_margin));
    }
  }
  if (total <= kHeavyLinkTriangles) return;
  spdlog::warn(
      "{}: the maps measure {} link mesh triangles exactly ({}; constraints.clearance."
      "link_meshes: {}, piece_margin_mm: {}, max_pieces: {}): a map may take minutes (the demo's "
      "with the Viper's own link meshes: 105 s against 0.5 s with its primitive links); a larger "
      "piece_margin_mm or max_pieces lets convex pieces stand in, and link_meshes: hull measures "
      "the convex hulls in seconds; both see a link up to their margin closer than it is",
      job.source.string(), total, each, clearance.link_meshes,
      config::formatNumber(clearance.piece_margin_mm), clearance.max_pieces);
}

namespace {

void requireScanPath(const config::JobSpec& job) {
  if (job.scan.paths.empty() && !job.scan.auto_scan.enabled) {
    throw InputError(job.source.string() +
                     ": scan.paths: empty: expected at least one path element (ring, raster, "
                     "waypoints or file) or scan.auto");
  }
}

// The pipeline's progress as terminal lines, one per stage ("auto", "map").
pipeline::ProgressFn stageProgress(Progress& passes, Progress& map) {
  return [&](std::string_view stage, std::size_t d, std::size_t n) {
    (stage == "auto" ? passes : map)(d, n);
  };
}

}  // namespace

PathContext buildPath(const config::JobSpec& job, const kinematics::CellModel& cell) {
  requireScanPath(job);
  PathContext context;
  context.part = config::loadPart(job, cell);
  try {
    // The pipeline's path stage: the automatic passes depend on the whole cell (reach).
    const pipeline::ScanProblem problem = config::toProblem(job, cell, context.part.mesh);
    const collision::Scene scene(problem.cell, problem.clearance);
    Progress passes("auto"), map("map");
    pipeline::ScanPathResult path = pipeline::scanPath(problem, scene, stageProgress(passes, map));
    context.window = path.window;
    context.generated = std::move(path.path);
    context.auto_scan = std::move(path.auto_scan);
  } catch (const InputError& e) {
    throw InputError(job.source.string() + ": " + e.what());
  }
  return context;
}

scanner::GeneratedPath generateScanPath(const config::JobSpec& job,
                                        const kinematics::CellModel& cell) {
  return buildPath(job, cell).generated;
}

ExitCode runPath(const PlanArguments& options) {
  const config::JobSpec job = config::loadJob(options.job_file, options.overrides);
  checkOutputApartFromInputs(options.out_dir, config::jobInputFiles(job));
  const kinematics::CellModel cell = config::buildCell(job);
  OutputStage stage(options.out_dir, {"path.csv", "path.png"});
  const PathContext context = buildPath(job, cell);
  writePathOutputs(stage.dir(), cell, context.part.mesh, context.generated.path);
  stage.commit();
  std::string text = pathSummary(context.window, context.generated);
  if (context.auto_scan) text += autoScanSummary(*context.auto_scan);
  text += fmt::format(
      "wrote      {} (path.csv, path.png: iso, top and front views; green start, orange end)\n",
      options.out_dir.string());
  std::fputs(text.c_str(), stdout);
  return ExitCode::kOk;
}

MapRun computeMap(const config::JobSpec& job,
                  const collision::Scene& scene,
                  const kinematics::ScanPath& path) {
  const planner::MapRequest request = pipeline::mapRequest(config::mapSettings(job));
  Progress progress("map");
  const auto start = std::chrono::steady_clock::now();
  MapRun run;
  try {
    run.map =
        planner::buildConfigMap(scene, config::constraintSettings(job), path, request,
                                [&progress](std::size_t d, std::size_t t) { progress(d, t); });
  } catch (const InputError& e) {  // the map's size, over map.memory_limit_mb
    throw InputError(job.source.string() + ": " + e.what());
  }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return run;
}

void writePathOutputs(const std::filesystem::path& dir,
                      const kinematics::CellModel& cell,
                      const kinematics::TriangleMesh& part,
                      const kinematics::ScanPath& path,
                      const WriteSettings& settings) {
  writeFileAtomically(dir / "path.csv", scanner::pathToCsv(path));
  writePng(dir / "path.png", pathPicture(part, path, TableTop{cell.table.radius, cell.part.X_RP}),
           settings.views);
}

const char* const kMapFilesNote =
    "path.csv, path.png, configmap.npy (+ _joint, _singularity, _clearance, _limit), "
    "configmap.json, configmap.png/.svg, configmap_why.png/.svg, configmap_cylinder.png";

std::string buildAndWriteMaps(const config::JobSpec& job,
                              const kinematics::CellModel& cell,
                              const std::filesystem::path& out) {
  requireScanPath(job);
  OutputStage stage(out, {"path.csv", "path.png", "configmap*"});
  const kinematics::LoadedMesh part = config::loadPart(job, cell);
  warnSlowLinkMeshes(job, cell);
  std::shared_ptr<const pipeline::PreparedScan> prepared;
  try {
    // The pipeline's path and map stages, as `plan` runs them.
    Progress passes("auto"), map("map");
    prepared =
        pipeline::prepareScan(config::toProblem(job, cell, part.mesh), stageProgress(passes, map));
  } catch (const InputError& e) {
    throw InputError(job.source.string() + ": " + e.what());
  }
  writePathOutputs(stage.dir(), cell, part.mesh, prepared->path.path);
  writeMapOutputs(stage.dir(), job, prepared->map);
  stage.commit();
  return pathSummary(prepared->window, prepared->path) +
         (prepared->auto_scan ? autoScanSummary(*prepared->auto_scan) : std::string()) +
         linkMeshSummary(*prepared->scene) + mapSummary(prepared->map, prepared->map_seconds) +
         fmt::format("wrote      {}: {}\n", out.string(), kMapFilesNote);
}

ExitCode runMap(const PlanArguments& options) {
  const config::JobSpec job = config::loadJob(options.job_file, options.overrides);
  checkOutputApartFromInputs(options.out_dir, config::jobInputFiles(job));
  const kinematics::CellModel cell = config::buildCell(job);
  std::fputs(buildAndWriteMaps(job, cell, options.out_dir).c_str(), stdout);
  return ExitCode::kOk;
}

std::size_t bestBranch(const planner::ConfigMap& map) {
  std::size_t best = 0;
  double best_score = -1.0;
  const std::size_t cells = map.cellsPerBranch();
  for (std::size_t b = 0; b < map.branches.size(); ++b) {
    double feasible = 0.0;
    for (std::size_t i = b * cells; i < (b + 1) * cells; ++i)
      feasible += map.f[i] > 0.0f ? 1.0 : 0.0;
    if (feasible > best_score) {
      best_score = feasible;
      best = b;
    }
  }
  return best;
}

namespace {

// configmap.json: what the layers are, their axes and the branch the images show.
Json mapJson(const config::JobSpec& job,
             const planner::ConfigMap& map,
             const std::vector<std::size_t>& shape,
             std::size_t shown) {
  Json json;
  json["format"] = "scanplan configuration map 1";
  json["job"] = job.name;
  json["job_hash"] = config::jobHash(job);
  json["shape"] = shape;
  json["axes"] = {"branch", "angle_deg", "time_s"};
  Json branches = Json::array();
  for (const auto& b : map.branches) branches.push_back(b.words());
  json["branch"] = std::move(branches);
  std::vector<double> angles;
  for (double a : map.angles) angles.push_back(toDeg(a));
  json["angle_deg"] = angles;
  json["time_s"] = map.times;
  json["layers"] = {{"f", "configmap.npy"},
                    {"joint", "configmap_joint.npy"},
                    {"singularity", "configmap_singularity.npy"},
                    {"clearance", "configmap_clearance.npy"},
                    {"limit", "configmap_limit.npy"}};
  Json codes = Json::object();
  for (int k = 0; k < planner::kLimitCount; ++k)
    codes[std::to_string(k)] = planner::limitName(static_cast<planner::Limit>(k));
  json["limit_codes"] = std::move(codes);
  json["images_branch"] = map.branches[shown].words();
  return json;
}

}  // namespace

void writeMapOutputs(const std::filesystem::path& dir,
                     const config::JobSpec& job,
                     const planner::ConfigMap& map,
                     const WriteSettings& settings) {
  const std::vector<std::size_t> shape{map.branches.size(), map.angles.size(), map.times.size()};
  const bool stream = settings.stream_binary;
  writeNpy(dir / "configmap.npy", map.f, shape, stream);
  writeNpy(dir / "configmap_joint.npy", map.joint, shape, stream);
  writeNpy(dir / "configmap_singularity.npy", map.singularity, shape, stream);
  writeNpy(dir / "configmap_clearance.npy", map.clearance, shape, stream);
  writeNpy(dir / "configmap_limit.npy", map.limit, shape, stream);

  const std::size_t shown = bestBranch(map);
  writeFileAtomically(dir / "configmap.json", jsonDocument(mapJson(job, map, shape, shown)));

  writeMapFigures(dir, map, shown, settings);
}

}  // namespace scanplan::cli
