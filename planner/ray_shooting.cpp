#include "planner/ray_shooting.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

namespace scanplan::planner {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr std::size_t kMergeEvery = 10;  // samples between checks for runs that met

// One run from one start angle: the path so far and, when it stopped early, where and why.
struct Run {
  std::vector<double> theta;  // rad, unwrapped; complete when it has one angle per time sample
  std::string why;            // why it stopped early; empty while it goes on
  double omega = 0.0;         // rad/s, from rest
  double cost = 0.0;          // s, the objective terms of the applied steps
  std::size_t last_i = 0;     // the ray applied last
  bool merged = false;        // dropped: another run reached the same state more cheaply
};

struct RayScore {
  bool blocked_first = true;  // f = 0 on the first step: the ray can never be applied
  bool pruned = false;        // stopped early: already costlier than the best ray so far
  double cost = 0.0;          // s
};

// Candidate accelerations (rad/s²) sorted by (|a|, a), so a strict "<" keeps the tie-break rule.
// An integer numerator makes the middle candidate exactly 0 and the set exactly symmetric.
std::vector<double> rayAccelerations(std::size_t n_rays, double alpha_max) {
  std::vector<double> accel(n_rays, 0.0);
  for (std::size_t i = 0; n_rays > 1 && i < n_rays; ++i) {
    const double num = 2.0 * static_cast<double>(i) - static_cast<double>(n_rays - 1);
    accel[i] = alpha_max * num / static_cast<double>(n_rays - 1);
  }
  std::stable_sort(accel.begin(), accel.end(), [](double x, double y) {
    return std::abs(x) < std::abs(y) || (std::abs(x) == std::abs(y) && x < y);
  });
  return accel;
}

// The rays and the rules a run advances by; shared read-only by the runs of all threads.
class Shooter {
 public:
  Shooter(const ConfigMap& map,
          const detail::Grid& g,
          std::size_t branch,
          const PlannerSettings& settings,
          bool continuous,
          const RayShootingSettings& rs)
      : map_(map),
        g_(g),
        branch_(branch),
        settings_(settings),
        continuous_(continuous),
        rs_(rs),
        accel_(rayAccelerations(static_cast<std::size_t>(rs.rays), settings.alpha_max)) {}

  double fAt(double theta, std::size_t k) const {
    return detail::mapValue(map_, g_, branch_, theta, k, continuous_);
  }

  // Rolls one ray out from (theta, omega) at sample k for h steps. Every term is >= 0, so a ray
  // whose partial cost already exceeds `bound` cannot win: it stops there (exact pruning).
  RayScore shoot(
      double theta, double omega, std::size_t k, std::size_t h, double a, double bound) const {
    const double dt = g_.dt, w_max = settings_.omega_max;
    RayScore s;
    for (std::size_t j = 1; j <= h; ++j) {
      const double w = std::clamp(omega + a * dt, -w_max, w_max);
      const double alpha = (w - omega) / dt;
      theta += w * dt;
      omega = w;
      const double f = fAt(theta, k + j);
      if (!(f > 0.0)) {
        s.cost += rs_.blocked_penalty * static_cast<double>(h - j + 1);
        return s;
      }
      s.blocked_first = false;
      s.cost += (-std::log(f) + settings_.k_omega * w * w) * dt;
      if (k + j >= 2) s.cost += settings_.k_alpha * alpha * alpha * dt;  // as evaluate()
      if (s.cost > bound) {
        s.pruned = true;
        return s;
      }
    }
    return s;
  }

  // The best ray from (theta, omega) at sample k over a horizon h: the previous step's ray
  // `last_i` first (it usually stays best, and its cost bounds the others). Candidates are ranked
  // by (cost, position in `accel_`), so the order of trial does not change the choice.
  std::size_t bestRay(double theta,
                      double omega,
                      std::size_t k,
                      std::size_t h,
                      std::size_t last_i,
                      RayScore& best) const {
    const std::size_t n_rays = accel_.size();
    std::size_t best_i = n_rays;
    const auto tryRay = [&](std::size_t i) {
      const double bound = best.blocked_first ? kInfinity : best.cost;
      const RayScore s = shoot(theta, omega, k, h, accel_[i], bound);
      if (s.pruned) return;
      const bool better =
          best_i == n_rays || (s.blocked_first != best.blocked_first
                                   ? !s.blocked_first
                                   : s.cost < best.cost || (s.cost == best.cost && i < best_i));
      if (better) {
        best = s;
        best_i = i;
      }
    };
    tryRay(last_i);
    for (std::size_t i = 0; i < n_rays; ++i) {
      if (i != last_i) tryRay(i);
    }
    return best_i;
  }

