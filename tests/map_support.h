#pragma once

// Hand-built configuration maps for the planner tests (test_planner_dp, _ray, _ompl, _refine):
// a one-branch ConfigMap from a function f(a, k), seeded random bump maps, the circular angle
// distance they are built with, and the feasibility check a solved path has to pass.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <numbers>
#include <random>
#include <vector>

#include <scanplan/planner/config_map.h>
#include <scanplan/planner/dp_planner.h>
#include <scanplan/planner/objective.h>

namespace scanplan::test {

/// Objective terms are sums of a few hundred to a few thousand terms: rounding stays far below
/// this (relative to max(1, J)).
inline constexpr double kSumTol = 1e-9;

/// One branch; continuous: `na` angles over [0, 2π); limited: [-1, -1 + (na − 1)·step] rad.
/// `nt` time samples `dt` apart; f(a, k) is the value at angle index a, time sample k.
inline planner::ConfigMap makeMap(std::size_t na,
                                  std::size_t nt,
                                  double dt,
                                  bool continuous,
                                  const std::function<float(std::size_t, std::size_t)>& f,
                                  double step = 0.1) {
  planner::ConfigMap map;
  for (std::size_t i = 0; i < na; ++i) {
    map.angles.push_back(continuous ? static_cast<double>(i) * 2.0 * std::numbers::pi /
                                          static_cast<double>(na)
                                    : -1.0 + static_cast<double>(i) * step);
  }
  for (std::size_t k = 0; k < nt; ++k) map.times.push_back(static_cast<double>(k) * dt);
  map.branches.resize(1);
  map.f.resize(na * nt);
  for (std::size_t a = 0; a < na; ++a) {
    for (std::size_t k = 0; k < nt; ++k) map.f[map.index(0, a, k)] = f(a, k);
  }
  return map;
}

/// Circular distance between angle a and centre c (rad), in [−π, π].
inline double wrapDist(double a, double c) { return std::remainder(a - c, 2.0 * std::numbers::pi); }

/// f from a sum of 8 seeded Gaussian bumps (Δt = 0.1 s) over a floor of 0.15, capped at 1.
/// With `cut`, zero where it falls below 0.25 (so some maps have forbidden regions), and `holes`
/// elliptic forbidden blobs (up to ±0.3 rad × ±1.8 s) the path has to pass; holes = 0 draws no
/// further numbers from `rng`. Limited tables span [-1, -1 + 2π·(na − 1)/na].
inline planner::ConfigMap randomMap(std::mt19937& rng,
                                    std::size_t na,
                                    std::size_t nt,
                                    bool continuous,
                                    bool cut = true,
                                    int holes = 0) {
  constexpr double kPi = std::numbers::pi;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  struct Bump {
    double theta, t, sigma_theta, sigma_t, height;
  };
  std::vector<Bump> bumps(8);
  const double t_end = static_cast<double>(nt - 1) * 0.1;
  for (Bump& b : bumps) {
    b = {2.0 * kPi * u(rng), t_end * u(rng), 0.3 + 0.7 * u(rng), 0.5 + 2.0 * u(rng), u(rng)};
  }
  struct Hole {
    double theta, t, half_theta, half_t;
  };
  std::vector<Hole> hole(static_cast<std::size_t>(holes));
  for (Hole& h : hole) {
    h = {2.0 * kPi * u(rng), t_end * u(rng), 0.05 + 0.25 * u(rng), 0.3 + 1.5 * u(rng)};
  }
  const double step = 2.0 * kPi / static_cast<double>(na);
  return makeMap(
      na, nt, 0.1, continuous,
      [&](std::size_t a, std::size_t k) {
        const double th =
            continuous ? static_cast<double>(a) * step : -1.0 + static_cast<double>(a) * step;
        const double t = static_cast<double>(k) * 0.1;
        double v = 0.15;
        for (const Bump& b : bumps) {
          const double d = wrapDist(th, b.theta) / b.sigma_theta, e = (t - b.t) / b.sigma_t;
          v += b.height * std::exp(-0.5 * (d * d + e * e));
        }
        v = std::min(v, 1.0);
        for (const Hole& h : hole) {
          const double d = wrapDist(th, h.theta) / h.half_theta, e = (t - h.t) / h.half_t;
          if (d * d + e * e < 1.0) return 0.0f;
        }
        return cut && v < 0.25 ? 0.0f : static_cast<float>(v);
      },
      step);
}

/// For solvedAndFeasible(): the result is a sampling planner's (OMPL's), with its extra checks.
inline constexpr bool kSamplingPlanner = true;

/// A solved path on branch 0: one angle per sample, terms = evaluate() (J within kSumTol),
/// feasible (f > 0, |ω|, |α| within their bounds). With `sampling` (kSamplingPlanner: OMPL)
/// also: the failure names the planner's `detail`, the result is not flagged approximate, and
/// mapValue() is > 0 at every sample.
inline ::testing::AssertionResult solvedAndFeasible(const planner::ConfigMap& map,
                                                    const planner::PlanResult& r,
                                                    const planner::PlannerSettings& s,
                                                    bool continuous,
                                                    bool sampling = false) {
  if (r.status != planner::PlanResult::Status::kExact) {
    auto failure = ::testing::AssertionFailure() << "kNoPath: " << r.reason;
    if (sampling) failure << " [" << r.detail << "]";
    return failure;
  }
  if (r.theta.size() != map.times.size()) {
    return ::testing::AssertionFailure() << r.theta.size() << " angles for " << map.times.size();
  }
  if (sampling && r.status == planner::PlannerStatus::kApproximate) {
    return ::testing::AssertionFailure() << "solved but flagged approximate";
  }
  const planner::ObjectiveTerms e = planner::evaluate(map, 0, r.theta, s, continuous);
  if (!e.feasible || !(e.min_f > 0.0) ||
      e.max_abs_omega > s.omega_max * (1 + planner::kBoundTolerance) ||
      e.max_abs_alpha > s.alpha_max * (1 + planner::kBoundTolerance)) {
    return ::testing::AssertionFailure() << "infeasible: min f " << e.min_f << ", max|w| "
                                         << e.max_abs_omega << ", max|a| " << e.max_abs_alpha;
  }
  if (sampling) {
    for (std::size_t k = 0; k < r.theta.size(); ++k) {
      if (!(planner::mapValue(map, 0, r.theta[k], k, continuous) > 0.0)) {
        return ::testing::AssertionFailure() << "f = 0 at sample " << k;
      }
    }
  }
  if (std::abs(e.total - r.terms.total) > kSumTol * std::max(1.0, e.total)) {
    return ::testing::AssertionFailure() << "J " << r.terms.total << " vs evaluate " << e.total;
  }
  return ::testing::AssertionSuccess();
}

}  // namespace scanplan::test
