#include <scanplan/planner/ray_shooting.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

namespace scanplan::planner {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr std::size_t kMergeEvery = 10;  // samples between checks for runs that met

// One run from one start angle: the path so far and, when it stopped early, where and why.
struct Run {
  std::vector<double> theta;  // rad, unwrapped; complete when it has one angle per time sample
  std::string why;            // why it stopped early; empty while it goes on
  double omega = 0.0;         // rad/s, from rest
  double cost = 0.0;          // s, the objective terms of the applied steps
  std::size_t last_i = 0;     // the ray applied last
  bool merged = false;        // dropped: another run reached the same state more cheaply
};

struct RayScore {
  bool blocked_first = true;  // f = 0 on the first step: the ray can never be applied
  bool pruned = false;        // stopped early: already costlier than the best ray so far
  double cost = 0.0;          // s
};

// Candidate accelerations (rad/s²) sorted by (|a|, a), so a strict "<" keeps the tie-break rule.
// An integer numerator makes the middle candidate exactly 0 and the set exactly symmetric.
std::vector<double> rayAccelerations(std::size_t n_rays, double alpha_max) {
  std::vector<double> accel(n_rays, 0.0);
  for (std::size_t i = 0; n_rays > 1 && i < n_rays; ++i) {
    const double num = 2.0 * static_cast<double>(i) - static_cast<double>(n_rays - 1);
    accel[i] = alpha_max * num / static_cast<double>(n_rays - 1);
  }
  std::stable_sort(accel.begin(), accel.end(), [](double x, double y) {
    return std::abs(x) < std::abs(y) || (std::abs(x) == std::abs(y) && x < y);
  });
  return accel;
}

// The rays and the rules a run advances by; shared read-only by the runs of all threads.
class Shooter {
 public:
  Shooter(const ConfigMap& map,
          const detail::Grid& g,
          std::size_t branch,
          const PlannerSettings& settings,
          bool continuous,
          const RayShootingSettings& rs,
          const detail::CostToGo* guide)
      : map_(map),
        g_(g),
        branch_(branch),
        settings_(settings),
        continuous_(continuous),
        rs_(rs),
        guide_(guide),
        accel_(rayAccelerations(static_cast<std::size_t>(rs.rays), settings.alpha_max)) {}

  double fAt(double theta, std::size_t k) const {
    return detail::mapValue(map_, g_, branch_, theta, k, continuous_);
  }

  // The horizon at sample k: H, or up to the last sample; with a guide, lengthened (by less than
  // a stride) so the ray ends on a stage sample of the cost-to-go.
  std::size_t horizon(std::size_t k) const {
    const std::size_t nt = map_.times.size(), h = static_cast<std::size_t>(rs_.horizon);
    if (k + h >= nt - 1) return nt - 1 - k;
    return guide_ ? h + (nt - 1 - k - h) % guide_->stride : h;
  }

  // Rolls one ray out from (theta, omega) at sample k for h steps. Every term is >= 0, so a ray
  // whose partial cost already exceeds `bound` cannot win: it stops there (exact pruning). With
  // a guide the ray's end state adds its cost-to-go, and a blocked ray also pays for the samples
  // after its horizon (as the cost-to-go does), so all scores count every sample to the end.
  RayScore shoot(
      double theta, double omega, std::size_t k, std::size_t h, double a, double bound) const {
    const double dt = g_.dt, w_max = settings_.omega_max;
    const std::size_t nt = map_.times.size();
    RayScore s;
    for (std::size_t j = 1; j <= h; ++j) {
      const double w = std::clamp(omega + a * dt, -w_max, w_max);
      const double alpha = (w - omega) / dt;
      theta += w * dt;
      omega = w;
      const double f = fAt(theta, k + j);
      if (!(f > 0.0)) {
        const std::size_t unreached = h - j + 1 + (guide_ ? nt - 1 - k - h : 0);
        s.cost += rs_.blocked_penalty * static_cast<double>(unreached);
        return s;
      }
      s.blocked_first = false;
      s.cost += (-std::log(f) + settings_.k_omega * w * w) * dt;
      if (k + j >= 2) s.cost += settings_.k_alpha * alpha * alpha * dt;  // as evaluate()
      if (s.cost > bound) {
        s.pruned = true;
        return s;
      }
    }
    if (guide_) s.cost += guide_->at(map_, g_, theta, k + h, continuous_);
    return s;
  }

