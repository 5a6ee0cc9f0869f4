#include <scanplan/planner/objective.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace scanplan::planner {

namespace detail {

Grid gridOf(const ConfigMap& map, std::size_t branch, bool continuous) {
  const std::size_t na = map.angles.size(), nt = map.times.size();
  if (na < 2 || nt < 2 || branch >= map.branches.size() ||
      map.f.size() != map.branches.size() * na * nt) {
    throw std::logic_error("planner: map needs >= 2 angles, >= 2 times, f for every branch");
  }
  Grid g;
  g.angle0 = map.angles.front();
  // A continuous grid closes on itself (mapAngles): n steps of 2π/n.
  g.angle_step = continuous
                     ? 2.0 * std::numbers::pi / static_cast<double>(na)
                     : (map.angles.back() - map.angles.front()) / static_cast<double>(na - 1);
  g.dt = (map.times.back() - map.times.front()) / static_cast<double>(nt - 1);
  return g;
}

}  // namespace detail

double mapValue(
    const ConfigMap& map, std::size_t branch, double theta, std::size_t t, bool continuous) {
  return detail::mapValue(map, detail::gridOf(map, branch, continuous), branch, theta, t,
                          continuous);
}

double detail::mapValue(const ConfigMap& map,
                        const Grid& g,
                        std::size_t branch,
                        double theta,
                        std::size_t t,
                        bool continuous) noexcept {
  const std::size_t na = map.angles.size();
  const double n = static_cast<double>(na);
  double u = (theta - g.angle0) / g.angle_step;  // in grid steps
  if (continuous) {
    if (u < 0.0 || u >= n) u -= n * std::floor(u / n);  // cheaper than fmod in the hot loop
    if (u >= n) u = 0.0;                                // u just below 0 can round up to n
  } else if (u < -1e-9 || u > n - 1.0 + 1e-9) {
    return 0.0;
  }
  // Snap near-grid angles so a grid path reads its cells exactly (a zero neighbour must not leak
  // in through a rounding-sized weight).
  if (std::abs(u - std::round(u)) <= 1e-9) u = std::round(u);
  const double lower = std::floor(u);
  const double w = u - lower;
  const auto i0 = static_cast<std::size_t>(lower) % na;
  const double f0 = map.f[map.index(branch, i0, t)];
  if (w == 0.0) return f0;
  const std::size_t i1 = (i0 + 1) % na;  // i0 < na − 1 here for a limited table
  const double f1 = map.f[map.index(branch, i1, t)];
  // Between a feasible and a forbidden cell nothing is known (the pose may already collide or be
  // unreachable): only the span between two feasible cells is interpolated.
  if (!(f0 > 0.0) || !(f1 > 0.0)) return 0.0;
  return (1.0 - w) * f0 + w * f1;
}

ObjectiveTerms evaluate(const ConfigMap& map,
                        std::size_t branch,
                        const std::vector<double>& theta,
                        const PlannerSettings& settings,
                        bool continuous) {
  const detail::Grid g = detail::gridOf(map, branch, continuous);
  if (theta.size() != map.times.size()) {
    throw std::logic_error("planner::evaluate: one angle per time sample expected");
  }
  const double dt = g.dt;
  ObjectiveTerms r;
  r.min_f = std::numeric_limits<double>::infinity();
  double omega_prev = 0.0;
  for (std::size_t k = 0; k < theta.size(); ++k) {
    const double f = mapValue(map, branch, theta[k], k, continuous);
    if (f < r.min_f) {
      r.min_f = f;
      r.min_f_sample = k;
    }
    r.cost_f += f > 0.0 ? -std::log(f) * dt : std::numeric_limits<double>::infinity();
    if (k == 0) continue;
    const double omega = (theta[k] - theta[k - 1]) / dt;
    r.cost_omega += settings.k_omega * omega * omega * dt;
    r.max_abs_omega = std::max(r.max_abs_omega, std::abs(omega));
    if (k >= 2) {
      const double alpha = (omega - omega_prev) / dt;
      r.cost_alpha += settings.k_alpha * alpha * alpha * dt;
      r.max_abs_alpha = std::max(r.max_abs_alpha, std::abs(alpha));
    }
    omega_prev = omega;
  }
  r.total = r.cost_f + r.cost_omega + r.cost_alpha;
  r.feasible = r.min_f > 0.0 && r.max_abs_omega <= settings.omega_max * (1.0 + kBoundTolerance) &&
               r.max_abs_alpha <= settings.alpha_max * (1.0 + kBoundTolerance);
  return r;
}

}  // namespace scanplan::planner
