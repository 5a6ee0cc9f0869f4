// Configuration-map throughput on the demo job, 2 threads: the full map (every branch), then a
// time-subsampled map built twice, with the bounded clearance query and with plain
// fcl::distance, compared cell by cell. CPU time of the process (both threads' work) per cell
// and per branch-cell; wall time beside it for the cells/s target of issue 4.
// Usage (from the repository root): build/tests/bench/bench_map [JOB] [SUBSAMPLE]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <utility>

#include <tbb/global_control.h>

#include "cli/config/job.h"
#include "collision/scene.h"
#include "kinematics/mesh.h"
#include "kinematics/units.h"
#include "planner/config_map.h"
#include "scanner/path_generators.h"
#include "scanner/raycaster.h"
#include "tests/bench/bench_timing.h"

using namespace scanplan;
using Clock = std::chrono::steady_clock;

namespace {

double seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

// `f`'s wall time and the process's CPU time over it, s.
template <class F>
std::pair<double, double> timed(F&& f) {
  const auto start = Clock::now();
  const double cpu = bench::processCpuSeconds();
  f();
  return {seconds(start), bench::processCpuSeconds() - cpu};
}

bool identical(const planner::ConfigMap& a, const planner::ConfigMap& b) {
  const auto same = [](const auto& x, const auto& y) {
    return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) == 0;
  };
  return same(a.f, b.f) && same(a.joint, b.joint) && same(a.singularity, b.singularity) &&
         same(a.clearance, b.clearance) && same(a.limit, b.limit);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string job_file = argc > 1 ? argv[1] : "data/jobs/demo_rings.yaml";
  const int subsample = argc > 2 ? std::max(1, std::atoi(argv[2])) : 25;
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);

  const cli::JobSpec job = cli::loadJob(job_file);
  const kinematics::CellModel cell = cli::buildCell(job);
  const kinematics::LoadedMesh part =
      kinematics::loadMesh(cell.part.mesh.path, cell.part.mesh.options);
  const scanner::Raycaster raycaster(part.mesh);
  const kinematics::ScanPath path =
      scanner::generatePath(cli::pathRequest(job), part.mesh, raycaster,
                            scanner::laserWindow(cli::laserOptics(job)))
          .path;
  const collision::Scene scene(cell, cli::clearanceConfig(job));
  const planner::ConstraintSettings settings = cli::constraintSettings(job);

  planner::MapRequest request;
  request.angle_step = job.map.angle_step_deg * kDegToRad;
  if (job.map.branch == "auto") {
    for (int i = 0; i < 8; ++i) request.branches.push_back(kinematics::IkBranch::fromIndex(i));
  } else {
    request.branches = {*cli::parseBranch(job.map.branch)};
  }
  planner::ConfigMap full;
  const auto [full_s, full_cpu] =
      timed([&] { full = planner::buildConfigMap(scene, settings, path, request); });
  const std::size_t cells = full.cellsPerBranch();
  std::printf("bench_map: %s, part %zu triangles, %zu pairs, 2 threads\n", job_file.c_str(),
              part.mesh.triangles.size(), scene.pairs().size());
  std::printf(
      "full map: %zu angles x %zu samples = %zu cells, %zu branch(es): %.2f s = %.0f cells/s (%.0f "
      "branch-cells/s)   target >= 20000 cells/s: %s\n",
      full.angles.size(), full.times.size(), cells, full.branches.size(), full_s,
      static_cast<double>(cells) / full_s,
      static_cast<double>(cells * full.branches.size()) / full_s,
      static_cast<double>(cells) / full_s >= 20000.0 ? "met" : "MISSED");
  std::printf("full map CPU time: %.2f s = %.1f us a cell, %.2f us a branch-cell\n", full_cpu,
              1e6 * full_cpu / static_cast<double>(cells),
              1e6 * full_cpu / static_cast<double>(cells * full.branches.size()));

  // Exact distances cost ~35 ms a pose on this part: compare on every `subsample`-th time
  // sample, one branch (the job's, or the first).
  kinematics::ScanPath sub;
  sub.dt = path.dt * subsample;
  for (std::size_t i = 0; i < path.samples.size(); i += static_cast<std::size_t>(subsample))
    sub.samples.push_back(path.samples[i]);
  planner::MapRequest one = request;
  one.branches = {request.branches.front()};
  planner::ConfigMap ours, exact;
  const double ours_s =
      timed([&] { ours = planner::buildConfigMap(scene, settings, sub, one); }).second;
  one.exact_distances = true;
  const double exact_s =
      timed([&] { exact = planner::buildConfigMap(scene, settings, sub, one); }).second;
  const std::size_t sub_cells = ours.cellsPerBranch();
  std::printf(
      "comparison map (every %d-th sample, %s): %zu cells; CPU time: bounded %.2f s (%.0f "
      "cells/s), "
      "exact %.1f s (%.0f cells/s)\n",
      subsample, one.branches.front().words().c_str(), sub_cells, ours_s,
      static_cast<double>(sub_cells) / ours_s, exact_s, static_cast<double>(sub_cells) / exact_s);
  std::printf("speed-up over the exact-distance map: %.1fx   target >= 10x: %s\n", exact_s / ours_s,
              exact_s / ours_s >= 10.0 ? "met" : "MISSED");
  const bool same = identical(ours, exact);
  std::printf("maps identical (all layers, byte for byte): %s\n", same ? "yes" : "NO");
  return same ? 0 : 1;
}