  // The best ray from (theta, omega) at sample k over a horizon h: the previous step's ray
  // `last_i` first (it usually stays best, and its cost bounds the others). Candidates are ranked
  // by (cost, position in `accel_`), so the order of trial does not change the choice.
  std::size_t bestRay(double theta,
                      double omega,
                      std::size_t k,
                      std::size_t h,
                      std::size_t last_i,
                      RayScore& best) const {
    const std::size_t n_rays = accel_.size();
    std::size_t best_i = n_rays;
    const auto tryRay = [&](std::size_t i) {
      const double bound = best.blocked_first ? kInfinity : best.cost;
      const RayScore s = shoot(theta, omega, k, h, accel_[i], bound);
      if (s.pruned) return;
      const bool better =
          best_i == n_rays || (s.blocked_first != best.blocked_first
                                   ? !s.blocked_first
                                   : s.cost < best.cost || (s.cost == best.cost && i < best_i));
      if (better) {
        best = s;
        best_i = i;
      }
    };
    tryRay(last_i);
    for (std::size_t i = 0; i < n_rays; ++i) {
      if (i != last_i) tryRay(i);
    }
    return best_i;
  }

  // Advances a run from its last sample to sample k_end (or until it is blocked).
  void advance(Run& run, std::size_t k_end) const {
    const double dt = g_.dt, w_max = settings_.omega_max;
    double& omega = run.omega;
    std::size_t& last_i = run.last_i;
    for (std::size_t k = run.theta.size() - 1; k < k_end; ++k) {
      const std::size_t h = horizon(k);
      const double theta = run.theta.back();
      RayScore best;
      last_i = bestRay(theta, omega, k, h, last_i, best);
      const double best_a = accel_[last_i];
      if (best.blocked_first) {
        run.why = fmt::format(
            "time sample {} (t = {} s): f = 0 wherever the speed and acceleration bounds allow "
            "from theta = {} rad, omega = {} rad/s",
            k + 1, map_.times[k + 1], theta, omega);
        return;
      }
      const double w = std::clamp(omega + best_a * dt, -w_max, w_max);
      run.theta.push_back(theta + w * dt);
      // Carry evaluate()'s finite difference so its rounding does not accumulate.
      const double omega_new = (run.theta.back() - theta) / dt;
      const double alpha = (omega_new - omega) / dt;
      run.cost +=
          (-std::log(fAt(run.theta.back(), k + 1)) + settings_.k_omega * omega_new * omega_new) *
          dt;
      if (k >= 1) run.cost += settings_.k_alpha * alpha * alpha * dt;
      omega = omega_new;
    }
  }