  // Advances a run from its last sample to sample k_end (or until it is blocked).
  void advance(Run& run, std::size_t k_end) const {
    const std::size_t nt = map_.times.size();
    const double dt = g_.dt, w_max = settings_.omega_max;
    double& omega = run.omega;
    std::size_t& last_i = run.last_i;
    for (std::size_t k = run.theta.size() - 1; k < k_end; ++k) {
      const std::size_t h = std::min(static_cast<std::size_t>(rs_.horizon), nt - 1 - k);
      const double theta = run.theta.back();
      RayScore best;
      last_i = bestRay(theta, omega, k, h, last_i, best);
      const double best_a = accel_[last_i];
      if (best.blocked_first) {
        run.why = fmt::format(
            "time sample {} (t = {} s): f = 0 wherever the speed and acceleration bounds allow "
            "from theta = {} rad, omega = {} rad/s",
            k + 1, map_.times[k + 1], theta, omega);
        return;
      }
      const double w = std::clamp(omega + best_a * dt, -w_max, w_max);
      run.theta.push_back(theta + w * dt);
      // Carry evaluate()'s finite difference so its rounding does not accumulate.
      const double omega_new = (run.theta.back() - theta) / dt;
      const double alpha = (omega_new - omega) / dt;
      run.cost +=
          (-std::log(fAt(run.theta.back(), k + 1)) + settings_.k_omega * omega_new * omega_new) *
          dt;
      if (k >= 1) run.cost += settings_.k_alpha * alpha * alpha * dt;
      omega = omega_new;
    }
  }

 private:
  const ConfigMap& map_;
  const detail::Grid& g_;
  std::size_t branch_;
  const PlannerSettings& settings_;
  bool continuous_;
  const RayShootingSettings& rs_;
  std::vector<double> accel_;  // rad/s², sorted by (|a|, a)
};

// `count` start angles (rad) spread evenly over the first column's open cells.
std::vector<double> spreadStarts(const ConfigMap& map, std::size_t branch, std::size_t count) {
  std::vector<std::size_t> open;
  for (std::size_t a = 0; a < map.angles.size(); ++a) {
    if (map.f[map.index(branch, a, 0)] > 0.0f) open.push_back(a);
  }
  std::vector<double> starts;
  const std::size_t n = std::min(open.size(), count);
  for (std::size_t i = 0; i < n; ++i) starts.push_back(map.angles[open[i * open.size() / n]]);
  return starts;
}

// A run that has come within `theta_near` (rad) and `omega_near` (rad/s) of another run's state,
// at a higher cost so far, is dropped: from (nearly) the same state both would shoot (nearly)
// the same rays.
void mergeRuns(std::vector<Run>& runs, bool continuous, double theta_near, double omega_near) {
  const auto alive = [](const Run& r) { return !r.merged && r.why.empty(); };
  for (std::size_t i = 0; i < runs.size(); ++i) {
    for (std::size_t j = i + 1; j < runs.size() && alive(runs[i]); ++j) {
      if (!alive(runs[j])) continue;
      double d = runs[i].theta.back() - runs[j].theta.back();
      if (continuous) d = std::remainder(d, 2.0 * std::numbers::pi);
      if (std::abs(d) > theta_near || std::abs(runs[i].omega - runs[j].omega) > omega_near) {
        continue;
      }
      (runs[j].cost < runs[i].cost ? runs[i] : runs[j]).merged = true;
    }
  }
}

// Combines the runs in start order: the lowest feasible J wins (into `result`); otherwise the
// furthest run explains why.
void combineRuns(const ConfigMap& map,
                 std::size_t branch,
                 const PlannerSettings& settings,
                 bool continuous,
                 const std::vector<double>& starts,
                 std::vector<Run>& runs,
                 PlanResult& result) {
  const std::size_t nt = map.times.size();
  std::size_t furthest = 0;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    Run& run = runs[i];
    if (run.theta.size() == nt) {
      const ObjectiveTerms terms = evaluate(map, branch, run.theta, settings, continuous);
      if (terms.feasible) {
        if (result.status != PlanResult::Status::kExact || terms.total < result.terms.total) {
          result.status = PlanResult::Status::kExact;
          result.terms = terms;
          result.theta = run.theta;
        }
        continue;
      }
      run.why = fmt::format(
          "the path breaks a bound: min f {} at time sample {}, max |omega| {} rad/s, max |alpha| "
          "{} rad/s^2",
          terms.min_f, terms.min_f_sample, terms.max_abs_omega, terms.max_abs_alpha);
    }
    if (!run.merged && (runs[furthest].merged || run.theta.size() > runs[furthest].theta.size())) {
      furthest = i;
    }
  }
  if (result.status != PlanResult::Status::kExact) {
    result.reason = fmt::format(
        "no start of {} reached the end; the furthest (theta0 = {} rad) "
        "stopped: {}",
        starts.size(), starts[furthest], runs[furthest].why);
  }
}

}  // namespace

