#include <scanplan/pipeline/program_moves.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <unordered_map>

#include <fmt/format.h>
#include <tbb/collaborative_call_once.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <scanplan/collision/clearance.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/pipeline/cancel.h>

namespace scanplan::pipeline {

namespace {

using kinematics::AxisVector;
using kinematics::JointVector;
using kinematics::Trajectory;
using kinematics::TrajectorySample;

constexpr double kTwoPi = 6.283185307179586;

AxisVector axesOf(const TrajectorySample& s) {
  AxisVector x;
  x(0) = s.theta;
  x.tail<kinematics::kNumJoints>() = s.q;
  return x;
}

// The speed at a segment's start (first interval) or end (last interval).
AxisVector startSpeed(const Trajectory& seg) {
  const auto& s = seg.samples;
  if (s.size() < 2) return AxisVector::Zero();
  return (axesOf(s[1]) - axesOf(s[0])) / (s[1].t - s[0].t);
}
AxisVector endSpeed(const Trajectory& seg) {
  const auto& s = seg.samples;
  if (s.size() < 2) return AxisVector::Zero();
  const std::size_t n = s.size();
  return (axesOf(s[n - 1]) - axesOf(s[n - 2])) / (s[n - 1].t - s[n - 2].t);
}

// The segment turned by whole turns of the table (a table that turns without end) and of each
// joint whose whole track then stays in its limits, to start as near `at` as it can.
Trajectory unwound(const kinematics::CellModel& cell, Trajectory seg, const AxisVector& at) {
  auto& s = seg.samples;
  if (cell.table.continuous) {
    const double turns = std::round((at(0) - s.front().theta) / kTwoPi);
    for (auto& x : s) x.theta += turns * kTwoPi;
  }
  for (int j = 0; j < kinematics::kNumJoints; ++j) {
    const kinematics::DhJoint& joint = cell.robot.joint(j);
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const auto& x : s) {
      lo = std::min(lo, x.q(j));
      hi = std::max(hi, x.q(j));
    }
    double best = 0.0;
    for (const double k : {-2.0, -1.0, 1.0, 2.0}) {
      const double shift = k * kTwoPi;
      if (lo + shift < joint.min || hi + shift > joint.max) continue;
      if (std::abs(s.front().q(j) + shift - at(j + 1)) <
          std::abs(s.front().q(j) + best - at(j + 1)))
        best = shift;
    }
    if (best != 0.0)
      for (auto& x : s) x.q(j) += best;
  }
  return seg;
}

// A sample of a move: the scanner pose it reaches (part frame), not scanning, f unknown.
TrajectorySample moveSample(const kinematics::CellModel& cell, double t, const AxisVector& x) {
  TrajectorySample s;
  s.t = t;
  s.theta = x(0);
  s.q = x.tail<kinematics::kNumJoints>();
  s.f = std::numeric_limits<double>::quiet_NaN();
  s.scanning = false;
  s.X_PS = cell.partIn(s.theta).inverse() * cell.robot.fk(s.q) * cell.scanner.X_FS;
  return s;
}

// How far the nearest pair of the cell is beyond its d_low at a pose (m); nullopt when a pair
// is not (f_C = 0, Eq. 8) or a joint is outside its limits.
std::optional<double> poseMargin(const collision::Scene& scene,
                                 collision::ClearanceEvaluator& clearance,
                                 const AxisVector& x) {
  const JointVector q = x.tail<kinematics::kNumJoints>();
  if (!scene.cell().robot.withinLimits(q)) return std::nullopt;
  const collision::ClearanceResult r = clearance.evaluate(x(0), q);
  if (!(r.factor > 0.0)) return std::nullopt;
  const auto& pairs = scene.pairs();
  double margin = std::numeric_limits<double>::infinity();
  for (std::size_t p = 0; p < pairs.size(); ++p)
    margin = std::min(margin, r.pairs[p].distance - pairs[p].thresholds.d_low);
  return margin;
}

// The lowest i in [0, n) for which `clear(i, stop)` is false; n when there is none. The calls run
// in parallel (a move's slow check spread over the threads the other moves left idle); none above
// a failing one already found is started, and `stop()` tells a running one that its answer is no
// longer needed. Every one below the answer runs to its end: the answer does not depend on the
// threads.
template <class Clear>
std::size_t firstBlocked(std::size_t n, Clear clear) {
  std::atomic<std::size_t> first{n};
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    const auto stop = [&] { return first.load(std::memory_order_relaxed) < i; };
    if (stop() || clear(i, stop)) return;
    for (std::size_t seen = first.load(); i < seen && !first.compare_exchange_weak(seen, i);) {
    }
  });
  return first.load();
}

// The margins at a move's samples (its own poses, `move.axes`), nullopt when one is blocked;
// then `blocked_at` (if given) gets how far along the samples the first blocked one is (0 to 1).
// A way is checked at all its samples first: a blocked one is found before any pose between them
// is. `start`: the margin at the first sample when it is known (the end of the leg before).
std::optional<std::vector<double>> sampleMargins(const collision::Scene& scene,
                                                 const kinematics::PtpMove& move,
                                                 double* blocked_at = nullptr,
                                                 std::optional<double> start = std::nullopt) {
  const std::size_t n = move.axes.size();
  std::vector<double> margins(n);
  const std::size_t blocked = firstBlocked(n, [&](std::size_t k, const auto&) {
    collision::ClearanceEvaluator clearance(scene);
    const std::optional<double> m =
        k == 0 && start ? start : poseMargin(scene, clearance, move.axes[k]);
    if (m) margins[k] = *m;
    return m.has_value();
  });
  if (blocked == n) return margins;
  if (blocked_at && n > 1) *blocked_at = static_cast<double>(blocked) / static_cast<double>(n - 1);
  return std::nullopt;
}

// A stretch of a leg between two poses found clear: from u0 to u1 of the span between the leg's
// samples `a` and `b`, with the margins m0 and m1 there. The span starts `along` the leg's samples
// (0 to 1) and takes `length` of it.
struct Stretch {
  const AxisVector* a;
  const AxisVector* b;
  double u0, u1, m0, m1;
  double along, length;
};