 private:
  const ConfigMap& map_;
  const detail::Grid& g_;
  std::size_t branch_;
  const PlannerSettings& settings_;
  bool continuous_;
  const RayShootingSettings& rs_;
  const detail::CostToGo* guide_;  // nullptr: the seed's plain horizon cost
  std::vector<double> accel_;      // rad/s², sorted by (|a|, a)
};

// `count` start angles (rad) spread evenly over the first column's open cells.
std::vector<double> spreadStarts(const ConfigMap& map, std::size_t branch, std::size_t count) {
  std::vector<std::size_t> open;
  for (std::size_t a = 0; a < map.angles.size(); ++a) {
    if (map.f[map.index(branch, a, 0)] > 0.0f) open.push_back(a);
  }
  std::vector<double> starts;
  const std::size_t n = std::min(open.size(), count);
  for (std::size_t i = 0; i < n; ++i) starts.push_back(map.angles[open[i * open.size() / n]]);
  return starts;
}

// With a cost-to-go: besides the spread starts, the best grid angle of every corridor (run of
// open cells) of the first column by −ln f·Δt + the cost-to-go at the first stage sample, so
// every corridor the guide can pass has a run. Sorted, without duplicates.
std::vector<double> corridorStarts(const ConfigMap& map,
                                   const detail::Grid& g,
                                   std::size_t branch,
                                   bool continuous,
                                   const detail::CostToGo& guide,
                                   std::vector<double> starts) {
  const std::size_t na = map.angles.size(), k0 = (map.times.size() - 1) % guide.stride;
  std::size_t best = na;
  double best_score = kInfinity;
  for (std::size_t a = 0; a <= na; ++a) {
    const bool open = a < na && map.f[map.index(branch, a, 0)] > 0.0f;
    if (open) {
      const double score = -std::log(double{map.f[map.index(branch, a, 0)]}) * g.dt +
                           guide.at(map, g, map.angles[a], k0, continuous);
      if (score < best_score) {
        best_score = score;
        best = a;
      }
      continue;
    }
    if (best < na) starts.push_back(map.angles[best]);
    best = na;
    best_score = kInfinity;
  }
  std::sort(starts.begin(), starts.end());
  starts.erase(std::unique(starts.begin(), starts.end()), starts.end());
  return starts;
}

// A run that has come within `theta_near` (rad) and `omega_near` (rad/s) of another run's state,
// at a higher cost so far, is dropped: from (nearly) the same state both would shoot (nearly)
// the same rays.
void mergeRuns(std::vector<Run>& runs, bool continuous, double theta_near, double omega_near) {
  const auto alive = [](const Run& r) { return !r.merged && r.why.empty(); };
  for (std::size_t i = 0; i < runs.size(); ++i) {
    for (std::size_t j = i + 1; j < runs.size() && alive(runs[i]); ++j) {
      if (!alive(runs[j])) continue;
      double d = runs[i].theta.back() - runs[j].theta.back();
      if (continuous) d = std::remainder(d, 2.0 * std::numbers::pi);
      if (std::abs(d) > theta_near || std::abs(runs[i].omega - runs[j].omega) > omega_near) {
        continue;
      }
      (runs[j].cost < runs[i].cost ? runs[i] : runs[j]).merged = true;
    }
  }
}

// Combines the runs in start order: the lowest feasible J wins (into `result`); otherwise the
// furthest run explains why.
void combineRuns(const ConfigMap& map,
                 std::size_t branch,
                 const PlannerSettings& settings,
                 bool continuous,
                 const std::vector<double>& starts,
                 std::vector<Run>& runs,
                 PlanResult& result) {
  const std::size_t nt = map.times.size();
  std::size_t furthest = 0;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    Run& run = runs[i];
    if (run.theta.size() == nt) {
      const ObjectiveTerms terms = evaluate(map, branch, run.theta, settings, continuous);
      if (terms.feasible) {
        if (result.status != PlanResult::Status::kExact || terms.total < result.terms.total) {
          result.status = PlanResult::Status::kExact;
          result.terms = terms;
          result.theta = run.theta;
        }
        continue;
      }
      run.why = fmt::format(
          "the path breaks a bound: min f {} at time sample {}, max |omega| {} rad/s, max |alpha| "
          "{} rad/s^2",
          terms.min_f, terms.min_f_sample, terms.max_abs_omega, terms.max_abs_alpha);
    }
    if (!run.merged && (runs[furthest].merged || run.theta.size() > runs[furthest].theta.size())) {
      furthest = i;
    }
  }
  if (result.status != PlanResult::Status::kExact) {
    result.reason = fmt::format(
        "no start of {} reached the end; the furthest (theta0 = {} rad) "
        "stopped: {}",
        starts.size(), starts[furthest], runs[furthest].why);
  }
}

