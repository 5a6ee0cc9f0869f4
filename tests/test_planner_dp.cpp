// The planning objective (docs/design.md §5) and the exact DP baseline (§5.2) on hand-built maps:
// a hand-computed J, interpolation and wrap-around, corridors with known answers, a blocked
// time column, and DP against brute-force enumeration of every grid path on tiny maps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include <scanplan/planner/config_map.h>
#include <scanplan/planner/dp_planner.h>
#include <scanplan/planner/objective.h>

#include "map_support.h"

namespace {

using namespace scanplan::planner;
using scanplan::test::makeMap;
constexpr double kPi = std::numbers::pi;
using Status = PlanResult::Status;

// DP and evaluate() sum the same terms in a different order.
constexpr double kSumRel = 1e-9;

::testing::AssertionResult closeRel(double actual, double expected, const char* what) {
  if (std::abs(actual - expected) <= kSumRel * std::max(1.0, std::abs(expected))) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure() << what << ": " << actual << " vs expected " << expected;
}

double angleStep(const ConfigMap& map) { return map.angles[1] - map.angles[0]; }

// DP's own terms must be evaluate()'s, and the path feasible.
void expectConsistent(const ConfigMap& map,
                      const PlanResult& r,
                      const PlannerSettings& s,
                      bool continuous) {
  ASSERT_EQ(r.status, Status::kExact) << r.reason;
  ASSERT_EQ(r.theta.size(), map.times.size());
  const ObjectiveTerms e = evaluate(map, 0, r.theta, s, continuous);
  EXPECT_TRUE(e.feasible) << "max|w| " << e.max_abs_omega << " max|a| " << e.max_abs_alpha
                          << " min f " << e.min_f;
  EXPECT_GT(e.min_f, 0.0);
  EXPECT_TRUE(closeRel(r.terms.total, e.total, "total"));
  EXPECT_TRUE(closeRel(r.terms.cost_f, e.cost_f, "cost_f"));
  EXPECT_TRUE(closeRel(r.terms.cost_omega, e.cost_omega, "cost_omega"));
  EXPECT_TRUE(closeRel(r.terms.cost_alpha, e.cost_alpha, "cost_alpha"));
  EXPECT_TRUE(closeRel(r.terms.max_abs_omega, e.max_abs_omega, "max_abs_omega"));
  EXPECT_TRUE(closeRel(r.terms.max_abs_alpha, e.max_abs_alpha, "max_abs_alpha"));
  EXPECT_EQ(r.terms.min_f, e.min_f);
  EXPECT_EQ(r.terms.min_f_sample, e.min_f_sample);
}

// 4 angles (step π/2), Δt = 0.5 s, path θ = {0, π/2, 3π/4}:
//   f: 0.5 (grid), 0.75 (grid), 0.5 (halfway between 0.25 and 0.75)
//   cost_f = −(ln 0.5 + ln 0.75 + ln 0.5)·0.5
//   ω1 = (π/2)/0.5 = π, ω2 = (π/4)/0.5 = π/2  → cost_ω = k_ω·(π² + π²/4)·0.5
//   α2 = (π/2 − π)/0.5 = −π                   → cost_α = k_a·π²·0.5
TEST(Objective, ThreeSamplePathMatchesHandComputedJ) {
  const ConfigMap map = makeMap(4, 3, 0.5, true, [](std::size_t a, std::size_t k) {
    if (k == 0 && a == 0) return 0.5f;
    if (k == 1 && a == 1) return 0.75f;
    if (k == 2) return a == 1 ? 0.25f : a == 2 ? 0.75f : 0.0f;
    return 0.0f;
  });
  PlannerSettings s;
  s.k_omega = 1.0;
  s.k_alpha = 0.1;
  s.omega_max = 4.0;
  s.alpha_max = 4.0;
  const ObjectiveTerms t = evaluate(map, 0, {0.0, kPi / 2, 3 * kPi / 4}, s, true);
  const double cost_f = -(std::log(0.5) + std::log(0.75) + std::log(0.5)) * 0.5;
  const double cost_omega = 1.0 * (kPi * kPi + kPi * kPi / 4) * 0.5;
  const double cost_alpha = 0.1 * kPi * kPi * 0.5;
  EXPECT_TRUE(closeRel(t.cost_f, cost_f, "cost_f"));
  EXPECT_TRUE(closeRel(t.cost_omega, cost_omega, "cost_omega"));
  EXPECT_TRUE(closeRel(t.cost_alpha, cost_alpha, "cost_alpha"));
  EXPECT_TRUE(closeRel(t.total, cost_f + cost_omega + cost_alpha, "total"));
  EXPECT_DOUBLE_EQ(t.min_f, 0.5);
  EXPECT_EQ(t.min_f_sample, 0u);  // the first of the two 0.5s
  EXPECT_DOUBLE_EQ(t.max_abs_omega, kPi);
  EXPECT_DOUBLE_EQ(t.max_abs_alpha, kPi);
  EXPECT_TRUE(t.feasible);

  s.omega_max = 3.0;  // < π
  EXPECT_FALSE(evaluate(map, 0, {0.0, kPi / 2, 3 * kPi / 4}, s, true).feasible);
  s.omega_max = 4.0;
  s.alpha_max = 3.0;  // < π
  EXPECT_FALSE(evaluate(map, 0, {0.0, kPi / 2, 3 * kPi / 4}, s, true).feasible);

  // f = 0 anywhere: J = +inf, infeasible.
  const ObjectiveTerms blocked = evaluate(map, 0, {0.0, 0.0, 0.0}, s, true);
  EXPECT_TRUE(std::isinf(blocked.total));
  EXPECT_FALSE(blocked.feasible);
  EXPECT_EQ(blocked.min_f, 0.0);
  EXPECT_EQ(blocked.min_f_sample, 1u);
}

TEST(Objective, MapValueInterpolatesAndWraps) {
  // Continuous, 4 angles: f(a) = 0.1·(a + 1) at time 0.
  const ConfigMap c = makeMap(
      4, 2, 1.0, true, [](std::size_t a, std::size_t) { return 0.1f * static_cast<float>(a + 1); });
  const auto fa = [&](std::size_t a) { return static_cast<double>(c.f[c.index(0, a, 0)]); };
  EXPECT_DOUBLE_EQ(mapValue(c, 0, kPi / 2, 0, true), fa(1));
  EXPECT_DOUBLE_EQ(mapValue(c, 0, kPi / 4, 0, true), 0.5 * (fa(0) + fa(1)));
  EXPECT_DOUBLE_EQ(mapValue(c, 0, kPi / 8, 0, true), 0.75 * fa(0) + 0.25 * fa(1));
  // Across the seam: −π/4 lies halfway between angle 3 (3π/2) and angle 0 (2π).
  EXPECT_DOUBLE_EQ(mapValue(c, 0, -kPi / 4, 0, true), 0.5 * (fa(3) + fa(0)));
  EXPECT_DOUBLE_EQ(mapValue(c, 0, 7 * kPi / 4, 0, true), 0.5 * (fa(3) + fa(0)));
  // Whole turns away reads the same cell.
  EXPECT_DOUBLE_EQ(mapValue(c, 0, 4 * kPi + kPi / 2, 0, true), fa(1));
  EXPECT_DOUBLE_EQ(mapValue(c, 0, -6 * kPi, 0, true), fa(0));

  // Limited, angles −1, −0.9, …, −0.6.
  const ConfigMap l = makeMap(5, 2, 1.0, false, [](std::size_t a, std::size_t) {
    return 0.2f * static_cast<float>(a + 1);
  });
  const auto fl = [&](std::size_t a) { return static_cast<double>(l.f[l.index(0, a, 0)]); };
  EXPECT_DOUBLE_EQ(mapValue(l, 0, -1.0, 0, false), fl(0));
  EXPECT_DOUBLE_EQ(mapValue(l, 0, -0.6, 0, false), fl(4));
  EXPECT_NEAR(mapValue(l, 0, -0.85, 0, false), 0.5 * (fl(1) + fl(2)), 1e-12);
  EXPECT_EQ(mapValue(l, 0, -1.01, 0, false), 0.0);
  EXPECT_EQ(mapValue(l, 0, -0.59, 0, false), 0.0);
  EXPECT_EQ(mapValue(l, 0, -1.0 + 2 * kPi, 0, false), 0.0);  // no wrap on a limited table

  // Next to a forbidden cell only the feasible grid angle itself reads f > 0.
  const ConfigMap z =
      makeMap(4, 1 + 1, 1.0, true, [](std::size_t a, std::size_t) { return a == 2 ? 0.0f : 0.5f; });
  EXPECT_EQ(mapValue(z, 0, kPi / 2, 0, true), 0.5);
  EXPECT_EQ(mapValue(z, 0, kPi / 2 + 1e-6, 0, true), 0.0);
  EXPECT_EQ(mapValue(z, 0, 3 * kPi / 2 - 1e-6, 0, true), 0.0);
  EXPECT_EQ(mapValue(z, 0, 3 * kPi / 2, 0, true), 0.5);
  EXPECT_DOUBLE_EQ(mapValue(z, 0, kPi / 4, 0, true), 0.5);
}

// f = 1 on angles 10..12, 0.01 elsewhere: the optimum stands still inside the band (J = 0).
TEST(DpPlanner, StraightCorridorStandsStillInside) {
  for (const bool continuous : {true, false}) {
    const ConfigMap map = makeMap(36, 50, 0.1, continuous, [](std::size_t a, std::size_t) {
      return a >= 10 && a <= 12 ? 1.0f : 0.01f;
    });
    PlannerSettings s;
    s.omega_max = 3 * angleStep(map) / 0.1;
    s.alpha_max = 1 * angleStep(map) / 0.01;
    const PlanResult r = planDp(map, 0, s, continuous);
    expectConsistent(map, r, s, continuous);
    for (const double theta : r.theta) {
      EXPECT_EQ(theta, r.theta.front());
      EXPECT_GE(theta, map.angles[10] - 1e-12);
      EXPECT_LE(theta, map.angles[12] + 1e-12);
    }
    EXPECT_EQ(r.terms.total, 0.0);
    EXPECT_EQ(r.terms.max_abs_omega, 0.0);
  }
}

// A one-cell corridor (f = 0 elsewhere) that holds, moves one grid step per sample for four
// samples, then holds: the only feasible path. On the continuous table it starts two steps
// below the seam, so the unwrapped path passes 2π.
TEST(DpPlanner, ShiftingCorridorIsFollowedWithinBounds) {
  for (const bool continuous : {true, false}) {
    const std::size_t na = 36, start = continuous ? 34 : 5;
    const auto centre = [&](std::size_t k) {
      return start + std::clamp<std::size_t>(k, 10, 14) - 10;
    };
    const ConfigMap map = makeMap(na, 30, 0.1, continuous, [&](std::size_t a, std::size_t k) {
      return a == centre(k) % na ? 0.8f : 0.0f;
    });
    const double h = continuous ? 2 * kPi / 36 : angleStep(map);
    PlannerSettings s;
    s.omega_max = 2.5 * h / 0.1;   // D = 2
    s.alpha_max = 1.5 * h / 0.01;  // A = 1: a step change of one grid step per sample
    const PlanResult r = planDp(map, 0, s, continuous);
    expectConsistent(map, r, s, continuous);
    for (std::size_t k = 0; k < r.theta.size(); ++k) {
      const double expected =
          continuous ? static_cast<double>(centre(k)) * h : map.angles[centre(k)];
      EXPECT_NEAR(r.theta[k], expected, 1e-12) << "sample " << k;
    }
    if (continuous) {
      EXPECT_GT(r.theta.back(), 2 * kPi);
    }
    EXPECT_NEAR(r.terms.max_abs_omega, h / 0.1, 1e-12);
    EXPECT_NEAR(r.terms.max_abs_alpha, h / 0.01, 1e-9);

    // Resolution caveat: α_max·Δt²/Δθ < 1 leaves only constant speed. The free first step must
    // be 0 to stay in the corridor, so the first move (sample 11) is out of reach.
    s.alpha_max = 0.9 * h / 0.01;
    const PlanResult slow = planDp(map, 0, s, continuous);
    EXPECT_EQ(slow.status, Status::kNoPath);
    EXPECT_TRUE(slow.theta.empty());
    EXPECT_NE(slow.reason.find("time sample 11 "), std::string::npos) << slow.reason;
  }
}

TEST(DpPlanner, BlockedTimeColumnIsNoPath) {
  const ConfigMap map =
      makeMap(24, 20, 0.1, true, [](std::size_t, std::size_t k) { return k == 7 ? 0.0f : 0.5f; });
  PlannerSettings s;
  const PlanResult r = planDp(map, 0, s, true);
  EXPECT_EQ(r.status, Status::kNoPath);
  EXPECT_TRUE(r.theta.empty());
  EXPECT_NE(r.reason.find("time sample 7 "), std::string::npos) << r.reason;
  EXPECT_NE(r.reason.find("f = 0 at every table angle"), std::string::npos) << r.reason;
}

TEST(DpPlanner, FixedStartIsKept) {
  // f rises with the angle index, so the free optimum would start and stay at angle 35.
  const ConfigMap map = makeMap(36, 10, 0.1, true, [](std::size_t a, std::size_t) {
    return 0.1f + 0.02f * static_cast<float>(a);
  });
  const double h = 2 * kPi / 36;
  PlannerSettings s;
  s.k_omega = 1e-3;  // cheap motion, so climbing pays
  s.k_alpha = 1e-4;
  s.omega_max = 1.5 * h / 0.1;
  s.alpha_max = 1.5 * h / 0.01;
  const double start = 2 * kPi + 3 * h + 0.2 * h;  // next turn, snaps to grid angle 3
  const PlanResult r = planDp(map, 0, s, true, start);
  expectConsistent(map, r, s, true);
  EXPECT_NEAR(r.theta.front(), 2 * kPi + 3 * h, 1e-12);
  // The best cell (angle 35, f = 0.8) is four steps down across the seam; at one step per
  // sample it is reached at sample 4 and held, on the turn the start was given on.
  EXPECT_NEAR(r.theta.back(), 2 * kPi - h, 1e-12);

  const ConfigMap limited =
      makeMap(10, 5, 0.1, false, [](std::size_t, std::size_t) { return 1.0f; });
  const PlanResult outside = planDp(limited, 0, s, false, 2.0);
  EXPECT_EQ(outside.status, Status::kNoPath);
  EXPECT_NE(outside.reason.find("time sample 0"), std::string::npos) << outside.reason;
}

// Every grid path on a 6 × 5 map (steps up to one more than the speed bound allows, filtered by
// evaluate()), against DP, for random f (with zeros) and random bounds away from grid multiples.
TEST(DpPlanner, EqualsBruteForceOnTinyMaps) {
  constexpr std::size_t kAngles = 6, kTimes = 5;
  constexpr double kDt = 0.2;
  std::mt19937 rng(20240605);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int solved = 0, no_path = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const bool continuous = trial % 2 == 0;
    const double zero_fraction = trial % 4 < 2 ? 0.15 : 0.4;
    std::vector<float> values(kAngles * kTimes);
    for (float& v : values) {
      v = unit(rng) < zero_fraction ? 0.0f : static_cast<float>(0.05 + 0.95 * unit(rng));
    }
    const ConfigMap map =
        makeMap(kAngles, kTimes, kDt, continuous,
                [&](std::size_t a, std::size_t k) { return values[a * kTimes + k]; });
    const double h = continuous ? 2 * kPi / kAngles : angleStep(map);
    const int d_bound = 1 + trial % 2 + (trial / 8) % 2;  // 1 or 2 or 3
    PlannerSettings s;
    s.k_omega = 2.0 * unit(rng);
    s.k_alpha = 2.0 * unit(rng);
    s.omega_max = (d_bound + 0.05 + 0.9 * unit(rng)) * h / kDt;
    s.alpha_max = (static_cast<double>(trial % 3) + 0.05 + 0.9 * unit(rng)) * h / (kDt * kDt);

    double best = std::numeric_limits<double>::infinity();
    const int d_max = d_bound + 1;
    const int w = 2 * d_max + 1;
    std::vector<double> theta(kTimes);
    for (std::size_t a0 = 0; a0 < kAngles; ++a0) {
      for (int code = 0; code < w * w * w * w; ++code) {
        int s_k = static_cast<int>(a0), rest = code;
        theta[0] = map.angles[a0];
        for (std::size_t k = 1; k < kTimes; ++k) {
          s_k += rest % w - d_max;
          rest /= w;
          theta[k] = map.angles[0] + static_cast<double>(s_k) * h;
        }
        const ObjectiveTerms t = evaluate(map, 0, theta, s, continuous);
        if (t.feasible) best = std::min(best, t.total);
      }
    }
    const PlanResult r = planDp(map, 0, s, continuous);
    if (std::isinf(best)) {
      ++no_path;
      EXPECT_EQ(r.status, Status::kNoPath) << "trial " << trial;
      EXPECT_NE(r.reason.find("time sample"), std::string::npos);
    } else {
      ++solved;
      SCOPED_TRACE("trial " + std::to_string(trial));
      expectConsistent(map, r, s, continuous);
      EXPECT_TRUE(closeRel(r.terms.total, best, "DP J vs brute force"));
    }
  }
  // Both outcomes exercised.
  EXPECT_GT(solved, 10);
  EXPECT_GT(no_path, 2);
}

