#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include <scanplan/planner/config_map.h>
#include <scanplan/planner/dp_planner.h>
#include <scanplan/planner/objective.h>

namespace scanplan::planner {

/// Parameters of Ray Shooting (docs/design.md §5.1).
struct RayShootingSettings {
  int rays = 21;    ///< N_a candidate accelerations evenly over [−α_max, α_max] (0 when odd)
  int horizon = 5;  ///< H, samples each ray holds its acceleration (fewer near the end)
  int starts = 36;  ///< start angles tried across the first column when no start is given
  double blocked_penalty = 1e3;  ///< s, per time sample a ray or the cost-to-go does not reach
  /// Score each ray's end state by a cost-to-go (detail::costToGo()) on top of its own steps;
  /// false: the seed's plain horizon cost (then a horizon of 10–20 suits better).
  bool cost_to_go = true;
  /// When no run reaches the end, return DP's optimum (planDpRefined()) if it has one.
  bool dp_fallback = true;
};

/// Ray Shooting (docs/design.md §5.1), a receding-horizon heuristic in continuous (unwrapped) θ.
/// From the state (θ_k, ω_k) every candidate acceleration a is held for up to H samples:
/// ω_{j+1} = clamp(ω_j + a·Δt, ±ω_max), θ_{j+1} = θ_j + ω_{j+1}·Δt (so ω and α are exactly
/// evaluate()'s finite differences and |α| ≤ α_max). A ray costs the objective terms of its steps
/// (f read with mapValue(), the α term from sample 2 on as in evaluate()); a ray reaching f = 0
/// (or leaving a limited table) stops there and costs what it had plus blocked_penalty per step
/// not completed. The best ray's first step is applied (a ray blocked on its first step is never
/// applied; ties go to the lowest |a|, then the lowest a), and so on to the last sample.
///
/// What this adds to the seed (`cost_to_go`, on by default): a ray's score also counts
/// the rest of the scan. The cost-to-go — a DP over (grid angle, stage sample) relaxed to
/// constant-speed stages without the α term, built once per call (detail::costToGo()) — is added
/// at the ray's end, which is moved (by less than one stage) onto a stage sample; a blocked ray
/// pays blocked_penalty per sample to the end of the scan, as the cost-to-go does, so every
/// score is on one scale: "reaches further" first, then "costs less". A greedy horizon alone
/// cannot see which corridor closes later; the cost-to-go can, and the rays keep the speed and
/// acceleration bounds it leaves out. Plain Ray Shooting was 38–222 % above the DP optimum on the
/// bench maps, the guided one is within a few per cent (tests/bench/README.md, bench_planners).
///
/// Each run starts from rest (ω_0 = 0). With `start_theta` (rad) one run starts there; otherwise
/// up to `starts` runs start from grid angles spread evenly over the first column's cells with
/// f > 0 — with the cost-to-go also the best cell of each run of open cells (corridor) by
/// −ln f·Δt + cost-to-go — and the feasible path with the lowest J = evaluate() wins (ties: the
/// lower start angle). The runs advance in lockstep; every 10 samples a run that has come within
/// half a grid step (θ) and half an acceleration step (α_max·Δt, ω) of another run's state at a
/// higher cost so far is dropped — from nearly the same state both would shoot nearly the same
/// rays — so starts that collapse into one corridor cost one run. Each ray stops as soon as its
/// partial cost exceeds the best complete ray's (every term is ≥ 0), which does not change the
/// choice.
///
/// kExact only when evaluate() calls the path feasible. When no run reaches the end and
/// `dp_fallback` is set, DP's optimum on the auto grid is returned if it has one (kExact, with
/// `detail` saying so): rays in continuous θ cannot pass a gap one grid cell wide, DP can, so
/// Ray Shooting never reports "no path" where DP has one. Otherwise kNoPath with the reason (the
/// furthest time sample any run reached, and why it stopped). Deterministic: the runs are
/// independent (TBB over starts) and combined in start order.
PlanResult planRayShooting(const ConfigMap& map,
                           std::size_t branch,
                           const PlannerSettings& settings,
                           bool continuous,
                           const RayShootingSettings& rs,
                           std::optional<double> start_theta = {});

namespace detail {

/// The cost-to-go that guides Ray Shooting: a DP from the last sample backwards over
/// (grid angle, stage sample), stages `stride` samples apart and ending at the last sample. A
/// stage step moves d ∈ [−D, D] grid steps at constant speed, D = ⌈ω_max·stride·Δt/Δθ⌉ (rounded
/// up, so the grid does not close a corridor the table can just keep up with), with f
/// interpolated as mapValue() does on every sample it passes, and costs the objective's f and ω
/// terms; the α term and bound are left to the rays. An estimate, not a bound (the grid and the
/// constant-speed stages cut both ways), cheap next to DP: no acceleration state. A
/// step that meets f = 0 at sample i costs what it had plus blocked_penalty per sample from i to
/// the end, so every value is finite and ranks "gets further" before "costs less".
struct CostToGo {
  std::size_t stride = 1;  ///< samples per stage: the fewest with ω_max·stride·Δt ≥ 3 Δθ, ≤ 16
  int max_step = 0;        ///< D, grid steps per stage
  std::vector<double> value;  ///< s, per stage (from the last sample back) × grid angle
  /// The value (s) at θ (rad) and stage sample k, linear between grid angles: the cost from k
  /// on, f at k excluded. Requires (last sample − k) % stride == 0.
  double at(const ConfigMap& map,
            const Grid& g,
            double theta,
            std::size_t k,
            bool continuous) const noexcept;
};

/// Builds the cost-to-go of `branch`: N_θ·stride·N_t logarithms (TBB over samples) and
/// N_θ·(2D+1)·N_t additions; deterministic.
CostToGo costToGo(const ConfigMap& map,
                  std::size_t branch,
                  const PlannerSettings& settings,
                  bool continuous,
                  double blocked_penalty);

}  // namespace detail

}  // namespace scanplan::planner
