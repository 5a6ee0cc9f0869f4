// Refinement (docs/design.md §5.4) on hand-built maps: the smooth model against evaluate() and its
// gradients against central finite differences; the guarantees (J never rises, the result is
// feasible, deterministic, an infeasible input throws) on DP, Ray Shooting and random paths over
// seeded random maps; a strict gain where the grid forces a DP path into jerky steps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <scanplan/planner/config_map.h>
#include <scanplan/planner/dp_planner.h>
#include <scanplan/planner/objective.h>
#include <scanplan/planner/ray_shooting.h>
#include <scanplan/planner/refine.h>

#include "map_support.h"

namespace {

using namespace scanplan::planner;
using namespace scanplan::test;
constexpr double kPi = std::numbers::pi;
using Status = PlanResult::Status;

// Central differences with h = 1e-6 rad: truncation O(h²·J''') and rounding O(1e-16·J/h) both
// sit below this relative error on these maps.
constexpr double kGradTol = 1e-5;
constexpr double kFdStep = 1e-6;

// The guarantees: feasible per evaluate(), J not above the input's, `after` = evaluate(theta),
// and an unimproved result is the input itself.
::testing::AssertionResult keepsGuarantees(const ConfigMap& map,
                                           const std::vector<double>& input,
                                           const RefineResult& r,
                                           const PlannerSettings& s,
                                           bool continuous) {
  if (r.theta.size() != input.size()) {
    return ::testing::AssertionFailure() << r.theta.size() << " angles for " << input.size();
  }
  const ObjectiveTerms in = evaluate(map, 0, input, s, continuous);
  const ObjectiveTerms out = evaluate(map, 0, r.theta, s, continuous);
  if (!out.feasible || !(out.min_f > 0.0)) {
    return ::testing::AssertionFailure() << "infeasible: min f " << out.min_f << ", max|w| "
                                         << out.max_abs_omega << ", max|a| " << out.max_abs_alpha;
  }
  if (out.total > in.total) {
    return ::testing::AssertionFailure() << "J rose: " << in.total << " -> " << out.total;
  }
  if (r.before.total != in.total || r.after.total != out.total) {
    return ::testing::AssertionFailure() << "terms: before " << r.before.total << " vs " << in.total
                                         << ", after " << r.after.total << " vs " << out.total;
  }
  if (r.improved != (out.total < in.total)) {
    return ::testing::AssertionFailure()
           << "improved = " << r.improved << " but J " << in.total << " -> " << out.total;
  }
  if (!r.improved && r.theta != input) {
    return ::testing::AssertionFailure() << "not improved, yet theta differs from the input";
  }
  return ::testing::AssertionSuccess();
}

// |a − b| ≤ tol·max(|a|, |b|, floor): relative where it is meaningful.
::testing::AssertionResult closeRel(double a, double b, double tol, double floor) {
  const double scale = std::max({std::abs(a), std::abs(b), floor});
  if (std::abs(a - b) <= tol * scale) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << a << " vs " << b << " (rel. error " << std::abs(a - b) / scale << ")";
}

// A path over the map that stays off grid angles (fractional grid position in [0.2, 0.8]) so
// central differences never straddle a kink of the piecewise-linear f, with random steps large
// enough that the ω and α terms matter.
std::vector<double> offGridPath(std::mt19937& rng, const ConfigMap& map, bool continuous) {
  const detail::Grid g = detail::gridOf(map, 0, continuous);
  std::uniform_real_distribution<double> frac(0.2, 0.8);
  std::uniform_int_distribution<int> jump(-2, 2);
  std::vector<double> theta;
  const double na = static_cast<double>(map.angles.size());
  double cell = std::floor(na / 2.0);
  for (std::size_t k = 0; k < map.times.size(); ++k) {
    cell = std::clamp(cell + jump(rng), 1.0, na - 3.0);
    theta.push_back(g.angle0 + (cell + frac(rng)) * g.angle_step);
  }
  return theta;
}

TEST(RefineProblem, ModelReadsMapValueAndMatchesEvaluateAwayFromCorners) {
  std::mt19937 rng(11);
  const PlannerSettings s;
  for (const bool continuous : {true, false}) {
    const ConfigMap map = randomMap(rng, 90, 40, continuous, false);
    const std::vector<double> theta = offGridPath(rng, map, continuous);
    const detail::RefineProblem p(map, 0, s, continuous, theta.size(), 1e-3, 0.0);
    for (std::size_t k = 0; k < theta.size(); ++k) {
      EXPECT_EQ(p.fModel(theta[k], k).f, mapValue(map, 0, theta[k], k, continuous));
    }
    const double j = p.objective(theta.data(), nullptr);
    EXPECT_TRUE(closeRel(j, evaluate(map, 0, theta, s, continuous).total, kSumTol, 1.0));
  }
}

TEST(RefineProblem, CornersAreRoundedToC1) {
  // Limited 5-angle table (step 0.1 rad), one sample: f = 0.2, 0.5, 0.3, 0.3, 0.6 by angle.
  // At grid angle 1 the slopes per grid step are sl = 0.3, sr = −0.2; with r = 0.1 the corner
  // q(δ) = f1 + (sl + sr)/2·δ + (sr − sl)/(4r)·(δ² + r²) reads 0.5 − 0.0125 at δ = 0, slope
  // (sl + sr)/2 per step, and meets both lines (value and slope) at δ = ±r.
  const std::vector<float> cells{0.2f, 0.5f, 0.3f, 0.3f, 0.6f};
  const ConfigMap map =
      makeMap(5, 2, 0.1, false, [&](std::size_t a, std::size_t) { return cells[a]; });
  detail::RefineProblem p(map, 0, {}, false, 2, 1e-3, 0.0);
  p.setKinkRadius(0.1);
  const double h = 0.1, r = 0.1;
  const double sl = double{0.5f} - double{0.2f}, sr = double{0.3f} - double{0.5f};
  const auto at = [&](double u) { return p.fModel(-1.0 + u * h, 0); };
  EXPECT_NEAR(at(1.0).f, double{0.5f} + (sr - sl) * r / 4.0, 1e-12);
  EXPECT_NEAR(at(1.0).df, 0.5 * (sl + sr) / h, 1e-9);
  EXPECT_NEAR(at(1.0).d2f, (sr - sl) / (2.0 * r) / (h * h), 1e-6);
  for (const double e : {1e-9, -1e-9}) {
    // Just inside and outside δ = ±r: value and slope continuous.
    EXPECT_NEAR(at(1.0 + r + e).f, at(1.0 + r - e).f, 1e-8);
    EXPECT_NEAR(at(1.0 + r + e).df, at(1.0 + r - e).df, 1e-5);
    EXPECT_NEAR(at(1.0 - r + e).f, at(1.0 - r - e).f, 1e-8);
    EXPECT_NEAR(at(1.0 - r + e).df, at(1.0 - r - e).df, 1e-5);
  }
  EXPECT_NEAR(at(1.5).df, sr / h, 1e-9);  // the straight part
  EXPECT_EQ(at(1.5).d2f, 0.0);
  // A flat corner (angles 2, 3 → slopes −0.2 and 0) and the table's last angle, where f runs on
  // towards 0 one grid step out (sr = −0.6).
  EXPECT_NEAR(at(4.0).f, double{0.6f} + (-double{0.6f} - (double{0.6f} - double{0.3f})) * r / 4.0,
              1e-12);
  EXPECT_EQ(at(6.0).f, 0.0);  // off the table
  EXPECT_EQ(at(6.0).df, 0.0);
}

TEST(RefineProblem, FeasibleIntervalIsTheOpenRunAroundTheAngle) {
  // Continuous 12-angle table, open on cells 3..6 at sample 0 and everywhere at sample 1.
  const ConfigMap map = makeMap(12, 2, 0.1, true, [](std::size_t a, std::size_t k) {
    return k == 1 || (a >= 3 && a <= 6) ? static_cast<float>(0.1 * static_cast<double>(a + 1))
                                        : 0.0f;
  });
  const double step = 2.0 * kPi / 12.0;
  const detail::RefineProblem p(map, 0, {}, true, 2, 1e-3, 0.0);
  double lo = 0.0, hi = 0.0, f_min = 0.0;
  // In the next turn (θ unwrapped past 2π), between cells 4 and 5.
  const double theta = 2.0 * kPi + 4.5 * step;
  p.feasibleInterval(theta, 0, lo, hi, f_min);
  EXPECT_NEAR(lo, 2.0 * kPi + 3.0 * step, 1e-12);
  EXPECT_NEAR(hi, 2.0 * kPi + 6.0 * step, 1e-12);
  EXPECT_FLOAT_EQ(static_cast<float>(f_min), 0.4f);
  // On a grid angle at the run's end.
  p.feasibleInterval(6.0 * step, 0, lo, hi, f_min);
  EXPECT_NEAR(lo, 3.0 * step, 1e-12);
  EXPECT_EQ(hi, 6.0 * step);
  // A fully open column: one turn either way, the lowest cell over it.
  p.feasibleInterval(4.0 * step, 1, lo, hi, f_min);
  EXPECT_LE(lo, 4.0 * step - 2.0 * kPi + step + 1e-12);
  EXPECT_GE(hi, 4.0 * step + 2.0 * kPi - step - 1e-12);
  EXPECT_FLOAT_EQ(static_cast<float>(f_min), 0.1f);
}

TEST(RefineProblem, DerivativesMatchCentralDifferences) {
  // Gradients of J and of the merit, the constraint Jacobian and the merit's Hessian band, at
  // off-grid points (no corner within a central difference), with the bounds set at half the
  // path's own speeds and a box on every sample so that many penalty terms are active.
  std::mt19937 rng(5);
  for (const bool continuous : {true, false}) {
    PlannerSettings s;
    s.k_omega = 0.7;
    s.k_alpha = 0.3;
    const ConfigMap map = randomMap(rng, 120, 30, continuous, false);
    const std::vector<double> theta = offGridPath(rng, map, continuous);
    const std::size_t n = theta.size();
    SCOPED_TRACE(continuous ? "continuous" : "limited");
    const ObjectiveTerms e = evaluate(map, 0, theta, s, continuous);
    s.omega_max = 0.5 * e.max_abs_omega;
    s.alpha_max = 0.5 * e.max_abs_alpha;
    detail::RefineProblem p(map, 0, s, continuous, n, 1e-3, 1e-6);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<double> lo(n), hi(n);
    for (std::size_t k = 0; k < n; ++k) {  // a third of the samples outside their box
      lo[k] = theta[k] + (k % 3 == 0 ? 1e-3 : -0.05);
      hi[k] = theta[k] + (k % 3 == 1 ? -1e-3 : 0.05);
    }
    p.setBoxes(lo, hi);
    std::vector<double> lambda(p.constraintCount());
    for (double& l : lambda) l = u(rng) < 0.5 ? 0.0 : 2.0 * u(rng);
    const double rho = 3.0;

    std::vector<double> grad_j(n), grad_m(n), x = theta;
    p.objective(theta.data(), grad_j.data());
    p.merit(theta.data(), lambda.data(), rho, grad_m.data());
    double scale_j = 0.0, scale_m = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      scale_j = std::max(scale_j, std::abs(grad_j[k]));
      scale_m = std::max(scale_m, std::abs(grad_m[k]));
    }
    const detail::RefineProblem::Band band = p.meritHessian(theta.data(), lambda.data(), rho);
    double scale_h = 0.0;
    for (const double d : band.diag) scale_h = std::max(scale_h, std::abs(d));
    std::vector<double> gp(n), gm(n);
    for (std::size_t k = 0; k < n; ++k) {
      x[k] = theta[k] + kFdStep;
      const double jp = p.objective(x.data(), nullptr);
      const double mp = p.merit(x.data(), lambda.data(), rho, gp.data());
      x[k] = theta[k] - kFdStep;
      const double jm = p.objective(x.data(), nullptr);
      const double mm = p.merit(x.data(), lambda.data(), rho, gm.data());
      x[k] = theta[k];
      EXPECT_TRUE(closeRel(grad_j[k], (jp - jm) / (2.0 * kFdStep), kGradTol, 1e-3 * scale_j))
          << "dJ/dtheta_" << k;
      EXPECT_TRUE(closeRel(grad_m[k], (mp - mm) / (2.0 * kFdStep), kGradTol, 1e-3 * scale_m))
          << "dmerit/dtheta_" << k;
      // Column k of the Hessian: rows k, k+1, k+2 from the band (symmetric), the rest zero.
      for (std::size_t r = 0; r < n; ++r) {
        const double fd = (gp[r] - gm[r]) / (2.0 * kFdStep);
        const double an = r == k       ? band.diag[k]
                          : r == k + 1 ? band.sub1[r]
                          : r == k + 2 ? band.sub2[r]
                          : k == r + 1 ? band.sub1[k]
                          : k == r + 2 ? band.sub2[k]
                                       : 0.0;
        EXPECT_TRUE(closeRel(an, fd, 1e-4, 1e-4 * scale_h)) << "H(" << r << "," << k << ")";
      }
    }

    // Constraint Jacobian: every entry against differences of g, and no entry missing.
    const std::size_t m = p.constraintCount();
    EXPECT_EQ(m, 2 * (n - 1) + 2 * (n - 2) + 2 * n);
    std::vector<double> g0(m), gpc(m), gmc(m), dense(m * n, 0.0);
    std::vector<detail::RefineProblem::JacobianEntry> jac;
    p.constraints(theta.data(), g0.data(), &jac);
    for (const auto& entry : jac) dense[entry.constraint * n + entry.variable] += entry.value;
    for (std::size_t k = 0; k < n; ++k) {
      x[k] = theta[k] + kFdStep;
      p.constraints(x.data(), gpc.data());
      x[k] = theta[k] - kFdStep;
      p.constraints(x.data(), gmc.data());
      x[k] = theta[k];
      for (std::size_t i = 0; i < m; ++i) {
        const double fd = (gpc[i] - gmc[i]) / (2.0 * kFdStep);
        // g is linear in θ: only rounding of g (~1e-16·|g|/h) separates fd from the slope.
        ASSERT_TRUE(closeRel(dense[i * n + k], fd, kGradTol, 1.0)) << "dg_" << i << "/dtheta_" << k;
      }
    }
    // The values: ω of sample 1 and α of sample 2 ("+" and "−"), the box of sample 0.
    const double dt = 0.1;
    const double w1 = (theta[1] - theta[0]) / dt;
    const double a2 = ((theta[2] - theta[1]) / dt - w1) / dt;
    const std::size_t alphas = 2 * (n - 1), boxes = alphas + 2 * (n - 2);
    EXPECT_NEAR(g0[0], (w1 - (1 - 1e-6) * s.omega_max) / s.omega_max, 1e-12);
    EXPECT_NEAR(g0[1], (-w1 - (1 - 1e-6) * s.omega_max) / s.omega_max, 1e-12);
    EXPECT_NEAR(g0[alphas], (a2 - (1 - 1e-6) * s.alpha_max) / s.alpha_max, 1e-12);
    EXPECT_NEAR(g0[alphas + 1], (-a2 - (1 - 1e-6) * s.alpha_max) / s.alpha_max, 1e-12);
    EXPECT_NEAR(g0[boxes], (theta[0] - hi[0]) / p.angleStep(), 1e-9);
    EXPECT_NEAR(g0[boxes + 1], (lo[0] - theta[0]) / p.angleStep(), 1e-9);
  }
}

