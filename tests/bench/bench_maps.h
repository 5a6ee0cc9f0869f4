#pragma once
// The maps the planner benchmarks share: seeded synthetic maps and the demo job's map.

#include <cmath>
#include <cstddef>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <scanplan/collision/scene.h>
#include <scanplan/config/job.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/planner/config_map.h>
#include <scanplan/planner/objective.h>
#include "cli/commands/commands.h"

namespace scanplan::bench {

// f from seeded Gaussian bumps over (θ, t), zero below a threshold: open corridors that drift,
// split and close, like a real map's feasible bands.
inline planner::ConfigMap syntheticMap(std::size_t na, std::size_t nt, double dt, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  struct Bump {
    double theta, t, sigma_theta, sigma_t, height;
  };
  const double t_end = static_cast<double>(nt - 1) * dt;
  std::vector<Bump> bumps(40);
  for (Bump& b : bumps) {
    b = {2.0 * std::numbers::pi * u(rng), t_end * u(rng), 0.2 + 0.6 * u(rng), 2.0 + 8.0 * u(rng),
         0.3 + 0.7 * u(rng)};
  }
  planner::ConfigMap map;
  for (std::size_t i = 0; i < na; ++i)
    map.angles.push_back(2.0 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(na));
  for (std::size_t k = 0; k < nt; ++k) map.times.push_back(static_cast<double>(k) * dt);
  map.branches.resize(1);
  map.f.resize(na * nt);
  for (std::size_t a = 0; a < na; ++a) {
    for (std::size_t k = 0; k < nt; ++k) {
      double v = 0.05;
      for (const Bump& b : bumps) {
        const double d =
            std::remainder(map.angles[a] - b.theta, 2 * std::numbers::pi) / b.sigma_theta;
        const double e = (map.times[k] - b.t) / b.sigma_t;
        v += b.height * std::exp(-0.5 * (d * d + e * e));
      }
      v = std::min(v, 1.0);
      map.f[map.index(0, a, k)] = v < 0.2 ? 0.0f : static_cast<float>(v);
    }
  }
  return map;
}

// The demo job's map on its best branch, the scan path sampled so it has `samples` samples.
inline planner::ConfigMap demoMap(const std::string& job_file, std::size_t samples, double& dt) {
  config::JobSpec job = config::loadJob(job_file, {"map.branch=RIGHTY ABOVE NOFLIP"});
  const kinematics::CellModel cell0 = config::buildCell(job);
  const double duration = cli::generateScanPath(job, cell0).path.duration();
  dt = duration / static_cast<double>(samples - 1);
  job = config::loadJob(job_file,
                        {"map.branch=RIGHTY ABOVE NOFLIP", "scan.dt_s=" + std::to_string(dt)});
  const kinematics::CellModel cell = config::buildCell(job);
  const kinematics::ScanPath path = cli::generateScanPath(job, cell).path;
  const collision::Scene scene(cell, config::clearanceConfig(job));
  return cli::computeMap(job, scene, path).map;
}

// A job's map on the one branch its overrides name (e.g. "map.branch=RIGHTY ABOVE FLIP"), with
// the job's planner weights and table bounds and whether its table is continuous.
struct JobMap {
  planner::ConfigMap map;
  planner::PlannerSettings settings;
  bool continuous = true;
};

// `job_file` with `overrides`; its scan path resampled to `samples` samples, or on the job's own
// scan.dt_s when samples = 0 (an automatic scan is planned once then, not twice).
inline JobMap jobMap(const std::string& job_file,
                     std::vector<std::string> overrides,
                     std::size_t samples) {
  if (samples > 1) {
    const config::JobSpec job0 = config::loadJob(job_file, overrides);
    const double duration = cli::generateScanPath(job0, config::buildCell(job0)).path.duration();
    overrides.push_back("scan.dt_s=" + std::to_string(duration / static_cast<double>(samples - 1)));
  }
  const config::JobSpec job = config::loadJob(job_file, overrides);
  const kinematics::CellModel cell = config::buildCell(job);
  const kinematics::ScanPath path = cli::generateScanPath(job, cell).path;
  const collision::Scene scene(cell, config::clearanceConfig(job));
  const pipeline::PlanSettings plan = config::planSettings(job);
  return {cli::computeMap(job, scene, path).map, plan.objective, plan.continuous};
}

}  // namespace scanplan::bench
