// The automatic scan (scan.auto, issue 16) on the demo cell, part by part: the scannable share of
// the area, how much of it the simulated cloud covers, passes, program time and planning time,
// and today's hand-written demo job (data/jobs/demo_rings.yaml) on the same housing beside it.
// Parts: the demo housing, every mesh under ../shared/data/meshes (scaled to 150 mm, placed on
// the table; skipped when absent) and synthetic parts with known hard spots written here (thin
// walls, a deep pocket, a through hole).
// Usage (from the repository root):
//   build/tests/bench/bench_autoscan [--quick] [PART_NAME_FILTER]
// --quick: 1 mm point spacing (a faster plan for a smoke run); otherwise the demo job's 0.5 mm.
// Coverage is measured by the simulation and recomputed independently here from the points
// (another area sampling, its own nearest-point search); "delta" is the difference.
// Timing: cpu_s is the process's CPU time (both threads) of the whole pipeline for the part, the
// unit of work (issue 20); plan_s is the pipeline's own wall time of path, maps, plan and
// trajectory, for comparison with the README's figures.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cli/config/job.h"
#include "cli/config/problem.h"
#include "kinematics/mesh.h"
#include "kinematics/units.h"
#include "pipeline/plan_scan.h"
#include "scanner/area_coverage.h"
#include "tests/bench/bench_timing.h"

using namespace scanplan;
namespace fs = std::filesystem;

