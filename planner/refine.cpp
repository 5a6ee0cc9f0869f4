#include "planner/refine.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlopt.hpp>

namespace scanplan::planner {

namespace detail {

namespace {

// One non-zero of a constraint's gradient: ∂g/∂θ_j.
struct Term {
  std::size_t j;
  double d;
};

}  // namespace

RefineProblem::RefineProblem(const ConfigMap& map,
                             std::size_t branch,
                             const PlannerSettings& settings,
                             bool continuous,
                             std::size_t samples,
                             double f_floor,
                             double bound_margin)
    : map_(map),
      grid_(gridOf(map, branch, continuous)),
      branch_(branch),
      settings_(settings),
      continuous_(continuous),
      n_(samples),
      f_floor_(f_floor),
      omega_bar_((1.0 - bound_margin) * settings.omega_max),
      alpha_bar_((1.0 - bound_margin) * settings.alpha_max),
      omega_scale_(settings.omega_max > 0.0 ? settings.omega_max : 1.0),
      alpha_scale_(settings.alpha_max > 0.0 ? settings.alpha_max : 1.0) {
  if (samples != map.times.size() || !(f_floor > 0.0)) {
    throw std::logic_error("RefineProblem: one variable per time sample and f_floor > 0");
  }
}

std::size_t RefineProblem::constraintCount() const {
  return 2 * (n_ - 1) + (n_ >= 2 ? 2 * (n_ - 2) : 0);
}

double RefineProblem::cell(std::ptrdiff_t angle, std::size_t k) const noexcept {
  const auto na = static_cast<std::ptrdiff_t>(map_.angles.size());
  if (continuous_) {
    angle = ((angle % na) + na) % na;
  } else if (angle < 0 || angle >= na) {
    return 0.0;
  }
  return static_cast<double>(map_.f[map_.index(branch_, static_cast<std::size_t>(angle), k)]);
}

void RefineProblem::fAndSlope(double theta,
                              std::size_t k,
                              double& f,
                              double& slope) const noexcept {
  // The value is mapValue()'s own, so the model and evaluate() read the same f.
  f = mapValue(map_, grid_, branch_, theta, k, continuous_);
  slope = 0.0;
  if (!(f > 0.0)) return;
  const auto na = static_cast<std::ptrdiff_t>(map_.angles.size());
  // The cell mapValue() interpolates in, found the same way (wrap, then snap to grid angles).
  double u = (theta - grid_.angle0) / grid_.angle_step;
  if (continuous_) {
    u = std::fmod(u, static_cast<double>(na));
    if (u < 0.0) u += static_cast<double>(na);
  }
  if (std::abs(u - std::round(u)) <= 1e-9) u = std::round(u);
  auto i0 = static_cast<std::ptrdiff_t>(std::floor(u));
  if (!continuous_ && i0 >= na - 1) i0 = na - 2;  // the last angle: the cell below
  slope = (cell(i0 + 1, k) - cell(i0, k)) / grid_.angle_step;
}

void RefineProblem::feasibleInterval(
    double theta, std::size_t k, double& lo, double& hi, double& f_min) const noexcept {
  const auto na = static_cast<std::ptrdiff_t>(map_.angles.size());
  const double step = grid_.angle_step;
  // Grid index in θ's own turn (not wrapped), snapped as mapValue() snaps.
  double u = (theta - grid_.angle0) / step;
  if (std::abs(u - std::round(u)) <= 1e-9) u = std::round(u);
  const auto below = static_cast<std::ptrdiff_t>(std::floor(u));
  const std::ptrdiff_t above = static_cast<double>(below) == u ? below : below + 1;
  double f = 0.0, slope = 0.0;
  fAndSlope(theta, k, f, slope);
  f_min = f;
  // Walk out over open cells; a fully open column of a continuous table stops one turn out.
  std::ptrdiff_t a_lo = below, a_hi = above;
  const bool lo_open = cell(below, k) > 0.0, hi_open = cell(above, k) > 0.0;
  if (lo_open) {
    f_min = std::min(f_min, cell(below, k));
    while (a_lo - 1 > below - na && cell(a_lo - 1, k) > 0.0) f_min = std::min(f_min, cell(--a_lo, k));
  }
  if (hi_open) {
    f_min = std::min(f_min, cell(above, k));
    while (a_hi + 1 < above + na && cell(a_hi + 1, k) > 0.0) f_min = std::min(f_min, cell(++a_hi, k));
  }
  // A closed neighbour cell (θ inside a cell whose far end has f = 0, only possible if mapValue()
  // interpolates towards 0) caps the interval at θ itself.
  lo = lo_open ? std::min(theta, grid_.angle0 + static_cast<double>(a_lo) * step) : theta;
  hi = hi_open ? std::max(theta, grid_.angle0 + static_cast<double>(a_hi) * step) : theta;
}

double RefineProblem::objective(const double* theta, double* grad) const noexcept {
  const double dt = grid_.dt, k_w = settings_.k_omega, k_a = settings_.k_alpha;
  if (grad != nullptr) std::fill(grad, grad + n_, 0.0);
  double cost_f = 0.0, cost_w = 0.0, cost_a = 0.0;
  for (std::size_t k = 0; k < n_; ++k) {
    double f = 0.0, slope = 0.0;
    fAndSlope(theta[k], k, f, slope);
    double c = 0.0, dc_df = 0.0;
    if (f >= f_floor_) {
      c = -std::log(f);
      dc_df = -1.0 / f;
    } else {
      // Second-order Taylor polynomial of −ln f at the floor: finite (and still pushing up the
      // slope) where f = 0, so the line search never sees an infinity.
      const double d = (f - f_floor_) / f_floor_;
      c = -std::log(f_floor_) - d + 0.5 * d * d;
      dc_df = (d - 1.0) / f_floor_;
    }
    cost_f += c * dt;
    if (grad != nullptr) grad[k] += dc_df * slope * dt;
  }
  double omega_prev = 0.0;
  for (std::size_t k = 1; k < n_; ++k) {
    // The finite differences exactly as evaluate() forms them.
    const double omega = (theta[k] - theta[k - 1]) / dt;
    cost_w += k_w * omega * omega * dt;
    if (grad != nullptr) {
      grad[k] += 2.0 * k_w * omega;
      grad[k - 1] -= 2.0 * k_w * omega;
    }
    if (k >= 2) {
      const double alpha = (omega - omega_prev) / dt;
      cost_a += k_a * alpha * alpha * dt;
      if (grad != nullptr) {
        const double d = 2.0 * k_a * alpha / dt;  // ∂(k_a α² Δt)/∂θ_k, α = Δ²θ/Δt²
        grad[k] += d;
        grad[k - 1] -= 2.0 * d;
        grad[k - 2] += d;
      }
    }
    omega_prev = omega;
  }
  return cost_f + cost_w + cost_a;
}

template <class Visit>
void RefineProblem::visitConstraints(const double* theta, Visit&& visit) const noexcept {
  const double dt = grid_.dt;
  std::size_t i = 0;
  const double dw = 1.0 / (dt * omega_scale_);
  for (std::size_t k = 1; k < n_; ++k) {
    const double omega = (theta[k] - theta[k - 1]) / dt;
    const std::array<Term, 2> up{{{k, dw}, {k - 1, -dw}}}, down{{{k, -dw}, {k - 1, dw}}};
    visit(i++, (omega - omega_bar_) / omega_scale_, up.data(), up.size());
    visit(i++, (-omega - omega_bar_) / omega_scale_, down.data(), down.size());
  }
  const double da = 1.0 / (dt * dt * alpha_scale_);
  for (std::size_t k = 2; k < n_; ++k) {
    const double alpha =
        ((theta[k] - theta[k - 1]) / dt - (theta[k - 1] - theta[k - 2]) / dt) / dt;
    const std::array<Term, 3> up{{{k, da}, {k - 1, -2.0 * da}, {k - 2, da}}};
    const std::array<Term, 3> down{{{k, -da}, {k - 1, 2.0 * da}, {k - 2, -da}}};
    visit(i++, (alpha - alpha_bar_) / alpha_scale_, up.data(), up.size());
    visit(i++, (-alpha - alpha_bar_) / alpha_scale_, down.data(), down.size());
  }
}

void RefineProblem::constraints(const double* theta,
                                double* g,
                                std::vector<JacobianEntry>* jacobian) const {
  if (jacobian != nullptr) jacobian->clear();
  visitConstraints(theta, [&](std::size_t i, double value, const Term* t, std::size_t count) {
    g[i] = value;
    for (std::size_t c = 0; jacobian != nullptr && c < count; ++c) {
      jacobian->push_back({i, t[c].j, t[c].d});
    }
  });
}

double RefineProblem::merit(const double* theta,
                            const double* lambda,
                            double rho,
                            double* grad) const noexcept {
  double value = objective(theta, grad);
  double penalty = 0.0;
  visitConstraints(theta, [&](std::size_t i, double g, const Term* t, std::size_t count) {
    const double m = std::max(0.0, lambda[i] + rho * g);
    if (m == 0.0 && lambda[i] == 0.0) return;
    penalty += (m * m - lambda[i] * lambda[i]) / (2.0 * rho);
    for (std::size_t c = 0; grad != nullptr && c < count; ++c) grad[t[c].j] += m * t[c].d;
  });
  value += penalty;
  return value;
}

double RefineProblem::updateMultipliers(const double* theta,
                                        double* lambda,
                                        double rho) const noexcept {
  double violation = 0.0;
  visitConstraints(theta, [&](std::size_t i, double g, const Term*, std::size_t) {
    violation = std::max(violation, g);
    lambda[i] = std::max(0.0, lambda[i] + rho * g);
  });
  return violation;
}

}  // namespace detail

namespace {

// The optimiser works on bounds this much (relative) inside ω_max, α_max, so a point that meets
// them to constraint_tol ≪ this still passes evaluate()'s check.
constexpr double kBoundMargin = 1e-6;
// The continuation of −ln f starts at this fraction of the lowest f inside the boxes: never
// reached inside them, it only keeps the merit finite should a trial point leave them.
constexpr double kFloorFraction = 0.5;
// Augmented-Lagrangian schedule (Nocedal & Wright, Alg. 17.4 in spirit): the penalty grows ×10
// whenever a round did not cut the violation to a quarter.
constexpr double kRho0 = 1.0, kRhoGrowth = 10.0, kRhoMax = 1e10, kViolationShrink = 0.25;
constexpr int kMaxRounds = 30;
constexpr unsigned kLbfgsMemory = 10;
// Two rounds whose J differ by less than this (relative) with the bounds met end the run.
constexpr double kRoundJTol = 1e-10;

struct Context {
  const detail::RefineProblem* problem = nullptr;
  const double* lambda = nullptr;
  double rho = 1.0;
  int evaluations = 0;
  double best = std::numeric_limits<double>::infinity();
  std::vector<double> best_theta;
};

double meritCallback(unsigned n, const double* x, double* grad, void* data) {
  auto& c = *static_cast<Context*>(data);
  ++c.evaluations;
  const double v = c.problem->merit(x, c.lambda, c.rho, grad);
  // Keep the best point of the round ourselves: NLopt's x after a line-search failure is not
  // documented to be the best one seen.
  if (v < c.best) {
    c.best = v;
    std::copy(x, x + n, c.best_theta.begin());
  }
  return v;
}

}  // namespace

RefineResult refinePath(const ConfigMap& map,
                        std::size_t branch,
                        const std::vector<double>& theta,
                        const PlannerSettings& settings,
                        bool continuous,
                        const RefineSettings& rs) {
  const auto clock_start = std::chrono::steady_clock::now();
  const auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
  };
  if (!(settings.omega_max >= 0.0) || !(settings.alpha_max >= 0.0) ||
      !(settings.k_omega >= 0.0) || !(settings.k_alpha >= 0.0)) {
    throw std::invalid_argument("refinePath: bounds and weights must be >= 0");
  }
  if (rs.max_evaluations < 1 || !(rs.time_limit_s >= 0.0) || !(rs.ftol_rel >= 0.0) ||
      !(rs.xtol_rel >= 0.0) || !(rs.constraint_tol >= 0.0) ||
      rs.constraint_tol >= kBoundMargin) {
    throw std::invalid_argument(
        "refinePath: max_evaluations >= 1, time_limit_s, tolerances >= 0, constraint_tol < 1e-6");
  }
  for (std::size_t k = 0; k < theta.size(); ++k) {
    if (!std::isfinite(theta[k])) {
      throw std::invalid_argument(fmt::format("refinePath: theta[{}] is not finite", k));
    }
  }

