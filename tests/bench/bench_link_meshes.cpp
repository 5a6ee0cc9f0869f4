// Mesh links at speed: the demo map with real link meshes against the same map with primitive
// links. Target: mesh links at most 3x the primitive links' map CPU time. Side by side from one
// run, process CPU time (2 threads) per cell, best of RUNS, the two maps in turn:
// - the Adept Viper s650's own link meshes (../shared/data/robots/viper_s650, 2 000 triangles a
//   link; skipped when absent) against the bundled robot file's primitive links:
//   - as simplified convex hulls (link_meshes: hull);
//   - both again with the self pairs the mesh robot never brings into contact left out (what
//     MoveIt's setup assistant disables by default; `scanplan robot check` lists them), so that
//     the two robots are compared on the same pairs;
//   - as convex pieces within PIECE_MARGIN_MM (link_meshes: pieces; 2 mm unless given);
// - the KUKA KR6 R700 sixx from its URDF: ROS-Industrial's collision meshes
//   (data/robots/urdf/kuka_kr6_r700_sixx_meshes, Apache-2.0) as convex pieces against the
//   primitive links of data/robots/urdf/kuka_kr6_r700_sixx.urdf;
// - each against its meshes measured exactly (link_meshes: exact), on every SUBSAMPLE-th time
//   sample: ~100x slower. On those cells the hull and piece maps must never exceed the exact map
//   (they are conservative); how much lower they are is printed.
// The pieces are fitted once and kept in $TMPDIR/scanplan_bench_pieces.
// Usage (from the repository root):
//   build/tests/bench/bench_link_meshes [JOB] [RUNS] [SUBSAMPLE] [PIECE_MARGIN_MM] [ROBOTS]
// ROBOTS: all (default), viper or kuka. (JOB: a job with hand-written scan.paths; the automatic
// demo's path comes from the coverage planner, which this bench does not run.)
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <tbb/global_control.h>

#include <scanplan/collision/scene.h>
#include <scanplan/collision/self_collision.h>
#include <scanplan/config/job.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/planner/config_map.h>
#include <scanplan/scanner/path_generators.h>
#include <scanplan/scanner/raycaster.h>
#include "tests/bench/bench_timing.h"

using namespace scanplan;
namespace fs = std::filesystem;