TEST(RefineProblem, RelaxedBoundsAdmitAPathOnTheBound) {
  // θ moving at exactly ω_max: the tightened constraint (margin 1e-6) sees it 1e-6 over; after
  // relaxBoundsTo() it sits exactly on the bound, and faster paths are still over.
  const ConfigMap map = makeMap(36, 4, 0.1, true, [](std::size_t, std::size_t) { return 0.5f; });
  const PlannerSettings s;
  std::vector<double> theta(4);
  for (std::size_t k = 0; k < 4; ++k) theta[k] = 1.0 + s.omega_max * 0.1 * static_cast<double>(k);
  detail::RefineProblem p(map, 0, s, true, 4, 1e-3, 1e-6);
  std::vector<double> g(p.constraintCount());
  p.constraints(theta.data(), g.data());
  EXPECT_NEAR(g[0], 1e-6, 1e-12);
  p.relaxBoundsTo(theta.data());
  p.constraints(theta.data(), g.data());
  for (std::size_t i = 0; i < g.size(); ++i) EXPECT_LE(g[i], 1e-12) << i;
  std::vector<double> faster = theta;
  faster[3] += 1e-4;
  p.constraints(faster.data(), g.data());
  EXPECT_GT(g[4], 0.0);  // ω_3 "+"
}

