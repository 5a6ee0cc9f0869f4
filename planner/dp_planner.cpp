#include <scanplan/planner/dp_planner.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
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
  double cellCost(Index a, Index k) const { return costOf(cellF(a, k)); }
  double costOf(double f) const { return f > 0.0 ? -std::log(f) * g.dt : kInf; }
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

// Layer k from layer k − 1 as docs/design.md §5.2 writes it: the best predecessor of every (a, j),
// and its step index in back_k. Each (a, j) reads only the previous layer: the parallel loop is
// deterministic. Kept as the reference planDp's step-major kernels must equal (tests, bench_dp).
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

// The result from the grid path (angle index, step index per sample): the unwrapped angles and
// the DP's own terms, which must sum to the optimum `best_value` the layers held.
void fillResult(const DpGrid& dp,
                const std::vector<Index>& angle,
                const std::vector<Index>& step,
                std::optional<Index> start_step,
                double best_value,
                PlanResult& result) {
  const Index nt = dp.nt, D = dp.D, A = dp.A;
  const double dt = dp.g.dt, h = dp.g.angle_step;
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

// The reference's layers: value[a·W + j] of the last two samples, back[(k·N + a)·W + j] the
// previous sample's step index.
class ReferenceLayers {
 public:
  explicit ReferenceLayers(const DpGrid& dp)
      : dp_(dp),
        prev_(static_cast<std::size_t>(dp.na * dp.W), kInf),
        cur_(prev_.size(), kInf),
        back_(static_cast<std::size_t>(dp.nt) * prev_.size(), 0) {}

  void start(Index a, double cost) { prev_[dp_.at(a, dp_.D)] = cost; }
  bool started() const { return anyFinite(prev_); }

  // Layer k from layer k − 1; false when no state of layer k is finite.
  bool relax(Index k) {
    relaxLayerReference(dp_, k, prev_, cur_,
                        back_.data() + static_cast<std::size_t>(k * dp_.na * dp_.W));
    if (!anyFinite(cur_)) return false;
    std::swap(prev_, cur_);
    return true;
  }

  // The best final state (the first of equal values in (a, j) order) and the states before it.
  double backtrack(std::vector<Index>& angle, std::vector<Index>& step) const {
    const Index na = dp_.na, W = dp_.W, D = dp_.D;
    const auto best_it = std::min_element(prev_.begin(), prev_.end());
    const auto cell = static_cast<Index>(best_it - prev_.begin());
    angle.back() = cell / W;
    step.back() = cell % W;
    for (Index k = dp_.nt - 1; k >= 1; --k) {
      const auto uk = static_cast<std::size_t>(k);
      step[uk - 1] = back_[static_cast<std::size_t>(k * na * W) + dp_.at(angle[uk], step[uk])];
      angle[uk - 1] = dp_.wrap(angle[uk] - (step[uk] - D));
    }
    return *best_it;
  }

 private:
  static bool anyFinite(const std::vector<double>& v) {
    return std::any_of(v.begin(), v.end(), [](double x) { return x < kInf; });
  }

  const DpGrid& dp_;
  std::vector<double> prev_, cur_;
  std::vector<std::uint16_t> back_;
};

// planDp's layers are step-major: row j holds the value of every angle a with last
// step j − D. The states (a, j) of consecutive a then read their predecessors
// (a − (j − D), j + o), o = −A … A, as one contiguous run of each previous row, so the
// relaxation runs over angles in vector lanes with the reference's arithmetic and order per
// lane. Each row has D ghost cells on both sides (a continuous table's wrap-around; +inf past a
// limited table's ends), so no lane wraps or tests its predecessor angle, and is padded to a
// whole number of kBlock angles: the last block runs on past the last angle, over cells whose
// cost is +inf.
constexpr Index kBlock = 16;

// Back pointers hold the predecessor's step as its offset o + A + 1 (1 … 2A + 1) from the
// state's own step: one byte unless the acceleration window is wider than 255 steps.
template <class Back>
struct KernelArgs {
  const double* prev;  // row j, angle p at prev[j·stride + pad + p], p = −pad … width + pad − 1
  double* cur;
  Back* back;          // the layer's back pointers, back[j·width + a]
  const double* cell;  // the layer's cell costs, +inf from na to width
  const double* alpha_cost;
  const double* omega_cost;
  Index W, D, A, pad, stride, width;
};

template <int N>
struct Lanes {
  using Real [[gnu::vector_size(N * sizeof(double))]] = double;
  using Mask [[gnu::vector_size(N * sizeof(double))]] = std::int64_t;
  using Int [[gnu::vector_size(N * sizeof(std::int32_t))]] = std::int32_t;
};

// Layer k ≥ 2 at the angles [a0, a1) (whole blocks of N·G), every step j. Per lane the
// reference's loop: the candidates in increasing jp and a strict <, so the first of equal
// values wins, then (best + c) + ω(j). The best value is min(v, best), which is
// `v < best ? v : best` (one instruction); the mark of the best, o + A + 1, is set where
// v < best, o increasing, so it ends on the first minimum; a state left +inf keeps mark 0 (the
// backtrack never reads it). With mask registers (kMaskRegisters) the mark is a masked move;
// without, a blend costs three µops on recent x86, so the mark is kept as max(mark, better &
// (o + A + 1)) instead, and the compare is spelt !(v >= best) (the same, there is no NaN here)
// so that the compiler does not fold it into the min and make both blends. G groups of N lanes
// make independent chains. Returns whether any state is finite.
template <int N, int G, bool kMaskRegisters, class Back>
[[gnu::always_inline]] inline bool relaxSpan(const KernelArgs<Back>& x,
                                             Index a0,
                                             Index a1) noexcept {
  using L = Lanes<N>;
  using Real = typename L::Real;
  using Mask = typename L::Mask;
  constexpr Index kLanes = Index{N} * G;
  constexpr auto kGroups = static_cast<std::size_t>(G);
  static_assert(kBlock % kLanes == 0);
  // Locals, since the stores below (memcpy) could otherwise alias x and force reloads.
  const double* const prev = x.prev;
  double* const cur = x.cur;
  Back* const back_k = x.back;
  const double* const cell = x.cell;
  const double* const alpha_cost = x.alpha_cost;
  const Index W = x.W, D = x.D, A = x.A, pad = x.pad, stride = x.stride, width = x.width;
  Real lowest = Real{} + kInf;
  for (Index j = 0; j < W; ++j) {
    const Index o_lo = std::max(-A, -j), o_hi = std::min(A, W - 1 - j);
    const double* from = prev + pad + (D - j);  // from[jp·stride + a]: state (a − (j − D), jp)
    double* out = cur + j * stride + pad;
    Back* back = back_k + j * width;
    const double omega = x.omega_cost[j];
    for (Index a = a0; a < a1; a += kLanes) {
      Real best[kGroups], mark[kGroups];
      for (std::size_t g = 0; g < kGroups; ++g) {
        best[g] = Real{} + kInf;
        mark[g] = Real{};
      }
      for (Index o = o_lo; o <= o_hi; ++o) {
        const double* row = from + (j + o) * stride + a;
        const double alpha = alpha_cost[A - o];
        const Real here = Real{} + static_cast<double>(o + A + 1);
        for (std::size_t g = 0; g < kGroups; ++g) {
          Real v;
          std::memcpy(&v, row + g * N, sizeof v);
          v += alpha;
          if constexpr (kMaskRegisters) {
            const Mask better = v < best[g];
            mark[g] = better ? here : mark[g];
          } else {
            const Mask better = !(v >= best[g]);
            const Real m = __builtin_bit_cast(Real, better & __builtin_bit_cast(Mask, here));
            mark[g] = mark[g] < m ? m : mark[g];
          }
          best[g] = v < best[g] ? v : best[g];
        }
      }
      std::int32_t marks[kGroups * N];
      for (std::size_t g = 0; g < kGroups; ++g) {
        const Index ag = a + static_cast<Index>(g) * N;
        Real c;
        std::memcpy(&c, cell + ag, sizeof c);
        const Real value = best[g] + c + omega;
        std::memcpy(out + ag, &value, sizeof value);
        lowest = value < lowest ? value : lowest;
        const auto mark32 = __builtin_convertvector(mark[g], typename L::Int);
        std::memcpy(marks + g * N, &mark32, sizeof mark32);
      }
      // Narrowed for the whole block at once, which compilers do with register packs (group by
      // group they move lane by lane).
      for (Index l = 0; l < kLanes; ++l) back[a + l] = static_cast<Back>(marks[l]);
    }
  }
  bool any = false;
  for (int l = 0; l < N; ++l) any = any || lowest[l] < kInf;
  return any;
}

// The portable kernel: SSE2 on x86-64, the target's baseline elsewhere.
template <class Back>
bool relaxSpanPortable(const KernelArgs<Back>& x, Index a0, Index a1) noexcept {
  return relaxSpan<2, 4, false>(x, a0, a1);
}

#if defined(__x86_64__)
// The same source for wider registers, chosen at run time: the build assumes no more than
// x86-64 (docs/design.md §9). Same results bit for bit: the same operations per lane, and no
// contraction (there is no product to fuse). AVX2: four lanes a register; AVX-512: eight, and
// a compare into a mask register selects the mark in one µop.
template <class Back>
[[gnu::target("avx2")]] bool relaxSpanAvx2(const KernelArgs<Back>& x, Index a0, Index a1) noexcept {
  return relaxSpan<4, 4, false>(x, a0, a1);
}

template <class Back>
[[gnu::target("avx512f")]] bool relaxSpanAvx512(const KernelArgs<Back>& x,
                                                Index a0,
                                                Index a1) noexcept {
  return relaxSpan<8, 2, true>(x, a0, a1);
}
#endif

template <class Back>
using RelaxSpan = bool (*)(const KernelArgs<Back>&, Index, Index) noexcept;

template <class Back>
RelaxSpan<Back> kernelOf(detail::DpKernel kernel) {
  using detail::DpKernel;
  if (kernel == DpKernel::kBest) {
    for (const DpKernel k : {DpKernel::kAvx512, DpKernel::kAvx2}) {
      if (detail::dpKernelAvailable(k)) return kernelOf<Back>(k);
    }
    return relaxSpanPortable<Back>;
  }
  if (!detail::dpKernelAvailable(kernel)) {
    throw std::logic_error("planDp: this CPU cannot run the requested kernel");
  }
#if defined(__x86_64__)
  if (kernel == DpKernel::kAvx512) return relaxSpanAvx512<Back>;
  if (kernel == DpKernel::kAvx2) return relaxSpanAvx2<Back>;
#endif
  return relaxSpanPortable<Back>;
}

template <class Back>
class StepMajorLayers {
 public:
  static constexpr Index kCellBatch = 128, kPrefetch = 8;

  StepMajorLayers(const DpGrid& dp, detail::DpKernel kernel)
      : dp_(dp),
        relax_span_(kernelOf<Back>(kernel)),
        pad_(dp.D),
        width_((dp.na + kBlock - 1) / kBlock * kBlock),
        stride_(pad_ + width_ + pad_),
        prev_(toSize(dp.W * stride_), kInf),
        cur_(prev_.size(), kInf),
        f_batch_(toSize(kCellBatch * width_)),
        cell_(toSize(width_), kInf),
        // Layers 2 … nt − 1; every byte is written before it is read.
        back_(std::make_unique_for_overwrite<Back[]>(
            toSize(std::max<Index>(0, dp.nt - 2) * dp.W * width_))) {}

  void start(Index a, double cost) { prev_[toSize(dp_.D * stride_ + pad_ + a)] = cost; }
  bool started() {
    fillGhosts(prev_);
    return std::any_of(prev_.begin(), prev_.end(), [](double x) { return x < kInf; });
  }

  bool relax(Index k) {
    const Index na = dp_.na, W = dp_.W, A = dp_.A;
    const KernelArgs<Back> x{prev_.data(),
                             cur_.data(),
                             k >= 2 ? back_.get() + toSize((k - 2) * W * width_) : nullptr,
                             cell_.data(),
                             dp_.alpha_cost.data(),
                             dp_.omega_cost.data(),
                             W,
                             dp_.D,
                             A,
                             pad_,
                             stride_,
                             width_};
    const auto grain = toSize(std::max<Index>(1, 65536 / (kBlock * W * (2 * A + 1))));
    std::atomic<bool> open{false};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, toSize(width_ / kBlock), grain),
                      [&](const tbb::blocked_range<std::size_t>& blocks) noexcept {
                        const auto a0 = static_cast<Index>(blocks.begin()) * kBlock;
                        const auto a1 = static_cast<Index>(blocks.end()) * kBlock;
                        if ((k - 1) % kCellBatch == 0) readBatch(k, a0, std::min(a1, na));
                        const float* f = f_batch_.data() + toSize((k - 1) % kCellBatch * width_);
                        for (Index a = a0; a < std::min(a1, na); ++a) {
                          cell_[toSize(a)] = dp_.costOf(static_cast<double>(f[a]));
                        }
                        const bool any = k == 1 ? firstStep(x, a0, a1) : relax_span_(x, a0, a1);
                        if (any) open.store(true, std::memory_order_relaxed);
                      });
    if (!open.load()) return false;
    fillGhosts(cur_);
    std::swap(prev_, cur_);
    return true;
  }

  double backtrack(std::vector<Index>& angle, std::vector<Index>& step) const {
    const Index na = dp_.na, W = dp_.W, D = dp_.D, A = dp_.A;
    // The reference's choice among equal final values: the first in (a, j) order.
    double best = kInf;
    for (Index a = 0; a < na; ++a) {
      for (Index j = 0; j < W; ++j) {
        const double v = prev_[toSize(j * stride_ + pad_ + a)];
        if (v < best) {
          best = v;
          angle.back() = a;
          step.back() = j;
        }
      }
    }
    for (Index k = dp_.nt - 1; k >= 1; --k) {
      const auto uk = static_cast<std::size_t>(k);
      if (k == 1) {
        step[0] = D;  // the start has no step yet
      } else {
        const Index mark = back_[toSize(((k - 2) * W + step[uk]) * width_ + angle[uk])];
        if (mark < 1) throw std::logic_error("planDp: backtracked into an unreachable state");
        step[uk - 1] = step[uk] + mark - 1 - A;
      }
      angle[uk - 1] = dp_.wrap(angle[uk] - (step[uk] - D));
    }
    return best;
  }

 private:
  static std::size_t toSize(Index n) { return static_cast<std::size_t>(n); }

  // f of layers k … k + kCellBatch − 1 at the angles [a0, a1), layer by layer. The map holds
  // an angle's samples together and angles a page apart: read one layer at a time, every angle
  // would cost a cache miss and a page walk (an eighth of the time); read in batches, one walk
  // per angle and batch, the lines fetched ahead as no hardware prefetcher would.
  void readBatch(Index k, Index a0, Index a1) noexcept {
    const Index n = std::min(k + kCellBatch, dp_.nt) - k;
    const float* f = dp_.map.f.data();
    for (Index a = a0; a < a1; ++a) {
      if (a + kPrefetch < a1) {
        const float* ahead = f + dp_.map.index(dp_.branch, toSize(a + kPrefetch), toSize(k));
        for (Index i = 0; i < n; i += 16) __builtin_prefetch(ahead + i);
        __builtin_prefetch(ahead + (n - 1));
      }
      const float* run = f + dp_.map.index(dp_.branch, toSize(a), toSize(k));
      for (Index i = 0; i < n; ++i) f_batch_[toSize(i * width_ + a)] = run[i];
    }
  }

  // Layer 1: the first step is free of the acceleration bound, so (a, j) has the one
  // predecessor (a − (j − D), D).
  static bool firstStep(const KernelArgs<Back>& x, Index a0, Index a1) noexcept {
    bool any = false;
    for (Index j = 0; j < x.W; ++j) {
      const double* from = x.prev + x.D * x.stride + x.pad + (x.D - j);
      double* out = x.cur + j * x.stride + x.pad;
      for (Index a = a0; a < a1; ++a) {
        out[a] = from[a] + x.cell[a] + x.omega_cost[j];
        any = any || out[a] < kInf;
      }
    }
    return any;
  }

  // A continuous table's rows wrap: ghost p < 0 is angle p + N, ghost p ≥ N is angle p − N
  // (|p − a| ≤ D < N). A limited table's ghosts stay +inf (no relaxation writes them but the
  // last block's, whose cell cost is +inf).
  void fillGhosts(std::vector<double>& layer) const {
    if (!dp_.continuous) return;
    const Index na = dp_.na;
    for (Index j = 0; j < dp_.W; ++j) {
      double* row = layer.data() + j * stride_ + pad_;
      std::copy(row + na - pad_, row + na, row - pad_);
      std::copy(row, row + pad_, row + na);
    }
  }

  const DpGrid& dp_;
  RelaxSpan<Back> relax_span_;
  Index pad_, width_, stride_;
  std::vector<double> prev_, cur_;
  std::vector<float> f_batch_;  // f of the current batch of layers, [k − k_batch][a]
  std::vector<double> cell_;    // the layer's cell costs, +inf from na to width
  std::unique_ptr<Back[]> back_;
};

