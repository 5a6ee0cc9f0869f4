#include <scanplan/planner/refine.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlopt.hpp>

namespace scanplan::planner {

namespace detail {

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
      omega_scale_(settings.omega_max > 0.0 ? settings.omega_max : 1.0),
      alpha_scale_(settings.alpha_max > 0.0 ? settings.alpha_max : 1.0),
      lo_(samples, -std::numeric_limits<double>::infinity()),
      hi_(samples, std::numeric_limits<double>::infinity()) {
  if (samples != map.times.size() || samples < 2 || !(f_floor > 0.0)) {
    throw std::logic_error("RefineProblem: one variable per time sample (>= 2), f_floor > 0");
  }
  bound_.assign(2 * (n_ - 1), (1.0 - bound_margin) * settings.omega_max);
  bound_.resize(bound_.size() + 2 * (n_ - 2), (1.0 - bound_margin) * settings.alpha_max);
}

void RefineProblem::setKinkRadius(double radius) {
  if (!(radius > 0.0 && radius <= 0.5))
    throw std::logic_error("RefineProblem: kink radius in (0, 0.5]");
  kink_radius_ = radius;
}

void RefineProblem::relaxBoundsTo(const double* theta) {
  // The bound terms g_i = (s·ω − b_i)/scale: raise b_i to s·ω where θ exceeds it.
  visitConstraints(theta, [&](std::size_t i, double g, const Term*, std::size_t) {
    if (i < bound_.size() && g > 0.0) {
      bound_[i] += g * (i < 2 * (n_ - 1) ? omega_scale_ : alpha_scale_);
    }
  });
}

bool RefineProblem::movable(const Term* t, std::size_t count) const noexcept {
  for (std::size_t c = 0; c < count; ++c) {
    if (lo_[t[c].j] < hi_[t[c].j]) return true;
  }
  return false;
}

void RefineProblem::setBoxes(std::vector<double> lo, std::vector<double> hi) {
  if (lo.size() != n_ || hi.size() != n_)
    throw std::logic_error("RefineProblem: one box per sample");
  lo_ = std::move(lo);
  hi_ = std::move(hi);
}

std::size_t RefineProblem::constraintCount() const { return 2 * (n_ - 1) + 2 * (n_ - 2) + 2 * n_; }

double RefineProblem::cell(std::ptrdiff_t angle, std::size_t k) const noexcept {
  const auto na = static_cast<std::ptrdiff_t>(map_.angles.size());
  if (continuous_) {
    angle = ((angle % na) + na) % na;
  } else if (angle < 0 || angle >= na) {
    return 0.0;
  }
  return static_cast<double>(map_.f[map_.index(branch_, static_cast<std::size_t>(angle), k)]);
}

RefineProblem::FValue RefineProblem::fModel(double theta, std::size_t k) const noexcept {
  const auto na = static_cast<std::ptrdiff_t>(map_.angles.size());
  const double h = grid_.angle_step;
  double u = (theta - grid_.angle0) / h;  // in grid steps
  if (continuous_) {
    u = std::fmod(u, static_cast<double>(na));
    if (u < 0.0) u += static_cast<double>(na);
  }
  const double lower = std::floor(u);
  const double w = u - lower;
  const auto i0 = static_cast<std::ptrdiff_t>(lower);
  const double f0 = cell(i0, k), f1 = cell(i0 + 1, k);
  // The corner at grid angle i with slopes sl, sr (per grid step) on its sides, rounded over
  // |δ| ≤ r by the quadratic that meets both lines with their slopes (C¹).
  const auto corner = [&](double fi, double sl, double sr, double delta) {
    const double r = kink_radius_;
    return FValue{fi + 0.5 * (sl + sr) * delta + (sr - sl) / (4.0 * r) * (delta * delta + r * r),
                  (0.5 * (sl + sr) + (sr - sl) * delta / (2.0 * r)) / h,
                  (sr - sl) / (2.0 * r) / (h * h)};
  };
  if (w < kink_radius_) return corner(f0, f0 - cell(i0 - 1, k), f1 - f0, w);
  if (w > 1.0 - kink_radius_) return corner(f1, f1 - f0, cell(i0 + 2, k) - f1, w - 1.0);
  return FValue{(1.0 - w) * f0 + w * f1, (f1 - f0) / h, 0.0};
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
  f_min = mapValue(map_, grid_, branch_, theta, k, continuous_);
  // Walk out over open cells; a fully open column of a continuous table stops one turn out.
  std::ptrdiff_t a_lo = below, a_hi = above;
  const bool lo_open = cell(below, k) > 0.0, hi_open = cell(above, k) > 0.0;
  if (lo_open) {
    f_min = std::min(f_min, cell(below, k));
    while (a_lo - 1 > below - na && cell(a_lo - 1, k) > 0.0)
      f_min = std::min(f_min, cell(--a_lo, k));
  }
  if (hi_open) {
    f_min = std::min(f_min, cell(above, k));
    while (a_hi + 1 < above + na && cell(a_hi + 1, k) > 0.0)
      f_min = std::min(f_min, cell(++a_hi, k));
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
    const FValue fv = fModel(theta[k], k);
    double c = 0.0, dc_df = 0.0;
    if (fv.f >= f_floor_) {
      c = -std::log(fv.f);
      dc_df = -1.0 / fv.f;
    } else {
      // Second-order Taylor polynomial of −ln f at the floor: finite (and still pushing up the
      // slope) where f ≤ 0, so the line search never sees an infinity.
      const double d = (fv.f - f_floor_) / f_floor_;
      c = -std::log(f_floor_) - d + 0.5 * d * d;
      dc_df = (d - 1.0) / f_floor_;
    }
    cost_f += c * dt;
    if (grad != nullptr) grad[k] += dc_df * fv.df * dt;
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
    visit(i, (omega - bound_[i]) / omega_scale_, up.data(), up.size());
    ++i;
    visit(i, (-omega - bound_[i]) / omega_scale_, down.data(), down.size());
    ++i;
  }
  const double da = 1.0 / (dt * dt * alpha_scale_);
  for (std::size_t k = 2; k < n_; ++k) {
    const double alpha = ((theta[k] - theta[k - 1]) / dt - (theta[k - 1] - theta[k - 2]) / dt) / dt;
    const std::array<Term, 3> up{{{k, da}, {k - 1, -2.0 * da}, {k - 2, da}}};
    const std::array<Term, 3> down{{{k, -da}, {k - 1, 2.0 * da}, {k - 2, -da}}};
    visit(i, (alpha - bound_[i]) / alpha_scale_, up.data(), up.size());
    ++i;
    visit(i, (-alpha - bound_[i]) / alpha_scale_, down.data(), down.size());
    ++i;
  }
  const double db = 1.0 / grid_.angle_step;
  for (std::size_t k = 0; k < n_; ++k) {
    const std::array<Term, 1> up{{{k, db}}}, down{{{k, -db}}};
    visit(i++, (theta[k] - hi_[k]) * db, up.data(), up.size());
    visit(i++, (lo_[k] - theta[k]) * db, down.data(), down.size());
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
  double penalty = 0.0;
  const double value = objective(theta, grad);
  visitConstraints(theta, [&](std::size_t i, double g, const Term* t, std::size_t count) {
    const double m = std::max(0.0, lambda[i] + rho * g);
    if ((m == 0.0 && lambda[i] == 0.0) || !movable(t, count)) return;
    penalty += (m * m - lambda[i] * lambda[i]) / (2.0 * rho);
    for (std::size_t c = 0; grad != nullptr && c < count; ++c) grad[t[c].j] += m * t[c].d;
  });
  return value + penalty;
}

RefineProblem::Band RefineProblem::meritHessian(const double* theta,
                                                const double* lambda,
                                                double rho) const {
  Band h{std::vector<double>(n_, 0.0), std::vector<double>(n_, 0.0), std::vector<double>(n_, 0.0)};
  const double dt = grid_.dt;
  // −ln f: c''(f)·f'² + c'(f)·f'' per sample·Δt, c' = −1/f, c'' = 1/f² (−1/f_floor·(…) and
  // 1/f_floor² on the continuation). The second term only counts where it is positive (the
  // rounded peaks): a valley's negative curvature would spoil the factorisation.
  for (std::size_t k = 0; k < n_; ++k) {
    const FValue fv = fModel(theta[k], k);
    const double fc = std::max(fv.f, f_floor_);
    const double dc_df =
        fv.f >= f_floor_ ? -1.0 / fv.f : ((fv.f - f_floor_) / f_floor_ - 1.0) / f_floor_;
    h.diag[k] += (fv.df * fv.df / (fc * fc) + std::max(0.0, dc_df * fv.d2f)) * dt;
  }
  // k_ω Σ (Δθ)²/Δt and k_a Σ (Δ²θ)²/Δt³: 2k_ω/Δt·D1ᵀD1 + 2k_a/Δt³·D2ᵀD2.
  const double cw = 2.0 * settings_.k_omega / dt, ca = 2.0 * settings_.k_alpha / (dt * dt * dt);
  for (std::size_t k = 1; k < n_; ++k) {
    h.diag[k] += cw;
    h.diag[k - 1] += cw;
    h.sub1[k] -= cw;
  }
  for (std::size_t k = 2; k < n_; ++k) {
    h.diag[k] += ca;
    h.diag[k - 1] += 4.0 * ca;
    h.diag[k - 2] += ca;
    h.sub1[k] -= 2.0 * ca;
    h.sub1[k - 1] -= 2.0 * ca;
    h.sub2[k] += ca;
  }
  // The active penalty terms: ρ ∇g∇gᵀ (each g is linear and spans at most three neighbours).
  visitConstraints(theta, [&](std::size_t i, double g, const Term* t, std::size_t count) {
    if (!(lambda[i] + rho * g > 0.0) || !movable(t, count)) return;
    for (std::size_t a = 0; a < count; ++a) {
      for (std::size_t b = 0; b < count; ++b) {
        const std::size_t r = t[a].j, c = t[b].j;
        if (r == c) {
          h.diag[r] += rho * t[a].d * t[b].d;
        } else if (r == c + 1) {
          h.sub1[r] += rho * t[a].d * t[b].d;
        } else if (r == c + 2) {
          h.sub2[r] += rho * t[a].d * t[b].d;
        }
      }
    }
  });
  return h;
}

double RefineProblem::updateMultipliers(const double* theta,
                                        double* lambda,
                                        double rho) const noexcept {
  double violation = 0.0;
  visitConstraints(theta, [&](std::size_t i, double g, const Term* t, std::size_t count) {
    if (!movable(t, count)) return;
    violation = std::max(violation, g);
    lambda[i] = std::max(0.0, lambda[i] + rho * g);
  });
  return violation;
}

}  // namespace detail

namespace {

// The optimiser works on bounds and boxes this much (relative) inside the real ones, so a point
// that meets them to constraint_tol ≪ this still passes evaluate()'s check and reads f > 0.
constexpr double kBoundMargin = 1e-6;
// The continuation of −ln f starts at this fraction of the lowest f inside the boxes: never
// reached inside them, it only keeps the merit finite where a trial point leaves them.
constexpr double kFloorFraction = 0.5;
// Augmented-Lagrangian schedule (Nocedal & Wright §17.4): the penalty grows ×10 whenever a round
// did not cut the violation to a quarter. The preconditioner carries the penalty's curvature, so
// a large penalty does not stall L-BFGS.
constexpr double kRho0 = 10.0, kRhoGrowth = 10.0, kRhoMax = 1e12, kViolationShrink = 0.25;
constexpr int kMaxRounds = 30;  // per smoothing stage
// Continuation over the rounding of f's corners (grid steps): wide corners first (smooth, fast),
// then narrower ones, each stage warm-started, so the model ends within 1e-3 grid steps of J's
// own f.
constexpr std::array<double, 3> kKinkRadii = {0.1, 0.01, 0.001};
// NLopt's default L-BFGS memory is MEMAVAIL/n vectors (thousands for n = 1000), which makes an
// iteration cost O(n·memory); preconditioned, a few vectors suffice.
constexpr unsigned kLbfgsMemory = 10;
// Evaluations per L-BFGS run before the preconditioner is rebuilt at the current point: −ln f's
// curvature changes along the way (near forbidden cells above all), and a fresh factor there
// costs O(N), about one evaluation. Measured on 360 × 1000 maps: 100 → 25 halves the work with
// forbidden regions, below 25 it no longer helps.
constexpr int kInnerEvaluations = 25;
// Rounds whose J differ by less than this (relative), with the bounds met, end the run.
constexpr double kRoundJTol = 1e-12;
// Regularisation of the preconditioner, relative to its mean diagonal: keeps the factor
// positive definite where the Hessian is singular (f flat in θ and a path at rest).
constexpr double kPrecondRegularisation = 1e-9;

// Cholesky factor L of a symmetric positive-definite pentadiagonal matrix (in place: diag, sub1,
// sub2 become L(k,k), L(k,k−1), L(k,k−2)), and the two triangular solves.
struct BandCholesky {
  std::vector<double> d0, d1, d2;