TEST(RefineProblem, ContinuationBelowTheFloorIsSmoothAndFinite) {
  // f = 0.05 at every cell, floor 0.1: the continuation −ln f_floor − d + d²/2 with
  // d = (f − f_floor)/f_floor = −0.5 gives −ln 0.1 + 0.625 per sample·Δt, and f = 0 off a limited
  // table stays finite.
  const ConfigMap map = makeMap(5, 2, 0.1, false, [](std::size_t, std::size_t) { return 0.05f; });
  const detail::RefineProblem p(map, 0, {}, false, 2, 0.1, 0.0);
  const std::vector<double> theta{-0.75, -0.75};  // between grid angles
  const double d = (double{0.05f} - 0.1) / 0.1;
  EXPECT_NEAR(p.objective(theta.data(), nullptr), 2.0 * 0.1 * (-std::log(0.1) - d + 0.5 * d * d),
              1e-12);
  const std::vector<double> off{-5.0, -5.0};
  EXPECT_TRUE(std::isfinite(p.objective(off.data(), nullptr)));
}

TEST(Refine, NeverRaisesJOnDpAndRayShootingPaths) {
  // Seeded random maps, continuous and limited, with forbidden regions (low f cut to 0, and
  // blobs) that the paths run along and between.
  std::mt19937 rng(20240605);
  PlannerSettings s;
  s.alpha_max = 2.0;  // A ≥ 1 on the 2° grid, so DP can change speed
  int refined = 0, moving = 0, improved = 0;
  for (int trial = 0; trial < 24; ++trial) {
    const bool continuous = trial % 3 != 2;
    const ConfigMap map = randomMap(rng, 180, 80, continuous, trial % 2 == 0, trial % 4);
    SCOPED_TRACE("trial " + std::to_string(trial));
    for (const PlanResult& plan :
         {planDp(map, 0, s, continuous), planRayShooting(map, 0, s, continuous, {})}) {
      if (plan.status != Status::kExact) continue;
      const RefineResult r = refinePath(map, 0, plan.theta, s, continuous);
      ++refined;
      // A moving grid path or greedy ray always leaves room in continuous θ. A path standing on a
      // grid angle that is a peak of f (a kink of −ln f) at (nearly) every sample is (nearly)
      // optimal: what is left, a move of ~1e-5 rad at the odd sample, gains ~1e-6 s, below the
      // model's rounded corners (measured over 400 trials: every unimproved path stood still).
      if (r.before.max_abs_omega > 0.0) {
        ++moving;
        improved += r.improved ? 1 : 0;
      }
      EXPECT_TRUE(keepsGuarantees(map, plan.theta, r, s, continuous)) << r.stop_reason;
      EXPECT_LE(r.evaluations, RefineSettings{}.max_evaluations);
      EXPECT_FALSE(r.algorithm.empty());
      EXPECT_FALSE(r.stop_reason.empty());
    }
  }
  EXPECT_GE(refined, 40);
  EXPECT_GE(moving, 12);
  EXPECT_EQ(improved, moving);
  RecordProperty("refined", refined);
  RecordProperty("moving", moving);
  RecordProperty("improved", improved);
}

