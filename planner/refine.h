#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <scanplan/planner/config_map.h>
#include <scanplan/planner/objective.h>

namespace scanplan::planner {

/// Budget and tolerances of refinePath(). The defaults refine a 1000-sample path in well under
/// a second; the evaluation budget, not the clock, is meant to stop a run (see time_limit_s).
struct RefineSettings {
  /// Objective evaluations over the whole run (each costs O(N)), a hard cap. >= 1. A
  /// 1000-sample path typically needs 200–1000.
  int max_evaluations = 10000;
  /// s, wall-clock backstop (0: none). A run it stops depends on the machine's speed, so it is
  /// not reproducible; `stop_reason` says when that happened.
  double time_limit_s = 5.0;
  /// Relative change of the merit function, and of the (preconditioned) variables, that ends one
  /// L-BFGS run.
  double ftol_rel = 1e-12;
  double xtol_rel = 1e-12;
  /// Constraint violation that ends the augmented-Lagrangian rounds, relative to ω_max, α_max
  /// and the grid step (< 1e-6, the tightening of the bounds). Every round's end is judged by
  /// evaluate() in any case.
  double constraint_tol = 1e-10;
  /// Hold θ_0 at the input's value (a path planned from a fixed start angle).
  bool keep_start = false;
};

/// What refinePath() did. `theta` is either a strictly better feasible path or the input itself.
struct RefineResult {
  std::vector<double> theta;  ///< rad, unwrapped, one per time sample (see evaluate())
  ObjectiveTerms before;      ///< evaluate() of the input
  ObjectiveTerms after;       ///< evaluate() of `theta` (== before when !improved)
  bool improved = false;      ///< after.total < before.total (and theta differs from the input)
  int evaluations = 0;        ///< objective evaluations spent
  double seconds = 0.0;       ///< wall time
  std::string algorithm;      ///< the optimiser, for reports
  std::string stop_reason;    ///< why the optimiser stopped, and why the input was kept if it was
};

/// Refinement (docs/design.md §5.4): moves a feasible path off the grid to lower
/// J = evaluate(map, branch, theta, settings, continuous).total in continuous θ (f read with
/// mapValue(), ω and α the finite differences of evaluate()), keeping |ω_k| ≤ ω_max,
/// |α_k| ≤ α_max and f(θ_k, t_k) > 0.
///
/// Method: each θ_k is boxed to the run of consecutive grid angles with f > 0 (at time t_k) that
/// holds the input's θ_k, so f > 0 holds inside and the path keeps its way between the forbidden
/// regions (refinement is local). The speed and acceleration bounds (tightened by 1e-6 relative,
/// but never below the input's own value) and the boxes are sparse linear inequality constraints
/// handled by an augmented Lagrangian (Powell–Hestenes–Rockafellar) that costs O(N) per
/// evaluation. A round minimises it for fixed multipliers with NLopt's LD_LBFGS in preconditioned
/// variables y, θ = θ₀ + L⁻ᵀy, L the banded Cholesky factor of the merit's Hessian at θ₀
/// (pentadiagonal: −ln f is diagonal in θ, the ω and α terms are first and second differences),
/// rebuilt every 25 evaluations; then the multipliers are updated and, when the violation did not
/// shrink enough, the penalty. f is piecewise linear in θ; its corners at grid angles are rounded
/// (C¹) over ±0.1, then ±0.01, then ±0.001 grid steps, each stage warm-started from the last.
///
/// Guarantees: the result is judged by evaluate() alone. It is returned only when evaluate()
/// calls it feasible and its J is strictly lower than the input's; otherwise the input comes back
/// unchanged with improved = false and the reason in stop_reason. So J never increases and the
/// result is always feasible. Deterministic: the same inputs give bit-identical `theta` unless
/// the time limit stops the run. Throws std::invalid_argument when the input path is infeasible
/// per evaluate() or not finite, or the settings are out of range, and std::logic_error (from
/// evaluate()) when `theta` does not have one angle per time sample or the map/branch is broken.
RefineResult refinePath(const ConfigMap& map,
                        std::size_t branch,
                        const std::vector<double>& theta,
                        const PlannerSettings& settings,
                        bool continuous,
                        const RefineSettings& rs = {});

namespace detail {

/// The smooth problem refinePath() hands to NLopt, exposed for the derivative tests. Variables:
/// θ_0..θ_{N−1} (rad). Constraints g_i(θ) ≤ 0, dimensionless, in this order:
///   for k = 1..N−1:  (±ω_k − b_i)/ω_max, "+" first     (b_i = (1 − margin)·ω_max)
///   for k = 2..N−1:  (±α_k − b_i)/α_max, "+" first     (b_i = (1 − margin)·α_max)
///   for k = 0..N−1:  (θ_k − hi_k)/Δθ, then (lo_k − θ_k)/Δθ   (the boxes, Δθ the grid step)
/// (a zero bound scales by 1 instead), with ω_k, α_k formed as in evaluate(). The boxes are
/// ±infinity until setBoxes(); a sample with lo_k = hi_k is fixed, and merit(), meritHessian()
/// and updateMultipliers() leave out every constraint on fixed samples only (it is constant).
class RefineProblem {
 public:
  struct JacobianEntry {
    std::size_t constraint, variable;
    double value;
  };
  /// A symmetric pentadiagonal matrix: diag[k] = H(k,k), sub1[k] = H(k,k−1), sub2[k] = H(k,k−2)
  /// (sub1[0], sub2[0], sub2[1] unused).
  struct Band {
    std::vector<double> diag, sub1, sub2;
  };