// The DP over samples 0 … nt − 1: with_layers(dp, run) makes the layers (the reference's or
// the step-major ones) and returns run(layers).
template <class WithLayers>
PlanResult solveDp(const ConfigMap& map,
                   std::size_t branch,
                   const PlannerSettings& settings,
                   bool continuous,
                   std::optional<double> start_theta,
                   WithLayers with_layers) {
  const auto clock_start = std::chrono::steady_clock::now();
  const detail::Grid g = detail::gridOf(map, branch, continuous);
  if (!(settings.omega_max >= 0.0) || !(settings.alpha_max >= 0.0)) {
    throw std::logic_error("planDp: omega_max and alpha_max must be >= 0");
  }
  const DpGrid dp = makeDpGrid(map, branch, settings, continuous, g);
  const Index na = dp.na, nt = dp.nt;

  PlanResult result;
  result.branch = branch;
  const auto finish = [&](PlanResult& r) -> PlanResult& {
    r.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
    return r;
  };

  std::optional<Index> start_step;  // unwrapped grid index of a fixed start
  if (start_theta) {
    start_step = static_cast<Index>(std::llround((*start_theta - g.angle0) / g.angle_step));
    if (!continuous && (*start_step < 0 || *start_step >= na)) {
      result.reason =
          fmt::format("time sample 0: start angle {} rad is outside the table range", *start_theta);
      return finish(result);
    }
  }
  const auto run = [&](auto& layers) -> PlanResult {
    for (Index a = 0; a < na; ++a) {
      if (!start_step || a == dp.wrap(*start_step)) layers.start(a, dp.cellCost(a, 0));
    }
    if (!layers.started()) {
      result.reason = noPathReason(dp, settings, 0);
      return finish(result);
    }
    for (Index k = 1; k < nt; ++k) {
      if (!layers.relax(k)) {
        result.reason = noPathReason(dp, settings, k);
        return finish(result);
      }
    }
    std::vector<Index> angle(static_cast<std::size_t>(nt)), step(static_cast<std::size_t>(nt));
    const double best_value = layers.backtrack(angle, step);
    fillResult(dp, angle, step, start_step, best_value, result);
    result.status = PlanResult::Status::kExact;
    return finish(result);
  };
  return with_layers(dp, run);
}

}  // namespace

