#include "planner/dp_planner.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace scanplan::planner {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

using Index = std::ptrdiff_t;

// The DP over (angle a, last step j − D) on the map's grid: bounds in grid steps, the per-step
// speed and acceleration costs (the evaluate() terms for a grid move) and cell access.
struct DpGrid {
  const ConfigMap& map;
  std::size_t branch;
  bool continuous;
  detail::Grid g;
  Index na = 0, nt = 0;
  Index D = 0;  // most grid steps per sample
  Index A = 0;  // largest change of steps between samples
  Index W = 0;  // step indices: 2D + 1
  std::vector<double> omega_cost{}, alpha_cost{};

  double cellF(Index a, Index k) const {
    return static_cast<double>(
        map.f[map.index(branch, static_cast<std::size_t>(a), static_cast<std::size_t>(k))]);
  }
  double cellCost(Index a, Index k) const {
    const double f = cellF(a, k);
    return f > 0.0 ? -std::log(f) * g.dt : kInf;
  }
  // value[a·W + j]
  std::size_t at(Index a, Index j) const { return static_cast<std::size_t>(a * W + j); }
  Index wrap(Index i) const { return ((i % na) + na) % na; }
};

DpGrid makeDpGrid(const ConfigMap& map,
                  std::size_t branch,
                  const PlannerSettings& settings,
                  bool continuous,
                  const detail::Grid& g) {
  DpGrid dp{map, branch, continuous, g};
  dp.na = static_cast<Index>(map.angles.size());
  dp.nt = static_cast<Index>(map.times.size());
  const double dt = g.dt, h = g.angle_step;
  // Bounds in grid steps. The 1e-12 only absorbs the rounding of the ratio, so every DP move
  // stays inside what evaluate() accepts (kBoundTolerance = 1e-9).
  const auto steps = [&](double ratio, Index cap) {
    return static_cast<Index>(
        std::min(std::floor(ratio * (1.0 + 1e-12)), static_cast<double>(cap)));
  };
  dp.D = steps(settings.omega_max * dt / h, dp.na - 1);
  dp.A = steps(settings.alpha_max * dt * dt / h, 2 * dp.D);
  dp.W = 2 * dp.D + 1;
  if (dp.W > std::numeric_limits<std::uint16_t>::max()) {
    throw std::logic_error("planDp: W too large");
  }
  dp.omega_cost.resize(static_cast<std::size_t>(dp.W));
  dp.alpha_cost.resize(static_cast<std::size_t>(2 * dp.A + 1));
  for (Index j = 0; j < dp.W; ++j) {
    const double omega = static_cast<double>(j - dp.D) * h / dt;
    dp.omega_cost[static_cast<std::size_t>(j)] = settings.k_omega * omega * omega * dt;
  }
  for (Index j = 0; j <= 2 * dp.A; ++j) {
    const double alpha = static_cast<double>(j - dp.A) * h / (dt * dt);
    dp.alpha_cost[static_cast<std::size_t>(j)] = settings.k_alpha * alpha * alpha * dt;
  }
  return dp;
}

std::string noPathReason(const DpGrid& dp, const PlannerSettings& settings, Index k) {
  Index open = 0;
  for (Index a = 0; a < dp.na; ++a) open += dp.cellF(a, k) > 0.0 ? 1 : 0;
  const std::string where = fmt::format("no feasible path reaches time sample {} (t = {} s): ", k,
                                        dp.map.times[static_cast<std::size_t>(k)]);
  if (open == 0) return where + "f = 0 at every table angle";
  if (k == 0) return where + "f = 0 at the start angle";
  return where + fmt::format(
                     "{} of {} angles have f > 0 but none is reachable within |omega| <= {} "
                     "rad/s and |alpha| <= {} rad/s^2 (at most {} grid steps per sample, "
                     "step changes of at most {})",
                     open, dp.na, settings.omega_max, settings.alpha_max, dp.D, dp.A);
}

