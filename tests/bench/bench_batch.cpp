// `scanplan batch` throughput: a small sweep (2 planners x 3 horizons x 2 seeds on the
// lightened demo) run in process with --jobs 1 and --jobs 2, and with map reuse off, side by
// side. Each configuration runs `repeats` times; the fastest run counts (a shared machine only
// ever slows a run down).
// Usage (from the repository root): build/tests/bench/bench_batch [REPEATS]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "cli/batch/batch.h"
#include "tests/bench/bench_timing.h"

using namespace scanplan;
namespace fs = std::filesystem;

namespace {

struct Timing {
  double seconds = 1e300;  ///< wall
  double cpu = 1e300;      ///< process CPU, all threads
  std::size_t cases = 0, maps = 0;
};

Timing run(const fs::path& sweep, const fs::path& out, int jobs, bool reuse, int repeats) {
  Timing best;
  for (int r = 0; r < repeats; ++r) {
    fs::remove_all(out);
    cli::BatchOptions options;
    options.sweep_file = sweep;
    options.out_dir = out;
    options.jobs = jobs;
    options.reuse_maps = reuse;
    options.report = false;  // the cases only: plots are not what is measured
    options.print = false;
    const double cpu = bench::processCpuSeconds();
    const cli::BatchStats s = cli::runBatchCases(options);
    const double used = bench::processCpuSeconds() - cpu;
    if (s.seconds < best.seconds) best = {s.seconds, std::min(best.cpu, used), s.ran, s.maps};
    best.cpu = std::min(best.cpu, used);
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 2;
  const fs::path job = fs::absolute("data/jobs/demo_rings.yaml");
  if (!fs::exists(job)) {
    std::fprintf(stderr, "run from the repository root (no %s)\n", job.c_str());
    return 2;
  }
  const fs::path dir = fs::temp_directory_path() / "scanplan_bench_batch";
  fs::create_directories(dir);
  const fs::path sweep = dir / "sweep.yaml";
  std::ofstream(sweep) << "jobs: ['" << job.string() << "']\n"
                       << "set:\n"
                          "  - scan.dt_s=0.2\n"
                          "  - 'scan.paths=[{type: ring, height_mm: 35, tilt_deg: 25}, {type: "
                          "ring, height_mm: 105, tilt_deg: 60}]'\n"
                          "  - simulation.enabled=false\n"
                          "  - planner.refine.enabled=false\n"
                          "vary:\n"
                          "  planner.method: [ray, dp]\n"
                          "  planner.ray.horizon: [10, 15, 30]\n"
                          "seeds: {from: 1, to: 2}\n";

  const Timing one = run(sweep, dir / "jobs1", 1, true, repeats);
  const Timing two = run(sweep, dir / "jobs2", 2, true, repeats);
  const Timing fresh = run(sweep, dir / "noreuse", 1, false, repeats);
  const Timing fresh2 = run(sweep, dir / "noreuse2", 2, false, repeats);
  const auto rate = [](const Timing& t) { return static_cast<double>(t.cases) / t.seconds; };
  const auto perCase = [](const Timing& t) { return 1e3 * t.cpu / static_cast<double>(t.cases); };
  std::printf("small sweep: 12 cases, best of %d run(s) each\n\n", repeats);
  std::printf(
      "| run | maps | CPU | CPU per case | wall | cases/s (wall) |\n|---|---|---|---|---|---|\n");
  const auto row = [&](const char* name, const Timing& t) {
    std::printf("| %s | %zu | %.2f s | %.0f ms | %.2f s | %.2f |\n", name, t.maps, t.cpu,
                perCase(t), t.seconds, rate(t));
  };
  row("--jobs 1, map reuse", one);
  row("--jobs 2, map reuse", two);
  row("--jobs 1, no reuse", fresh);
  row("--jobs 2, no reuse", fresh2);
  std::printf("\nspeed-up --jobs 2 / --jobs 1 (wall): %.2fx (target >= 1.7x)\n",
              one.seconds / two.seconds);
  std::printf("speed-up --jobs 2 / --jobs 1 without reuse (wall): %.2fx\n",
              fresh.seconds / fresh2.seconds);
  std::printf("CPU per case, --jobs 2 / --jobs 1: %.2f (parallel overhead)\n",
              perCase(two) / perCase(one));
  std::printf("map reuse: %.1fx less CPU per case (--jobs 1), %.1fx (--jobs 2)\n",
              perCase(fresh) / perCase(one), perCase(fresh2) / perCase(two));
  fs::remove_all(dir);
  return 0;
}
