// `scanplan batch` throughput: the small sweep (2 planners x 3 horizons x 2 seeds on the
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

using namespace scanplan;
namespace fs = std::filesystem;

namespace {

struct Timing {
  double seconds = 1e300;
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
    const cli::BatchStats s = cli::runBatchCases(options);
    if (s.seconds < best.seconds) best = {s.seconds, s.ran, s.maps};
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
  std::printf("small sweep: 12 cases, best of %d run(s) each\n\n", repeats);
  std::printf("| run | maps | wall | cases/s |\n|---|---|---|---|\n");
  std::printf("| --jobs 1, map reuse | %zu | %.2f s | %.2f |\n", one.maps, one.seconds, rate(one));
  std::printf("| --jobs 2, map reuse | %zu | %.2f s | %.2f |\n", two.maps, two.seconds, rate(two));
  std::printf("| --jobs 1, no reuse | %zu | %.2f s | %.2f |\n", fresh.maps, fresh.seconds,
              rate(fresh));
  std::printf("| --jobs 2, no reuse | %zu | %.2f s | %.2f |\n\n", fresh2.maps, fresh2.seconds,
              rate(fresh2));
  std::printf("speed-up --jobs 2 / --jobs 1: %.2fx (target >= 1.7x)\n", one.seconds / two.seconds);
  std::printf("speed-up --jobs 2 / --jobs 1 without reuse: %.2fx\n",
              fresh.seconds / fresh2.seconds);
  std::printf("map reuse: %.1fx the cases/s (--jobs 1), %.1fx (--jobs 2)\n",
              rate(one) / rate(fresh), rate(two) / rate(fresh2));
  fs::remove_all(dir);
  return 0;
}
