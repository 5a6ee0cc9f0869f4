// The exact DP baseline: planDp against the straightforward relaxation it replaced
// (planner::detail::planDpReference), on the fine grid `plan` uses, in the same run. CPU time,
// best of N: one thread (thread CPU time) and two threads (process CPU time: the work of both).
// The two must give the same optimum and the same path (bit for bit). Issue 20: ≥ 3× on the
// demo map.
// Usage (from the repository root): build/tests/bench/bench_dp [runs] [JOB]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <tbb/global_control.h>

#include "planner/dp_planner.h"
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
  const planner::PlannerSettings s;
  int r = 1;
  const planner::ConfigMap map = fineGrid(coarse, s, r);
  std::printf("%s: %zu angles (map grid / %d) x %zu samples\n", title, map.angles.size(), r,
              map.times.size());
  PlanResult fast, ref;
  double t1_fast = 0, t1_ref = 0, t2_fast = 0, t2_ref = 0;
  {
    const tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    t1_fast = bench::bestThreadCpuSeconds(runs, [&] { fast = planner::planDp(map, 0, s, true); });
    t1_ref = bench::bestThreadCpuSeconds(
        runs, [&] { ref = planner::detail::planDpReference(map, 0, s, true); });
  }
  {
    const tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
    t2_fast = bench::bestProcessCpuSeconds(runs, [&] { fast = planner::planDp(map, 0, s, true); });
    t2_ref = bench::bestProcessCpuSeconds(
        runs, [&] { ref = planner::detail::planDpReference(map, 0, s, true); });
  }
  const double cells = static_cast<double>(map.angles.size() * map.times.size());
  std::printf("  1 thread:  planDp %7.3f s CPU (%5.1f ns a cell)   reference %7.3f s   %.2fx\n",
              t1_fast, 1e9 * t1_fast / cells, t1_ref, t1_ref / t1_fast);
  std::printf("  2 threads: planDp %7.3f s CPU (%5.1f ns a cell)   reference %7.3f s   %.2fx\n",
              t2_fast, 1e9 * t2_fast / cells, t2_ref, t2_ref / t2_fast);
  std::printf("  J %.12f vs %.12f; same path: %s; target %.0fx: %s\n\n", fast.terms.total,
              ref.terms.total, samePlan(fast, ref) ? "yes" : "NO", kTargetSpeedUp,
              std::min(t1_ref / t1_fast, t2_ref / t2_fast) >= kTargetSpeedUp ? "met" : "MISSED");
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