  RefineResult result;
  result.algorithm = "augmented Lagrangian (PHR, sparse) over NLopt LD_LBFGS";
  result.theta = theta;
  result.before = evaluate(map, branch, theta, settings, continuous);
  result.after = result.before;
  if (!result.before.feasible) {
    throw std::invalid_argument(fmt::format(
        "refinePath: the input path is infeasible (min f {} at sample {}, max |omega| {} rad/s, "
        "max |alpha| {} rad/s^2)",
        result.before.min_f, result.before.min_f_sample, result.before.max_abs_omega,
        result.before.max_abs_alpha));
  }

  const std::size_t n = theta.size();
  // Boxes first (they do not depend on f_floor), then the problem with the floor below them.
  std::vector<double> lb(n), ub(n);
  double f_min = std::numeric_limits<double>::infinity();
  {
    const detail::RefineProblem probe(map, branch, settings, continuous, n, 1.0, kBoundMargin);
    for (std::size_t k = 0; k < n; ++k) {
      double box_f_min = 0.0;
      probe.feasibleInterval(theta[k], k, lb[k], ub[k], box_f_min);
      f_min = std::min(f_min, box_f_min);
    }
  }
  if (rs.keep_start) lb[0] = ub[0] = theta[0];
  const detail::RefineProblem problem(map, branch, settings, continuous, n, kFloorFraction * f_min,
                                      kBoundMargin);
  std::vector<double> lambda(problem.constraintCount(), 0.0);
  Context ctx;
  ctx.problem = &problem;
  ctx.best_theta.resize(n);