// Layer k from layer k − 1 as DESIGN.md §5.2 writes it: the best predecessor of every (a, j),
// and its step index in back_k. Each (a, j) reads only the previous layer: the parallel loop is
// deterministic. Kept as the reference relaxLayer() must equal (tests, bench_dp).
void relaxLayerReference(const DpGrid& dp,
                         Index k,
                         const std::vector<double>& prev,
                         std::vector<double>& cur,
                         std::uint16_t* back_k) {
  const Index na = dp.na, W = dp.W, D = dp.D, A = dp.A;
  const auto grain = static_cast<std::size_t>(std::max<Index>(1, 4096 / (W * (2 * A + 1))));
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, static_cast<std::size_t>(na), grain),
      [&](const tbb::blocked_range<std::size_t>& range) noexcept {
        for (auto ua = range.begin(); ua != range.end(); ++ua) {
          const auto a = static_cast<Index>(ua);
          const double c = dp.cellCost(a, k);
          for (Index j = 0; j < W; ++j) {
            Index p = a - (j - D);  // the previous angle
            if (dp.continuous) p = dp.wrap(p);
            double best = kInf;
            Index best_j = D;
            if (c < kInf && p >= 0 && p < na) {
              if (k == 1) {
                best = prev[dp.at(p, D)];  // the first step is free of the acceleration bound
              } else {
                for (Index jp = std::max<Index>(0, j - A); jp <= std::min(W - 1, j + A); ++jp) {
                  const double v =
                      prev[dp.at(p, jp)] + dp.alpha_cost[static_cast<std::size_t>(j - jp + A)];
                  if (v < best) {
                    best = v;
                    best_j = jp;
                  }
                }
              }
            }
            cur[dp.at(a, j)] = best + c + dp.omega_cost[static_cast<std::size_t>(j)];
            back_k[dp.at(a, j)] = static_cast<std::uint16_t>(best_j);
          }
        }
      });
}

// The best predecessor of (a, j) among the steps jp = j − A … j + A of the previous angle's
// row, in the reference's order (the first of equal values wins, none leaves D), so the paths
// are the same bit for bit. Branch-free: a compare and two selects per step, no misprediction,
// and the chains of neighbouring j overlap.
inline void bestPredecessor(const double* row,
                            const double* alpha_cost,
                            Index j,
                            Index A,
                            Index W,
                            double& best,
                            Index& best_j) noexcept {
  const Index lo = std::max<Index>(0, j - A), hi = std::min(W - 1, j + A);
  const double* cost = alpha_cost + (j - lo + A);  // cost[-(jp - lo)] = α(j − jp)
  double b = best;
  Index bj = best_j;
  for (Index jp = lo; jp <= hi; ++jp) {
    const double v = row[jp] + *(cost - (jp - lo));
    const bool better = v < b;
    bj = better ? jp : bj;
    b = better ? v : b;
  }
  best = b;
  best_j = bj;
}

// relaxLayer with the same arithmetic in the same order, so the same values bit for bit
// (issue 20: DP 3× faster). What the reference spends its time on and this does not: two
// integer divisions per (a, j) to wrap the previous angle (one compare-and-add here, as
// |j − D| ≤ D < N_θ), mispredicted branches in the search over the acceleration window, and
// the cells of closed angles computed one (a, j) at a time.
void relaxLayer(const DpGrid& dp,
                Index k,
                const std::vector<double>& prev,
                std::vector<double>& cur,
                std::uint16_t* back_k) {
  const Index na = dp.na, W = dp.W, D = dp.D, A = dp.A;
  const auto grain = static_cast<std::size_t>(std::max<Index>(1, 4096 / (W * (2 * A + 1))));
  const double* alpha_cost = dp.alpha_cost.data();
  const double* omega_cost = dp.omega_cost.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, static_cast<std::size_t>(na), grain),
                    [&](const tbb::blocked_range<std::size_t>& range) noexcept {
                      for (auto ua = range.begin(); ua != range.end(); ++ua) {
                        const auto a = static_cast<Index>(ua);
                        const double c = dp.cellCost(a, k);
                        double* out = cur.data() + a * W;
                        std::uint16_t* back = back_k + a * W;
                        if (!(c < kInf)) {
                          std::fill(out, out + W, kInf);
                          std::fill(back, back + W, static_cast<std::uint16_t>(D));
                          continue;
                        }
                        for (Index j = 0; j < W; ++j) {
                          Index p = a - (j - D);  // the previous angle
                          if (dp.continuous) p += p < 0 ? na : (p >= na ? -na : 0);
                          double best = kInf;
                          Index best_j = D;
                          if (p >= 0 && p < na) {
                            const double* row = prev.data() + p * W;
                            if (k == 1) {
                              best = row[D];  // the first step is free of the acceleration bound
                            } else {
                              bestPredecessor(row, alpha_cost, j, A, W, best, best_j);
                            }
                          }
                          out[j] = best + c + omega_cost[j];
                          back[j] = static_cast<std::uint16_t>(best_j);
                        }
                      }
                    });
}