  void factor(double floor) {
    const std::size_t n = d0.size();
    for (std::size_t k = 0; k < n; ++k) {
      if (k >= 2) d2[k] /= d0[k - 2];
      if (k >= 1) d1[k] = (d1[k] - (k >= 2 ? d2[k] * d1[k - 1] : 0.0)) / d0[k - 1];
      const double r = d0[k] - (k >= 1 ? d1[k] * d1[k] : 0.0) - (k >= 2 ? d2[k] * d2[k] : 0.0);
      d0[k] = std::sqrt(std::max(r, floor));  // rounding only: the matrix is regularised
    }
  }
  // v ← L⁻¹ v
  void solveLower(double* v) const noexcept {
    for (std::size_t k = 0; k < d0.size(); ++k) {
      double s = v[k];
      if (k >= 1) s -= d1[k] * v[k - 1];
      if (k >= 2) s -= d2[k] * v[k - 2];
      v[k] = s / d0[k];
    }
  }
  // v ← L⁻ᵀ v
  void solveUpper(double* v) const noexcept {
    const std::size_t n = d0.size();
    for (std::size_t k = n; k-- > 0;) {
      double s = v[k];
      if (k + 1 < n) s -= d1[k + 1] * v[k + 1];
      if (k + 2 < n) s -= d2[k + 2] * v[k + 2];
      v[k] = s / d0[k];
    }
  }
};

// One round's preconditioned problem: θ = base + Pᵀ L⁻ᵀ y over the free samples (P picks them).
struct Context {
  const detail::RefineProblem* problem = nullptr;
  const double* lambda = nullptr;
  double rho = 1.0;
  const std::vector<std::size_t>* free = nullptr;
  BandCholesky chol;
  std::vector<double> base, theta, grad, scratch;
  int evaluations = 0;
  int max_evaluations = 0;
  nlopt::opt* opt = nullptr;
  double best = std::numeric_limits<double>::infinity();
  std::vector<double> best_theta;
};

double meritCallback(unsigned n, const double* y, double* grad_y, void* data) {
  auto& c = *static_cast<Context*>(data);
  // NLopt's L-BFGS checks maxeval only between line searches, and may evaluate once more after
  // force_stop(): the budget is a hard cap here.
  if (c.evaluations >= c.max_evaluations) {
    c.opt->force_stop();
    if (grad_y != nullptr) std::fill(grad_y, grad_y + n, 0.0);
    return HUGE_VAL;
  }
  ++c.evaluations;
  const std::vector<std::size_t>& free = *c.free;
  std::copy(y, y + n, c.scratch.begin());
  c.chol.solveUpper(c.scratch.data());
  c.theta = c.base;
  for (std::size_t i = 0; i < n; ++i) c.theta[free[i]] += c.scratch[i];
  const double v = c.problem->merit(c.theta.data(), c.lambda, c.rho,
                                    grad_y != nullptr ? c.grad.data() : nullptr);
  if (grad_y != nullptr) {
    for (std::size_t i = 0; i < n; ++i) grad_y[i] = c.grad[free[i]];
    c.chol.solveLower(grad_y);
  }
  // Keep the best point of the round ourselves: NLopt's x after a line-search failure is not
  // documented to be the best one seen.
  if (v < c.best) {
    c.best = v;
    c.best_theta = c.theta;
  }
  if (c.evaluations >= c.max_evaluations) c.opt->force_stop();
  return v;
}

// Pentadiagonal Hessian restricted to the free samples (still pentadiagonal: dropping indices
// only brings neighbours closer), regularised and factored.
void precondition(const detail::RefineProblem::Band& h,
                  const std::vector<std::size_t>& free,
                  BandCholesky& chol) {
  const std::size_t m = free.size();
  chol.d0.assign(m, 0.0);
  chol.d1.assign(m, 0.0);
  chol.d2.assign(m, 0.0);
  const auto entry = [&](std::size_t r, std::size_t c) {  // r > c, original indices
    return r - c == 1 ? h.sub1[r] : r - c == 2 ? h.sub2[r] : 0.0;
  };
  double mean = 0.0;
  for (std::size_t i = 0; i < m; ++i) {
    chol.d0[i] = h.diag[free[i]];
    mean += chol.d0[i] / static_cast<double>(m);
    if (i >= 1) chol.d1[i] = entry(free[i], free[i - 1]);
    if (i >= 2) chol.d2[i] = entry(free[i], free[i - 2]);
  }
  const double reg = kPrecondRegularisation * std::max(mean, 1e-300);
  for (double& d : chol.d0) d += reg;
  chol.factor(reg);
}

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void checkInputs(const std::vector<double>& theta,
                 const PlannerSettings& settings,
                 const RefineSettings& rs) {
  if (!(settings.omega_max >= 0.0) || !(settings.alpha_max >= 0.0) || !(settings.k_omega >= 0.0) ||
      !(settings.k_alpha >= 0.0)) {
    throw std::invalid_argument("refinePath: bounds and weights must be >= 0");
  }
  if (rs.max_evaluations < 1 || !(rs.time_limit_s >= 0.0) || !(rs.ftol_rel >= 0.0) ||
      !(rs.xtol_rel >= 0.0) || !(rs.constraint_tol >= 0.0) || rs.constraint_tol >= kBoundMargin) {
    throw std::invalid_argument(
        "refinePath: max_evaluations >= 1, time_limit_s, tolerances >= 0, constraint_tol < 1e-6");
  }
  for (std::size_t k = 0; k < theta.size(); ++k) {
    if (!std::isfinite(theta[k])) {
      throw std::invalid_argument(fmt::format("refinePath: theta[{}] is not finite", k));
    }
  }
}

// evaluate() on one branch of one map: the judge of every candidate path.
struct Judge {
  const ConfigMap& map;
  std::size_t branch;
  const PlannerSettings& settings;
  bool continuous;