PlanResult planDp(const ConfigMap& map,
                  std::size_t branch,
                  const PlannerSettings& settings,
                  bool continuous,
                  std::optional<double> start_theta) {
  return detail::planDpWithKernel(map, branch, settings, continuous, detail::DpKernel::kBest,
                                  start_theta);
}

namespace detail {
bool dpKernelAvailable(DpKernel kernel) {
  switch (kernel) {
    case DpKernel::kBest:
    case DpKernel::kPortable:
      return true;
#if defined(__x86_64__)
    case DpKernel::kAvx2:
      return __builtin_cpu_supports("avx2");
    case DpKernel::kAvx512:
      return __builtin_cpu_supports("avx512f");
#else
    case DpKernel::kAvx2:
    case DpKernel::kAvx512:
      return false;
#endif
  }
  return false;
}

PlanResult planDpWithKernel(const ConfigMap& map,
                            std::size_t branch,
                            const PlannerSettings& settings,
                            bool continuous,
                            DpKernel kernel,
                            std::optional<double> start_theta) {
  return solveDp(map, branch, settings, continuous, start_theta,
                 [&](const DpGrid& dp, const auto& run) {
                   // One byte a back pointer when the acceleration window's offsets fit.
                   if (2 * dp.A + 1 <= std::numeric_limits<std::uint8_t>::max()) {
                     StepMajorLayers<std::uint8_t> layers(dp, kernel);
                     return run(layers);
                   }
                   if (2 * dp.A + 1 > std::numeric_limits<std::uint16_t>::max()) {
                     throw std::logic_error("planDp: acceleration window too wide");
                   }
                   StepMajorLayers<std::uint16_t> layers(dp, kernel);
                   return run(layers);
                 });
}

PlanResult planDpReference(const ConfigMap& map,
                           std::size_t branch,
                           const PlannerSettings& settings,
                           bool continuous,
                           std::optional<double> start_theta) {
  return solveDp(map, branch, settings, continuous, start_theta,
                 [](const DpGrid& dp, const auto& run) {
                   ReferenceLayers layers(dp);
                   return run(layers);
                 });
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
