// The automatic scan (scan.auto) on the demo cell, part by part: the program's time (scanning
// and moving between passes), the passes, the single-coverage bound and the program's ratio to
// it, the share of the scannable area the simulated cloud covers, planning time and validity;
// beside each part the program as recorded before passes were timed by what they see and joined
// by point-to-point moves (tests/bench/README.md). Then the demo job on the KUKA KR6 R900 beside
// the Viper (a faster arm, a shorter program), and with --threads the demo's stages on 1 thread
// against 2.
// Parts: the demo housing, every mesh under ../shared/data/meshes (scaled to 150 mm, placed on
// the table; skipped when absent) and synthetic parts with known hard spots written here (thin
// walls, a deep pocket, a through hole).
// Usage (from the repository root):
//   build/tests/bench/bench_autoscan [--quick] [--threads] [PART_NAME_FILTER]
// --quick: 1 mm point spacing (a faster plan for a smoke run); otherwise the demo job's 0.5 mm.
// The single-coverage bound: the covered area swept once at the requested spacing, covered area
// / (line width at mid depth x point spacing x frame rate).
// Coverage is measured by the simulation and recomputed independently here from the points
// (another area sampling, its own nearest-point search); "delta" is the difference. "meas%" is
// the coverage the automatic scan measured on its passes before any motion was planned
// (AutoScanReport::measured_fraction), beside the cloud's "of_scan%".
// Timing: cpu_s is the process's CPU time (both threads) of the whole pipeline for the part;
// plan_s is the pipeline's own wall time of path, maps, plan and trajectory.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include <scanplan/config/job.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/pipeline/auto_scan.h>
#include <scanplan/pipeline/plan_scan.h>
#include <scanplan/scanner/area_coverage.h>
#include "tests/bench/bench_timing.h"
#include "tests/part_support.h"

using namespace scanplan;
namespace fs = std::filesystem;

namespace {

struct Part {
  std::string name;
  fs::path mesh;
  double scale = 1.0;  // after mm
  std::string note;
};

std::vector<Part> parts(const fs::path& scratch) {
  std::vector<Part> out{{"demo_housing", "data/parts/demo_housing.stl", 1.0, "the demo"}};
  using namespace scanplan::test;
  writeStl(scratch / "deep_pocket.stl", blockWithHole(100, 100, 80, 16, 60));
  writeStl(scratch / "through_hole.stl", blockWithHole(100, 80, 60, 30, 60));
  writeStl(scratch / "thin_walls.stl", thinWalls());
  out.push_back({"deep_pocket", scratch / "deep_pocket.stl", 1.0, "16 mm pocket 60 mm deep"});
  out.push_back({"through_hole", scratch / "through_hole.stl", 1.0, "30 mm square through hole"});
  out.push_back({"thin_walls", scratch / "thin_walls.stl", 1.0, "2 mm fins 12 mm apart"});
  writeStl(scratch / "cavities.stl", blockWithCavities(100, 100, 60, 3, 14, 20));
  out.push_back({"cavities", scratch / "cavities.stl", 1.0, "3 x 3 pockets 14 mm, 20 deep"});
  const fs::path shared = fs::path(SCANPLAN_SHARED_DATA_DIR) / "meshes";
  if (!fs::is_directory(shared)) return out;
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(shared))
    if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  for (const fs::path& f : files) {
    // Scaled so the largest side is 150 mm (the demo table is 400 mm across).
    const auto mesh = kinematics::loadMesh(f).mesh;
    const double size = mesh.bounds().sizes().maxCoeff();
    out.push_back({f.stem().string(), f, 0.15 / size, "shared, scaled to 150 mm"});
  }
  return out;
}