// The runs from `starts`, advanced in lockstep kMergeEvery samples at a time. In between, runs
// that met are merged (mergeRuns()), so most starts collapse into the few corridors of the map
// after a while.
std::vector<Run> shootRuns(const Shooter& shooter,
                           const detail::Grid& g,
                           std::size_t nt,
                           const PlannerSettings& settings,
                           bool continuous,
                           const std::vector<double>& starts) {
  std::vector<Run> runs(starts.size());
  for (std::size_t i = 0; i < starts.size(); ++i) {
    runs[i].theta.reserve(nt);
    runs[i].theta.push_back(starts[i]);
    runs[i].cost = -std::log(shooter.fAt(starts[i], 0)) * g.dt;
  }
  const auto going = [&](const Run& r) {
    return !r.merged && r.why.empty() && r.theta.size() < nt;
  };
  // Within half a grid step and half an acceleration step.
  const double theta_near = 0.5 * g.angle_step, omega_near = 0.5 * settings.alpha_max * g.dt;
  for (std::size_t k_end = 0; k_end + 1 < nt;) {
    k_end = std::min(nt - 1, k_end + kMergeEvery);
    tbb::parallel_for(std::size_t{0}, runs.size(), [&](std::size_t i) {
      if (going(runs[i])) shooter.advance(runs[i], k_end);
    });
    mergeRuns(runs, continuous, theta_near, omega_near);
  }
  return runs;
}

// When no run reached the end: DP's optimum (planDpRefined() on the auto grid) if it has one,
// else `ray` with its reason. Rays move in continuous θ and cannot pass a gap only one grid cell
// wide (between an open and a closed cell mapValue() reads 0); DP's grid paths can.
PlanResult dpFallback(const ConfigMap& map,
                      std::size_t branch,
                      const PlannerSettings& settings,
                      bool continuous,
                      std::optional<double> start_theta,
                      PlanResult ray) {
  const int r = autoAngleSubdivisions(map, branch, settings, continuous);
  PlanResult dp = planDpRefined(map, branch, settings, continuous, r, start_theta);
  if (!dp.solved()) return ray;
  dp.detail = "Ray Shooting found no path (" + ray.reason + "); DP's optimum instead (grid / " +
              std::to_string(r) + ")";
  return dp;
}

}  // namespace

PlanResult planRayShooting(const ConfigMap& map,
                           std::size_t branch,
                           const PlannerSettings& settings,
                           bool continuous,
                           const RayShootingSettings& rs,
                           std::optional<double> start_theta) {
  const auto clock_start = std::chrono::steady_clock::now();
  const detail::Grid g = detail::gridOf(map, branch, continuous);
  if (rs.rays < 1 || rs.horizon < 1 || rs.starts < 1 || !(rs.blocked_penalty >= 0.0) ||
      !(settings.omega_max >= 0.0) || !(settings.alpha_max >= 0.0)) {
    throw std::logic_error("planRayShooting: rays, horizon, starts >= 1; bounds, penalty >= 0");
  }
  std::optional<detail::CostToGo> guide;
  if (rs.cost_to_go) {
    guide = detail::costToGo(map, branch, settings, continuous, rs.blocked_penalty);
  }
  const Shooter shooter(map, g, branch, settings, continuous, rs, guide ? &*guide : nullptr);

  PlanResult result;
  result.branch = branch;
  std::vector<double> starts;
  if (start_theta) {
    if (shooter.fAt(*start_theta, 0) > 0.0) starts.push_back(*start_theta);
  } else {
    starts = spreadStarts(map, branch, static_cast<std::size_t>(rs.starts));
    if (guide) starts = corridorStarts(map, g, branch, continuous, *guide, std::move(starts));
  }
  if (starts.empty()) {
    result.reason = fmt::format("time sample 0 (t = {} s): f = 0 at {}", map.times[0],
                                start_theta ? "the start angle" : "every table angle");
  } else {
    std::vector<Run> runs = shootRuns(shooter, g, map.times.size(), settings, continuous, starts);
    combineRuns(map, branch, settings, continuous, starts, runs, result);
    if (!result.solved() && rs.dp_fallback) {
      result = dpFallback(map, branch, settings, continuous, start_theta, std::move(result));
    }
  }
  result.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
  return result;
}