TEST(Refine, NeverRaisesJOnRandomFeasiblePaths) {
  // Random smooth paths (a sum of two sines, scaled into the bounds) over random maps, kept when
  // evaluate() calls them feasible.
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const PlannerSettings s;
  int tried = 0;
  for (int trial = 0; trial < 40 && tried < 12; ++trial) {
    const bool continuous = trial % 2 == 0;
    const ConfigMap map = randomMap(rng, 120, 60, continuous, trial % 4 < 2);
    const double c = continuous ? 2.0 * kPi * u(rng) : 1.0 + 2.0 * u(rng);
    const double a1 = 0.3 * u(rng), w1 = 0.5 + u(rng), a2 = 0.05 * u(rng), w2 = 2.0 + 2.0 * u(rng);
    const double p1 = 2.0 * kPi * u(rng), p2 = 2.0 * kPi * u(rng);
    std::vector<double> theta;
    for (std::size_t k = 0; k < map.times.size(); ++k) {
      const double t = map.times[k];
      theta.push_back(c + a1 * std::sin(w1 * t + p1) + a2 * std::sin(w2 * t + p2));
    }
    if (!evaluate(map, 0, theta, s, continuous).feasible) continue;
    ++tried;
    SCOPED_TRACE("trial " + std::to_string(trial));
    const RefineResult r = refinePath(map, 0, theta, s, continuous);
    EXPECT_TRUE(keepsGuarantees(map, theta, r, s, continuous)) << r.stop_reason;
    EXPECT_TRUE(r.improved) << r.stop_reason;  // a random path is nowhere near optimal
  }
  EXPECT_GE(tried, 8);
}

