#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <scanplan/planner/config_map.h>
#include <scanplan/planner/objective.h>
#include <scanplan/planner/plan_result.h>

namespace scanplan::planner {

/// The exact optimum of the discretised problem (docs/design.md §5.2): dynamic programming over
/// (grid angle, previous step). The path sits on grid angles and moves an integer number d_k of
/// grid steps Δθ per time sample, with |d_k|·Δθ/Δt ≤ ω_max and, from the second step on,
/// |d_k − d_{k−1}|·Δθ/Δt² ≤ α_max (the first step is free, as in evaluate()). Cost per time
/// sample N_θ·W·(2A+1) ≤ N_θ·W², W = 2D+1, D = floor(ω_max·Δt/Δθ), A = floor(α_max·Δt²/Δθ).
///
/// Resolution caveat: when α_max·Δt²/Δθ < 1 (A = 0) no speed change is representable on the
/// grid, so the only paths are constant-speed ones (d_k = d_1 for every k); the bounds are never
/// relaxed to compensate — refine the angle grid or coarsen Δt instead. Likewise D = 0 leaves
/// only standing still.
///
/// A continuous table's grid wraps (the returned path is unwrapped by accumulating steps); a
/// limited table's path stays within [angles.front(), angles.back()]. Steps are limited to less
/// than one grid turn (|d| ≤ N_θ − 1). `start_theta` (rad), when given, fixes the first sample
/// to the nearest grid angle (for a continuous table on the same turn as start_theta). The
/// returned terms are the DP's own and equal evaluate() of the path up to summation order.
/// Deterministic (TBB over angles, each cell computed independently). The layers are held
/// step-major and relaxed over angles in vector lanes; path and J are those of
/// detail::planDpReference bit for bit.
PlanResult planDp(const ConfigMap& map,
                  std::size_t branch,
                  const PlannerSettings& settings,
                  bool continuous,
                  std::optional<double> start_theta = {});

/// The smallest angle-grid subdivision r (1 ≤ r ≤ max_subdivisions) for which the grid step
/// Δθ/r resolves at least `accel_steps` acceleration levels each way (A ≥ accel_steps in
/// planDp's terms); max_subdivisions when none does.
int autoAngleSubdivisions(const ConfigMap& map,
                          std::size_t branch,
                          const PlannerSettings& settings,
                          bool continuous,
                          int accel_steps = 3,
                          int max_subdivisions = 16);

/// planDp on a finer angle grid: every map step Δθ split into `subdivisions` equal steps, f on
/// the new grid angles read with mapValue() (the same linear interpolation every planner and
/// evaluate() use), so the optimum is exact for the finer discretisation and its J is the J of
/// evaluate() on the original map. subdivisions = 1 is planDp itself. The returned terms are
/// evaluate()'s on `map`.
PlanResult planDpRefined(const ConfigMap& map,
                         std::size_t branch,
                         const PlannerSettings& settings,
                         bool continuous,
                         int subdivisions,
                         std::optional<double> start_theta = {});

namespace detail {
/// The relaxation kernel of planDp, chosen at run time (the build assumes no more than
/// x86-64): kBest is the widest this CPU runs — AVX-512, AVX2, else the portable one (SSE2 on
/// x86-64). All give the same results bit for bit; tests and bench_dp run each.
enum class DpKernel { kBest, kPortable, kAvx2, kAvx512 };

/// Whether this CPU runs `kernel` (kBest and kPortable always).
bool dpKernelAvailable(DpKernel kernel);

/// planDp with the given kernel (planDp is kBest); std::logic_error if !dpKernelAvailable.
PlanResult planDpWithKernel(const ConfigMap& map,
                            std::size_t branch,
                            const PlannerSettings& settings,
                            bool continuous,
                            DpKernel kernel,
                            std::optional<double> start_theta = {});

/// planDp with each layer relaxed the straightforward way (docs/design.md §5.2, one (angle, step)
/// cell at a time): the reference planDp must equal bit for bit (tests, bench_dp).
PlanResult planDpReference(const ConfigMap& map,
                           std::size_t branch,
                           const PlannerSettings& settings,
                           bool continuous,
                           std::optional<double> start_theta = {});
}  // namespace detail

}  // namespace scanplan::planner
