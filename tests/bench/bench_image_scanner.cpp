// Image-mode scanner simulation against the geometric mode (seed §5.3) on a
// demo's planned motion, side by side in one run:
//  - process CPU time per profile of both modes over the whole scan, and their ratio;
//  - the image mode's point-to-surface error: each point on the part (as the simulator labels
//    it) to the nearest triangle of the part mesh, found here by a grid search over the whole
//    mesh (independent of the simulator's hit bookkeeping): mean, p99, max; the geometric mode's
//    with the same measure as the floor;
//  - dropouts: per profile, the points the image mode loses against the geometric one (and
//    those it gains), both 200 per profile at most;
//  - a sweep of image resolution (rows), sheet thickness, sensor noise and detection method
//    over every STRIDE-th profile.
// Usage (from the repository root):
//   build/tests/bench/bench_image_scanner [JOB] [STRIDE]
// JOB defaults to data/jobs/demo_rings.yaml, STRIDE (sweep subsample) to 20.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

#include <tbb/info.h>

#include <scanplan/config/job.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/pipeline/plan_scan.h>
#include <scanplan/planner/validation.h>
#include <scanplan/scanner/simulator.h>
#include "tests/bench/bench_timing.h"
#include "tests/geometry_support.h"

using namespace scanplan;

namespace {

// Point-to-mesh distance by a uniform grid of triangle boxes: exact for distances up to the
// cell size (the 3 × 3 × 3 cells around the point hold every triangle that near); beyond, the
// cell size is reported (a point that far off the part is an outlier whatever its distance).
class MeshDistance {
 public:
  MeshDistance(const kinematics::TriangleMesh& mesh, double cell) : mesh_(mesh), cell_(cell) {
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      Eigen::AlignedBox3d box;
      for (int k = 0; k < 3; ++k) box.extend(vertex(t, k));
      const Eigen::Vector3i lo = key(box.min()), hi = key(box.max());
      for (int x = lo.x(); x <= hi.x(); ++x)
        for (int y = lo.y(); y <= hi.y(); ++y)
          for (int z = lo.z(); z <= hi.z(); ++z) cells_[hash({x, y, z})].push_back(t);
    }
  }
  double operator()(const Eigen::Vector3d& p) const {
    const Eigen::Vector3i c = key(p);
    double best = cell_;
    for (int x = -1; x <= 1; ++x)
      for (int y = -1; y <= 1; ++y)
        for (int z = -1; z <= 1; ++z) {
          const auto it = cells_.find(hash(c + Eigen::Vector3i(x, y, z)));
          if (it == cells_.end()) continue;
          for (const std::size_t t : it->second)
            best = std::min(
                best, test::pointTriangleDistance(p, vertex(t, 0), vertex(t, 1), vertex(t, 2)));
        }
    return best;
  }

 private:
  const Eigen::Vector3d& vertex(std::size_t t, int k) const {
    return mesh_.vertices[static_cast<std::size_t>(mesh_.triangles[t](k))];
  }
  Eigen::Vector3i key(const Eigen::Vector3d& p) const {
    return (p / cell_).array().floor().cast<int>();
  }
  static long long hash(const Eigen::Vector3i& k) {
    return (static_cast<long long>(k.x()) * 73856093LL) ^
           (static_cast<long long>(k.y()) * 19349663LL) ^
           (static_cast<long long>(k.z()) * 83492791LL);
  }
  const kinematics::TriangleMesh& mesh_;
  double cell_;
  std::unordered_map<long long, std::vector<std::size_t>> cells_;
};

struct ErrorStats {
  double mean = 0.0, p99 = 0.0, max = 0.0;
  std::size_t points = 0;
};

ErrorStats surfaceError(const scanner::SimulatedCloud& cloud, const MeshDistance& distance) {
  std::vector<double> d;
  for (const auto& p : cloud.points) {
    if (p.part_triangle >= 0) d.push_back(distance(p.p_P));
  }
  ErrorStats s;
  s.points = d.size();
  if (d.empty()) return s;
  double sum = 0.0;
  for (const double v : d) sum += v;
  s.mean = sum / static_cast<double>(d.size());
  std::sort(d.begin(), d.end());
  s.p99 = d[std::min(d.size() - 1, d.size() * 99 / 100)];
  s.max = d.back();
  return s;
}