namespace {

const fs::path kSharedData = SCANPLAN_SHARED_DATA_DIR;

// The Viper robot file with its link meshes (mesh k in DH frame k; Rz(180°) for k = 3, 4, 5:
// SOURCES.md) in place of the primitive links.
fs::path writeMeshRobot(const fs::path& dir) {
  std::ifstream in("data/robots/viper_s650.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  text = text.substr(0, text.find("\nlinks:") + 1) + "links:\n";
  const char* names[] = {"base", "link1", "link2", "link3", "link4", "link5", "link6"};
  for (int k = 0; k <= 6; ++k) {
    const fs::path mesh = kSharedData / fmt::format("robots/viper_s650/link{}.stl", k);
    const bool turned = k >= 3 && k <= 5;
    text += fmt::format("  - {{name: {}, shapes: [{{type: mesh, file: {}, units: m{}}}]}}\n",
                        names[k], mesh.string(), turned ? ", pose: {rpy_deg: [0, 0, 180]}" : "");
  }
  const fs::path file = dir / "viper_s650_meshes.yaml";
  std::ofstream(file) << text;
  return file;
}

struct Cell {
  config::JobSpec job;
  kinematics::CellModel cell;
  kinematics::ScanPath path;
};

Cell loadCell(const std::string& job_file, const std::vector<std::string>& overrides) {
  config::JobSpec job = config::loadJob(job_file, overrides);
  kinematics::CellModel cell = config::buildCell(job);
  const kinematics::LoadedMesh part =
      kinematics::loadMesh(cell.part.mesh.path, cell.part.mesh.options);
  const scanner::Raycaster raycaster(part.mesh);
  kinematics::ScanPath path = scanner::generatePath(config::pathRequest(job), part.mesh, raycaster,
                                                    scanner::laserWindow(config::laserOptics(job)))
                                  .path;
  return {std::move(job), std::move(cell), std::move(path)};
}

kinematics::ScanPath subsampled(const kinematics::ScanPath& path, std::size_t every) {
  kinematics::ScanPath sub;
  sub.dt = path.dt * static_cast<double>(every);
  for (std::size_t i = 0; i < path.samples.size(); i += every)
    sub.samples.push_back(path.samples[i]);
  return sub;
}

// The self pairs that never touch in `samples` random configurations, as exclusion rules.
std::vector<collision::PairRule> neverPairs(const kinematics::RobotModel& robot,
                                            std::string& names) {
  std::vector<collision::PairRule> rules;
  for (const auto& p : collision::surveySelfCollisions(robot, 2000, 1).pairs) {
    if (p.adjacent || p.allowed || p.colliding > 0) continue;
    rules.push_back({p.a, p.b, collision::PairRule::Action::kExclude});
    names += fmt::format("{}{}-{}", names.empty() ? "" : ", ", p.a, p.b);
  }
  return rules;
}

struct Timed {
  planner::ConfigMap map;
  double cpu = std::numeric_limits<double>::infinity();  // s, best of the runs
};

// One map of `scene` over `path` with every branch, into t.map; its CPU time kept if the best.
void mapOnce(const collision::Scene& scene,
             const Cell& c,
             const kinematics::ScanPath& path,
             Timed& t) {
  planner::MapRequest request;
  request.angle_step = c.job.map.angle_step_deg * kDegToRad;
  for (int i = 0; i < 8; ++i) request.branches.push_back(kinematics::IkBranch::fromIndex(i));
  const planner::ConstraintSettings settings = config::constraintSettings(c.job);
  const double start = bench::processCpuSeconds();
  t.map = planner::buildConfigMap(scene, settings, path, request);
  t.cpu = std::min(t.cpu, bench::processCpuSeconds() - start);
}

// The primitive and the hull map in turn, round after round (a slow spell of the machine falls
// on both alike), best of `runs` each.
std::pair<Timed, Timed> timeMaps(const collision::Scene& primitive_scene,
                                 const Cell& primitive,
                                 const collision::Scene& hull_scene,
                                 const Cell& meshes,
                                 int runs) {
  std::pair<Timed, Timed> t;
  for (int r = 0; r < runs; ++r) {
    mapOnce(primitive_scene, primitive, primitive.path, t.first);
    mapOnce(hull_scene, meshes, meshes.path, t.second);
  }
  return t;
}

// CPU time a cell, and the share of branch-cells the map keeps feasible (f > 0).
std::string perCell(const Timed& t) {
  const double cells = static_cast<double>(t.map.cellsPerBranch());
  const auto feasible =
      std::count_if(t.map.f.begin(), t.map.f.end(), [](float f) { return f > 0.0f; });
  return fmt::format("{:6.2f} s = {:6.2f} us a cell, feasible {:4.1f}%", t.cpu, 1e6 * t.cpu / cells,
                     100.0 * static_cast<double>(feasible) / static_cast<double>(t.map.f.size()));
}

// Hull map against the exact map on the same cells: cells above (must be none), cells lower.
std::string conservative(const planner::ConfigMap& hull,
                         const planner::ConfigMap& exact,
                         bool& ok) {
  std::size_t above = 0, lower = 0, feasible_hull = 0, feasible_exact = 0;
  for (std::size_t i = 0; i < hull.f.size(); ++i) {
    above += hull.clearance[i] > exact.clearance[i] + 1e-6f ? 1u : 0u;
    lower += hull.clearance[i] < exact.clearance[i] - 1e-6f ? 1u : 0u;
    feasible_hull += hull.f[i] > 0.0f ? 1u : 0u;
    feasible_exact += exact.f[i] > 0.0f ? 1u : 0u;
  }
  ok = above == 0;
  const double n = static_cast<double>(hull.f.size());
  return fmt::format(
      "clearance above the exact map's in {} cells ({}), lower in {:.1f}%; feasible "
      "branch-cells {:.1f}% (exact {:.1f}%)",
      above, ok ? "conservative" : "NOT CONSERVATIVE", 100.0 * static_cast<double>(lower) / n,
      100.0 * static_cast<double>(feasible_hull) / n,
      100.0 * static_cast<double>(feasible_exact) / n);
}

// The primitive map's and a mesh map's CPU time a cell, and their ratio against the target.
void printRatio(const char* mesh_label, const Timed& prim, const Timed& mesh) {
  const double ratio = mesh.cpu / prim.cpu;
  std::printf("  primitive links              %s\n", perCell(prim).c_str());
  std::printf("  mesh links (%s)%*s%s   %.2fx primitive   target <= 3x: %s\n", mesh_label,
              static_cast<int>(16 - std::string(mesh_label).size()), "", perCell(mesh).c_str(),
              ratio, ratio <= 3.0 ? "met" : "MISSED");
}

// Convex pieces within `margin` (collision/link_standin.h) against the primitive links: the map's
// CPU time, and on every `every`-th sample against the meshes measured exactly (`exact_sub`:
// that map, measured before; computed here when null). The pieces are kept in a cache folder,
// so that a second run skips the fitting. Returns whether the piece map is conservative.
bool piecesSection(const std::string& robot,
                   const Cell& primitive,
                   const collision::Scene& prim_scene,
                   const Cell& meshes,
                   collision::ClearanceConfig config,
                   int runs,
                   std::size_t every,
                   double margin,
                   const Timed* exact_sub) {
  collision::ClearanceConfig piece_config = config;
  piece_config.link_meshes = collision::LinkMeshes::kPieces;
  piece_config.piece_margin = margin;
  piece_config.max_pieces = 256;
  piece_config.piece_cache = fs::temp_directory_path() / "scanplan_bench_pieces";
  const double start = bench::processCpuSeconds();
  const collision::Scene piece_scene(meshes.cell, piece_config);
  std::printf("%s: convex pieces within %.1f mm (cache %s), scene build CPU %.1f s:\n",
              robot.c_str(), toMm(margin), piece_config.piece_cache.c_str(),
              bench::processCpuSeconds() - start);
  for (const collision::MapHull& h : piece_scene.mapHulls()) {
    const char* name = piece_scene.bodies()[static_cast<std::size_t>(h.body)].name.c_str();
    if (h.cylinder) {
      std::printf(
          "  %-9s mesh %5zu triangles -> a cylinder about its joint axis, margin %4.2f mm\n", name,
          h.mesh_triangles, toMm(h.margin));
      continue;
    }
    std::printf(
        "  %-9s mesh %5zu triangles -> %3zu pieces, %4zu vertices, margin %4.2f mm%s, %s %.1f s\n",
        name, h.mesh_triangles, h.pieces, h.piece_vertices, toMm(h.margin),
        h.pieces_fit ? "" : " (over the limits)", h.from_cache ? "read" : "fitted", h.fit_seconds);
  }
  const auto [prim, pieces] = timeMaps(prim_scene, primitive, piece_scene, meshes, runs);
  std::printf("full map, %zu cells x 8 branches, CPU time:\n", prim.map.cellsPerBranch());
  printRatio("pieces", prim, pieces);
  const kinematics::ScanPath sub = subsampled(meshes.path, every);
  Timed exact_here, piece_sub;
  if (!exact_sub) {
    config.link_meshes = collision::LinkMeshes::kExact;
    const collision::Scene exact_scene(meshes.cell, config);
    mapOnce(exact_scene, meshes, sub, exact_here);
    exact_sub = &exact_here;
  }
  mapOnce(piece_scene, meshes, sub, piece_sub);
  std::printf("every %zu-th sample, %zu cells x 8 branches, CPU time:\n", every,
              piece_sub.map.cellsPerBranch());
  std::printf("  mesh links exactly           %s\n", perCell(*exact_sub).c_str());
  std::printf("  mesh links (pieces)          %s   %.1fx faster than exactly\n",
              perCell(piece_sub).c_str(), exact_sub->cpu / piece_sub.cpu);
  bool ok = false;
  std::printf("  piece map vs exact map: %s\n",
              conservative(piece_sub.map, exact_sub->map, ok).c_str());
  return ok;
}

// The Viper s650 with its own link meshes: as hulls, without the self pairs they never bring
// into contact, as convex pieces; against the meshes measured exactly. Returns whether the hull
// and the piece maps are conservative.
bool viperSection(const std::string& job_file, int runs, std::size_t every, double piece_margin) {
  const fs::path dir = fs::temp_directory_path() / fmt::format("bench_link_meshes_{}", getpid());
  fs::create_directories(dir);
  const Cell primitive = loadCell(job_file, {});
  const Cell meshes = loadCell(job_file, {"robot=" + writeMeshRobot(dir).string()});
  fs::remove_all(dir);

  collision::ClearanceConfig config = config::clearanceConfig(meshes.job);
  config.link_meshes = collision::LinkMeshes::kHull;  // every link as its hull
  double start = bench::processCpuSeconds();
  const collision::Scene prim_scene(primitive.cell, config::clearanceConfig(primitive.job));
  const double prim_load = bench::processCpuSeconds() - start;
  start = bench::processCpuSeconds();
  const collision::Scene hull_scene(meshes.cell, config);
  const double hull_load = bench::processCpuSeconds() - start;
  std::printf(
      "Adept Viper s650, %s, 2 threads, best of %d; scene build CPU: primitive %.3f s, "
      "mesh links with hulls %.3f s (qhull, simplification, margins)\n",
      job_file.c_str(), runs, prim_load, hull_load);
  for (const collision::MapHull& h : hull_scene.mapHulls()) {
    std::printf("  %-6s mesh %5zu triangles -> hull of %2zu vertices, margin %5.1f mm\n",
                hull_scene.bodies()[static_cast<std::size_t>(h.body)].name.c_str(),
                h.mesh_triangles, h.hull_vertices, toMm(h.margin));
  }

  const auto [prim, hull] = timeMaps(prim_scene, primitive, hull_scene, meshes, runs);
  std::printf("full map, %zu cells x 8 branches, CPU time:\n", prim.map.cellsPerBranch());
  printRatio("hulls", prim, hull);

  std::string never;
  const auto rules = neverPairs(meshes.cell.robot, never);
  collision::ClearanceConfig prim_config = config::clearanceConfig(primitive.job);
  prim_config.rules.insert(prim_config.rules.end(), rules.begin(), rules.end());
  collision::ClearanceConfig hull_config = config;
  hull_config.rules.insert(hull_config.rules.end(), rules.begin(), rules.end());
  const collision::Scene prim_same(primitive.cell, prim_config);
  const collision::Scene hull_same(meshes.cell, hull_config);
  const auto [prim2, hull2] = timeMaps(prim_same, primitive, hull_same, meshes, runs);
  std::printf("the same without the self pairs the meshes never bring into contact (%s):\n",
              never.c_str());
  printRatio("hulls", prim2, hull2);

  collision::ClearanceConfig exact_config = config;
  exact_config.link_meshes = collision::LinkMeshes::kExact;
  const collision::Scene exact_scene(meshes.cell, exact_config);
  const kinematics::ScanPath sub = subsampled(meshes.path, every);
  Timed hull_sub, exact_sub;
  mapOnce(hull_scene, meshes, sub, hull_sub);
  mapOnce(exact_scene, meshes, sub, exact_sub);
  std::printf("every %zu-th sample, %zu cells x 8 branches, CPU time:\n", every,
              hull_sub.map.cellsPerBranch());
  std::printf("  mesh links (hulls)           %s\n", perCell(hull_sub).c_str());
  std::printf("  mesh links exactly (before)  %s   %.1fx the hulls\n", perCell(exact_sub).c_str(),
              exact_sub.cpu / hull_sub.cpu);
  bool ok = false;
  std::printf("  hull map vs exact map: %s\n",
              conservative(hull_sub.map, exact_sub.map, ok).c_str());
  const bool ok_pieces = piecesSection("Adept Viper s650", primitive, prim_scene, meshes, config,
                                       runs, every, piece_margin, &exact_sub);
  return ok && ok_pieces;
}

// The KUKA KR6 R700 sixx from its URDF: primitive links (written from the datasheet) against
// ROS-Industrial's collision meshes as convex pieces (both bundled in data/robots/urdf).
bool kukaSection(const std::string& job_file, int runs, std::size_t every, double piece_margin) {
  const fs::path urdf = fs::absolute("data/robots/urdf");
  const Cell primitive =
      loadCell(job_file, {"robot=" + (urdf / "kuka_kr6_r700_sixx.urdf").string()});
  const Cell meshes =
      loadCell(job_file, {"robot=" + (urdf / "kuka_kr6_r700_sixx_meshes.urdf").string()});
  const collision::Scene prim_scene(primitive.cell, config::clearanceConfig(primitive.job));
  std::printf("\nKUKA KR6 R700 sixx, %s, 2 threads, best of %d\n", job_file.c_str(), runs);
  return piecesSection("KUKA KR6 R700 sixx", primitive, prim_scene, meshes,
                       config::clearanceConfig(meshes.job), runs, every, piece_margin, nullptr);
}

int run(int argc, char** argv) {
  const std::string job_file = argc > 1 ? argv[1] : "data/jobs/demo_rings.yaml";
  const int runs = argc > 2 ? std::max(1, std::atoi(argv[2])) : 2;
  const auto every = static_cast<std::size_t>(argc > 3 ? std::max(1, std::atoi(argv[3])) : 25);
  const double piece_margin = argc > 4 ? mm(std::atof(argv[4])) : 0.002;
  const std::string robots = argc > 5 ? argv[5] : "all";
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
  bool ok = true;
  if (robots == "kuka") {
    std::printf("bench_link_meshes: the Viper part left out (ROBOTS kuka)\n");
  } else if (fs::exists(kSharedData / "robots/viper_s650/link0.stl")) {
    ok = viperSection(job_file, runs, every, piece_margin) && ok;
  } else {
    std::printf("bench_link_meshes: the Viper part skipped: its link meshes (%s) are absent\n",
                (kSharedData / "robots/viper_s650").c_str());
  }
  if (robots != "viper") ok = kukaSection(job_file, runs, every, piece_margin) && ok;
  return ok ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {  // a job without scan.paths (scan.auto), a missing file
    std::fprintf(stderr, "bench_link_meshes: %s\n", e.what());
    return 2;
  }
}