TEST(Refine, OptimalPathComesBackUnchanged) {
  // f peaks at grid angle 40 in every column and falls linearly on both sides (by `left` per grid
  // step below, `right` above), so −ln f has a strict local minimum, a kink, there. The path
  // standing at angle 40 has ω = α = 0 and the least −ln f at every sample: no path scores lower
  // (in continuous θ too, f being linear between grid angles), so refinement must hand back the
  // input itself, also when the kink is lopsided and the rounded model's minimum sits a little
  // off the grid angle.
  for (const auto& slopes : {std::pair{0.05, 0.05}, std::pair{0.1, 0.01}}) {
    const double left = slopes.first;  // not a binding: clang 14 cannot capture one
    const double right = slopes.second;
    const ConfigMap map = makeMap(90, 100, 0.1, true, [&](std::size_t a, std::size_t) {
      const double d = static_cast<double>(a) - 40.0;
      return static_cast<float>(std::max(0.9 - (d < 0 ? -left * d : right * d), 0.05));
    });
    const PlannerSettings s;
    const std::vector<double> theta(100, map.angles[40]);
    const RefineResult r = refinePath(map, 0, theta, s, true);
    EXPECT_TRUE(keepsGuarantees(map, theta, r, s, true));
    EXPECT_FALSE(r.improved) << r.stop_reason;
    EXPECT_EQ(r.theta, theta);
    EXPECT_EQ(r.after.total, r.before.total);
    EXPECT_NE(r.stop_reason.find("input kept"), std::string::npos) << r.stop_reason;
  }
}