// Backtracks from the best final state of `last` (the layer of the last sample), then rebuilds
// the unwrapped path and its terms into `result`.
void rebuildPath(const DpGrid& dp,
                 const std::vector<double>& last,
                 const std::vector<std::uint16_t>& back,
                 std::optional<Index> start_step,
                 PlanResult& result) {
  const Index na = dp.na, nt = dp.nt, W = dp.W, D = dp.D, A = dp.A;
  const double dt = dp.g.dt, h = dp.g.angle_step;
  const auto uW = static_cast<std::size_t>(W);
  const auto best_it = std::min_element(last.begin(), last.end());
  const double best_value = *best_it;
  std::vector<Index> angle(static_cast<std::size_t>(nt)), step(static_cast<std::size_t>(nt));
  auto cell = static_cast<Index>(best_it - last.begin());
  angle.back() = cell / W;
  step.back() = cell % W;
  for (Index k = nt - 1; k >= 1; --k) {
    const auto uk = static_cast<std::size_t>(k);
    step[uk - 1] = back[static_cast<std::size_t>(k * na) * uW + dp.at(angle[uk], step[uk])];
    angle[uk - 1] = dp.wrap(angle[uk] - (step[uk] - D));
  }
  ObjectiveTerms& t = result.terms;
  t.min_f = kInf;
  Index s = start_step ? *start_step : angle[0];
  result.theta.resize(static_cast<std::size_t>(nt));
  for (Index k = 0; k < nt; ++k) {
    const auto uk = static_cast<std::size_t>(k);
    const Index d = step[uk] - D;
    if (k >= 1) {
      s += d;
      t.cost_omega += dp.omega_cost[static_cast<std::size_t>(step[uk])];
      t.max_abs_omega = std::max(t.max_abs_omega, static_cast<double>(std::abs(d)) * h / dt);
    }
    if (k >= 2) {
      const Index dd = step[uk] - step[uk - 1];
      t.cost_alpha += dp.alpha_cost[static_cast<std::size_t>(dd + A)];
      t.max_abs_alpha =
          std::max(t.max_abs_alpha, static_cast<double>(std::abs(dd)) * h / (dt * dt));
    }
    t.cost_f += dp.cellCost(angle[uk], k);
    if (dp.cellF(angle[uk], k) < t.min_f) {
      t.min_f = dp.cellF(angle[uk], k);
      t.min_f_sample = uk;
    }
    result.theta[uk] = dp.continuous ? dp.g.angle0 + static_cast<double>(s) * h
                                     : dp.map.angles[static_cast<std::size_t>(s)];
  }
  t.total = t.cost_f + t.cost_omega + t.cost_alpha;
  t.feasible = true;
  if (!(std::abs(t.total - best_value) <= 1e-9 * std::max(1.0, std::abs(best_value)))) {
    throw std::logic_error("planDp: backtracked path does not reproduce the optimum");
  }
}

using RelaxLayer = void (*)(
    const DpGrid&, Index, const std::vector<double>&, std::vector<double>&, std::uint16_t*);

PlanResult solveDp(const ConfigMap& map,
                   std::size_t branch,
                   const PlannerSettings& settings,
                   bool continuous,
                   std::optional<double> start_theta,
                   RelaxLayer relax) {
  const auto clock_start = std::chrono::steady_clock::now();
  const detail::Grid g = detail::gridOf(map, branch, continuous);
  if (!(settings.omega_max >= 0.0) || !(settings.alpha_max >= 0.0)) {
    throw std::logic_error("planDp: omega_max and alpha_max must be >= 0");
  }
  const DpGrid dp = makeDpGrid(map, branch, settings, continuous, g);
  const Index na = dp.na, nt = dp.nt, D = dp.D;
  const auto uW = static_cast<std::size_t>(dp.W);

  PlanResult result;
  result.branch = branch;
  const auto finish = [&](PlanResult& r) -> PlanResult& {
    r.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
    return r;
  };

  // value[a·W + j]: best cost of a path up to sample k ending at angle a with last step j − D.
  // back[(k·N + a)·W + j]: the previous sample's step index.
  std::vector<double> prev(static_cast<std::size_t>(na) * uW, kInf), cur(prev.size(), kInf);
  std::vector<std::uint16_t> back(static_cast<std::size_t>(nt) * prev.size(), 0);

  std::optional<Index> start_step;  // unwrapped grid index of a fixed start
  if (start_theta) {
    start_step = static_cast<Index>(std::llround((*start_theta - g.angle0) / g.angle_step));
    if (!continuous && (*start_step < 0 || *start_step >= na)) {
      result.reason =
          fmt::format("time sample 0: start angle {} rad is outside the table range", *start_theta);
      return finish(result);
    }
  }
  for (Index a = 0; a < na; ++a) {
    if (!start_step || a == dp.wrap(*start_step)) prev[dp.at(a, D)] = dp.cellCost(a, 0);
  }

  const auto anyFinite = [](const std::vector<double>& v) {
    return std::any_of(v.begin(), v.end(), [](double x) { return x < kInf; });
  };
  if (!anyFinite(prev)) {
    result.reason = noPathReason(dp, settings, 0);
    return finish(result);
  }
  for (Index k = 1; k < nt; ++k) {
    relax(dp, k, prev, cur, back.data() + static_cast<std::size_t>(k * na) * uW);
    if (!anyFinite(cur)) {
      result.reason = noPathReason(dp, settings, k);
      return finish(result);
    }
    std::swap(prev, cur);
  }

  rebuildPath(dp, prev, back, start_step, result);
  result.status = PlanResult::Status::kExact;
  return finish(result);
}

}  // namespace