namespace {

// ---- synthetic parts (mm, ASCII STL, outward winding) ---------------------------------------

struct Quad {
  Eigen::Vector3d a, b, c, d;  // counter-clockwise seen from outside
};

void writeStl(const fs::path& file, const std::vector<Quad>& quads) {
  std::ofstream out(file);
  out << "solid part\n";
  for (const Quad& q : quads) {
    for (const auto& t : {std::array<Eigen::Vector3d, 3>{q.a, q.b, q.c},
                          std::array<Eigen::Vector3d, 3>{q.a, q.c, q.d}}) {
      out << "facet normal 0 0 0\nouter loop\n";
      for (const auto& v : t) out << "vertex " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
      out << "endloop\nendfacet\n";
    }
  }
  out << "endsolid part\n";
}

// An axis-aligned box [lo, hi] as six outward quads.
void addBox(std::vector<Quad>& q, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const auto P = [&](int x, int y, int z) {
    return Eigen::Vector3d(x ? hi.x() : lo.x(), y ? hi.y() : lo.y(), z ? hi.z() : lo.z());
  };
  q.push_back({P(0, 0, 0), P(0, 1, 0), P(1, 1, 0), P(1, 0, 0)});
  q.push_back({P(0, 0, 1), P(1, 0, 1), P(1, 1, 1), P(0, 1, 1)});
  q.push_back({P(0, 0, 0), P(1, 0, 0), P(1, 0, 1), P(0, 0, 1)});
  q.push_back({P(0, 1, 0), P(0, 1, 1), P(1, 1, 1), P(1, 1, 0)});
  q.push_back({P(0, 0, 0), P(0, 0, 1), P(0, 1, 1), P(0, 1, 0)});
  q.push_back({P(1, 0, 0), P(1, 1, 0), P(1, 1, 1), P(1, 0, 1)});
}

// A block with a square hole of side h from the top down to `depth` (through when depth = z):
// the top as four quads around the hole, the hole's walls facing in, a floor for a blind hole.
std::vector<Quad> blockWithHole(double x, double y, double z, double h, double depth) {
  std::vector<Quad> q;
  const double x0 = 0.5 * (x - h), x1 = 0.5 * (x + h), y0 = 0.5 * (y - h), y1 = 0.5 * (y + h);
  const double zb = z - depth;
  const auto V = [](double a, double b, double c) { return Eigen::Vector3d(a, b, c); };
  // Sides.
  q.push_back({V(0, 0, 0), V(x, 0, 0), V(x, 0, z), V(0, 0, z)});
  q.push_back({V(0, y, 0), V(0, y, z), V(x, y, z), V(x, y, 0)});
  q.push_back({V(0, 0, 0), V(0, 0, z), V(0, y, z), V(0, y, 0)});
  q.push_back({V(x, 0, 0), V(x, y, 0), V(x, y, z), V(x, 0, z)});
  // Top around the hole (+z).
  q.push_back({V(0, 0, z), V(x, 0, z), V(x, y0, z), V(0, y0, z)});
  q.push_back({V(0, y1, z), V(x, y1, z), V(x, y, z), V(0, y, z)});
  q.push_back({V(0, y0, z), V(x0, y0, z), V(x0, y1, z), V(0, y1, z)});
  q.push_back({V(x1, y0, z), V(x, y0, z), V(x, y1, z), V(x1, y1, z)});
  // Hole walls, normals into the hole.
  q.push_back({V(x0, y0, zb), V(x0, y0, z), V(x1, y0, z), V(x1, y0, zb)});  // +y facing
  q.push_back({V(x0, y1, zb), V(x1, y1, zb), V(x1, y1, z), V(x0, y1, z)});  // −y facing
  q.push_back({V(x0, y0, zb), V(x0, y1, zb), V(x0, y1, z), V(x0, y0, z)});  // +x facing
  q.push_back({V(x1, y0, zb), V(x1, y0, z), V(x1, y1, z), V(x1, y1, zb)});  // −x facing
  if (depth < z) {
    q.push_back({V(x0, y0, zb), V(x1, y0, zb), V(x1, y1, zb), V(x0, y1, zb)});  // floor, up
    q.push_back({V(0, 0, 0), V(0, y, 0), V(x, y, 0), V(x, 0, 0)});              // bottom
  } else {
    // Bottom around the through hole (−z).
    q.push_back({V(0, 0, 0), V(0, y0, 0), V(x, y0, 0), V(x, 0, 0)});
    q.push_back({V(0, y1, 0), V(0, y, 0), V(x, y, 0), V(x, y1, 0)});
    q.push_back({V(0, y0, 0), V(0, y1, 0), V(x0, y1, 0), V(x0, y0, 0)});
    q.push_back({V(x1, y0, 0), V(x1, y1, 0), V(x, y1, 0), V(x, y0, 0)});
  }
  return q;
}

// A base plate with three thin upright fins (2 mm walls, 60 mm tall, 12 mm apart): boxes that
// touch, fine for ray casting (no interior faces are seen).
std::vector<Quad> thinWalls() {
  std::vector<Quad> q;
  addBox(q, {0, 0, 0}, {120, 80, 10});
  for (int k = 0; k < 3; ++k) {
    const double x = 40.0 + 14.0 * k;
    addBox(q, {x, 10, 10}, {x + 2, 70, 70});
  }
  return q;
}

struct Part {
  std::string name;
  fs::path mesh;
  double scale = 1.0;  // after mm
  std::string note;
};

std::vector<Part> parts(const fs::path& scratch) {
  std::vector<Part> out{{"demo_housing", "data/parts/demo_housing.stl", 1.0, "the demo"}};
  writeStl(scratch / "deep_pocket.stl", blockWithHole(100, 100, 80, 16, 60));
  writeStl(scratch / "through_hole.stl", blockWithHole(100, 80, 60, 30, 60));
  writeStl(scratch / "thin_walls.stl", thinWalls());
  out.push_back({"deep_pocket", scratch / "deep_pocket.stl", 1.0, "16 mm pocket 60 mm deep"});
  out.push_back({"through_hole", scratch / "through_hole.stl", 1.0, "30 mm square through hole"});
  out.push_back({"thin_walls", scratch / "thin_walls.stl", 1.0, "2 mm fins 12 mm apart"});
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

struct Row {
  std::string name, note;
  double area_m2 = 0, scannable = 0, covered = 0, of_scannable = 0, delta = 0;
  std::size_t passes = 0;
  double program_s = 0, planning_s = 0, cpu_s = 0;
  bool valid = false;
  double clearance_mm = 0;
  std::string status;
};

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
    const pipeline::ScanProblem problem = cli::toProblem(cli::loadJob(job, overrides));
    r.area_m2 = problem.part.area();
    const pipeline::ScanPlan plan = pipeline::planScan(problem);
    r.status = std::string(pipeline::scanStatusName(plan.status));
    r.planning_s = plan.times.path + plan.times.map + plan.times.plan + plan.times.trajectory;
    r.cpu_s = bench::processCpuSeconds() - cpu;
    if (plan.prepared->auto_scan) r.passes = plan.prepared->auto_scan->passes.size();
    if (plan.trajectory) r.program_s = plan.trajectory->trajectory.samples.back().t;
    if (plan.validation) {
      r.valid = plan.validation->valid;
      r.clearance_mm = toMm(plan.validation->min_distance);
    }
    if (plan.simulation) {
      r.covered = plan.simulation->area.covered_fraction;
      r.delta = independentCoverage(problem, *plan.simulation) - r.covered;
    }
    if (plan.certificate) {
      r.scannable = plan.certificate->scannable_fraction;
      r.of_scannable = plan.certificate->covered_of_scannable;
    }
  } catch (const std::exception& e) {
    r.status = std::string("error: ") + e.what();
  }
  return r;
}