TEST(Refine, SmoothsTheGridStepsOfADpPathInAShiftingCorridor) {
  // A Gaussian corridor (σ = 3 grid steps) drifting at 0.35 grid steps per sample. On the grid
  // DP has to move in whole steps (0, 1, 0, 1, 1, …), paying α on every change and ω² above the
  // mean speed; in continuous θ the path can glide at the corridor's speed near its centre line,
  // so J must drop strictly.
  const std::size_t na = 360, nt = 150;
  const double dt = 0.1, step = 2.0 * kPi / na, sigma = 3.0 * step, v = 0.35 * step / dt;
  const auto centre = [&](std::size_t k) { return 1.0 + v * static_cast<double>(k) * dt; };
  const ConfigMap map = makeMap(na, nt, dt, true, [&](std::size_t a, std::size_t k) {
    const double d = wrapDist(static_cast<double>(a) * step, centre(k)) / sigma;
    return std::abs(d) > 4.0 ? 0.0f : static_cast<float>(std::exp(-0.5 * d * d));
  });
  PlannerSettings s;
  s.alpha_max = 2.0;  // A = 1: DP can change its step by one grid step per sample
  const PlanResult dp = planDp(map, 0, s, true);
  ASSERT_EQ(dp.status, Status::kExact) << dp.reason;
  const RefineResult r = refinePath(map, 0, dp.theta, s, true);
  EXPECT_TRUE(keepsGuarantees(map, dp.theta, r, s, true)) << r.stop_reason;
  ASSERT_TRUE(r.improved) << r.stop_reason;
  // Measured: the ω and α terms shrink most (α to nearly 0); require a clear gain.
  EXPECT_LT(r.after.total, r.before.total - 0.01 * std::abs(r.before.total)) << r.stop_reason;
  EXPECT_LT(r.after.cost_alpha, 0.5 * r.before.cost_alpha);
  for (std::size_t k = 0; k < nt; ++k) {
    EXPECT_LT(std::abs(wrapDist(r.theta[k], centre(k))), 4.0 * sigma) << "sample " << k;
  }
  RecordProperty("J_dp", std::to_string(r.before.total));
  RecordProperty("J_refined", std::to_string(r.after.total));
}