struct Dropouts {
  double lost = 0.0, gained = 0.0;  // points per profile
};

Dropouts dropouts(const scanner::SimulatedCloud& geometric,
                  const scanner::SimulatedCloud& image,
                  std::size_t profiles) {
  std::vector<long> g(profiles, 0), i(profiles, 0);
  for (const auto& p : geometric.points) ++g[p.profile];
  for (const auto& p : image.points) ++i[p.profile];
  Dropouts d;
  for (std::size_t k = 0; k < profiles; ++k) {
    d.lost += static_cast<double>(std::max(0L, g[k] - i[k]));
    d.gained += static_cast<double>(std::max(0L, i[k] - g[k]));
  }
  d.lost /= static_cast<double>(std::max<std::size_t>(1, profiles));
  d.gained /= static_cast<double>(std::max<std::size_t>(1, profiles));
  return d;
}

struct Run {
  scanner::SimulatedCloud cloud;
  double cpu = 0.0;  // process CPU seconds
};

Run simulate(const scanner::ScanSimulator& sim,
             const std::vector<scanner::ScanFrame>& frames,
             const scanner::LaserOptics& optics,
             const scanner::SimulationSettings& settings) {
  Run r;
  const double start = bench::processCpuSeconds();
  r.cloud = sim.simulate(frames, optics, settings);
  r.cpu = bench::processCpuSeconds() - start;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  const std::filesystem::path job_file = argc > 1 ? argv[1] : "data/jobs/demo_rings.yaml";
  const std::size_t stride =
      argc > 2 ? static_cast<std::size_t>(std::max(1, std::atoi(argv[2]))) : 20;
  // Plan the job as `plan` does, without its simulation; the frames as simulateTrajectory
  // takes them.
  const config::JobSpec job = config::loadJob(job_file, {"simulation.mode=image"});
  kinematics::CellModel cell = config::buildCell(job);
  kinematics::LoadedMesh part = config::loadPart(job, cell);
  const pipeline::SimulationSettings settings = config::simulationSettings(job, cell);
  pipeline::ScanProblem problem = config::toProblem(job, cell, part.mesh);
  problem.simulation.reset();
  const pipeline::ScanPlan plan = pipeline::planScan(problem, {});
  if (!plan.trajectory || !plan.trajectory->ok) {
    std::fprintf(stderr, "bench_image_scanner: %s gives no trajectory\n", job_file.c_str());
    return 1;
  }
  const kinematics::Trajectory dense =
      planner::densify(plan.trajectory->trajectory, 1.0 / settings.frame_rate_hz);
  std::vector<scanner::ScanFrame> frames, sweep_frames;
  for (const auto& s : dense.samples) {
    if (s.scanning) frames.push_back({s.t, s.theta, s.q});
  }
  for (std::size_t i = 0; i < frames.size(); i += stride) sweep_frames.push_back(frames[i]);
  const scanner::LaserOptics optics = config::laserOptics(job);
  const scanner::ScanSimulator sim(cell, part.mesh);
  const MeshDistance distance(part.mesh, 2e-3);

  scanner::SimulationSettings geometric = settings.scanner;
  geometric.mode = scanner::SimulationMode::kGeometric;
  const scanner::SimulationSettings image = settings.scanner;
  std::printf(
      "job %s: %zu profiles, %d fan rays / %d x %d pixels (rows x columns), sheet %.2f mm, "
      "%d threads\n",
      job_file.c_str(), frames.size(), geometric.rays_per_profile, image.image.rows,
      image.image.columns, image.image.thickness * 1e3, tbb::info::default_concurrency());

  const Run g = simulate(sim, frames, optics, geometric);
  const Run i = simulate(sim, frames, optics, image);
  const double n = static_cast<double>(frames.size());
  std::printf("\nwhole scan          CPU ms/profile   points/profile   rays/profile\n");
  std::printf("geometric           %12.3f   %14.1f   %12.0f\n", 1e3 * g.cpu / n,
              static_cast<double>(g.cloud.points.size()) / n,
              static_cast<double>(g.cloud.stats.laser_rays + g.cloud.stats.occlusion_rays) / n);
  std::printf("image               %12.3f   %14.1f   %12.0f\n", 1e3 * i.cpu / n,
              static_cast<double>(i.cloud.points.size()) / n,
              static_cast<double>(i.cloud.stats.pixel_rays + i.cloud.stats.occlusion_rays) / n);
  std::printf("ratio image / geometric: %.0fx CPU time\n", i.cpu / g.cpu);
  const ErrorStats eg = surfaceError(g.cloud, distance), ei = surfaceError(i.cloud, distance);
  const Dropouts d = dropouts(g.cloud, i.cloud, frames.size());
  std::printf("\npoint-to-surface error (points on the part, mm):  mean      p99       max\n");
  std::printf("geometric (%8zu points)                     %8.5f  %8.5f  %8.4f\n", eg.points,
              1e3 * eg.mean, 1e3 * eg.p99, 1e3 * eg.max);
  std::printf("image     (%8zu points)                     %8.5f  %8.5f  %8.4f\n", ei.points,
              1e3 * ei.mean, 1e3 * ei.p99, 1e3 * ei.max);
  std::printf(
      "dropouts: image mode loses %.2f points/profile against the geometric mode and "
      "gains %.2f (net %+.2f)\n",
      d.lost, d.gained, d.gained - d.lost);

  // The sweep: one setting changed at a time from the job's, every STRIDE-th profile.
  std::printf("\nsweep over %zu profiles (every %zu-th):\n", sweep_frames.size(), stride);
  std::printf("%-24s %10s %10s %10s %12s %12s\n", "setting", "mean mm", "p99 mm", "pts/prof",
              "lost/prof", "CPU ms/prof");
  const Run gs = simulate(sim, sweep_frames, optics, geometric);
  const auto row = [&](const std::string& name, const scanner::SimulationSettings& s) {
    const Run r = simulate(sim, sweep_frames, optics, s);
    const ErrorStats e = surfaceError(r.cloud, distance);
    const Dropouts dd = dropouts(gs.cloud, r.cloud, sweep_frames.size());
    const double m = static_cast<double>(sweep_frames.size());
    std::printf("%-24s %10.5f %10.5f %10.1f %12.2f %12.3f\n", name.c_str(), 1e3 * e.mean,
                1e3 * e.p99, static_cast<double>(r.cloud.points.size()) / m, dd.lost,
                1e3 * r.cpu / m);
  };
  {
    const ErrorStats e = surfaceError(gs.cloud, distance);
    std::printf(
        "%-24s %10.5f %10.5f %10.1f %12s %12.3f\n", "geometric", 1e3 * e.mean, 1e3 * e.p99,
        static_cast<double>(gs.cloud.points.size()) / static_cast<double>(sweep_frames.size()), "-",
        1e3 * gs.cpu / static_cast<double>(sweep_frames.size()));
  }
  row("image (job's settings)", image);
  for (const int rows : {128, 512, 1024}) {
    scanner::SimulationSettings s = image;
    s.image.rows = rows;
    row("rows " + std::to_string(rows), s);
  }
  for (const double mm : {0.25, 0.5, 2.0}) {
    scanner::SimulationSettings s = image;
    s.image.thickness = mm * 1e-3;
    char name[64];
    std::snprintf(name, sizeof name, "thickness %.2f mm", mm);
    row(name, s);
  }
  for (const double sigma : {2.0, 5.0, 10.0}) {
    scanner::SimulationSettings s = image;
    s.image.noise = sigma;
    char name[64];
    std::snprintf(name, sizeof name, "noise %.0f grey", sigma);
    row(name, s);
  }
  {
    scanner::SimulationSettings s = image;
    s.image.method = scanner::StripeMethod::kGaussian;
    row("detection gauss", s);
    s.image.noise = 5.0;
    row("gauss, noise 5 grey", s);
  }
  return 0;
}
