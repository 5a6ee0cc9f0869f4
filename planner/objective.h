#pragma once

#include <cstddef>
#include <vector>

#include <scanplan/planner/config_map.h>

namespace scanplan::planner {

/// Weights and bounds of the planning problem (docs/design.md §5), SI units. The objective's
/// integrand is dimensionless, so J is in seconds: k_omega is in s²/rad² (k_omega·ω² is
/// dimensionless like −ln f) and k_alpha in s⁴/rad².
struct PlannerSettings {
  double k_omega = 1.0;                   ///< s²/rad²
  double k_alpha = 0.1;                   ///< s⁴/rad²
  double omega_max = 0.5235987755982988;  ///< rad/s, |ω| bound (placeholder 30°/s)
  double alpha_max = 1.0471975511965976;  ///< rad/s², |α| bound (placeholder 60°/s²)
};

/// Relative tolerance on the speed and acceleration bounds when judging a path feasible.
inline constexpr double kBoundTolerance = 1e-9;

/// f of `branch` at table angle `theta` (rad) and time sample `t`, linearly interpolated between
/// the two neighbouring grid angles (an angle within 1e-9 grid steps of a grid angle reads that
/// cell exactly). Between a cell with f > 0 and a cell with f = 0 it reads 0: the map says
/// nothing about the poses in between (they may already be unreachable or colliding), so paths
/// only leave grid angles between two feasible cells. A continuous table's grid wraps modulo 2π;
/// for a limited table an angle outside [angles.front(), angles.back()] reads 0.
double mapValue(
    const ConfigMap& map, std::size_t branch, double theta, std::size_t t, bool continuous);

/// The objective and the path's limits, each term in s (see PlannerSettings).
struct ObjectiveTerms {
  double cost_f = 0.0;           ///< Σ_k −ln f(θ_k, t_k)·Δt (+inf where f = 0)
  double cost_omega = 0.0;       ///< Σ_{k≥1} k_ω·ω_k²·Δt
  double cost_alpha = 0.0;       ///< Σ_{k≥2} k_a·α_k²·Δt
  double total = 0.0;            ///< J, the sum of the three
  double min_f = 0.0;            ///< lowest f along the path
  std::size_t min_f_sample = 0;  ///< where (first such sample)
  double max_abs_omega = 0.0;    ///< rad/s
  double max_abs_alpha = 0.0;    ///< rad/s²
  bool feasible = false;         ///< f > 0 everywhere, bounds kept within kBoundTolerance
};

/// Scores a path: `theta` holds one table angle per time sample of the map (rad, unwrapped:
/// consecutive differences are the real motion, so a continuous table may pass 2π). With
/// Δt the uniform time step, ω_k = (θ_k − θ_{k−1})/Δt and α_k = (ω_k − ω_{k−1})/Δt:
/// J = Σ_k −ln f(θ_k, t_k)·Δt + Σ_{k≥1} k_ω·ω_k²·Δt + Σ_{k≥2} k_a·α_k²·Δt.
/// Requires theta.size() == map.times.size() ≥ 2 and a valid branch.
ObjectiveTerms evaluate(const ConfigMap& map,
                        std::size_t branch,
                        const std::vector<double>& theta,
                        const PlannerSettings& settings,
                        bool continuous);

namespace detail {
/// Grid geometry shared by the planners: origin and step of the angle grid (rad), time step (s).
struct Grid {
  double angle0 = 0.0, angle_step = 0.0, dt = 0.0;
};
/// Checks the map and branch (throws std::logic_error on a broken invariant).
Grid gridOf(const ConfigMap& map, std::size_t branch, bool continuous);
/// mapValue() with the grid already derived and checked: the planners' inner loops.
double mapValue(const ConfigMap& map,
                const Grid& grid,
                std::size_t branch,
                double theta,
                std::size_t t,
                bool continuous) noexcept;
}  // namespace detail

}  // namespace scanplan::planner