namespace detail {

namespace {

constexpr double kGuideSteps = 3.0;     // D wanted per stage: speeds 0, ±1/3, ±2/3, ±1 ω_max
constexpr std::size_t kMaxStride = 16;  // coarser stages would look past short corridors

// −ln f·Δt (∞ where f = 0) on the sub-grid Δθ/stride of every time sample, f interpolated
// between grid angles as mapValue() does. Row k covers positions −pad … positions − 1 + pad: a
// continuous grid wraps into the padding, a limited one is closed there.
class SubGridCosts {
 public:
  SubGridCosts(const ConfigMap& map,
               const Grid& g,
               std::size_t branch,
               bool continuous,
               std::size_t stride,
               std::size_t pad)
      : na_(map.angles.size()),
        stride_(stride),
        positions_(continuous ? na_ * stride : (na_ - 1) * stride + 1),
        pad_(pad),
        row_(positions_ + 2 * pad) {
    const std::size_t nt = map.times.size();
    cost_.resize(nt * row_);
    tbb::parallel_for(std::size_t{0}, nt,
                      [&](std::size_t k) { fillRow(map, branch, continuous, g.dt, k); });
  }

  // Row k, indexed by the sub-grid position q ∈ [−pad, positions + pad).
  const float* row(std::size_t k) const { return cost_.data() + k * row_ + pad_; }

 private:
  void fillRow(
      const ConfigMap& map, std::size_t branch, bool continuous, double dt, std::size_t k) {
    float* r = cost_.data() + k * row_ + pad_;
    const auto inf = std::numeric_limits<float>::infinity();
    const auto cost = [&](double f) {
      return f > 0.0 ? -std::log(static_cast<float>(f)) * static_cast<float>(dt) : inf;
    };
    for (std::size_t a = 0; a < na_; ++a) {
      const double f0 = map.f[map.index(branch, a, k)];
      r[a * stride_] = cost(f0);
      if (a + 1 == na_ && !continuous) break;
      const double f1 = map.f[map.index(branch, (a + 1) % na_, k)];
      for (std::size_t m = 1; m < stride_; ++m) {
        const double w = static_cast<double>(m) / static_cast<double>(stride_);
        r[a * stride_ + m] = f0 > 0.0 && f1 > 0.0 ? cost((1.0 - w) * f0 + w * f1) : inf;
      }
    }
    const auto n = static_cast<std::ptrdiff_t>(positions_), p = static_cast<std::ptrdiff_t>(pad_);
    for (std::ptrdiff_t q = -p; q < 0; ++q) r[q] = continuous ? r[((q % n) + n) % n] : inf;
    for (std::ptrdiff_t q = n; q < n + p; ++q) r[q] = continuous ? r[q % n] : inf;
  }