  /// `f_floor` > 0: below it −ln f is continued by its second-order Taylor polynomial
  /// −ln f_floor − (f − f_floor)/f_floor + (f − f_floor)²/(2 f_floor²), so the merit stays
  /// finite where f = 0 (refinePath() picks it below every f inside the boxes).
  RefineProblem(const ConfigMap& map,
                std::size_t branch,
                const PlannerSettings& settings,
                bool continuous,
                std::size_t samples,
                double f_floor,
                double bound_margin);

  std::size_t size() const { return n_; }
  std::size_t constraintCount() const;
  double angleStep() const { return grid_.angle_step; }
  /// Box of each θ_k (rad), lo[k] ≤ hi[k].
  void setBoxes(std::vector<double> lo, std::vector<double> hi);
  /// Raises each speed and acceleration bound b_i that θ exceeds to θ's value, so θ (a path
  /// feasible for evaluate(), possibly at a bound) is feasible for the tightened constraints too.
  void relaxBoundsTo(const double* theta);
  /// r of fModel(), grid steps in (0, 0.5]; 1e-3 until set.
  void setKinkRadius(double radius);

  /// f of the model at θ (rad), time sample k, and its first two derivatives (1/rad, 1/rad²):
  /// the cells interpolated linearly (also towards a cell with f = 0, and towards 0 past a limited
  /// table's ends), each corner at a grid angle rounded over ±r grid steps (setKinkRadius()) by
  /// the quadratic that joins both lines with their slopes, so f is C¹ and L-BFGS meets no kinks.
  /// Equal to mapValue() at least r grid steps from grid angles, between two cells with f > 0.
  struct FValue {
    double f, df, d2f;
  };
  FValue fModel(double theta, std::size_t k) const noexcept;
  /// The run of grid angles with f > 0 at sample k around θ (rad) as an interval [lo, hi] in
  /// θ's turn (on a continuous table with the whole column open: one turn less a step either
  /// way), widened to contain θ, and the lowest f over it. Requires f(θ, k) > 0.
  void feasibleInterval(
      double theta, std::size_t k, double& lo, double& hi, double& f_min) const noexcept;
  /// J of evaluate() with the model's f (and the continuation below f_floor); its gradient when
  /// non-null.
  double objective(const double* theta, double* grad) const noexcept;
  /// g (constraintCount() values) and, when non-null, the non-zero Jacobian entries ∂g_i/∂θ_j.
  void constraints(const double* theta,
                   double* g,
                   std::vector<JacobianEntry>* jacobian = nullptr) const;
  /// PHR augmented Lagrangian: objective + Σ_i (max(0, λ_i + ρ g_i)² − λ_i²)/(2ρ); gradient
  /// when non-null. `lambda` has constraintCount() entries ≥ 0, ρ > 0.
  double merit(const double* theta, const double* lambda, double rho, double* grad) const noexcept;
  /// The Hessian of merit() at θ where it is twice differentiable (no constraint at its switching
  /// point) and the model's f is not in a rounded valley corner: exact, since f is linear in θ
  /// within a cell (quadratic in a corner) and every constraint is linear. In valley corners the
  /// negative −f''/f term is left out, keeping the matrix positive semidefinite.
  Band meritHessian(const double* theta, const double* lambda, double rho) const;
  /// λ_i ← max(0, λ_i + ρ g_i); returns max_i max(0, g_i) at θ (the violation before the update).
  double updateMultipliers(const double* theta, double* lambda, double rho) const noexcept;

 private:
  struct Term {  // one non-zero of a constraint's gradient: ∂g/∂θ_j = d
    std::size_t j;
    double d;
  };
  // Calls visit(i, g_i, terms, term count) for every constraint, in order.
  template <class Visit>
  void visitConstraints(const double* theta, Visit&& visit) const noexcept;
  double cell(std::ptrdiff_t angle, std::size_t k) const noexcept;  // 0 off a limited table
  bool movable(const Term* t, std::size_t count) const noexcept;    // touches a free sample

  const ConfigMap& map_;
  Grid grid_;
  std::size_t branch_;
  PlannerSettings settings_;
  bool continuous_;
  std::size_t n_;
  double f_floor_, omega_scale_, alpha_scale_;
  double kink_radius_ = 1e-3;
  std::vector<double> lo_, hi_;
  std::vector<double> bound_;  // b_i of the speed and acceleration constraints
};

}  // namespace detail

}  // namespace scanplan::planner