// Larger random smooth maps: bounds and f > 0 hold, terms match evaluate(), and the result does
// not depend on the thread count.
TEST(DpPlanner, RespectsBoundsAndIsDeterministic) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 4; ++trial) {
    const bool continuous = trial % 2 == 0;
    const double p1 = 2 * kPi * unit(rng), p2 = 2 * kPi * unit(rng);
    // Lobes drifting about one grid step per sample, f = 0 between them.
    const auto fill = [&](std::size_t a, std::size_t k) {
      const double x = static_cast<double>(a) * kPi / 360, t = static_cast<double>(k);
      const double v = 0.6 + 0.5 * std::sin(3.0 * x + p1 + 0.02 * t) * std::cos(x + p2 - 0.01 * t);
      return v > 0.2 ? static_cast<float>(std::min(v, 1.0)) : 0.0f;
    };
    const ConfigMap map = makeMap(720, 40, 0.1, continuous, fill, 0.5 * kPi / 180);
    const double h = continuous ? kPi / 360 : angleStep(map);
    PlannerSettings s;
    s.omega_max = (3.0 + unit(rng)) * h / 0.1;
    s.alpha_max = (1.0 + 2.0 * unit(rng)) * h / 0.01;
    const PlanResult parallel = planDp(map, 0, s, continuous);
    expectConsistent(map, parallel, s, continuous);
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    const PlanResult serial = planDp(map, 0, s, continuous);
    EXPECT_EQ(serial.theta, parallel.theta);
    EXPECT_EQ(serial.terms.total, parallel.terms.total);
  }
}