TEST(Refine, StaysInTheOpenRunAroundEachSample) {
  // A narrow open lane (grid angles 20..23 on a 2° limited grid, f rising from 0.3 to 0.6) with a
  // better region beyond a forbidden wall (f = 1 at 26..40, 0 at 24..25). From a path standing
  // at angle 21, refinement climbs towards angle 23 but is local: it must not jump the wall, and
  // every sample stays within its lane's grid angles.
  const double step = 2.0 * kPi / 180.0;
  const ConfigMap map = makeMap(
      60, 50, 0.1, false,
      [](std::size_t a, std::size_t) {
        if (a >= 20 && a <= 23) return static_cast<float>(0.3 + 0.1 * static_cast<double>(a - 20));
        return a >= 26 && a <= 40 ? 1.0f : 0.0f;
      },
      step);
  const PlannerSettings s;
  const std::vector<double> theta(50, map.angles[21]);
  const RefineResult r = refinePath(map, 0, theta, s, false);
  EXPECT_TRUE(keepsGuarantees(map, theta, r, s, false)) << r.stop_reason;
  EXPECT_TRUE(r.improved) << r.stop_reason;
  for (const double th : r.theta) {
    EXPECT_GE(th, map.angles[20] - 1e-12);
    EXPECT_LE(th, map.angles[23] + 1e-12);
  }
}

TEST(Refine, ThousandSampleDpPathWithForbiddenBlobs) {
  // The size the planners produce (360 angles × 1000 samples), forbidden blobs included.
  std::mt19937 rng(41);
  const ConfigMap map = randomMap(rng, 360, 1000, true, false, 100);
  PlannerSettings s;
  s.alpha_max = 2.0;
  const PlanResult dp = planDp(map, 0, s, true);
  ASSERT_EQ(dp.status, Status::kExact) << dp.reason;
  const RefineResult r = refinePath(map, 0, dp.theta, s, true);
  EXPECT_TRUE(keepsGuarantees(map, dp.theta, r, s, true)) << r.stop_reason;
  EXPECT_TRUE(r.improved) << r.stop_reason;
  EXPECT_LT(r.evaluations, RefineSettings{}.max_evaluations) << r.stop_reason;
  RecordProperty("J_dp", std::to_string(r.before.total));
  RecordProperty("J_refined", std::to_string(r.after.total));
  RecordProperty("evaluations", r.evaluations);
}

