// Configuration-map throughput on the demo job, 2 threads. The full map (every branch) three
// ways: as built now, without motion-bound skipping (must be byte-identical), and by the old
// path (planner::detail::buildConfigMapReference: FCL alone, every pair at every branch-cell);
// then a time-subsampled map with the bounded clearance query and with plain fcl::distance,
// compared cell by cell. CPU time of the process (both threads' work) per cell and per
// branch-cell, best of RUNS, the three paths timed in turn round after round; wall time beside
// it for the cells/s target.
// Usage (from the repository root):
//   build/tests/bench/bench_map [JOB] [SUBSAMPLE (0: none)] [RUNS] [THREADS (default 2)]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <utility>

#include <fmt/format.h>

#include <tbb/global_control.h>

#include <scanplan/collision/scene.h>
#include <scanplan/config/job.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/planner/config_map.h>
#include <scanplan/scanner/path_generators.h>
#include <scanplan/scanner/raycaster.h>
#include "tests/bench/bench_timing.h"

using namespace scanplan;
using Clock = std::chrono::steady_clock;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

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

// How far two maps of the same cells are apart: the cells whose f differs, the largest
// difference, and whether the limit layer agrees.
std::string difference(const planner::ConfigMap& a, const planner::ConfigMap& b) {
  std::size_t differ = 0, limits = 0;
  double largest = 0.0;
  for (std::size_t i = 0; i < a.f.size(); ++i) {
    const double d = std::abs(static_cast<double>(a.f[i]) - static_cast<double>(b.f[i]));
    differ += d > 0.0;
    largest = std::max(largest, d);
    limits += a.limit[i] != b.limit[i];
  }
  return fmt::format("f differs in {} of {} branch-cells, by at most {:.2e}; limit differs in {}",
                     differ, a.f.size(), largest, limits);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string job_file = argc > 1 ? argv[1] : "data/jobs/demo_rings.yaml";
  const int subsample = argc > 2 ? std::max(0, std::atoi(argv[2])) : 25;  // 0: no exact map
  const int runs = argc > 3 ? std::max(1, std::atoi(argv[3])) : 2;
  const int threads = argc > 4 ? std::clamp(std::atoi(argv[4]), 1, 64) : 2;
  const tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism,
                                        static_cast<std::size_t>(threads));

  const config::JobSpec job = config::loadJob(job_file);
  const kinematics::CellModel cell = config::buildCell(job);
  const kinematics::LoadedMesh part =
      kinematics::loadMesh(cell.part.mesh.path, cell.part.mesh.options);
  const scanner::Raycaster raycaster(part.mesh);
  const kinematics::ScanPath path =
      scanner::generatePath(config::pathRequest(job), part.mesh, raycaster,
                            scanner::laserWindow(config::laserOptics(job)))
          .path;
  const collision::Scene scene(cell, config::clearanceConfig(job));
  const planner::ConstraintSettings settings = config::constraintSettings(job);

  planner::MapRequest request;
  request.angle_step = job.map.angle_step_deg * kDegToRad;
  if (job.map.branch == "auto") {
    for (int i = 0; i < 8; ++i) request.branches.push_back(kinematics::IkBranch::fromIndex(i));
  } else {
    request.branches = {*config::parseBranch(job.map.branch)};
  }
  // The map as built now (closed forms, motion-bound skipping, per-cell sharing)
  // beside the same without skipping (must be identical) and the old path it replaced (FCL
  // alone, every pair at every branch-cell), best of `runs` by the process's CPU time.
  // The three in turn, round after round: a slow spell of the machine (another process, the
  // host) falls on all three alike instead of on one path's runs.
  planner::ConfigMap full, unskipped, old;
  planner::MapRequest plain = request;
  plain.motion_bounds = false;
  double full_s = kInf, full_cpu = kInf, unskipped_cpu = kInf, old_cpu = kInf;
  for (int r = 0; r < runs; ++r) {
    const auto [wall, cpu] =
        timed([&] { full = planner::buildConfigMap(scene, settings, path, request); });
    full_s = std::min(full_s, wall);
    full_cpu = std::min(full_cpu, cpu);
    unskipped_cpu = std::min(
        unskipped_cpu,
        timed([&] { unskipped = planner::buildConfigMap(scene, settings, path, plain); }).second);
    old_cpu = std::min(old_cpu, timed([&] {
                                  old = planner::detail::buildConfigMapReference(scene, settings,
                                                                                 path, request);
                                }).second);
  }
  const std::size_t cells = full.cellsPerBranch();
  const double nbc = static_cast<double>(cells * full.branches.size());
  std::printf("bench_map: %s, part %zu triangles, %zu pairs, %d thread(s), best of %d\n",
              job_file.c_str(), part.mesh.triangles.size(), scene.pairs().size(), threads, runs);
  std::printf(
      "full map: %zu angles x %zu samples = %zu cells, %zu branch(es): %.2f s wall = %.0f "
      "cells/s   target >= 20000 cells/s: %s\n",
      full.angles.size(), full.times.size(), cells, full.branches.size(), full_s,
      static_cast<double>(cells) / full_s,
      static_cast<double>(cells) / full_s >= 20000.0 ? "met" : "MISSED");
  const auto per = [&](double cpu) {
    return fmt::format("{:.2f} s = {:.2f} us a cell, {:.3f} us a branch-cell", cpu,
                       1e6 * cpu / static_cast<double>(cells), 1e6 * cpu / nbc);
  };
  std::printf("CPU time, new path:          %s\n", per(full_cpu).c_str());
  std::printf("CPU time, without skipping:  %s   (%.2fx the new)\n", per(unskipped_cpu).c_str(),
              unskipped_cpu / full_cpu);
  std::printf("CPU time, old path:          %s   (%.2fx the new)   target >= 5x: %s\n",
              per(old_cpu).c_str(), old_cpu / full_cpu,
              old_cpu / full_cpu >= 5.0 ? "met" : "MISSED");
  const bool same_unskipped = identical(full, unskipped);
  std::printf("new = without skipping (all layers, byte for byte): %s\n",
              same_unskipped ? "yes" : "NO");
  std::printf("new vs old path: %s\n", difference(full, old).c_str());
  if (subsample == 0) return same_unskipped ? 0 : 1;

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
  std::printf("bounded vs exact-distance map: %s\n", difference(ours, exact).c_str());
  return same_unskipped ? 0 : 1;
}