// The kernels this CPU runs: planDp's choice and each one by name.
std::vector<detail::DpKernel> availableKernels() {
  std::vector<detail::DpKernel> kernels;
  for (const auto k : {detail::DpKernel::kBest, detail::DpKernel::kPortable,
                       detail::DpKernel::kAvx2, detail::DpKernel::kAvx512}) {
    if (detail::dpKernelAvailable(k)) kernels.push_back(k);
  }
  return kernels;
}

const char* kernelName(detail::DpKernel k) {
  switch (k) {
    case detail::DpKernel::kBest:
      return "best";
    case detail::DpKernel::kPortable:
      return "portable";
    case detail::DpKernel::kAvx2:
      return "AVX2";
    case detail::DpKernel::kAvx512:
      return "AVX-512";
  }
  return "?";
}

// Same status, reason, path and terms, bit for bit.
void expectSamePlan(const PlanResult& fast, const PlanResult& ref) {
  ASSERT_EQ(fast.status, ref.status) << fast.reason << " / " << ref.reason;
  EXPECT_EQ(fast.reason, ref.reason);
  EXPECT_EQ(fast.theta, ref.theta);
  EXPECT_EQ(fast.terms.total, ref.terms.total);
  EXPECT_EQ(fast.terms.cost_f, ref.terms.cost_f);
  EXPECT_EQ(fast.terms.cost_omega, ref.terms.cost_omega);
  EXPECT_EQ(fast.terms.cost_alpha, ref.terms.cost_alpha);
  EXPECT_EQ(fast.terms.min_f_sample, ref.terms.min_f_sample);
}