TEST(Refine, DeterministicBitForBit) {
  std::mt19937 rng(7);
  const ConfigMap map = randomMap(rng, 180, 120, true, false);
  PlannerSettings s;
  s.alpha_max = 2.0;
  const PlanResult dp = planDp(map, 0, s, true);
  ASSERT_EQ(dp.status, Status::kExact) << dp.reason;
  const RefineResult a = refinePath(map, 0, dp.theta, s, true);
  const RefineResult b = refinePath(map, 0, dp.theta, s, true);
  ASSERT_EQ(a.theta.size(), b.theta.size());
  EXPECT_EQ(std::memcmp(a.theta.data(), b.theta.data(), a.theta.size() * sizeof(double)), 0);
  EXPECT_EQ(a.evaluations, b.evaluations);
  EXPECT_EQ(a.after.total, b.after.total);
  EXPECT_EQ(a.stop_reason, b.stop_reason);
}

TEST(Refine, KeepStartHoldsTheFirstAngle) {
  std::mt19937 rng(3);
  const ConfigMap map = randomMap(rng, 180, 60, true, false);
  PlannerSettings s;
  s.alpha_max = 2.0;
  const PlanResult dp = planDp(map, 0, s, true, map.angles[17]);
  ASSERT_EQ(dp.status, Status::kExact) << dp.reason;
  RefineSettings rs;
  rs.keep_start = true;
  const RefineResult r = refinePath(map, 0, dp.theta, s, true, rs);
  EXPECT_TRUE(keepsGuarantees(map, dp.theta, r, s, true)) << r.stop_reason;
  EXPECT_TRUE(r.improved) << r.stop_reason;
  EXPECT_EQ(r.theta.front(), dp.theta.front());
}

TEST(Refine, EvaluationBudgetIsRespectedAndStillSafe) {
  std::mt19937 rng(8);
  const ConfigMap map = randomMap(rng, 180, 80, true, true);
  PlannerSettings s;
  s.alpha_max = 2.0;
  const PlanResult dp = planDp(map, 0, s, true);
  ASSERT_EQ(dp.status, Status::kExact) << dp.reason;
  for (const int budget : {1, 5, 30}) {
    RefineSettings rs;
    rs.max_evaluations = budget;
    const RefineResult r = refinePath(map, 0, dp.theta, s, true, rs);
    EXPECT_LE(r.evaluations, budget);
    EXPECT_TRUE(keepsGuarantees(map, dp.theta, r, s, true)) << r.stop_reason;
    EXPECT_NE(r.stop_reason.find("budget"), std::string::npos) << r.stop_reason;
  }
}

TEST(Refine, InfeasibleOrBrokenInputThrows) {
  const ConfigMap map =
      makeMap(36, 10, 0.1, true, [](std::size_t a, std::size_t) { return a == 30 ? 0.0f : 0.8f; });
  const PlannerSettings s;
  const double step = 2.0 * kPi / 36.0;
  std::vector<double> ok(10, 5.0 * step);
  EXPECT_NO_THROW(refinePath(map, 0, ok, s, true));

  std::vector<double> blocked = ok;
  blocked[4] = 30.0 * step;  // f = 0 (and far too fast)
  EXPECT_THROW(refinePath(map, 0, blocked, s, true), std::invalid_argument);
  std::vector<double> fast = ok;
  for (std::size_t k = 0; k < fast.size(); ++k)
    fast[k] += 1.5 * s.omega_max * 0.1 * static_cast<double>(k);
  EXPECT_THROW(refinePath(map, 0, fast, s, true), std::invalid_argument);
  std::vector<double> nan = ok;
  nan[3] = std::nan("");
  EXPECT_THROW(refinePath(map, 0, nan, s, true), std::invalid_argument);
  EXPECT_THROW(refinePath(map, 0, std::vector<double>(9, 0.5), s, true), std::logic_error);
  RefineSettings rs;
  rs.max_evaluations = 0;
  EXPECT_THROW(refinePath(map, 0, ok, s, true, rs), std::invalid_argument);
}

}  // namespace