  std::size_t na_, stride_, positions_, pad_, row_;
  std::vector<float> cost_;
};

// The stage geometry of one map: stride and D (see CostToGo).
void stageSteps(const Grid& g, const PlannerSettings& settings, CostToGo& guide) {
  const double per_sample = settings.omega_max * g.dt / g.angle_step;  // grid steps
  double stride = per_sample > 0.0 ? std::ceil(kGuideSteps / per_sample - 1e-9) : 1.0;
  stride = std::clamp(stride, 1.0, static_cast<double>(kMaxStride));
  guide.stride = static_cast<std::size_t>(stride);
  guide.max_step = static_cast<int>(std::ceil(per_sample * stride - 1e-9));
}

// One stage of the backward DP: `cur` (values at stage sample p) from `next` (at p + stride),
// padded by D either side (wrapped for a continuous grid; a limited grid's padding is never
// read, its sub-grid costs are ∞ there).
void relaxStage(const SubGridCosts& costs,
                const CostToGo& guide,
                const std::vector<double>& speed_cost,
                const std::vector<double>& next_padded,
                std::size_t p,
                std::size_t nt,
                double blocked_penalty,
                double* cur,
                std::size_t na) {
  const std::size_t s = guide.stride;
  const int d_max = guide.max_step;
  const auto stride = static_cast<std::ptrdiff_t>(s);
  for (std::size_t a = 0; a < na; ++a) {
    double best = kInfinity;
    const auto q0 = static_cast<std::ptrdiff_t>(a) * stride;
    for (int d = -d_max; d <= d_max; ++d) {
      double partial = 0.0;
      std::size_t i = 1;
      for (; i <= s; ++i) {
        const float c = costs.row(p + i)[q0 + d * static_cast<std::ptrdiff_t>(i)];
        if (std::isinf(c)) break;
        partial += static_cast<double>(c);
      }
      const auto j = static_cast<std::size_t>(d + d_max);
      partial += i <= s ? blocked_penalty * static_cast<double>(nt - p - i)
                        : speed_cost[j] + next_padded[a + j];
      best = std::min(best, partial);
    }
    cur[a] = best;
  }
}

}  // namespace

double CostToGo::at(const ConfigMap& map,
                    const Grid& g,
                    double theta,
                    std::size_t k,
                    bool continuous) const noexcept {
  const std::size_t na = map.angles.size(), nt = map.times.size();
  const double* v = value.data() + (nt - 1 - k) / stride * na;
  const double n = static_cast<double>(na);
  double u = (theta - g.angle0) / g.angle_step;
  if (continuous) {
    u -= n * std::floor(u / n);
    if (u >= n) u = 0.0;
  } else {
    u = std::clamp(u, 0.0, n - 1.0);
  }
  if (std::abs(u - std::round(u)) <= 1e-9) u = std::round(u);
  const double lower = std::floor(u), w = u - lower;
  const auto i0 = static_cast<std::size_t>(lower) % na;
  if (w == 0.0) return v[i0];
  return (1.0 - w) * v[i0] + w * v[(i0 + 1) % na];
}

CostToGo costToGo(const ConfigMap& map,
                  std::size_t branch,
                  const PlannerSettings& settings,
                  bool continuous,
                  double blocked_penalty) {
  const Grid g = gridOf(map, branch, continuous);
  CostToGo guide;
  stageSteps(g, settings, guide);
  const std::size_t na = map.angles.size(), nt = map.times.size(), s = guide.stride;
  const auto d_max = static_cast<std::size_t>(guide.max_step);
  const SubGridCosts costs(map, g, branch, continuous, s, d_max * s);
  // ω term of one stage step of d grid steps at constant speed, d = −D … D.
  std::vector<double> speed_cost(2 * d_max + 1);
  for (std::size_t j = 0; j < speed_cost.size(); ++j) {
    const double w = (static_cast<double>(j) - static_cast<double>(d_max)) * g.angle_step /
                     (static_cast<double>(s) * g.dt);
    speed_cost[j] = settings.k_omega * w * w * static_cast<double>(s) * g.dt;
  }
  const std::size_t stages = (nt - 1) / s;
  guide.value.assign((stages + 1) * na, 0.0);
  std::vector<double> next_padded(na + 2 * d_max, 0.0);
  for (std::size_t j = 1; j <= stages; ++j) {
    const double* next = guide.value.data() + (j - 1) * na;
    for (std::size_t i = 0; i < next_padded.size(); ++i) {
      const std::ptrdiff_t a = static_cast<std::ptrdiff_t>(i) - static_cast<std::ptrdiff_t>(d_max);
      const auto n = static_cast<std::ptrdiff_t>(na);
      next_padded[i] = continuous || (a >= 0 && a < n) ? next[((a % n) + n) % n] : 0.0;
    }
    relaxStage(costs, guide, speed_cost, next_padded, nt - 1 - j * s, nt, blocked_penalty,
               guide.value.data() + j * na, na);
  }
  return guide;
}

}  // namespace detail

}  // namespace scanplan::planner