void print(const Row& r) {
  std::printf("%-26s %8.0f %9.1f %9.1f %9.1f %+6.2f %6zu %8.0f %8.1f %8.1f %5s %7.1f  %s\n",
              r.name.c_str(), r.area_m2 * 1e6, 100 * r.scannable, 100 * r.covered,
              100 * r.of_scannable, 100 * r.delta, r.passes, r.program_s, r.planning_s, r.cpu_s,
              r.valid ? "yes" : "NO", r.clearance_mm,
              r.status == "planned" ? r.note.c_str() : r.status.c_str());
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  std::string filter;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick")
      quick = true;
    else
      filter = a;
  }
  const fs::path scratch = fs::temp_directory_path() / "scanplan_bench_autoscan";
  fs::create_directories(scratch);
  std::vector<std::string> extra;
  if (quick) extra.push_back("scan.auto.point_spacing_mm=1.0");
  std::printf("bench_autoscan: the demo cell (Viper s650, 400 mm table), scan.auto%s\n",
              quick ? " at 1 mm (--quick)" : " as in data/jobs/demo.yaml (0.5 mm)");
  std::printf("%-26s %8s %9s %9s %9s %6s %6s %8s %8s %8s %5s %7s\n", "part", "area_mm2", "scannbl%",
              "covered%", "of_scan%", "delta", "passes", "prog_s", "plan_s", "cpu_s", "valid",
              "clr_mm");
  std::vector<Row> rows;
  for (const Part& part : parts(scratch)) {
    if (!filter.empty() && part.name.find(filter) == std::string::npos) continue;
    if (part.name == "demo_housing") {
      // Today's hand-written job on the same housing, for comparison (no certificate of its own:
      // its coverage against the automatic plan's scannable share is in the summary below).
      Row hand = run("data/jobs/demo_rings.yaml", part, {});
      hand.name = "demo_housing (hand-written)";
      hand.note = "data/jobs/demo_rings.yaml";
      print(hand);
      rows.push_back(hand);
    }
    Row r = run("data/jobs/demo.yaml", part, extra);
    print(r);
    rows.push_back(r);
  }
  if (rows.size() >= 2 && rows[0].name.starts_with("demo_housing (hand") && rows[1].scannable > 0) {
    std::printf(
        "\nhand-written vs automatic on the housing: %.1f%% vs %.1f%% of the scannable area "
        "(%.1fx), program %.0f s vs %.0f s\n",
        100 * rows[0].covered / rows[1].scannable, 100 * rows[1].of_scannable,
        rows[1].of_scannable / (rows[0].covered / rows[1].scannable), rows[0].program_s,
        rows[1].program_s);
  }
  fs::remove_all(scratch);
  return 0;
}