  nlopt::opt opt(std::getenv("REFINE_ALG") ? static_cast<nlopt::algorithm>(std::atoi(std::getenv("REFINE_ALG"))) : nlopt::LD_LBFGS, static_cast<unsigned>(n));
  opt.set_min_objective(meritCallback, &ctx);
  opt.set_ftol_rel(rs.ftol_rel);
  opt.set_xtol_rel(rs.xtol_rel);
  // NLopt's default L-BFGS memory is MEMAVAIL/n vectors (thousands for n = 1000), which makes each
  // iteration cost O(n·memory) instead of O(n).
  opt.set_vector_storage(kLbfgsMemory);
  opt.set_lower_bounds(lb);
  opt.set_upper_bounds(ub);

  std::vector<double> x = theta;
  double rho = kRho0;
  double prev_violation = std::numeric_limits<double>::infinity();
  double prev_j = problem.objective(x.data(), nullptr);
  std::string stop;
  int round = 0;
  for (;; ++round) {
    const int left = rs.max_evaluations - ctx.evaluations;
    if (left <= 0) {
      stop = fmt::format("evaluation budget ({}) spent", rs.max_evaluations);
      break;
    }
    opt.set_maxeval(left);
    if (rs.time_limit_s > 0.0) {
      const double remaining = rs.time_limit_s - elapsed();
      if (remaining <= 0.0) {
        stop = fmt::format("time limit ({} s) reached", rs.time_limit_s);
        break;
      }
      opt.set_maxtime(remaining);
    }
    ctx.lambda = lambda.data();
    ctx.rho = rho;
    ctx.best = std::numeric_limits<double>::infinity();
    nlopt::result status = nlopt::FAILURE;
    std::string failure;
    try {
      double value = 0.0;
      status = opt.optimize(x, value);
    } catch (const std::runtime_error& e) {  // roundoff_limited, forced_stop, failure
      failure = e.what();
    }
    if (ctx.best < std::numeric_limits<double>::infinity()) x = ctx.best_theta;
    const double violation = problem.updateMultipliers(x.data(), lambda.data(), rho);
    const double j = problem.objective(x.data(), nullptr);
    const bool met = violation <= rs.constraint_tol;
    if (std::getenv("REFINE_DEBUG")) fmt::print(stderr, "round {} rho {:g} evals {} status {} {} viol {:g} J {:.9f}\n", round, rho, ctx.evaluations, static_cast<int>(status), failure, violation, j);
    if (status == nlopt::MAXEVAL_REACHED) {
      stop = fmt::format("evaluation budget ({}) spent", rs.max_evaluations);
      break;
    }
    if (status == nlopt::MAXTIME_REACHED) {
      stop = fmt::format("time limit ({} s) reached", rs.time_limit_s);
      break;
    }
    // Round 0 starts with zero multipliers: if its minimiser already meets the bounds, it is the
    // constrained minimiser. Later rounds stop once J settles with the bounds met.
    if (met && (round == 0 || std::abs(j - prev_j) <= kRoundJTol * std::max(1.0, std::abs(j)))) {
      stop = "converged";
      break;
    }
    if (round + 1 >= kMaxRounds) {
      stop = fmt::format("{} augmented-Lagrangian rounds", kMaxRounds);
      break;
    }
    if (violation > kViolationShrink * prev_violation) rho = std::min(rho * kRhoGrowth, kRhoMax);
    prev_violation = violation;
    prev_j = j;
    (void)failure;
  }
  result.evaluations = ctx.evaluations;
  stop += fmt::format(" after {} round(s), {} evaluations", round + 1, ctx.evaluations);

  const ObjectiveTerms after = evaluate(map, branch, x, settings, continuous);
  if (!after.feasible) {
    stop += fmt::format(
        "; input kept: the refined path is infeasible (min f {}, max |omega| {} rad/s, max "
        "|alpha| {} rad/s^2)",
        after.min_f, after.max_abs_omega, after.max_abs_alpha);
  } else if (!(after.total < result.before.total)) {
    stop += fmt::format("; input kept: refined J {} s is not below the input's {} s", after.total,
                        result.before.total);
  } else {
    result.theta = std::move(x);
    result.after = after;
    result.improved = true;
  }
  result.stop_reason = std::move(stop);
  result.seconds = elapsed();
  return result;
}

}  // namespace scanplan::planner