// The area within the point spacing of a point, from the cloud alone (another sampling).
double independentCoverage(const pipeline::ScanProblem& problem,
                           const pipeline::SimulationRun& sim) {
  const auto sampling = scanner::sampleArea(problem.part, 2.0 * sim.point_spacing, 150'000, 424242);
  std::vector<Eigen::Vector3d> points;
  const double limit = problem.simulation->max_incidence;
  for (const auto& p : sim.cloud.points)
    if (p.part_triangle >= 0 && p.incidence <= limit) points.push_back(p.p_P);
  return scanner::areaCoverage(sampling, points, sim.point_spacing).covered_fraction;
}

// The program as recorded on 2026-11-25 (tests/bench/README.md), before passes were timed by
// what they see and joined by point-to-point moves: program s at the demo's 0.5 mm.
const std::map<std::string, double> kRecordedProgram{
    {"demo_housing", 1274},       {"deep_pocket", 134},
    {"through_hole", 184},        {"thin_walls", 253},
    {"bunny_npm_3674", 406},      {"cgal_couplingdown", 563},
    {"cgal_fandisk", 148},        {"openscad_example006", 803},
    {"stlmodels_bunny.bin", 489}, {"stlmodels_gearwheel.bin", 393}};

struct Row {
  std::string name, note;
  double area_m2 = 0, scannable = 0, covered = 0, of_scannable = 0, delta = 0, measured = 0;
  std::size_t passes = 0, dropped = 0;
  double program_s = 0, scanning_s = 0, moving_s = 0, bound_s = 0;
  double planning_s = 0, cpu_s = 0;
  pipeline::StageTimes stages;
  bool valid = false;
  std::string status;
  double ratio() const { return bound_s > 0 ? program_s / bound_s : 0.0; }
};

// The time to sweep the covered area once: area / (line width at mid depth · spacing · rate).
double singleCoverageBound(const pipeline::ScanProblem& problem, double covered_area) {
  const scanner::LaserWindow w = scanner::laserWindow(problem.optics);
  const double width = 2.0 * w.halfWidth(0.5 * (w.z_min + w.z_max));
  const double spacing = pipeline::autoPointSpacing(*problem.auto_scan, problem.optics,
                                                    problem.simulation->scanner.rays_per_profile);
  return covered_area / (width * spacing * problem.simulation->frame_rate_hz);
}

void fill(Row& r, const pipeline::ScanProblem& problem, const pipeline::ScanPlan& plan) {
  r.status = std::string(pipeline::scanStatusName(plan.status));
  r.stages = plan.times;
  r.planning_s = plan.times.path + plan.times.map + plan.times.plan + plan.times.trajectory;
  if (plan.prepared->auto_scan) {
    r.passes = plan.order.empty() ? 0 : plan.order.size();
    r.measured = plan.prepared->auto_scan->measured_fraction;
  }
  r.dropped = plan.dropped.size();
  if (plan.trajectory) {
    r.program_s = plan.program.total;
    r.scanning_s = plan.program.scanning;
    r.moving_s = plan.program.moving;
  }
  if (plan.validation) r.valid = plan.validation->valid;
  if (plan.simulation) {
    r.covered = plan.simulation->area.covered_fraction;
    r.delta = independentCoverage(problem, *plan.simulation) - r.covered;
    if (problem.auto_scan) r.bound_s = singleCoverageBound(problem, r.covered * r.area_m2);
  }
  if (plan.certificate) {
    r.scannable = plan.certificate->scannable_fraction;
    r.of_scannable = plan.certificate->covered_of_scannable;
  }
}

Row run(const fs::path& job, const Part& part, const std::vector<std::string>& extra) {
  std::vector<std::string> overrides{"part.mesh=" + fs::absolute(part.mesh).string(),
                                     "part.units=mm", "part.scale=" + std::to_string(part.scale),
                                     "part.place=table"};
  overrides.insert(overrides.end(), extra.begin(), extra.end());
  const double cpu = bench::processCpuSeconds();
  Row r;
  r.name = part.name;
  r.note = part.note;
  try {
    const pipeline::ScanProblem problem = config::toProblem(config::loadJob(job, overrides));
    r.area_m2 = problem.part.area();
    const pipeline::ScanPlan plan = pipeline::planScan(problem);
    r.cpu_s = bench::processCpuSeconds() - cpu;
    fill(r, problem, plan);
  } catch (const std::exception& e) {
    r.status = std::string("error: ") + e.what();
  }
  return r;
}

void printHeader() {
  std::printf("%-24s %8s %8s %8s %6s %7s %6s %8s %7s %8s %7s %7s %7s %5s %s\n", "part", "prog_s",
              "scan_s", "move_s", "passes", "bound_s", "ratio", "of_scan%", "meas%", "delta",
              "plan_s", "cpu_s", "old_s", "valid", "note");
}

void print(const Row& r) {
  const auto old = kRecordedProgram.find(r.name);
  std::printf(
      "%-24s %8.1f %8.1f %8.1f %6zu %7.1f %6.2f %8.2f %7.2f %+8.2f %7.1f %7.1f %7s %5s %s\n",
      r.name.c_str(), r.program_s, r.scanning_s, r.moving_s, r.passes, r.bound_s, r.ratio(),
      100 * r.of_scannable, 100 * r.measured, 100 * r.delta, r.planning_s, r.cpu_s,
      old == kRecordedProgram.end() ? "-" : std::to_string(std::lround(old->second)).c_str(),
      r.valid ? "yes" : "NO",
      r.status == "planned"
          ? (r.dropped ? (r.note + ", " + std::to_string(r.dropped) + " dropped").c_str()
                       : r.note.c_str())
          : r.status.c_str());
  std::fflush(stdout);
}

// The stages' fastest of `runs` runs (wall s each), alternating with the other thread count's
// runs so that a busy spell of the machine weighs on both.
pipeline::StageTimes fastest(const pipeline::StageTimes& a, const pipeline::StageTimes& b) {
  pipeline::StageTimes m = a;
  m.path = std::min(a.path, b.path);
  m.map = std::min(a.map, b.map);
  m.plan = std::min(a.plan, b.plan);
  m.trajectory = std::min(a.trajectory, b.trajectory);
  m.validation = std::min(a.validation, b.validation);
  m.simulation = std::min(a.simulation, b.simulation);
  m.total = std::min(a.total, b.total);
  return m;
}

// The demo's stages on 1 thread and on 2, wall time each (best of 3 runs, taken in turns), and
// their ratios.
void compareThreads(const Part& housing, const std::vector<std::string>& extra) {
  constexpr int kRuns = 3;
  std::printf(
      "\nstages of the demo housing, wall s, best of %d: 1 thread vs 2 threads (ratio 2/1)\n",
      kRuns);
  Row one, two;
  for (int k = 0; k < kRuns; ++k) {
    for (const int threads : {1, 2}) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                                static_cast<std::size_t>(threads));
      const Row r = run("data/jobs/demo.yaml", housing, extra);
      Row& best = threads == 1 ? one : two;
      best.stages = k == 0 ? r.stages : fastest(best.stages, r.stages);
    }
  }
  const auto line = [](const char* name, double a, double b) {
    std::printf("  %-12s %8.2f %8.2f %6.2f\n", name, a, b, a > 0 ? b / a : 0.0);
  };
  line("path+auto", one.stages.path, two.stages.path);
  line("map", one.stages.map, two.stages.map);
  line("plan", one.stages.plan, two.stages.plan);
  line("trajectory", one.stages.trajectory, two.stages.trajectory);
  line("validation", one.stages.validation, two.stages.validation);
  line("simulation", one.stages.simulation, two.stages.simulation);
  line("total", one.stages.total, two.stages.total);
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, threads = false;
  std::string filter;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick")
      quick = true;
    else if (a == "--threads")
      threads = true;
    else
      filter = a;
  }
  const fs::path scratch = fs::temp_directory_path() / "scanplan_bench_autoscan";
  fs::create_directories(scratch);
  std::vector<std::string> extra;
  if (quick) extra.push_back("scan.auto.point_spacing_mm=1.0");
  std::printf("bench_autoscan: the demo cell (Viper s650, 400 mm table), scan.auto%s\n",
              quick ? " at 1 mm (--quick)" : " as in data/jobs/demo.yaml (0.5 mm)");
  printHeader();
  std::vector<Row> rows;
  const std::vector<Part> all = parts(scratch);
  for (const Part& part : all) {
    if (!filter.empty() && part.name.find(filter) == std::string::npos) continue;
    Row r = run("data/jobs/demo.yaml", part, extra);
    print(r);
    rows.push_back(r);
  }
  std::vector<double> ratios;
  for (const Row& r : rows)
    if (r.ratio() > 0) ratios.push_back(r.ratio());
  if (!ratios.empty()) {
    std::sort(ratios.begin(), ratios.end());
    std::printf("\nprogram / single-coverage bound: median %.2f, max %.2f over %zu parts\n",
                ratios[ratios.size() / 2], ratios.back(), ratios.size());
  }
  if (filter.empty() || std::string("demo_housing").find(filter) != std::string::npos) {
    // The same job on the KUKA KR6 R900 sixx: other joint speeds, another program time.
    std::vector<std::string> kuka = extra;
    kuka.push_back("robot=" + fs::absolute("data/robots/kuka_kr6_r900_sixx.yaml").string());
    Row k = run("data/jobs/demo.yaml", all.front(), kuka);
    k.name = "demo_housing on KR6 R900";
    k.note = "data/robots/kuka_kr6_r900_sixx.yaml";
    print(k);
    if (threads) compareThreads(all.front(), extra);
  }
  fs::remove_all(scratch);
  return 0;
}