PlanResult planRayShooting(const ConfigMap& map,
                           std::size_t branch,
                           const PlannerSettings& settings,
                           bool continuous,
                           const RayShootingSettings& rs,
                           std::optional<double> start_theta) {
  const auto clock_start = std::chrono::steady_clock::now();
  const detail::Grid g = detail::gridOf(map, branch, continuous);
  if (rs.rays < 1 || rs.horizon < 1 || rs.starts < 1 || !(rs.blocked_penalty >= 0.0) ||
      !(settings.omega_max >= 0.0) || !(settings.alpha_max >= 0.0)) {
    throw std::logic_error("planRayShooting: rays, horizon, starts >= 1; bounds, penalty >= 0");
  }
  const std::size_t nt = map.times.size();
  const double dt = g.dt;
  const Shooter shooter(map, g, branch, settings, continuous, rs);

  PlanResult result;
  result.branch = branch;
  const auto finish = [&]() {
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
    return result;
  };

  std::vector<double> starts;
  if (start_theta) {
    if (shooter.fAt(*start_theta, 0) > 0.0) starts.push_back(*start_theta);
  } else {
    starts = spreadStarts(map, branch, static_cast<std::size_t>(rs.starts));
  }
  if (starts.empty()) {
    result.reason = fmt::format("time sample 0 (t = {} s): f = 0 at {}", map.times[0],
                                start_theta ? "the start angle" : "every table angle");
    return finish();
  }

  // The runs advance in lockstep, kMergeEvery samples at a time. In between, runs that met are
  // merged (mergeRuns()), so most starts collapse into the few corridors of the map after a while.
  std::vector<Run> runs(starts.size());
  for (std::size_t i = 0; i < starts.size(); ++i) {
    runs[i].theta.reserve(nt);
    runs[i].theta.push_back(starts[i]);
    runs[i].cost = -std::log(shooter.fAt(starts[i], 0)) * dt;
  }
  const auto going = [&](const Run& r) {
    return !r.merged && r.why.empty() && r.theta.size() < nt;
  };
  // Within half a grid step and half an acceleration step.
  const double theta_near = 0.5 * g.angle_step, omega_near = 0.5 * settings.alpha_max * dt;
  for (std::size_t k_end = 0; k_end + 1 < nt;) {
    k_end = std::min(nt - 1, k_end + kMergeEvery);
    tbb::parallel_for(std::size_t{0}, runs.size(), [&](std::size_t i) {
      if (going(runs[i])) shooter.advance(runs[i], k_end);
    });
    mergeRuns(runs, continuous, theta_near, omega_near);
  }

  combineRuns(map, branch, settings, continuous, starts, runs, result);
  return finish();
}

}  // namespace scanplan::planner