// Whether a stretch is clear without a look inside: a point of the cell moves at most levers(j)
// metres per radian of axis j, so at most `travel` over the stretch, and no pair can close a gap
// of m0 at one end and m1 at the other before the motion reaches m0 + m1 (0.8 of it is taken).
// At most `settings.check_step` rad on the fastest axis too; a stretch of kMinMotion of motion or
// less is not split.
constexpr double kMinMotion = 1.5e-3;  // m
bool certified(const Stretch& s, const AxisVector& levers, double check_step) {
  const AxisVector d = (*s.b - *s.a).cwiseAbs() * (s.u1 - s.u0);
  const double travel = levers.dot(d);
  return travel <= kMinMotion || (d.maxCoeff() <= check_step && travel <= 0.8 * (s.m0 + s.m1));
}

// Every pair of the cell beyond its d_low and every joint within its limits at the poses between
// the samples of a way's legs (clear themselves, with `margins` at them: sampleMargins()). Each
// span between samples is halved until its stretches are certified(): the poses at the middles
// are checked a level at a time, every stretch of the way at once and in parallel, so a blocked
// way is found at the coarsest level that meets the obstacle. The validation proves the motion
// between the poses. When blocked, `blocked_at` (if given) gets where the first blocked pose of
// that level lies along the first leg's samples (0 to 1; the direct move has one leg).
bool legsClear(const collision::Scene& scene,
               const std::vector<kinematics::PtpMove>& legs,
               const std::vector<std::vector<double>>& margins,
               const AxisVector& levers,
               const MoveSettings& settings,
               double* blocked_at = nullptr) {
  std::vector<Stretch> open;
  for (std::size_t l = 0; l < legs.size(); ++l) {
    const auto& axes = legs[l].axes;
    const double length = 1.0 / static_cast<double>(std::max<std::size_t>(1, axes.size() - 1));
    for (std::size_t k = 0; k + 1 < axes.size(); ++k)
      open.push_back({&axes[k], &axes[k + 1], 0.0, 1.0, margins[l][k], margins[l][k + 1],
                      static_cast<double>(k) * length, length});
  }
  for (;;) {
    std::erase_if(open,
                  [&](const Stretch& s) { return certified(s, levers, settings.check_step); });
    if (open.empty()) return true;
    std::vector<double> middle(open.size());
    const std::size_t blocked = firstBlocked(open.size(), [&](std::size_t i, const auto&) {
      pollCancel(settings.cancel);
      const Stretch& s = open[i];
      collision::ClearanceEvaluator clearance(scene);
      const auto m = poseMargin(scene, clearance, *s.a + (*s.b - *s.a) * (0.5 * (s.u0 + s.u1)));
      if (m) middle[i] = *m;
      return m.has_value();
    });
    if (blocked < open.size()) {
      const Stretch& s = open[blocked];
      if (blocked_at) *blocked_at = s.along + s.length * 0.5 * (s.u0 + s.u1);
      return false;
    }
    std::vector<Stretch> halves;
    halves.reserve(2 * open.size());
    for (std::size_t i = 0; i < open.size(); ++i) {
      Stretch lo = open[i], hi = open[i];
      lo.u1 = hi.u0 = 0.5 * (open[i].u0 + open[i].u1);
      lo.m1 = hi.m0 = middle[i];
      halves.push_back(lo);
      halves.push_back(hi);
    }
    open = std::move(halves);
  }
}

// How far a point of the cell can move per radian of each axis, m: for the table the farthest
// vertex of the part from its axis (or the table's edge); for joint j the links after it laid
// end to end (Σ |a_i| + |d_i|) and the scanner's reach from the flange.
AxisVector axisLevers(const kinematics::CellModel& cell, double part_reach) {
  double tool = cell.scanner.X_FS.translation().norm();
  for (const kinematics::Shape& shape : cell.scanner.body) {
    double far = 0.0;
    for (const Eigen::Vector3d& v : kinematics::shapeSurface(shape).vertices)
      far = std::max(far, (cell.scanner.X_FS * v).norm());
    tool = std::max(tool, far);
  }
  AxisVector l;
  l(0) = std::max(cell.table.radius, part_reach);
  double after = tool;
  for (int j = kinematics::kNumJoints - 1; j >= 0; --j) {
    l(j + 1) = after;
    after += std::abs(cell.robot.joint(j).a) + std::abs(cell.robot.joint(j).d);
  }
  return l;
}

// The IK solution at table angle theta for the scanner pose X_PS whose joints are nearest q.
std::optional<JointVector> nearestIk(const kinematics::CellModel& cell,
                                     double theta,
                                     const Eigen::Isometry3d& X_PS,
                                     const JointVector& q) {
  std::optional<JointVector> best;
  double best_d = std::numeric_limits<double>::infinity();
  for (const auto& sol : cell.robot.ik(cell.flangeTarget(theta, X_PS))) {
    if (!sol.within_limits) continue;
    JointVector v = sol.q;
    for (int j = 0; j < kinematics::kNumJoints; ++j) {
      // The whole-turn variant nearest q within the limits.
      const kinematics::DhJoint& joint = cell.robot.joint(j);
      for (const double k : {-1.0, 1.0}) {
        const double w = v(j) + k * kTwoPi;
        if (w >= joint.min && w <= joint.max && std::abs(w - q(j)) < std::abs(v(j) - q(j)))
          v(j) = w;
      }
    }
    const double d = (v - q).cwiseAbs().maxCoeff();
    if (d < best_d) {
      best_d = d;
      best = v;
    }
  }
  return best;
}

struct Leg {
  AxisVector from, to, v_from, v_to;
};
using Way = std::vector<Leg>;  // legs run one after the other; empty: not possible

// Joint values of `q` with the pose of `x`'s table: an axis vector.
AxisVector withJoints(const AxisVector& x, const JointVector& q) {
  AxisVector out = x;
  out.tail<kinematics::kNumJoints>() = q;
  return out;
}

