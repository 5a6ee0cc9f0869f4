#include "planner/ray_shooting.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

namespace scanplan::planner {

namespace {

// One run from one start angle: the path so far and, when it stopped early, where and why.
struct Run {
  std::vector<double> theta;  // rad, unwrapped; complete when it has one angle per time sample
  std::string why;            // empty when complete
};

struct RayScore {
  bool blocked_first = true;  // f = 0 on the first step: the ray can never be applied
  double cost = 0.0;          // s
};

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
  const std::size_t na = map.angles.size(), nt = map.times.size();
  const double dt = g.dt, w_max = settings.omega_max;

  // Candidates sorted by (|a|, a), so a strict "<" keeps the tie-break rule. An integer numerator
  // makes the middle candidate exactly 0 and the set exactly symmetric.
  const auto n_rays = static_cast<std::size_t>(rs.rays);
  std::vector<double> accel(n_rays, 0.0);
  for (std::size_t i = 0; n_rays > 1 && i < n_rays; ++i) {
    const double num = 2.0 * static_cast<double>(i) - static_cast<double>(n_rays - 1);
    accel[i] = settings.alpha_max * num / static_cast<double>(n_rays - 1);
  }
  std::stable_sort(accel.begin(), accel.end(), [](double x, double y) {
    return std::abs(x) < std::abs(y) || (std::abs(x) == std::abs(y) && x < y);
  });

  const auto fAt = [&](double theta, std::size_t k) {
    return detail::mapValue(map, g, branch, theta, k, continuous);
  };

  // Rolls one ray out from (theta, omega) at sample k for h steps.
  const auto shoot = [&](double theta, double omega, std::size_t k, std::size_t h, double a) {
    RayScore s;
    for (std::size_t j = 1; j <= h; ++j) {
      const double w = std::clamp(omega + a * dt, -w_max, w_max);
      const double alpha = (w - omega) / dt;
      theta += w * dt;
      omega = w;
      const double f = fAt(theta, k + j);
      if (!(f > 0.0)) {
        s.cost += rs.blocked_penalty * static_cast<double>(h - j + 1);
        return s;
      }
      s.blocked_first = false;
      s.cost += (-std::log(f) + settings.k_omega * w * w) * dt;
      if (k + j >= 2) s.cost += settings.k_alpha * alpha * alpha * dt;  // as evaluate()
    }
    return s;
  };

  const auto runFrom = [&](double theta0) {
    Run run;
    run.theta.reserve(nt);
    run.theta.push_back(theta0);
    double omega = 0.0;  // from rest
    for (std::size_t k = 0; k + 1 < nt; ++k) {
      const std::size_t h = std::min(static_cast<std::size_t>(rs.horizon), nt - 1 - k);
      const double theta = run.theta.back();
      RayScore best;
      double best_a = 0.0;
      bool first = true;
      for (const double a : accel) {
        const RayScore s = shoot(theta, omega, k, h, a);
        const bool better =
            s.blocked_first != best.blocked_first ? !s.blocked_first : s.cost < best.cost;
        if (first || better) {
          best = s;
          best_a = a;
          first = false;
        }
      }
      if (best.blocked_first) {
        run.why = fmt::format(
            "time sample {} (t = {} s): f = 0 wherever the speed and acceleration bounds allow "
            "from theta = {} rad, omega = {} rad/s",
            k + 1, map.times[k + 1], theta, omega);
        return run;
      }
      const double w = std::clamp(omega + best_a * dt, -w_max, w_max);
      run.theta.push_back(theta + w * dt);
      // Carry evaluate()'s finite difference so its rounding does not accumulate.
      omega = (run.theta.back() - theta) / dt;
    }
    return run;
  };

  PlanResult result;
  result.branch = branch;
  const auto finish = [&]() {
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
    return result;
  };

  std::vector<double> starts;
  if (start_theta) {
    if (fAt(*start_theta, 0) > 0.0) starts.push_back(*start_theta);
  } else {
    std::vector<std::size_t> open;
    for (std::size_t a = 0; a < na; ++a) {
      if (map.f[map.index(branch, a, 0)] > 0.0f) open.push_back(a);
    }
    const std::size_t n = std::min(open.size(), static_cast<std::size_t>(rs.starts));
    for (std::size_t i = 0; i < n; ++i) starts.push_back(map.angles[open[i * open.size() / n]]);
  }
  if (starts.empty()) {
    result.reason = fmt::format("time sample 0 (t = {} s): f = 0 at {}", map.times[0],
                                start_theta ? "the start angle" : "every table angle");
    return finish();
  }

  std::vector<Run> runs(starts.size());
  tbb::parallel_for(std::size_t{0}, starts.size(),
                    [&](std::size_t i) { runs[i] = runFrom(starts[i]); });

  // Combine in start order: the lowest feasible J wins; otherwise the furthest run explains why.
  std::size_t furthest = 0;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    Run& run = runs[i];
    if (run.theta.size() == nt) {
      const ObjectiveTerms terms = evaluate(map, branch, run.theta, settings, continuous);
      if (terms.feasible) {
        if (result.status != PlanResult::Status::kSolved || terms.total < result.terms.total) {
          result.status = PlanResult::Status::kSolved;
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
    if (run.theta.size() > runs[furthest].theta.size()) furthest = i;
  }
  if (result.status != PlanResult::Status::kSolved) {
    result.reason = fmt::format(
        "no start of {} reached the end; the furthest (theta0 = {} rad) "
        "stopped: {}",
        starts.size(), starts[furthest], runs[furthest].why);
  }
  return finish();
}

}  // namespace scanplan::planner