// planDp holds its layers step-major and relaxes them over angles in vector lanes;
// every kernel (portable, AVX2, AVX-512, as far as this CPU runs them) must find the
// reference's path, values and terms bit for bit, on continuous and limited tables, with and
// without a fixed start, with wide and narrow acceleration windows (A from 0 to several
// steps), on maps with closed regions.
TEST(DpPlanner, EqualsTheStraightforwardRelaxationBitForBit) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int solved = 0;
  for (int trial = 0; trial < 12; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    const bool continuous = trial % 2 == 0;
    const double p1 = 2 * kPi * unit(rng), p2 = 2 * kPi * unit(rng);
    const auto fill = [&](std::size_t a, std::size_t k) {
      const double x = static_cast<double>(a) * kPi / 90, t = static_cast<double>(k);
      const double v = 0.6 + 0.5 * std::sin(3.0 * x + p1 + 0.05 * t) * std::cos(x + p2 - 0.03 * t);
      return v > 0.25 ? static_cast<float>(std::min(v, 1.0)) : 0.0f;
    };
    const ConfigMap map = makeMap(180, 60, 0.1, continuous, fill, 2.0 * kPi / 180);
    const double h = continuous ? 2 * kPi / 180 : angleStep(map);
    PlannerSettings s;
    s.omega_max = (2.0 + 10.0 * unit(rng)) * h / 0.1;
    s.alpha_max = (0.5 + 8.0 * unit(rng)) * h / 0.01;
    const std::optional<double> start =
        trial % 3 == 0 ? std::optional<double>(map.angles[90]) : std::nullopt;
    const PlanResult ref = detail::planDpReference(map, 0, s, continuous, start);
    for (const detail::DpKernel kernel : availableKernels()) {
      SCOPED_TRACE(kernelName(kernel));
      expectSamePlan(detail::planDpWithKernel(map, 0, s, continuous, kernel, start), ref);
    }
    expectSamePlan(planDp(map, 0, s, continuous, start), ref);
    solved += ref.status == Status::kExact ? 1 : 0;
  }
  EXPECT_GE(solved, 8);  // most trials have a path to compare, not just the same "no path"
}