// Which ends of a move back off.
enum class Ends { kStart, kEnd, kBoth };

// The move backed off by `r` along −z_S at its start, its end or both; empty when a backed-off
// end has no IK there.
Way backedOff(const kinematics::CellModel& cell,
              const TrajectorySample& a,
              const TrajectorySample& b,
              const AxisVector& v_a,
              const AxisVector& v_b,
              double r,
              Ends ends = Ends::kBoth) {
  const Eigen::Isometry3d back(Eigen::Translation3d(0.0, 0.0, -r));
  const bool at_a = ends != Ends::kEnd, at_b = ends != Ends::kStart;
  const AxisVector xa = axesOf(a), xb = axesOf(b), zero = AxisVector::Zero();
  Way way;
  AxisVector from = xa, v_from = v_a;
  if (at_a) {
    const auto qa = nearestIk(cell, a.theta, a.X_PS * back, a.q);
    if (!qa) return {};
    from = withJoints(xa, *qa);
    v_from = zero;
    way.push_back({xa, from, v_a, zero});
  }
  if (!at_b) {
    way.push_back({from, xb, v_from, v_b});
    return way;
  }
  const auto qb = nearestIk(cell, b.theta, b.X_PS * back, b.q);
  if (!qb) return {};
  const AxisVector xb2 = withJoints(xb, *qb);
  way.push_back({from, xb2, v_from, zero});
  way.push_back({xb2, xb, zero, v_b});
  return way;
}

// The ways backed off by each retreat at one end (`side` first: the one the direct move was
// blocked nearer) or at both, fastest first (ties in that order): the first clear one is the
// fastest detour of them.
std::vector<Way> backedOffWays(const kinematics::CellModel& cell,
                               const kinematics::AxisLimits& limits,
                               const TrajectorySample& a,
                               const TrajectorySample& b,
                               const AxisVector& v_a,
                               const AxisVector& v_b,
                               const MoveSettings& settings,
                               Ends side) {
  std::vector<std::pair<double, Way>> timed;
  for (const double r : settings.retreats) {
    const Ends other = side == Ends::kStart ? Ends::kEnd : Ends::kStart;
    for (const Ends ends : {side, other, Ends::kBoth}) {
      if (ends != Ends::kBoth && !settings.one_sided) continue;
      Way way = backedOff(cell, a, b, v_a, v_b, r, ends);
      if (way.empty()) continue;
      double t = 0.0;
      for (const Leg& leg : way)
        t += kinematics::ptpDuration(leg.from, leg.to, leg.v_from, leg.v_to, limits);
      timed.push_back({t, std::move(way)});
    }
  }
  std::stable_sort(timed.begin(), timed.end(),
                   [](const auto& x, const auto& y) { return x.first < y.first; });
  std::vector<Way> out;
  for (auto& [t, way] : timed) out.push_back(std::move(way));
  return out;
}

// The head above the part: laser straight down at `above` (part frame), turned about the
// vertical to keep the end pose's x_S as far as it can (the wrist turns least).
Eigen::Isometry3d abovePose(const Eigen::Isometry3d& above, const Eigen::Isometry3d& X_PS) {
  const Eigen::Vector3d z = above.linear().col(2);
  Eigen::Vector3d x = X_PS.linear().col(0) - X_PS.linear().col(0).dot(z) * z;
  if (x.norm() < 1e-6) x = above.linear().col(0);
  x.normalize();
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear().col(0) = x;
  out.linear().col(1) = z.cross(x);
  out.linear().col(2) = z;
  out.translation() = above.translation();
  return out;
}

// The last resort: backed off, up above the part, across there (the table turning), down the
// other side.
Way viaAbove(const kinematics::CellModel& cell,
             const Eigen::Isometry3d& above,
             const TrajectorySample& a,
             const TrajectorySample& b,
             const AxisVector& v_a,
             const AxisVector& v_b,
             double r) {
  const Way back = backedOff(cell, a, b, v_a, v_b, r);  // out, across, in
  if (back.empty()) return {};
  const AxisVector &a1 = back[0].to, &b1 = back[2].from;
  const auto ua = nearestIk(cell, a.theta, abovePose(above, a.X_PS), a1.tail<6>());
  const auto ub = nearestIk(cell, b.theta, abovePose(above, b.X_PS), b1.tail<6>());
  if (!ua || !ub) return {};
  const AxisVector z = AxisVector::Zero();
  const AxisVector a2 = withJoints(a1, *ua), b2 = withJoints(b1, *ub);
  return {back[0], {a1, a2, z, z}, {a2, b2, z, z}, {b2, b1, z, z}, back[2]};
}

// The samples of a way after its first (the move's start, at t = 0, left out); nullopt when a
// leg is blocked.
std::optional<std::vector<TrajectorySample>> runWay(const collision::Scene& scene,
                                                    const kinematics::AxisLimits& limits,
                                                    const AxisVector& levers,
                                                    const Way& way,
                                                    const MoveSettings& settings,
                                                    double* blocked_at = nullptr,
                                                    AxisVector* by_axis = nullptr) {
  std::vector<kinematics::PtpMove> moves;
  std::vector<std::vector<double>> margins;
  for (const Leg& leg : way) {
    pollCancel(settings.cancel);
    moves.push_back(
        kinematics::ptpMove(leg.from, leg.to, leg.v_from, leg.v_to, limits, settings.max_step));
    // A leg starts where the one before ends: that pose is checked once.
    const std::optional<double> start = margins.empty() || margins.back().empty()
                                            ? std::nullopt
                                            : std::optional<double>(margins.back().back());
    auto m = sampleMargins(scene, moves.back(), blocked_at, start);
    if (!m) return std::nullopt;
    margins.push_back(std::move(*m));
  }
  if (!legsClear(scene, moves, margins, levers, settings, blocked_at)) return std::nullopt;
  std::vector<TrajectorySample> out;
  for (std::size_t l = 0; l < way.size(); ++l) {
    const Leg& leg = way[l];
    const kinematics::PtpMove& move = moves[l];
    if (by_axis)
      *by_axis += kinematics::ptpTimeByAxis(leg.from, leg.to, leg.v_from, leg.v_to, limits);
    const double t0 = out.empty() ? 0.0 : out.back().t;
    for (std::size_t k = 1; k < move.t.size(); ++k)
      out.push_back(moveSample(scene.cell(), t0 + move.t[k], move.axes[k]));
  }
  return out;
}

