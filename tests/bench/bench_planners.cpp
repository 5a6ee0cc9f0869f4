// Planner speed and quality side by side on one map: Ray Shooting, the exact DP baseline (on the
// map's own angle grid and on the finer grid `plan` uses), OMPL, and NLopt refinement of each.
// Two maps: a seeded synthetic 360 × 1000 map with forbidden regions, and the demo job's map
// (its scan path resampled to about 1000 time samples).
// Usage (from the repository root): build/tests/bench/bench_planners [JOB]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include "cli/commands/commands.h"
#include "cli/config/job.h"
#include "collision/scene.h"
#include "kinematics/units.h"
#include "planner/config_map.h"
#include "planner/dp_planner.h"
#include "planner/objective.h"
#include "planner/ompl_planner.h"
#include "planner/ray_shooting.h"
#include "planner/refine.h"
#include "tests/bench/bench_maps.h"
#include "tests/bench/bench_timing.h"

using namespace scanplan;
using bench::demoMap;
using bench::syntheticMap;
using planner::PlanResult;

namespace {

// A planner's result with `seconds` replaced by the process's CPU time over the call (its
// threads' work; a shared machine's other work does not count).
template <class F>
auto cpuTimed(F&& f) {
  const double start = bench::processCpuSeconds();
  auto r = f();
  r.seconds = bench::processCpuSeconds() - start;
  return r;
}

void line(const char* name, const PlanResult& r, double dp_j) {
  if (r.status != PlanResult::Status::kExact) {
    std::printf("  %-26s %9.1f ms   no path: %s\n", name, 1e3 * r.seconds, r.reason.c_str());
    return;
  }
  std::printf("  %-26s %9.1f ms   J = %9.4f s  (f %.4f, w %.4f, a %.4f)  gap to DP %+7.2f%%\n",
              name, 1e3 * r.seconds, r.terms.total, r.terms.cost_f, r.terms.cost_omega,
              r.terms.cost_alpha, 100.0 * (r.terms.total - dp_j) / dp_j);
}

void refined(const char* name,
             const planner::ConfigMap& map,
             std::size_t branch,
             const PlanResult& r,
             const planner::PlannerSettings& s,
             bool continuous,
             double dp_j) {
  if (r.status != PlanResult::Status::kExact) return;
  const planner::RefineResult x =
      cpuTimed([&] { return planner::refinePath(map, branch, r.theta, s, continuous); });
  std::printf("  %-26s %9.1f ms   J = %9.4f s  (was %.4f; %s)  gap to DP %+7.2f%%\n", name,
              1e3 * x.seconds, x.after.total, x.before.total, x.improved ? "improved" : "kept",
              100.0 * (x.after.total - dp_j) / dp_j);
}

void compare(const char* title,
             const planner::ConfigMap& map,
             std::size_t branch,
             const planner::PlannerSettings& s,
             bool continuous) {
  std::printf("%s: %zu angles x %zu samples, dt %.4f s\n", title, map.angles.size(),
              map.times.size(), map.times[1] - map.times[0]);
  const int r = planner::autoAngleSubdivisions(map, branch, s, continuous);
  const PlanResult dp1 = cpuTimed([&] { return planner::planDp(map, branch, s, continuous); });
  const PlanResult dp =
      cpuTimed([&] { return planner::planDpRefined(map, branch, s, continuous, r); });
  const double dp_j = dp.status == PlanResult::Status::kExact ? dp.terms.total : NAN;
  const PlanResult ray =
      cpuTimed([&] { return planner::planRayShooting(map, branch, s, continuous, {}); });
  planner::OmplSettings os;
  os.time_limit_s = 2.0;
  const PlanResult ompl =
      cpuTimed([&] { return planner::planOmpl(map, branch, s, continuous, os); });
  line("dp (map grid)", dp1, dp_j);
  line(("dp (grid / " + std::to_string(r) + ") = DP").c_str(), dp, dp_j);
  line("ray (21 rays, H 15, 36 st.)", ray, dp_j);
  line("ompl (SST, 2 s)", ompl, dp_j);
  refined("ray + refine", map, branch, ray, s, continuous, dp_j);
  refined("ompl + refine", map, branch, ompl, s, continuous, dp_j);
  refined("DP + refine", map, branch, dp, s, continuous, dp_j);
  // Ray Shooting's two parameters, around the defaults.
  for (const int horizon : {10, 30}) {
    for (const int rays : {11, 41}) {
      planner::RayShootingSettings rs;
      rs.horizon = horizon;
      rs.rays = rays;
      const std::string name =
          "ray (" + std::to_string(rays) + " rays, H " + std::to_string(horizon) + ")";
      line(name.c_str(),
           cpuTimed([&] { return planner::planRayShooting(map, branch, s, continuous, rs); }),
           dp_j);
    }
  }
  std::printf("  targets: ray <= 50 ms: %s (%.1f ms); dp <= 2 s: %s (%.2f s)\n\n",
              ray.seconds <= 0.05 ? "met" : "MISSED", 1e3 * ray.seconds,
              dp.seconds <= 2.0 ? "met" : "MISSED", dp.seconds);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string job_file = argc > 1 ? argv[1] : "data/jobs/demo_rings.yaml";
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
  planner::PlannerSettings s;  // the documented defaults (k_omega 1, k_alpha 0.1, 30°/s, 60°/s²)
  std::printf(
      "bench_planners: 2 threads; times are the process's CPU time (both threads' work); J in s "
      "(the objective of DESIGN.md §5); gap = (J - J_DP) / J_DP\n\n");
  for (const unsigned seed : {7u, 8u}) {
    const std::string title = "synthetic map (seed " + std::to_string(seed) + ")";
    compare(title.c_str(), syntheticMap(360, 1000, 0.1, seed), 0, s, true);
  }
  double dt = 0.0;
  const auto start = std::chrono::steady_clock::now();
  const planner::ConfigMap demo = demoMap(job_file, 1000, dt);
  std::printf("(demo map built in %.1f s)\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  compare(("demo job " + job_file + ", RIGHTY ABOVE NOFLIP").c_str(), demo, 0, s, true);
  return 0;
}