// The step-major layers at the edges of their layout, against the reference bit for bit with
// every kernel: fewer angles than a vector block and a block and one; the largest step a grid
// allows (D = N − 1, so the ghost cells span nearly a whole row and the path may jump past the
// seam); standing still only (D = 0); constant speed only (A = 0); and an acceleration window
// too wide for one-byte back pointers (2A + 1 > 255). Random f with zeros, a fixed start on a
// third of the cases, both table kinds; equal ties are likely on the flat maps (f = 1 in
// places), so the first-minimum rule is exercised too.
TEST(DpPlanner, StepMajorLayoutEdgesEqualTheReference) {
  struct Case {
    std::size_t na, nt;
    double d_steps, a_steps;  // ω_max·Δt/Δθ and α_max·Δt²/Δθ, off the grid multiples
  };
  const Case cases[] = {
      {5, 30, 1.5, 1.5},   {5, 30, 4.5, 8.5},    {17, 40, 2.5, 1.5},
      {17, 40, 16.5, 3.5}, {16, 40, 0.5, 2.5},   {33, 40, 3.5, 0.5},
      {40, 25, 9.5, 19.5}, {70, 8, 66.5, 130.5}, {70, 8, 69.5, 200.5},
  };
  constexpr double kDt = 0.1;
  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int solved = 0, compared = 0;
  for (const Case& c : cases) {
    for (int variant = 0; variant < 4; ++variant) {
      const bool continuous = variant % 2 == 0;
      SCOPED_TRACE("na " + std::to_string(c.na) + " D~" + std::to_string(c.d_steps) + " A~" +
                   std::to_string(c.a_steps) + (continuous ? " continuous" : " limited"));
      std::vector<float> values(c.na * c.nt);
      for (float& v : values) {
        const double u = unit(rng);
        v = u < 0.12 ? 0.0f : u < 0.3 ? 1.0f : static_cast<float>(0.2 + 0.8 * unit(rng));
      }
      const ConfigMap map = makeMap(c.na, c.nt, kDt, continuous, [&](std::size_t a, std::size_t k) {
        return values[a * c.nt + k];
      });
      const double h = continuous ? 2 * kPi / static_cast<double>(c.na) : angleStep(map);
      PlannerSettings s;
      s.k_omega = 0.5 * unit(rng);
      s.k_alpha = 0.05 * unit(rng);
      s.omega_max = c.d_steps * h / kDt;
      s.alpha_max = c.a_steps * h / (kDt * kDt);
      const std::optional<double> start =
          variant >= 2 ? std::optional<double>(map.angles[c.na / 2]) : std::nullopt;
      const PlanResult ref = detail::planDpReference(map, 0, s, continuous, start);
      for (const detail::DpKernel kernel : availableKernels()) {
        SCOPED_TRACE(kernelName(kernel));
        expectSamePlan(detail::planDpWithKernel(map, 0, s, continuous, kernel, start), ref);
        ++compared;
      }
      if (ref.status == Status::kExact) {
        ++solved;
        expectConsistent(map, ref, s, continuous);
      }
    }
  }
  EXPECT_GE(solved, 20);
  EXPECT_GE(compared, 2 * 36);
}