// A checked move from `a` (the end of one segment, moving at v_a) to `b` (the start of the
// next, moving at v_b): direct, else the fastest clear back-off, else via above the part.
struct Move {
  std::optional<std::vector<TrajectorySample>> samples;  // times from `a`'s: 0
  bool detour = false;
  AxisVector by_axis = AxisVector::Zero();  // s of it by the axis that set it
};
Move planMove(const collision::Scene& scene,
              const kinematics::AxisLimits& limits,
              const AxisVector& levers,
              const TrajectorySample& a,
              const TrajectorySample& b,
              const AxisVector& v_a,
              const AxisVector& v_b,
              const MoveSettings& settings) {
  const kinematics::CellModel& cell = scene.cell();
  Move m;
  double blocked_at = 0.5;
  m.samples = runWay(scene, limits, levers, {{axesOf(a), axesOf(b), v_a, v_b}}, settings,
                     &blocked_at, &m.by_axis);
  if (m.samples) return m;
  m.detour = true;
  const Ends side = blocked_at < 0.5 ? Ends::kStart : Ends::kEnd;
  for (const Way& way : backedOffWays(cell, limits, a, b, v_a, v_b, settings, side)) {
    m.by_axis.setZero();
    m.samples = runWay(scene, limits, levers, way, settings, nullptr, &m.by_axis);
    if (m.samples) return m;
  }
  if (settings.above) {
    for (const double r : {0.05, 0.12, 0.2, 0.0}) {
      const Way way = viaAbove(cell, *settings.above, a, b, v_a, v_b, r);
      if (way.empty()) continue;
      m.by_axis.setZero();
      m.samples = runWay(scene, limits, levers, way, settings, nullptr, &m.by_axis);
      if (m.samples) return m;
    }
  }
  return m;
}

// A move's ends and speeds, all seven axes of each: what planMove() depends on besides the cell
// and the settings (the poses' X_PS follow from the axes).
using MoveKey = std::array<double, 4 * kinematics::kNumAxes>;
MoveKey moveKey(const TrajectorySample& a,
                const TrajectorySample& b,
                const AxisVector& v_a,
                const AxisVector& v_b) {
  MoveKey k;
  const AxisVector xa = axesOf(a), xb = axesOf(b);
  for (int j = 0; j < kinematics::kNumAxes; ++j) {
    const auto at = [&](int block) {
      return static_cast<std::size_t>(block * kinematics::kNumAxes + j);
    };
    k[at(0)] = xa(j);
    k[at(1)] = xb(j);
    k[at(2)] = v_a(j);
    k[at(3)] = v_b(j);
  }
  return k;
}

}  // namespace

struct MoveCache::Impl {
  struct Entry {
    tbb::collaborative_once_flag once;
    Move move;
  };
  std::mutex mutex;  // guards the map; each entry is planned once, by whoever asks first
  std::map<MoveKey, std::unique_ptr<Entry>> moves;
};
MoveCache::MoveCache() : impl_(std::make_unique<Impl>()) {}
MoveCache::~MoveCache() = default;
std::size_t MoveCache::size() const {
  const std::lock_guard lock(impl_->mutex);
  return impl_->moves.size();
}