PlanResult planDp(const ConfigMap& map,
                  std::size_t branch,
                  const PlannerSettings& settings,
                  bool continuous,
                  std::optional<double> start_theta) {
  return solveDp(map, branch, settings, continuous, start_theta, relaxLayer);
}

namespace detail {
PlanResult planDpReference(const ConfigMap& map,
                           std::size_t branch,
                           const PlannerSettings& settings,
                           bool continuous,
                           std::optional<double> start_theta) {
  return solveDp(map, branch, settings, continuous, start_theta, relaxLayerReference);
}
}  // namespace detail

int autoAngleSubdivisions(const ConfigMap& map,
                          std::size_t branch,
                          const PlannerSettings& settings,
                          bool continuous,
                          int accel_steps,
                          int max_subdivisions) {
  const detail::Grid g = detail::gridOf(map, branch, continuous);
  const double per_step = settings.alpha_max * g.dt * g.dt / g.angle_step;  // A at r = 1
  for (int r = 1; r < max_subdivisions; ++r) {
    if (std::floor(per_step * r * (1.0 + 1e-12)) >= accel_steps) return r;
  }
  return std::max(1, max_subdivisions);
}

PlanResult planDpRefined(const ConfigMap& map,
                         std::size_t branch,
                         const PlannerSettings& settings,
                         bool continuous,
                         int subdivisions,
                         std::optional<double> start_theta) {
  if (subdivisions < 1) throw std::logic_error("planDpRefined: subdivisions must be >= 1");
  if (subdivisions == 1) return planDp(map, branch, settings, continuous, start_theta);
  const auto clock_start = std::chrono::steady_clock::now();
  const detail::Grid g = detail::gridOf(map, branch, continuous);
  const auto r = static_cast<std::size_t>(subdivisions);
  const std::size_t na = map.angles.size(), nt = map.times.size();
  ConfigMap fine;
  fine.times = map.times;
  fine.branches = {map.branches[branch]};
  const std::size_t nf = continuous ? na * r : (na - 1) * r + 1;
  const double h = g.angle_step / static_cast<double>(r);
  fine.angles.resize(nf);
  for (std::size_t i = 0; i < nf; ++i) fine.angles[i] = g.angle0 + static_cast<double>(i) * h;
  fine.f.resize(nf * nt);
  tbb::parallel_for(std::size_t{0}, nf, [&](std::size_t i) {
    for (std::size_t k = 0; k < nt; ++k) {
      // Cells on the original grid copy exactly; the others interpolate as mapValue() does.
      fine.f[fine.index(0, i, k)] =
          i % r == 0
              ? map.f[map.index(branch, i / r, k)]
              : static_cast<float>(detail::mapValue(map, g, branch, fine.angles[i], k, continuous));
    }
  });
  PlanResult result = planDp(fine, 0, settings, continuous, start_theta);
  result.branch = branch;
  if (result.status == PlanResult::Status::kExact) {
    result.terms = evaluate(map, branch, result.theta, settings, continuous);
    if (!result.terms.feasible) throw std::logic_error("planDpRefined: infeasible optimum");
  }
  result.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
  return result;
}

}  // namespace scanplan::planner