// The finer grid holds every path of the map grid (a coarse step is r fine steps, and the bounds
// allow at least r times the steps), so its optimum is never worse; where the map grid cannot
// change speed (A = 0) it is strictly better on a drifting corridor.
TEST(DpPlanner, RefinedGridIsNeverWorseAndResolvesAcceleration) {
  const double dt = 0.1;
  // A corridor 3 cells wide whose centre drifts by a quarter turn over the run, f peaked in it.
  const std::size_t na = 72, nt = 60;
  const auto fill = [&](std::size_t a, std::size_t k) {
    const double centre = 10.0 + 8.0 * std::sin(static_cast<double>(k) * 0.08);
    const double d = std::abs(static_cast<double>(a) - centre);
    return d > 3.0 ? 0.0f : static_cast<float>(1.0 - 0.2 * d);
  };
  for (const bool continuous : {true, false}) {
    SCOPED_TRACE(continuous ? "continuous" : "limited");
    const ConfigMap map = makeMap(na, nt, dt, continuous, fill, 2 * kPi / na);
    PlannerSettings s;
    s.omega_max = 3.0 * angleStep(map) / dt;
    s.alpha_max = 0.6 * angleStep(map) / (dt * dt);  // A = 0 on the map grid
    ASSERT_EQ(autoAngleSubdivisions(map, 0, s, continuous, 1), 2);
    ASSERT_EQ(autoAngleSubdivisions(map, 0, s, continuous, 3), 5);
    const PlanResult coarse = planDp(map, 0, s, continuous);
    const PlanResult fine = planDpRefined(map, 0, s, continuous, 5);
    expectConsistent(map, fine, s, continuous);
    ASSERT_EQ(coarse.status, Status::kNoPath) << "constant speed cannot follow the corridor";
    // With subdivisions 1 the refined planner is planDp itself.
    const PlanResult same = planDpRefined(map, 0, s, continuous, 1);
    EXPECT_EQ(same.status, coarse.status);
    // And on a map the coarse grid can solve, the finer optimum is never worse.
    PlannerSettings loose = s;
    loose.alpha_max = 1.5 * angleStep(map) / (dt * dt);
    const PlanResult c2 = planDp(map, 0, loose, continuous);
    const PlanResult f2 = planDpRefined(map, 0, loose, continuous, 3);
    expectConsistent(map, c2, loose, continuous);
    expectConsistent(map, f2, loose, continuous);
    EXPECT_LE(f2.terms.total, c2.terms.total + 1e-9);
  }
}