namespace {

// The move `key` names, from the cache when it holds it, else `plan()` (added to the cache when
// there is one). A move asked for while another thread plans it is waited for, the waiting thread
// helping with that planning's parallel checks. The planning is isolated: a thread waiting in its
// parallel checks takes no other move's work meanwhile (which would hold this move up).
template <class Plan>
Move cachedMove(const MoveSettings& settings, const MoveKey& key, Plan plan) {
  if (!settings.cache) return tbb::this_task_arena::isolate(plan);
  MoveCache::Impl& cache = settings.cache->impl();
  MoveCache::Impl::Entry* entry = nullptr;
  {
    const std::lock_guard lock(cache.mutex);
    auto& slot = cache.moves[key];
    if (!slot) slot = std::make_unique<MoveCache::Impl::Entry>();
    entry = slot.get();
  }
  tbb::collaborative_call_once(entry->once, [&] { entry->move = plan(); });
  return entry->move;
}

// The checked move from `a` to `b` (planMove()), from the cache when it holds it: a function of
// the key alone, whichever thread plans it first. Its times count from 0 (appendRun() moves
// them). With a table that turns without end, whole turns of it change nothing: the move is
// planned with the table at `a` brought into [−π, π] (both ends turned alike) and turned back
// after, so a move met again some turns on is planned once and the same each time. The table's
// angles and speeds are snapped to a fine grid (2^-36 rad, 2^-30 rad/s), which the rounding of
// those turns cannot move them off, and the poses' scanner frames follow from the axes.
Move moveBetween(const collision::Scene& scene,
                 const kinematics::AxisLimits& limits,
                 const AxisVector& levers,
                 const TrajectorySample& a,
                 const TrajectorySample& b,
                 AxisVector v_a,
                 AxisVector v_b,
                 const MoveSettings& settings) {
  const kinematics::CellModel& cell = scene.cell();
  const double turn = (cell.table.continuous ? std::round(a.theta / kTwoPi) : 0.0) * kTwoPi;
  const auto snap = [](double x, int bits) {
    return std::ldexp(std::round(std::ldexp(x, bits)), -bits);
  };
  const auto canonical = [&](const TrajectorySample& s) {
    AxisVector x = axesOf(s);
    x(0) = snap(x(0) - turn, 36);
    return moveSample(cell, 0.0, x);
  };
  const TrajectorySample ca = canonical(a), cb = canonical(b);
  v_a(0) = snap(v_a(0), 30);
  v_b(0) = snap(v_b(0), 30);
  Move move = cachedMove(settings, moveKey(ca, cb, v_a, v_b), [&] {
    return planMove(scene, limits, levers, ca, cb, v_a, v_b, settings);
  });
  if (move.samples && turn != 0.0)
    for (TrajectorySample& s : *move.samples) s.theta += turn;
  return move;
}

// Segment i's samples after the program so far, moved to start at t0.
void appendSegment(const Trajectory& seg, double t0, std::vector<TrajectorySample>& samples) {
  const double s0 = seg.samples.front().t;
  for (auto s : seg.samples) {
    s.t = t0 + (s.t - s0);
    samples.push_back(std::move(s));
  }
}

// A checked move and then segment i after it, at the end of the program. The move ends on the
// segment's first pose: the segment's samples follow its last step. (Nothing to move: the segment
// starts one step later, where the last one ended.)
void appendRun(Move move,
               const Trajectory& seg,
               std::size_t from,
               std::size_t i,
               double max_step,
               JoinedProgram& out) {
  auto& samples = out.trajectory.samples;
  const double end = samples.back().t;
  ++out.times.moves;
  out.times.detours += move.detour ? 1u : 0u;
  out.times.moving_by_axis += move.by_axis;
  auto& m = *move.samples;
  for (auto& x : m) x.t += samples.back().t;
  const double t0 = m.empty() ? samples.back().t + max_step : m.back().t;
  samples.insert(samples.end(), m.begin(), m.empty() ? m.end() : m.end() - 1);
  out.start_times[i] = t0;
  out.made.push_back({from, i, t0 - end});
  appendSegment(seg, t0, samples);
}

// A segment no move reached from the one before it, tried once more at the end of the program,
// run forwards and then backwards; dropped when neither is reached.
void appendDeferred(const collision::Scene& scene,
                    const kinematics::AxisLimits& limits,
                    const AxisVector& levers,
                    const std::vector<Trajectory>& segments,
                    std::size_t from,
                    std::size_t i,
                    const MoveSettings& settings,
                    JoinedProgram& out) {
  const kinematics::CellModel& cell = scene.cell();
  auto& samples = out.trajectory.samples;
  for (const bool backwards : {false, true}) {
    const Trajectory seg = unwound(cell, backwards ? reversedSegment(segments[i]) : segments[i],
                                   axesOf(samples.back()));
    const TrajectorySample &a = samples.back(), &b = seg.samples.front();
    const AxisVector v_a = endSpeed(out.trajectory), v_b = startSpeed(seg);
    Move move = moveBetween(scene, limits, levers, a, b, v_a, v_b, settings);
    if (!move.samples) continue;
    appendRun(std::move(move), seg, from, i, settings.max_step, out);
    out.flipped[i] = backwards ? 1 : 0;
    return;
  }
  out.dropped.emplace_back(
      i,
      "no collision-free point-to-point move reaches it, from the pass before or from the end of "
      "the program, either way round: direct, backed off along the laser or via above the part");
}

// The moves between neighbouring segments, planned in parallel (those in the cache taken from
// it, the new ones added to it).
std::vector<Move> neighbourMoves(const collision::Scene& scene,
                                 const kinematics::AxisLimits& limits,
                                 const AxisVector& levers,
                                 const std::vector<Trajectory>& unwrapped,
                                 const MoveSettings& settings) {
  std::vector<Move> moves(unwrapped.size());
  tbb::parallel_for(std::size_t{1}, unwrapped.size(), [&](std::size_t i) {
    const Trajectory &a = unwrapped[i - 1], &b = unwrapped[i];
    if (a.samples.empty() || b.samples.empty()) return;
    moves[i] = moveBetween(scene, limits, levers, a.samples.back(), b.samples.front(), endSpeed(a),
                           startSpeed(b), settings);
  });
  return moves;
}

}  // namespace

ProgramTimes programTimes(const Trajectory& trajectory) {
  ProgramTimes t;
  const auto& s = trajectory.samples;
  if (s.empty()) return t;
  t.total = s.back().t - s.front().t;
  for (std::size_t k = 1; k < s.size(); ++k)
    if (s[k].scanning && s[k - 1].scanning) t.scanning += s[k].t - s[k - 1].t;
  t.moving = t.total - t.scanning;
  return t;
}

JoinedProgram joinSegments(const collision::Scene& scene,
                           const std::vector<Trajectory>& segments,
                           const MoveSettings& settings) {
  const kinematics::CellModel& cell = scene.cell();
  const kinematics::AxisLimits limits =
      kinematics::axisLimits(cell.robot, cell.table, settings.speed_scale, settings.accel_time);
  const AxisVector levers = axisLevers(cell, settings.part_reach);
  JoinedProgram out;
  out.start_times.assign(segments.size(), std::numeric_limits<double>::quiet_NaN());
  out.flipped.assign(segments.size(), 0);
  // Each segment unwound against the one before (as if none is dropped), then every move
  // between neighbours planned in parallel; a move that fails drops its segment and the next
  // one is joined from the same end, in order.
  std::vector<Trajectory> unwrapped(segments.size());
  for (std::size_t i = 0; i < segments.size(); ++i) {
    if (segments[i].samples.empty()) continue;
    unwrapped[i] = i == 0 || unwrapped[i - 1].samples.empty()
                       ? segments[i]
                       : unwound(cell, segments[i], axesOf(unwrapped[i - 1].samples.back()));
  }
  std::vector<Move> moves = neighbourMoves(scene, limits, levers, unwrapped, settings);
  auto& samples = out.trajectory.samples;
  std::vector<std::size_t> deferred;  // segments no move reaches from the one before
  std::size_t last = 0;               // the segment the program ends with
  bool in_step = true;                // it ends as unwrapped[last] does
  for (std::size_t i = 0; i < segments.size(); ++i) {
    if (segments[i].samples.empty()) continue;
    if (samples.empty()) {
      appendSegment(segments[i], 0.0, samples);
      out.start_times[i] = 0.0;
      last = i;
      continue;
    }
    Trajectory seg = unwrapped[i];
    Move move = std::move(moves[i]);
    if (last + 1 != i || !in_step) {
      // After a dropped segment: unwound and planned again from where the program ends.
      seg = unwound(cell, segments[i], axesOf(samples.back()));
      const TrajectorySample &a = samples.back(), &b = seg.samples.front();
      const AxisVector v_a = endSpeed(out.trajectory), v_b = startSpeed(seg);
      move = moveBetween(scene, limits, levers, a, b, v_a, v_b, settings);
    }
    // The next precomputed move starts from unwrapped[i]: usable only if that is what runs.
    in_step = axesOf(seg.samples.back()) == axesOf(unwrapped[i].samples.back());
    if (!move.samples) {
      deferred.push_back(i);
      continue;
    }
    appendRun(std::move(move), seg, last, i, settings.max_step, out);
    last = i;
  }
  for (const std::size_t i : deferred) {
    appendDeferred(scene, limits, levers, segments, last, i, settings, out);
    if (!std::isnan(out.start_times[i])) last = i;
  }
  const ProgramTimes split = programTimes(out.trajectory);
  out.times.total = split.total;
  out.times.scanning = split.scanning;
  out.times.moving = split.moving;
  return out;
}

}  // namespace scanplan::pipeline

