#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <optional>

#include <scanplan/planner/config_map.h>
#include <scanplan/planner/dp_planner.h>
#include <scanplan/planner/objective.h>

namespace scanplan::planner {

/// Which OMPL control planner searches (docs/design.md §5.3).
enum class OmplPlanner {
  kSst,  ///< ompl::control::SST: asymptotically near-optimal, keeps improving J until stopped
  kRrt,  ///< ompl::control::RRT: feasibility only (J is scored, not optimised); stops when solved
};

/// Parameters of the OMPL search. Distances in OMPL's state space (the SST radii) are in
/// "steps": one time sample = 1, an angle difference of ω_max·Δt = 1 (one sample at full speed),
/// a speed difference of α_max·Δt = 1 (one sample at full acceleration), summed (weighted L1).
struct OmplSettings {
  double time_limit_s = 1.0;  ///< s, wall-clock budget of OMPL's solve()
  /// Seed of OMPL's random numbers (0 is used as 1: OMPL rejects a zero seed).
  std::uint32_t seed = 1;
  /// Cap on planner iterations, 0 = none. With a cap reached before the clock the result is a
  /// function of (map, settings, seed) only; a run cut by the clock depends on machine speed.
  std::size_t max_iterations = 0;
  /// Polled at every iteration: true ends the search (planner::Termination::cancel).
  const std::atomic<bool>* cancel = nullptr;
  OmplPlanner planner = OmplPlanner::kSst;
  int max_steps = 50;             ///< a control (target speed) is held for 1..max_steps samples
  std::size_t starts = 36;        ///< start cells spread over the first column's f > 0 (0 = all)
  double goal_bias = 0.05;        ///< share of samples drawn on the last time sample
  double stop_probability = 0.2;  ///< share of sampled controls with target speed exactly 0
  /// SST δ_BN, steps (see above): the cheapest tree node this close to a sample is extended.
  double selection_radius = 40.0;
  /// SST δ_s, steps: one active node per witness ball. Larger radii prune harder (a smaller tree
  /// on long horizons) but can starve a corridor narrower than the radius.
  double pruning_radius = 3.0;
  bool stop_at_first_solution = false;  ///< SST: stop at the first exact solution
};

/// The planning problem (docs/design.md §5) as an OMPL control problem (§5.3). State: table angle θ
/// (SO(2) for a continuous table, [angles.front(), angles.back()] for a limited one), speed
/// ω ∈ [−ω_max, ω_max], time sample k, and the objective accumulated so far (not part of the
/// distance). Control: a target speed u·ω_max, u ∈ [−1, 1], held for 1..max_steps samples of Δt
/// each and tracked at full acceleration: one sample steps ω' = ω + clamp(u·ω_max − ω,
/// ±α_max·Δt), θ' = θ + ω'·Δt, k' = k + 1 — except the first sample from k = 0, where
/// ω' = u·ω_max (evaluate() bounds no speed change into sample 1). So ω and α are exactly
/// evaluate()'s finite differences, and holding a control reaches and keeps a constant speed
/// (standing still included), which a held acceleration would not. Valid: |ω| ≤ ω_max and
/// f(θ, k) > 0 (mapValue()). Goal: k = the last time sample. Cost of a motion: the J terms of its
/// samples (including −ln f of the start sample), so the OMPL path cost is J.
///
/// Starts: `start_theta` (rad) when given, else `starts` grid angles of the first column with
/// f > 0 (several start states of one problem). A time column with f = 0 everywhere (or a
/// blocked start) is reported before OMPL runs.
///
/// kExact only with an exact OMPL solution whose per-sample path (one angle per time sample,
/// unwrapped, first = the start) evaluate() calls feasible; `terms` = evaluate() of it. Otherwise
/// `theta` empty, `reason` naming the first time sample not reached, and the status: kApproximate
/// when OMPL ended with only an approximate solution (the furthest sample it reached is in
/// `reason`), kTimeout when OMPL reports a timeout without one, kNoPath otherwise; `detail`
/// (always) the planner, OMPL's status, solve time and iterations.
///
/// Determinism: OMPL draws every seed from one process-wide generator, so calls are serialised
/// (a process-wide mutex) and the generator is reseeded with `seed` before anything is built.
/// With `max_iterations` ending the search the result repeats exactly, in one process or across
/// processes; OMPL used elsewhere in the process at the same time would break that. The planner
/// itself is single-threaded. OMPL's console output is silenced during the call (the log level
/// is restored afterwards).
PlanResult planOmpl(const ConfigMap& map,
                    std::size_t branch,
                    const PlannerSettings& settings,
                    bool continuous,
                    const OmplSettings& os,
                    std::optional<double> start_theta = {});

}  // namespace scanplan::planner