// The refined optimum equals planDp on a map built directly at the finer resolution with the same
// interpolated values (the resampling is mapValue(), nothing else).
TEST(DpPlanner, RefinedEqualsDpOnTheResampledMap) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.2, 1.0);
  const std::size_t na = 24, nt = 12, r = 3;
  std::vector<float> values(na * nt);
  for (float& v : values) v = static_cast<float>(unit(rng));
  const ConfigMap map =
      makeMap(na, nt, 0.1, true, [&](std::size_t a, std::size_t k) { return values[a * nt + k]; });
  const ConfigMap fine = makeMap(na * r, nt, 0.1, true, [&](std::size_t a, std::size_t k) {
    return static_cast<float>(
        mapValue(map, 0, 2 * kPi * static_cast<double>(a) / static_cast<double>(na * r), k, true));
  });
  PlannerSettings s;
  s.alpha_max = 2.0 * angleStep(fine) / 0.01;
  s.omega_max = 4.0 * angleStep(fine) / 0.1;
  const PlanResult a = planDpRefined(map, 0, s, true, static_cast<int>(r));
  const PlanResult b = planDp(fine, 0, s, true);
  ASSERT_EQ(a.status, Status::kExact) << a.reason;
  ASSERT_EQ(b.status, Status::kExact) << b.reason;
  ASSERT_EQ(a.theta.size(), b.theta.size());
  for (std::size_t k = 0; k < a.theta.size(); ++k) EXPECT_NEAR(a.theta[k], b.theta[k], 1e-12);
  EXPECT_NEAR(a.terms.total, b.terms.total, 1e-6 * b.terms.total);
}

}  // namespace