namespace scanplan::pipeline {

namespace {

// Where a segment is entered and left, run forwards or backwards, with the speeds there.
struct SegmentEnds {
  kinematics::AxisVector in, out, v_in, v_out;
};

SegmentEnds endsOf(const kinematics::Trajectory& seg, bool reversed) {
  SegmentEnds e{axesOf(seg.samples.front()), axesOf(seg.samples.back()), startSpeed(seg),
                endSpeed(seg)};
  if (reversed) e = {e.out, e.in, -e.v_out, -e.v_in};
  return e;
}

class MoveCosts {
 public:
  MoveCosts(const kinematics::CellModel& cell,
            const std::vector<kinematics::Trajectory>& segments,
            const MoveSettings& settings)
      : continuous_(cell.table.continuous),
        limits_(kinematics::axisLimits(
            cell.robot, cell.table, settings.speed_scale, settings.accel_time)) {
    for (const auto& s : segments) ends_.push_back({endsOf(s, false), endsOf(s, true)});
  }
  // Just the move from the end of `from` to the start of `to` (segments 0 and 1).
  MoveCosts(const kinematics::CellModel& cell,
            const kinematics::Trajectory& from,
            const kinematics::Trajectory& to,
            const MoveSettings& settings)
      : MoveCosts(cell, {}, settings) {
    ends_.push_back({endsOf(from, false), endsOf(from, true)});
    ends_.push_back({endsOf(to, false), endsOf(to, true)});
  }
  // The moves in `known` costed at their measured time, either way round.
  // Every other move costs its estimate plus what the known ones took beyond theirs on average
  // (the moves that had to back off): a move not yet made may have to as well.
  void setKnown(const std::vector<KnownMove>& known) {
    double beyond = 0.0;
    std::size_t moves = 0;
    for (const KnownMove& m : known) {
      const std::size_t k = key(m.from, m.from_reversed, m.to, m.to_reversed);
      if (known_.count(k)) continue;  // made more than once: counted once
      beyond += m.duration - (*this)(m.from, m.from_reversed, m.to, m.to_reversed);
      ++moves;
      known_[k] = m.duration;
      known_[key(m.to, !m.to_reversed, m.from, !m.from_reversed)] = m.duration;
    }
    if (moves > 0) unknown_extra_ = std::max(0.0, beyond / static_cast<double>(moves));
  }
  // From the end of (i, ri) to the start of (j, rj), s.
  double operator()(std::size_t i, bool ri, std::size_t j, bool rj) const {
    if (!known_.empty())
      if (const auto it = known_.find(key(i, ri, j, rj)); it != known_.end()) return it->second;
    const SegmentEnds& a = ends_[i][ri ? 1 : 0];
    const SegmentEnds& b = ends_[j][rj ? 1 : 0];
    kinematics::AxisVector to = b.in;
    if (continuous_) to(0) = a.out(0) + std::remainder(b.in(0) - a.out(0), kTwoPi);
    return kinematics::ptpDuration(a.out, to, a.v_out, b.v_in, limits_) + unknown_extra_;
  }

