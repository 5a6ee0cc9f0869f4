// The exact DP baseline: planDp against the straightforward relaxation it replaced
// (planner::detail::planDpReference), on the fine grid `plan` uses, in the same run. CPU time,
// best of N: one thread (thread CPU time) and two threads (process CPU time: the work of both);
// on one thread also each relaxation kernel this CPU runs (portable, AVX2, AVX-512), planDp
// being the widest. All must give the reference's optimum and path bit for bit. Target: ≥ 3×
// on the demo map.
// Usage (from the repository root): build/tests/bench/bench_dp [runs] [JOB]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>

#include <tbb/global_control.h>

#include <scanplan/planner/dp_planner.h>
#include "tests/bench/bench_maps.h"
#include "tests/bench/bench_timing.h"

using namespace scanplan;
using planner::PlanResult;

namespace {

constexpr double kTargetSpeedUp = 3.0;

// DP of `map` on the grid `plan` uses (each map step split as autoAngleSubdivisions says).
planner::ConfigMap fineGrid(const planner::ConfigMap& map,
                            const planner::PlannerSettings& s,
                            int& subdivisions) {
  subdivisions = planner::autoAngleSubdivisions(map, 0, s, true);
  // planDpRefined builds this grid and calls planDp on it; the bench times planDp alone.
  planner::ConfigMap fine;
  fine.times = map.times;
  fine.branches = {map.branches[0]};
  const std::size_t na = map.angles.size(), nt = map.times.size();
  const auto r = static_cast<std::size_t>(subdivisions);
  const double h = (map.angles[1] - map.angles[0]) / static_cast<double>(r);
  for (std::size_t i = 0; i < na * r; ++i) {
    fine.angles.push_back(map.angles[0] + static_cast<double>(i) * h);
  }
  fine.f.resize(fine.angles.size() * nt);
  for (std::size_t i = 0; i < fine.angles.size(); ++i) {
    for (std::size_t k = 0; k < nt; ++k) {
      fine.f[fine.index(0, i, k)] =
          static_cast<float>(planner::mapValue(map, 0, fine.angles[i], k, true));
    }
  }
  return fine;
}

bool samePlan(const PlanResult& a, const PlanResult& b) {
  return a.status == b.status && a.theta == b.theta && a.terms.total == b.terms.total;
}

void compare(const char* title, const planner::ConfigMap& coarse, int runs) {
  using planner::detail::DpKernel;
  const planner::PlannerSettings s;
  int r = 1;
  const planner::ConfigMap map = fineGrid(coarse, s, r);
  const double dt = map.times[1] - map.times[0], h = map.angles[1] - map.angles[0];
  const auto d = static_cast<int>(std::floor(s.omega_max * dt / h * (1 + 1e-12)));
  const auto a = static_cast<int>(std::floor(s.alpha_max * dt * dt / h * (1 + 1e-12)));
  const double cells = static_cast<double>(map.angles.size() * map.times.size());
  std::printf("%s: %zu angles (map grid / %d) x %zu samples = %.2f M cells, W %d, A %d\n", title,
              map.angles.size(), r, map.times.size(), cells * 1e-6, 2 * d + 1, a);
  PlanResult ref;
  bool same = true;
  double t1_ref = 0, t1_best = 0;
  {
    const tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    t1_ref = bench::bestThreadCpuSeconds(
        runs, [&] { ref = planner::detail::planDpReference(map, 0, s, true); });
    std::printf("  1 thread:  reference        %7.3f s CPU (%5.1f ns a cell)\n", t1_ref,
                1e9 * t1_ref / cells);
    const std::pair<DpKernel, const char*> kernels[] = {{DpKernel::kPortable, "portable (SSE2)"},
                                                        {DpKernel::kAvx2, "AVX2"},
                                                        {DpKernel::kAvx512, "AVX-512"},
                                                        {DpKernel::kBest, "planDp"}};
    for (const auto& [kernel, name] : kernels) {
      if (!planner::detail::dpKernelAvailable(kernel)) {
        std::printf("             %-16s (this CPU has not got it)\n", name);
        continue;
      }
      PlanResult fast;
      const double t = bench::bestThreadCpuSeconds(
          runs, [&] { fast = planner::detail::planDpWithKernel(map, 0, s, true, kernel); });
      same = same && samePlan(fast, ref);
      if (kernel == DpKernel::kBest) t1_best = t;
      std::printf("             %-16s %7.3f s CPU (%5.1f ns a cell)  %.2fx\n", name, t,
                  1e9 * t / cells, t1_ref / t);
    }
  }
  double t2_best = 0, t2_ref = 0;
  {
    const tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
    PlanResult fast;
    t2_best = bench::bestProcessCpuSeconds(runs, [&] { fast = planner::planDp(map, 0, s, true); });
    t2_ref = bench::bestProcessCpuSeconds(
        runs, [&] { ref = planner::detail::planDpReference(map, 0, s, true); });
    same = same && samePlan(fast, ref);
  }
  std::printf("  2 threads: planDp %7.3f s CPU (%5.1f ns a cell)   reference %7.3f s   %.2fx\n",
              t2_best, 1e9 * t2_best / cells, t2_ref, t2_ref / t2_best);
  std::printf("  J %.12f; same path and J, every kernel: %s; target %.0fx: %s\n\n", ref.terms.total,
              same ? "yes" : "NO", kTargetSpeedUp,
              std::min(t1_ref / t1_best, t2_ref / t2_best) >= kTargetSpeedUp ? "met" : "MISSED");
}

}  // namespace

int main(int argc, char** argv) {
  const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 3;
  const std::string job_file = argc > 2 ? argv[2] : "data/jobs/demo_rings.yaml";
  std::printf("bench_dp: CPU time, best of %d runs, default objective and bounds\n\n", runs);
  for (const unsigned seed : {7u, 8u}) {
    const std::string title = "synthetic map (seed " + std::to_string(seed) + ", 360 x 1000)";
    compare(title.c_str(), bench::syntheticMap(360, 1000, 0.1, seed), runs);
  }
  double dt = 0.0;
  compare(("demo job " + job_file + " (1000 samples)").c_str(), bench::demoMap(job_file, 1000, dt),
          runs);
  return 0;
}
