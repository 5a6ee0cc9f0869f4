#pragma once

#include <cstddef>
#include <optional>

#include "planner/config_map.h"
#include "planner/dp_planner.h"
#include "planner/objective.h"

namespace scanplan::planner {

/// Parameters of Ray Shooting (DESIGN.md §5.1); placeholder defaults.
struct RayShootingSettings {
  int rays = 21;     ///< N_a candidate accelerations evenly over [−α_max, α_max] (0 when odd)
  int horizon = 15;  ///< H, samples each ray holds its acceleration (fewer near the end)
  int starts = 36;   ///< start angles tried across the first column when no start is given
  double blocked_penalty = 1e3;  ///< s, added per ray step not completed (f = 0 reached)
};

/// Ray Shooting (DESIGN.md §5.1), a receding-horizon heuristic in continuous (unwrapped) θ.
/// From the state (θ_k, ω_k) every candidate acceleration a is held for up to H samples:
/// ω_{j+1} = clamp(ω_j + a·Δt, ±ω_max), θ_{j+1} = θ_j + ω_{j+1}·Δt (so ω and α are exactly
/// evaluate()'s finite differences and |α| ≤ α_max). A ray costs the objective terms of its steps
/// (f read with mapValue(), the α term from sample 2 on as in evaluate()); a ray reaching f = 0
/// (or leaving a limited table) stops there and costs what it had plus blocked_penalty per step
/// not completed. The best ray's first step is applied (a ray blocked on its first step is never
/// applied; ties go to the lowest |a|, then the lowest a), and so on to the last sample.
///
/// Each run starts from rest (ω_0 = 0). With `start_theta` (rad) one run starts there; otherwise
/// up to `starts` runs start from grid angles spread evenly over the first column's cells with
/// f > 0, and the feasible path with the lowest J = evaluate() wins (ties: the lower start angle
/// index). The runs advance in lockstep; every 10 samples a run that has come within half a grid
/// step (θ) and half an acceleration step (α_max·Δt, ω) of another run's state at a higher cost
/// so far is dropped — from nearly the same state both would shoot nearly the same rays — so
/// starts that collapse into one corridor cost one run. Each ray stops as soon as its partial
/// cost exceeds the best complete ray's (every term is ≥ 0), which does not change the choice. kExact only when evaluate() calls the path feasible; otherwise kNoPath with the reason
/// (the furthest time sample any run reached, and why it stopped). Deterministic: the runs are
/// independent (TBB over starts) and combined in start order.
PlanResult planRayShooting(const ConfigMap& map,
                           std::size_t branch,
                           const PlannerSettings& settings,
                           bool continuous,
                           const RayShootingSettings& rs,
                           std::optional<double> start_theta = {});

}  // namespace scanplan::planner