 private:
  std::size_t key(std::size_t i, bool ri, std::size_t j, bool rj) const {
    return ((i * ends_.size() + j) << 2) | (ri ? 2u : 0u) | (rj ? 1u : 0u);
  }
  bool continuous_;
  kinematics::AxisLimits limits_;
  std::vector<std::array<SegmentEnds, 2>> ends_;
  std::unordered_map<std::size_t, double> known_;
  double unknown_extra_ = 0.0;  // s
};

double tourCost(const MoveCosts& cost, const SegmentOrder& o) {
  double c = 0.0;
  for (std::size_t k = 1; k < o.order.size(); ++k)
    c += cost(o.order[k - 1], o.reversed[k - 1] != 0, o.order[k], o.reversed[k] != 0);
  return c;
}

// Nearest neighbour from `first` (after the fixed head), each segment either way.
SegmentOrder nearestFrom(const MoveCosts& cost,
                         std::size_t n,
                         std::size_t fixed,
                         std::size_t first) {
  SegmentOrder o;
  std::vector<std::uint8_t> used(n, 0);
  for (std::size_t i = 0; i < fixed; ++i) {
    o.order.push_back(i);
    o.reversed.push_back(0);
    used[i] = 1;
  }
  if (!used[first]) {
    o.order.push_back(first);
    o.reversed.push_back(0);
    used[first] = 1;
  }
  while (o.order.size() < n) {
    double best = std::numeric_limits<double>::infinity();
    std::size_t bj = 0;
    bool br = false;
    for (std::size_t j = 0; j < n; ++j) {
      if (used[j]) continue;
      for (const bool r : {false, true}) {
        const double c = cost(o.order.back(), o.reversed.back() != 0, j, r);
        if (c < best - 1e-12) {
          best = c;
          bj = j;
          br = r;
        }
      }
    }
    o.order.push_back(bj);
    o.reversed.push_back(br ? 1 : 0);
    used[bj] = 1;
  }
  return o;
}

// 2-opt: reverse the stretch k+1 … m (and each segment in it) where that shortens the tour. The
// move durations are symmetric under running a move backwards, so only the two cut edges change.
void twoOpt(const MoveCosts& cost, std::size_t fixed, SegmentOrder& o) {
  const std::size_t n = o.order.size();
  const auto c = [&](std::size_t a, bool ra, std::size_t b, bool rb) {
    return cost(o.order[a], ra, o.order[b], rb);
  };
  for (int sweep = 0; sweep < 50; ++sweep) {
    bool improved = false;
    for (std::size_t k = fixed == 0 ? 0 : fixed - 1; k + 1 < n; ++k) {
      for (std::size_t m = k + 1; m < n; ++m) {
        const bool rk = o.reversed[k] != 0, rk1 = o.reversed[k + 1] != 0, rm = o.reversed[m] != 0;
        double before = c(k, rk, k + 1, rk1), after = c(k, rk, m, !rm);
        if (m + 1 < n) {
          const bool rm1 = o.reversed[m + 1] != 0;
          before += c(m, rm, m + 1, rm1);
          after += c(k + 1, !rk1, m + 1, rm1);
        }
        if (after < before - 1e-9) {
          std::reverse(o.order.begin() + static_cast<std::ptrdiff_t>(k + 1),
                       o.order.begin() + static_cast<std::ptrdiff_t>(m + 1));
          std::reverse(o.reversed.begin() + static_cast<std::ptrdiff_t>(k + 1),
                       o.reversed.begin() + static_cast<std::ptrdiff_t>(m + 1));
          for (std::size_t i = k + 1; i <= m; ++i) o.reversed[i] ^= 1;
          improved = true;
        }
      }
    }
    if (!improved) break;
  }
}

// The gain of taking the chain first … first+len−1 out of the tour (its own moves stay).
double chainOutGain(const MoveCosts& cost,
                    const SegmentOrder& o,
                    std::size_t first,
                    std::size_t len) {
  const std::size_t n = o.order.size(), last = first + len - 1;
  const auto c = [&](std::size_t a, std::size_t b) {
    return cost(o.order[a], o.reversed[a] != 0, o.order[b], o.reversed[b] != 0);
  };
  double gain = 0.0;
  if (first > 0) gain += c(first - 1, first);
  if (last + 1 < n) gain += c(last, last + 1);
  if (first > 0 && last + 1 < n) gain -= c(first - 1, last + 1);
  return gain;
}

// Moves the chain first … first+len−1 into the gap before position `gap` (n: the end), reversed
// as a whole when `flip`. The gap lies outside first … first+len.
void moveChain(SegmentOrder& o, std::size_t first, std::size_t len, std::size_t gap, bool flip) {
  const auto at = [](std::size_t k) { return static_cast<std::ptrdiff_t>(k); };
  const auto shift = [&](auto& v) {
    if (flip) std::reverse(v.begin() + at(first), v.begin() + at(first + len));
    if (gap < first)
      std::rotate(v.begin() + at(gap), v.begin() + at(first), v.begin() + at(first + len));
    else
      std::rotate(v.begin() + at(first), v.begin() + at(first + len), v.begin() + at(gap));
  };
  if (flip)
    for (std::size_t k = first; k < first + len; ++k) o.reversed[k] ^= 1;
  shift(o.order);
  shift(o.reversed);
}

// What putting the chain head … tail (run as `rh`, `rt`) into the gap before position `gap` adds
// to the tour (n: the end).
double chainInCost(const MoveCosts& cost,
                   const SegmentOrder& o,
                   std::size_t gap,
                   std::size_t head,
                   bool rh,
                   std::size_t tail,
                   bool rt) {
  const std::size_t n = o.order.size();
  double in = 0.0;
  if (gap > 0) in += cost(o.order[gap - 1], o.reversed[gap - 1] != 0, o.order[head], rh);
  if (gap < n) in += cost(o.order[tail], rt, o.order[gap], o.reversed[gap] != 0);
  if (gap > 0 && gap < n)
    in -= cost(o.order[gap - 1], o.reversed[gap - 1] != 0, o.order[gap], o.reversed[gap] != 0);
  return in;
}

// Or-opt: a chain of 1 to 3 segments moved elsewhere in the tour (after the fixed head), either
// way round, where that shortens it. Until no such move does, or 50 sweeps.
void orOpt(const MoveCosts& cost, std::size_t fixed, SegmentOrder& o) {
  const std::size_t n = o.order.size();
  for (int sweep = 0; sweep < 50; ++sweep) {
    bool improved = false;
    for (std::size_t len = 1; len <= 3; ++len)
      for (std::size_t first = fixed; first + len <= n; ++first) {
        const std::size_t last = first + len - 1;
        const double out = chainOutGain(cost, o, first, len);
        double best = 1e-9;
        std::size_t best_gap = n + 1;
        bool best_flip = false;
        for (std::size_t gap = fixed; gap <= n; ++gap) {
          if (gap >= first && gap <= last + 1) continue;
          for (const bool flip : {false, true}) {
            const std::size_t head = flip ? last : first, tail = flip ? first : last;
            const bool rh = (o.reversed[head] != 0) != flip, rt = (o.reversed[tail] != 0) != flip;
            const double gain = out - chainInCost(cost, o, gap, head, rh, tail, rt);
            if (gain > best) {
              best = gain;
              best_gap = gap;
              best_flip = flip;
            }
          }
        }
        if (best_gap > n) continue;
        moveChain(o, first, len, best_gap, best_flip);
        improved = true;
      }
    if (!improved) break;
  }
}

// 2-opt and Or-opt in turn: each changes the tour only where that shortens it, so until a
// round of both changes nothing, the tour then a local optimum of each.
void localSearch(const MoveCosts& cost, std::size_t fixed, SegmentOrder& o) {
  for (int round = 0; round < 20; ++round) {
    const double before = tourCost(cost, o);
    twoOpt(cost, fixed, o);
    orOpt(cost, fixed, o);
    if (!(tourCost(cost, o) < before - 1e-9)) break;
  }
}

}  // namespace

SegmentOrder orderSegments(const kinematics::CellModel& cell,
                           const std::vector<kinematics::Trajectory>& segments,
                           std::size_t fixed,
                           const MoveSettings& settings,
                           bool or_opt) {
  const std::size_t n = segments.size();
  fixed = std::min(fixed, n);
  if (n == 0) return {};
  const MoveCosts cost(cell, segments, settings);
  SegmentOrder best;
  double best_cost = std::numeric_limits<double>::infinity();
  const std::size_t free = n - fixed;
  const std::size_t step = std::max<std::size_t>(1, free / 12);
  for (std::size_t first = fixed; first < n || (free == 0 && first == fixed); first += step) {
    SegmentOrder o = nearestFrom(cost, n, fixed, std::min(first, n - 1));
    const double c = tourCost(cost, o);
    if (c < best_cost - 1e-12) {
      best_cost = c;
      best = std::move(o);
    }
    if (free == 0) break;
  }
  if (or_opt)
    localSearch(cost, fixed, best);
  else
    twoOpt(cost, fixed, best);
  return best;
}

SegmentOrder reorderSegments(const kinematics::CellModel& cell,
                             const std::vector<kinematics::Trajectory>& segments,
                             std::size_t fixed,
                             const SegmentOrder& start,
                             const std::vector<KnownMove>& known,
                             const MoveSettings& settings) {
  MoveCosts cost(cell, segments, settings);
  cost.setKnown(known);
  SegmentOrder o = start;
  localSearch(cost, std::min(fixed, segments.size()), o);
  return o;
}

double moveCost(const kinematics::CellModel& cell,
                const kinematics::Trajectory& from,
                const kinematics::Trajectory& to,
                const MoveSettings& settings) {
  const MoveCosts cost(cell, from, to, settings);
  return cost(0, false, 1, false);
}

kinematics::Trajectory reversedSegment(const kinematics::Trajectory& segment) {
  kinematics::Trajectory out;
  const auto& s = segment.samples;
  if (s.empty()) return out;
  const double t0 = s.front().t, t1 = s.back().t;
  for (auto it = s.rbegin(); it != s.rend(); ++it) {
    kinematics::TrajectorySample x = *it;
    x.t = t0 + (t1 - it->t);
    out.samples.push_back(std::move(x));
  }
  return out;
}

}  // namespace scanplan::pipeline