  ObjectiveTerms operator()(const std::vector<double>& theta) const {
    return evaluate(map, branch, theta, settings, continuous);
  }
};

// Boxes: the open run around each input angle. A lone open grid angle, or the held start, fixes
// the sample at its input value (lo = hi); the others are `free`.
struct Boxes {
  std::vector<double> lo, hi;
  std::vector<std::size_t> free;
  double f_min = std::numeric_limits<double>::infinity();  // lowest f inside the boxes
};

Boxes openBoxes(const Judge& judge, const std::vector<double>& theta, bool keep_start) {
  const std::size_t n = theta.size();
  Boxes b;
  b.lo.resize(n);
  b.hi.resize(n);
  const detail::RefineProblem probe(judge.map, judge.branch, judge.settings, judge.continuous, n,
                                    1.0, kBoundMargin);
  for (std::size_t k = 0; k < n; ++k) {
    double box_f_min = 0.0;
    probe.feasibleInterval(theta[k], k, b.lo[k], b.hi[k], box_f_min);
    b.f_min = std::min(b.f_min, box_f_min);
    if (b.lo[k] < b.hi[k] && !(keep_start && k == 0)) {
      b.free.push_back(k);
    } else {
      b.lo[k] = b.hi[k] = theta[k];
    }
  }
  return b;
}

// L-BFGS on the free samples, preconditioned; every evaluation goes through `ctx`.
void setUpOptimiser(nlopt::opt& opt,
                    Context& ctx,
                    const detail::RefineProblem& problem,
                    const std::vector<std::size_t>& free,
                    std::size_t n,
                    const RefineSettings& rs) {
  ctx.problem = &problem;
  ctx.free = &free;
  ctx.scratch.resize(free.size());
  ctx.grad.resize(n);
  ctx.max_evaluations = rs.max_evaluations;
  ctx.opt = &opt;
  opt.set_min_objective(meritCallback, &ctx);
  opt.set_ftol_rel(rs.ftol_rel);
  opt.set_xtol_rel(rs.xtol_rel);
  opt.set_vector_storage(kLbfgsMemory);
}

// Before a round: why the budget is spent, or empty (and the round gets the time that is left).
std::string budgetSpent(const RefineSettings& rs,
                        int evaluations,
                        Clock::time_point clock_start,
                        nlopt::opt& opt) {
  if (evaluations >= rs.max_evaluations) {
    return fmt::format("evaluation budget ({}) spent", rs.max_evaluations);
  }
  if (rs.time_limit_s > 0.0) {
    const double remaining = rs.time_limit_s - secondsSince(clock_start);
    if (remaining <= 0.0) return fmt::format("time limit ({} s) reached", rs.time_limit_s);
    opt.set_maxtime(remaining);
  }
  return {};
}

// One round minimises the merit for fixed λ, ρ from x (updated to the best point seen): L-BFGS
// runs of at most kInnerEvaluations, each preconditioned afresh at its starting point (a
// Newton-like outer loop), until a run ends on its own tolerances.
nlopt::result minimiseMerit(const detail::RefineProblem& problem,
                            const std::vector<double>& lambda,
                            double rho,
                            int max_evaluations,
                            nlopt::opt& opt,
                            Context& ctx,
                            std::vector<double>& x) {
  const std::vector<std::size_t>& free = *ctx.free;
  ctx.lambda = lambda.data();
  ctx.rho = rho;
  nlopt::result status = nlopt::FAILURE;
  for (;;) {
    ctx.base = x;
    ctx.best = std::numeric_limits<double>::infinity();
    precondition(problem.meritHessian(x.data(), lambda.data(), rho), free, ctx.chol);
    opt.set_maxeval(kInnerEvaluations);
    std::vector<double> y(free.size(), 0.0);
    try {
      double value = 0.0;
      status = opt.optimize(y, value);
    } catch (const nlopt::forced_stop&) {
      status = nlopt::FORCED_STOP;
    } catch (const std::runtime_error&) {
      status = nlopt::FAILURE;  // roundoff-limited line search and the like: keep the best
    }
    if (ctx.best < std::numeric_limits<double>::infinity()) x = ctx.best_theta;
    if (status != nlopt::MAXEVAL_REACHED || ctx.evaluations >= max_evaluations) break;
  }
  return status;
}

// The lowest-J path evaluate() accepts so far.
struct Incumbent {
  std::vector<double> theta;
  ObjectiveTerms terms;
};

// Judges a round's end by evaluate(); if it is out, also its projection onto the boxes (a box
// edge overshot by more than mapValue()'s snap reads f = 0; the speed and acceleration margins
// absorb the clamp's tiny change of ω and α). Keeps the better of it and `best`; returns its terms.
ObjectiveTerms judgeRound(const Judge& judge,
                          const std::vector<double>& x,
                          const Boxes& boxes,
                          std::vector<double>& clamped,
                          Incumbent& best) {
  ObjectiveTerms terms = judge(x);
  const std::vector<double>* candidate = &x;
  if (!terms.feasible) {
    for (std::size_t k = 0; k < x.size(); ++k)
      clamped[k] = std::clamp(x[k], boxes.lo[k], boxes.hi[k]);
    const ObjectiveTerms clamped_terms = judge(clamped);
    if (clamped_terms.feasible) {
      terms = clamped_terms;
      candidate = &clamped;
    }
  }
  if (terms.feasible && terms.total < best.terms.total) {
    best.theta = *candidate;
    best.terms = terms;
  }
  return terms;
}

struct RoundsOutcome {
  Incumbent best;  // the best round end: a later round cut short by the budget cannot undo it
  std::string stop;
  int rounds = 0;
  int evaluations = 0;
};

// The augmented-Lagrangian stages (one per kink radius) and their rounds, from `input`.
RoundsOutcome runRounds(detail::RefineProblem& problem,
                        const Boxes& boxes,
                        const Judge& judge,
                        const RefineSettings& rs,
                        const Incumbent& input,
                        Clock::time_point clock_start) {
  std::vector<double> lambda(problem.constraintCount(), 0.0);
  nlopt::opt opt(nlopt::LD_LBFGS, static_cast<unsigned>(boxes.free.size()));
  Context ctx;
  setUpOptimiser(opt, ctx, problem, boxes.free, input.theta.size(), rs);

  std::vector<double> x = input.theta, clamped(x.size());
  RoundsOutcome out{input, {}, 0, 0};
  double rho = kRho0;
  bool out_of_budget = false;
  for (std::size_t stage = 0; stage < kKinkRadii.size() && !out_of_budget; ++stage) {
    problem.setKinkRadius(kKinkRadii[stage]);
    double prev_violation = std::numeric_limits<double>::infinity();
    double prev_j = problem.objective(x.data(), nullptr);
    for (int round = 0;; ++round) {
      out.stop = budgetSpent(rs, ctx.evaluations, clock_start, opt);
      if (!out.stop.empty()) {
        out_of_budget = true;
        break;
      }
      const nlopt::result status =
          minimiseMerit(problem, lambda, rho, rs.max_evaluations, opt, ctx, x);
      ++out.rounds;
      const double violation = problem.updateMultipliers(x.data(), lambda.data(), rho);
      const double j = problem.objective(x.data(), nullptr);
      const ObjectiveTerms terms = judgeRound(judge, x, boxes, clamped, out.best);
      if (status == nlopt::FORCED_STOP || ctx.evaluations >= rs.max_evaluations) {
        out.stop = fmt::format("evaluation budget ({}) spent", rs.max_evaluations);
        out_of_budget = true;
        break;
      }
      if (status == nlopt::MAXTIME_REACHED) {
        out.stop = fmt::format("time limit ({} s) reached", rs.time_limit_s);
        out_of_budget = true;
        break;
      }
      // The very first round starts with zero multipliers: if its minimiser meets the
      // constraints, it is the constrained minimiser. Otherwise a stage ends once J settles at a
      // point that meets them (or that evaluate() accepts: the margins absorb the rest); the next
      // stage then starts from it with narrower corners.
      const bool settled = std::abs(j - prev_j) <= kRoundJTol * std::max(1.0, std::abs(j));
      if ((stage == 0 && round == 0 && violation <= rs.constraint_tol) ||
          (settled && (violation <= rs.constraint_tol || terms.feasible))) {
        out.stop = "converged";
        break;
      }
      if (round + 1 >= kMaxRounds) {
        out.stop = fmt::format("{} augmented-Lagrangian rounds", kMaxRounds);
        break;
      }
      if (violation > kViolationShrink * prev_violation) rho = std::min(rho * kRhoGrowth, kRhoMax);
      prev_violation = violation;
      prev_j = j;
    }
  }
  out.evaluations = ctx.evaluations;
  return out;
}

}  // namespace

RefineResult refinePath(const ConfigMap& map,
                        std::size_t branch,
                        const std::vector<double>& theta,
                        const PlannerSettings& settings,
                        bool continuous,
                        const RefineSettings& rs) {
  const auto clock_start = Clock::now();
  checkInputs(theta, settings, rs);
  const Judge judge{map, branch, settings, continuous};

  RefineResult result;
  result.algorithm =
      "augmented Lagrangian (PHR, sparse) over NLopt LD_LBFGS, banded preconditioner";
  result.theta = theta;
  result.before = judge(theta);
  result.after = result.before;
  if (!result.before.feasible) {
    throw std::invalid_argument(fmt::format(
        "refinePath: the input path is infeasible (min f {} at sample {}, max |omega| {} rad/s, "
        "max |alpha| {} rad/s^2)",
        result.before.min_f, result.before.min_f_sample, result.before.max_abs_omega,
        result.before.max_abs_alpha));
  }

  const std::size_t n = theta.size();
  const Boxes boxes = openBoxes(judge, theta, rs.keep_start);
  if (boxes.free.empty()) {
    result.stop_reason = "every sample is fixed (lone open grid angles); input kept";
    result.seconds = secondsSince(clock_start);
    return result;
  }
  detail::RefineProblem problem(map, branch, settings, continuous, n, kFloorFraction * boxes.f_min,
                                kBoundMargin);
  problem.setBoxes(boxes.lo, boxes.hi);
  // Where the input sits on (or within the margin of) a bound, that bound is tightened only down
  // to the input's value: the tightened problem always has the input as a feasible point.
  problem.relaxBoundsTo(theta.data());

  RoundsOutcome rounds =
      runRounds(problem, boxes, judge, rs, Incumbent{theta, result.before}, clock_start);
  result.evaluations = rounds.evaluations;
  std::string stop = std::move(rounds.stop);
  stop += fmt::format(" after {} round(s), {} evaluations", rounds.rounds, rounds.evaluations);
  if (rounds.best.terms.total < result.before.total) {
    result.theta = std::move(rounds.best.theta);
    result.after = rounds.best.terms;
    result.improved = true;
  } else {
    stop += "; input kept: no round ended feasible with a lower J";
  }
  result.stop_reason = std::move(stop);
  result.seconds = secondsSince(clock_start);
  return result;
}

}  // namespace scanplan::planner