namespace scanplan::pipeline {

namespace {

// The largest share of its speed limit (scaled) any axis reaches between two samples.
double speedRatio(const kinematics::AxisLimits& limits,
                  const std::vector<TrajectorySample>& s,
                  double speed_scale) {
  double ratio = 0.0;
  for (std::size_t k = 1; k < s.size(); ++k) {
    const double dt = s[k].t - s[k - 1].t;
    const AxisVector speed = (axesOf(s[k]) - axesOf(s[k - 1])).cwiseAbs() / dt;
    ratio = std::max(ratio, (speed.array() / (speed_scale * limits.speed.array())).maxCoeff());
  }
  return ratio;
}

// Per axis, the largest share of its acceleration limit (scaled) it reaches: the change of the
// speeds between neighbouring intervals over the mean interval, as validation measures it.
AxisVector accelRatios(const kinematics::AxisLimits& limits,
                       const std::vector<TrajectorySample>& s,
                       double speed_scale) {
  AxisVector ratio = AxisVector::Zero();
  for (std::size_t k = 2; k < s.size(); ++k) {
    const double dt1 = s[k].t - s[k - 1].t, dt0 = s[k - 1].t - s[k - 2].t;
    const AxisVector v1 = (axesOf(s[k]) - axesOf(s[k - 1])) / dt1;
    const AxisVector v0 = (axesOf(s[k - 1]) - axesOf(s[k - 2])) / dt0;
    const AxisVector a = (v1 - v0).cwiseAbs() / (0.5 * (dt0 + dt1));
    ratio = ratio.cwiseMax((a.array() / (speed_scale * limits.accel.array())).matrix());
  }
  return ratio;
}

void stretchTimes(std::vector<TrajectorySample>& s, double factor) {
  if (s.empty() || factor == 1.0) return;
  const double t0 = s.front().t;
  for (auto& x : s) x.t = t0 + factor * (x.t - t0);
}

}  // namespace

double slowToLimits(const kinematics::CellModel& cell,
                    kinematics::Trajectory& segment,
                    double speed_scale) {
  const kinematics::AxisLimits limits = kinematics::axisLimits(cell.robot, cell.table);
  const double ratio = std::max(1.0, speedRatio(limits, segment.samples, speed_scale));
  stretchTimes(segment.samples, ratio);
  return ratio;
}

double retimeSegment(const kinematics::CellModel& cell,
                     kinematics::Trajectory& segment,
                     double duration,
                     double speed_scale) {
  constexpr double kLeast = 0.1;  // of its span at most: times stay well apart
  auto& s = segment.samples;
  if (s.size() < 2) return 1.0;
  const double span = s.back().t - s.front().t;
  if (!(span > 0.0)) return 1.0;
  const kinematics::AxisLimits limits = kinematics::axisLimits(cell.robot, cell.table);
  // Times scaled by c scale speeds by 1/c and accelerations by 1/c².
  const AxisVector accel = accelRatios(limits, s, speed_scale);
  double joints = 0.0;  // a joint's acceleration is held to its limit only where it was within
  for (int j = 1; j < accel.size(); ++j) joints = std::max(joints, std::min(1.0, accel(j)));
  // The accelerations only limit how far it shrinks: at its samples' times the planner's bounds
  // hold them (validation checks the table's).
  const double table = cell.table.max_accel > 0.0 ? std::min(1.0, accel(0)) : 0.0;
  const double factor =
      std::max({std::clamp(duration / span, kLeast, 1.0), speedRatio(limits, s, speed_scale),
                std::sqrt(joints), std::sqrt(table)});
  stretchTimes(s, factor);
  return factor;
}

}  // namespace scanplan::pipeline
