#include <scanplan/pipeline/segment_plan.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <set>
#include <tuple>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <scanplan/kinematics/units.h>
#include <scanplan/pipeline/cancel.h>
#include <scanplan/pipeline/certificate.h>
#include <scanplan/planner/wrap_sheets.h>

namespace scanplan::pipeline {

namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

struct Segment {
  std::size_t begin = 0, end = 0;
  kinematics::ScanPath path;
  planner::ConfigMap map;
  PathChoice choice;
  std::optional<planner::TrajectoryBuild> build;
  std::size_t build_branch = 0;  // the map branch `build` followed
  double trajectory_seconds = 0.0;
};

constexpr std::size_t kSegmentIterations = 1000;  // segmentBudget()'s least
constexpr double kSegmentSeconds = 1.0;

// The path search and the trajectory of one segment, on its slice of the map.
void planSegment(const ScanProblem& problem,
                 const PreparedScan& p,
                 const PlanOptions& options,
                 Segment& seg) {
  pollCancel(problem.planning.termination.cancel);
  seg.path = kinematics::slicePath(p.path.path, seg.begin, seg.end);
  seg.map = sliceMap(p.map, seg.begin, seg.end);
  const auto accept = [&](std::size_t b, const std::vector<double>& theta) {
    const auto t = Clock::now();
    seg.build = planner::buildTrajectory(*p.scene, problem.constraints, seg.path, theta,
                                         seg.map.branches[b]);
    seg.build_branch = b;
    seg.trajectory_seconds += since(t);
    return executableReason(*seg.build);
  };
  const auto wrap_sheets = [&](std::size_t b) -> std::shared_ptr<const planner::WrapSheets> {
    if (!seg.build || seg.build->wrap_joint < 0) return nullptr;
    return std::make_shared<const planner::WrapSheets>(p.scene->cell(), problem.constraints,
                                                       seg.path, seg.map, b, seg.build->wrap_joint);
  };
  // An iterative search (OMPL) starts with the segment's share of the budget and doubles it,
  // up to the whole path's, while its budget is what ended it.
  PlanSettings planning = problem.planning;
  const planner::Termination& whole = problem.planning.termination;
  planning.termination = segmentBudget(whole, seg.end - seg.begin, p.map.times.size());
  while (true) {
    seg.choice = choosePath(seg.map, planning, options, accept, wrap_sheets);
    planner::Termination& t = planning.termination;
    bool short_of_budget = !seg.choice.solved() && seg.choice.chosen.budget_ended;
    for (const PlannerOutcome& other : seg.choice.others)  // --compare's planners alike
      short_of_budget = short_of_budget || (!other.result.solved() && other.budget_ended);
    if (!short_of_budget ||
        (t.max_iterations == whole.max_iterations && t.time_limit_s == whole.time_limit_s))
      break;
    t.max_iterations = std::min(whole.max_iterations, 2 * t.max_iterations);
    t.time_limit_s = std::min(whole.time_limit_s, 2.0 * t.time_limit_s);
  }
  if (!seg.choice.solved()) seg.build.reset();
}

void addTerms(planner::ObjectiveTerms& sum, const planner::ObjectiveTerms& t, std::size_t offset) {
  sum.cost_f += t.cost_f;
  sum.cost_omega += t.cost_omega;
  sum.cost_alpha += t.cost_alpha;
  sum.total += t.total;
  if (t.min_f < sum.min_f) {
    sum.min_f = t.min_f;
    sum.min_f_sample = offset + t.min_f_sample;
  }
  sum.max_abs_omega = std::max(sum.max_abs_omega, t.max_abs_omega);
  sum.max_abs_alpha = std::max(sum.max_abs_alpha, t.max_abs_alpha);
  sum.feasible = sum.feasible && t.feasible;
}

// θ over every time sample: each planned segment's own, a dropped one held at the angle before.
std::vector<double> joinedTheta(const std::vector<Segment>& segs,
                                const std::vector<const std::vector<double>*>& thetas) {
  std::vector<double> theta;
  for (std::size_t s = 0; s < segs.size(); ++s) {
    const double hold = theta.empty() ? 0.0 : theta.back();
    if (thetas[s] && thetas[s]->size() == segs[s].end - segs[s].begin) {
      theta.insert(theta.end(), thetas[s]->begin(), thetas[s]->end());
    } else {
      theta.insert(theta.end(), segs[s].end - segs[s].begin, hold);
    }
  }
  return theta;
}

// One planner's results over the segments it solved, summed; nullopt when one is missing.
template <class Get>
std::optional<planner::PlanResult> sumResults(const std::vector<Segment>& segs,
                                              const std::vector<std::uint8_t>& kept,
                                              Get get) {
  planner::PlanResult sum;
  sum.status = planner::PlannerStatus::kExact;
  sum.terms.min_f = 1.0;
  sum.terms.feasible = true;
  std::vector<const std::vector<double>*> thetas(segs.size(), nullptr);
  for (std::size_t s = 0; s < segs.size(); ++s) {
    if (!kept[s]) continue;
    const planner::PlanResult* r = get(segs[s].choice);
    if (!r || !r->solved()) return std::nullopt;
    addTerms(sum.terms, r->terms, segs[s].begin);
    sum.seconds += r->seconds;
    thetas[s] = &r->theta;
  }
  sum.theta = joinedTheta(segs, thetas);
  return sum;
}

// The branch most time samples were planned on.
std::size_t mainBranch(const std::vector<Segment>& segs, const std::vector<std::uint8_t>& kept) {
  std::map<std::size_t, std::size_t> samples;
  for (std::size_t s = 0; s < segs.size(); ++s)
    if (kept[s]) samples[segs[s].choice.chosen.result.branch] += segs[s].end - segs[s].begin;
  std::size_t best = 0, most = 0;
  for (const auto& [b, n] : samples)
    if (n > most) {
      best = b;
      most = n;
    }
  return best;
}

// The refinements summed, when any segment was refined.
std::optional<planner::RefineResult> joinedRefine(const std::vector<Segment>& segs,
                                                  const std::vector<std::uint8_t>& kept) {
  std::optional<planner::RefineResult> out;
  for (std::size_t s = 0; s < segs.size(); ++s) {
    const auto& r = segs[s].choice.refine;
    if (!kept[s] || !r) continue;
    if (!out) {
      out.emplace();
      out->algorithm = r->algorithm;
      out->stop_reason = "per pass";
    }
    out->before.total += r->before.total;
    out->after.total += r->after.total;
    out->improved = out->improved || r->improved;
    out->evaluations += r->evaluations;
    out->seconds += r->seconds;
  }
  return out;
}

// The segments' choices as one: J summed, θ joined, the DP yardstick and comparisons summed.
PathChoice joinChoices(const std::vector<Segment>& segs, const std::vector<std::uint8_t>& kept) {
  PathChoice out;
  const auto own = [](const PathChoice& c) { return &c.chosen.result; };
  const auto chosen = sumResults(segs, kept, own);
  for (const Segment& s : segs) out.chosen.method = s.choice.chosen.method;
  if (!chosen) return out;  // not reached: every kept segment is solved
  out.chosen.result = *chosen;
  out.chosen.result.branch = mainBranch(segs, kept);
  out.chosen.seconds = chosen->seconds;
  out.terms.min_f = 1.0;
  out.terms.feasible = true;
  std::vector<const std::vector<double>*> final_theta(segs.size(), nullptr);
  for (std::size_t s = 0; s < segs.size(); ++s) {
    if (!kept[s]) continue;
    final_theta[s] = &segs[s].choice.theta;
    addTerms(out.terms, segs[s].choice.terms, segs[s].begin);
  }
  out.theta = joinedTheta(segs, final_theta);
  out.refine = joinedRefine(segs, kept);
  out.dp = sumResults(segs, kept, [](const PathChoice& c) {
    return c.dp ? &*c.dp : static_cast<const planner::PlanResult*>(nullptr);
  });
  if (out.dp) out.dp->branch = out.chosen.result.branch;
  for (const Segment& s : segs) out.dp_subdivisions = s.choice.dp_subdivisions;
  if (!segs.empty()) {
    for (const PlannerOutcome& o : segs.front().choice.others) {
      PlannerOutcome sum;
      sum.method = o.method;
      const auto r = sumResults(segs, kept, [&](const PathChoice& c) {
        for (const PlannerOutcome& x : c.others)
          if (x.method == o.method) return &x.result;
        return static_cast<const planner::PlanResult*>(nullptr);
      });
      if (r) {
        sum.result = *r;
        sum.seconds = r->seconds;
      } else {
        sum.result.reason = "no path on every pass";
      }
      out.others.push_back(std::move(sum));
    }
  }
  std::set<std::size_t> branches;
  for (std::size_t s = 0; s < segs.size(); ++s) {
    const PathChoice& c = segs[s].choice;
    for (const auto& [b, why] : c.rejected)
      out.rejected.emplace_back(b, fmt::format("pass {}: {}", s + 1, why));
    if (kept[s]) branches.insert(c.chosen.result.branch);
    out.segments.push_back(c);
  }
  out.why_chosen =
      fmt::format("per pass, the lowest J the arm can follow: {} passes on {} branch(es)",
                  std::count(kept.begin(), kept.end(), std::uint8_t{1}), branches.size());
  return out;
}

// The program cut after the last segment that ends within `limit` s (never before the first):
// the segments after it are dropped.
void cutAt(double limit,
           const std::vector<kinematics::Trajectory>& ordered,
           JoinedProgram& joined) {
  // In the order they run: the first always, then each that ends within the limit; the runs
  // follow each other, so the first past it ends the program.
  std::vector<std::size_t> runs;
  for (std::size_t k = 0; k < ordered.size(); ++k)
    if (!std::isnan(joined.start_times[k])) runs.push_back(k);
  std::sort(runs.begin(), runs.end(), [&](std::size_t a, std::size_t b) {
    return joined.start_times[a] < joined.start_times[b];
  });
  double last = 0.0;
  bool past = false;
  for (std::size_t r = 0; r < runs.size(); ++r) {
    const std::size_t k = runs[r];
    const double stop =
        joined.start_times[k] + ordered[k].duration() - ordered[k].samples.front().t;
    if (r == 0 || (!past && stop <= limit + 1e-9)) {
      last = stop;
      continue;
    }
    joined.dropped.emplace_back(
        k, past ? fmt::format("past scan.auto.max_program_s ({:.1f} s)", limit)
                : fmt::format("it would end at {:.1f} s, past scan.auto.max_program_s ({:.1f} s)",
                              stop, limit));
    past = true;
    joined.start_times[k] = std::numeric_limits<double>::quiet_NaN();
  }
  auto& s = joined.trajectory.samples;
  while (!s.empty() && s.back().t > last + 1e-9) s.pop_back();
  const ProgramTimes split = programTimes(joined.trajectory);
  joined.times.total = split.total;
  joined.times.scanning = split.scanning;
  joined.times.moving = split.moving;
}

// The moves' settings for this problem: the detour's pose above the part is the top of a sphere
// around it (its bounding sphere grown by the scanner housing's reach and 20 mm), the laser
// pointing down the table's axis.
MoveSettings moveSettings(const ScanProblem& problem) {
  MoveSettings m;
  m.cancel = problem.planning.termination.cancel;
  if (problem.part.vertices.empty()) return m;
  const Eigen::Vector3d centre = problem.part.bounds().center();
  double part = 0.0, head = 0.0;
  for (const Eigen::Vector3d& v : problem.part.vertices) part = std::max(part, (v - centre).norm());
  for (const kinematics::Shape& shape : problem.cell.scanner.body)
    for (const Eigen::Vector3d& v : kinematics::shapeSurface(shape).vertices)
      head = std::max(head, v.norm());
  const Eigen::Vector3d up = problem.cell.part.X_RP.linear().transpose().col(2);
  Eigen::Isometry3d above = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d z = -up;
  const Eigen::Vector3d x = z.unitOrthogonal();
  above.linear().col(0) = x;
  above.linear().col(1) = z.cross(x);
  above.linear().col(2) = z;
  above.translation() = centre + (part + head + 0.02) * up;
  m.above = above;
  for (const Eigen::Vector3d& v : problem.part.vertices)
    m.part_reach = std::max(m.part_reach, (problem.cell.part.X_RP * v).head<2>().norm());
  return m;
}

// The kept segments in the order of the shortest moves, each run in its own time (retimeSegment():
// as fast as planned, within the axes' limits) and, to fall back on, at its samples' times.
struct OrderedRuns {
  std::vector<std::size_t> index;                  // the kept segments' indices
  SegmentOrder order;                              // into index
  std::vector<kinematics::Trajectory> fast, slow;  // in the order they run, reversed as they run
  std::vector<kinematics::Trajectory> forwards;    // fast, forwards, in index's order
  std::size_t fixed = 0;                           // runs first, in order and forwards
};

// A segment's own duration: as planned, or its samples' span.
double ownDuration(const std::vector<double>& own, std::size_t s, const kinematics::Trajectory& t) {
  return s < own.size() ? own[s] : t.samples.back().t - t.samples.front().t;
}

// A segment as it may run, `reversed` or not: at its samples' times slowed to the axes' limits,
// and in its own time.
std::pair<kinematics::Trajectory, kinematics::Trajectory> runVersions(
    const kinematics::CellModel& cell, kinematics::Trajectory t, double own, bool reversed) {
  slowToLimits(cell, t);
  kinematics::Trajectory fast = t;
  retimeSegment(cell, fast, own);
  if (!reversed) return {std::move(t), std::move(fast)};
  return {reversedSegment(t), reversedSegment(fast)};
}

// The runs' trajectories in their order (`runs.order` set).
void arrange(const kinematics::CellModel& cell,
             const std::vector<kinematics::Trajectory>& trajectories,
             const std::vector<double>& own_durations,
             OrderedRuns& runs) {
  runs.fast.clear();
  runs.slow.clear();
  for (std::size_t k = 0; k < runs.order.order.size(); ++k) {
    const std::size_t s = runs.index[runs.order.order[k]];
    auto [slow, run] =
        runVersions(cell, trajectories[s], ownDuration(own_durations, s, trajectories[s]),
                    runs.order.reversed[k] != 0);
    runs.slow.push_back(std::move(slow));
    runs.fast.push_back(std::move(run));
  }
}

OrderedRuns orderedRuns(const kinematics::CellModel& cell,
                        const std::vector<kinematics::Trajectory>& trajectories,
                        const std::vector<double>& own_durations,
                        const std::vector<std::uint8_t>& kept,
                        std::size_t fixed) {
  OrderedRuns out;
  out.fixed = fixed;
  for (std::size_t s = 0; s < trajectories.size(); ++s) {
    if (!kept[s]) continue;
    out.index.push_back(s);
    const double own = ownDuration(own_durations, s, trajectories[s]);
    out.forwards.push_back(runVersions(cell, trajectories[s], own, false).second);
  }
  out.order = orderSegments(cell, out.forwards, fixed);
  arrange(cell, trajectories, own_durations, out);
  return out;
}

// Segment s's table path shifted evenly by `delta` (rad) and its trajectory built again on the
// branch it followed: the build when the map and the arm follow it there (f > 0 on the map all
// along it, the trajectory executable, its least f at least half of what it was), else nullopt.
std::optional<planner::TrajectoryBuild> shiftedBuild(const ScanProblem& problem,
                                                     const PreparedScan& p,
                                                     const Segment& seg,
                                                     double delta,
                                                     std::vector<double>& theta) {
  theta = seg.choice.theta;
  for (double& x : theta) x += delta;
  if (!problem.cell.table.continuous) {
    const auto [lo, hi] = std::minmax_element(theta.begin(), theta.end());
    if (*lo < p.map.angles.front() || *hi > p.map.angles.back()) return std::nullopt;
  }
  const planner::ObjectiveTerms terms = planner::evaluate(
      seg.map, seg.build_branch, theta, problem.planning.objective, problem.planning.continuous);
  if (!(terms.min_f > 0.0) || !std::isfinite(terms.total)) return std::nullopt;
  planner::TrajectoryBuild build = planner::buildTrajectory(
      *p.scene, problem.constraints, seg.path, theta, seg.map.branches[seg.build_branch]);
  if (!executableReason(build).empty() || build.min_f < 0.5 * seg.build->min_f) return std::nullopt;
  return build;
}

// A segment whose table path holdTable() shifted: by how much, the path and its trajectory.
struct HeldPass {
  std::size_t segment = 0;
  double shift = 0.0;  // rad
  std::vector<double> theta;
  planner::TrajectoryBuild build;
};

// The table held across the moves: in the order the program runs them, each segment's table
// path shifted evenly to start where the run before ends (the shorter way round on a table that
// turns without end), where the arm follows it there and the move into it gets shorter (the
// table, slow to start and stop, often sets a move's time). In order: each shift depends on
// where the run before ends. A segment planned on a joint-wrap sheet keeps its path. `runs` then
// hold the shifted segments; returns them (applyHeld() makes them the segments' own).
std::vector<HeldPass> holdTable(const ScanProblem& problem,
                                const PreparedScan& p,
                                const std::vector<double>& own_durations,
                                const std::vector<Segment>& segs,
                                OrderedRuns& runs) {
  constexpr double kLeastShift = 0.0035;  // rad (0.2°): a smaller shift gains nothing
  const kinematics::CellModel& cell = p.scene->cell();
  std::vector<HeldPass> held;
  for (std::size_t k = 1; k < runs.fast.size(); ++k) {
    pollCancel(problem.planning.termination.cancel);
    const std::size_t s = runs.index[runs.order.order[k]];
    const Segment& seg = segs[s];
    if (!seg.build || seg.choice.sheet_map || seg.choice.theta.size() != seg.path.samples.size())
      continue;
    const kinematics::Trajectory& before = runs.fast[k - 1];
    double delta = before.samples.back().theta - runs.fast[k].samples.front().theta;
    if (cell.table.continuous) delta = std::remainder(delta, 2.0 * std::numbers::pi);
    if (std::abs(delta) < kLeastShift) continue;
    // The moves into it and out of it (to the next run as it stands) together.
    const auto around = [&](const kinematics::Trajectory& run) {
      return moveCost(cell, before, run) +
             (k + 1 < runs.fast.size() ? moveCost(cell, run, runs.fast[k + 1]) : 0.0);
    };
    std::vector<double> theta;
    std::optional<planner::TrajectoryBuild> build = shiftedBuild(problem, p, seg, delta, theta);
    if (!build) continue;
    auto [slow, fast] =
        runVersions(cell, build->trajectory, ownDuration(own_durations, s, build->trajectory),
                    runs.order.reversed[k] != 0);
    if (!(around(fast) < around(runs.fast[k]) - 1e-3)) continue;
    runs.fast[k] = std::move(fast);
    runs.slow[k] = std::move(slow);
    held.push_back({s, delta, std::move(theta), std::move(*build)});
  }
  return held;
}

// The shifted table paths made the segments' own: their trajectories and objective terms.
// Returns what they added to J, s.
double applyHeld(const ScanProblem& problem,
                 std::vector<HeldPass>& held,
                 std::vector<Segment>& segs) {
  double added = 0.0;
  for (HeldPass& h : held) {
    Segment& seg = segs[h.segment];
    const double before = seg.choice.terms.total;
    seg.choice.terms = planner::evaluate(seg.map, seg.build_branch, h.theta,
                                         problem.planning.objective, problem.planning.continuous);
    added += seg.choice.terms.total - before;
    seg.choice.theta = std::move(h.theta);
    seg.choice.table_shift = h.shift;
    seg.build = std::move(h.build);
  }
  return added;
}

// The runs joined at their own speed. A run no move reaches at that speed (its ends run fastest
// then) is tried once more at its samples' times, with the runs either side of it: the join that
// drops fewer runs is kept, then the shorter. `ordered` returns the runs as joined.
JoinedProgram joinFastest(const collision::Scene& scene,
                          const OrderedRuns& runs,
                          const MoveSettings& moves,
                          std::vector<kinematics::Trajectory>& ordered) {
  ordered = runs.fast;
  JoinedProgram joined = joinSegments(scene, ordered, moves);
  if (joined.dropped.empty()) return joined;
  std::vector<kinematics::Trajectory> again = ordered;
  for (const auto& [k, why] : joined.dropped)
    for (std::size_t j = k == 0 ? 0 : k - 1; j <= k + 1 && j < again.size(); ++j)
      again[j] = runs.slow[j];
  JoinedProgram other = joinSegments(scene, again, moves);
  const auto worse = [](const JoinedProgram& a, const JoinedProgram& b) {
    return a.dropped.size() != b.dropped.size() ? a.dropped.size() > b.dropped.size()
                                                : a.times.total > b.times.total;
  };
  if (!worse(joined, other)) return joined;
  ordered = std::move(again);
  return other;
}

// The runs joined in their order (the hand-written path, when there is one, first), each as fast
// as planned where a move reaches it so (joinFastest()). The program's start times and the
// dropped segments are mapped back to the segments' own indices (`segments` of them).
JoinedProgram joinInOrder(const collision::Scene& scene,
                          const OrderedRuns& runs,
                          std::size_t segments,
                          double max_program,
                          const MoveSettings& moves,
                          std::vector<ScanPlan::Run>& run_order,
                          std::vector<KnownMove>* known = nullptr) {
  const std::vector<std::size_t>& index = runs.index;
  const SegmentOrder& order = runs.order;
  std::vector<kinematics::Trajectory> ordered;
  JoinedProgram joined = joinFastest(scene, runs, moves, ordered);
  if (known) {
    // The moves made, between the runs as they ran (a run put off to the end may run backwards).
    known->clear();
    const auto backwards = [&](std::size_t k) { return order.reversed[k] != joined.flipped[k]; };
    for (const JoinedProgram::Made& m : joined.made)
      known->push_back(
          {order.order[m.from], order.order[m.to], backwards(m.from), backwards(m.to), m.duration});
  }
  if (max_program > 0.0) cutAt(max_program, ordered, joined);
  JoinedProgram out;
  out.trajectory = std::move(joined.trajectory);
  out.times = joined.times;
  out.start_times.assign(segments, std::numeric_limits<double>::quiet_NaN());
  for (std::size_t k = 0; k < order.order.size(); ++k)
    out.start_times[index[order.order[k]]] = joined.start_times[k];
  for (const auto& [k, why] : joined.dropped) out.dropped.emplace_back(index[order.order[k]], why);
  run_order.clear();
  for (std::size_t k = 0; k < order.order.size(); ++k)
    run_order.push_back(
        {index[order.order[k]], (order.reversed[k] != joined.flipped[k]), joined.start_times[k]});
  // In the order they run (a segment put off to the end runs last), the dropped ones after.
  std::stable_sort(run_order.begin(), run_order.end(), [](const auto& a, const auto& b) {
    if (std::isnan(a.start) || std::isnan(b.start))
      return !std::isnan(a.start) && std::isnan(b.start);
    return a.start < b.start;
  });
  return out;
}

// Whether program a is worse than b: it drops more segments, or as many and is longer.
bool worseProgram(const JoinedProgram& a, const JoinedProgram& b) {
  return a.dropped.size() != b.dropped.size() ? a.dropped.size() > b.dropped.size()
                                              : !(a.times.total < b.times.total);
}

// The best program over orders of the same runs so far, and the moves its joins made.
struct OrderSearch {
  const ScanProblem& problem;
  const PreparedScan& p;
  const std::vector<kinematics::Trajectory>& trajectories;
  const MoveSettings& moves;
  std::size_t segments;
  OrderedRuns runs;
  JoinedProgram joined;
  std::vector<ScanPlan::Run> run_order;
  std::vector<KnownMove> known;

  double maxProgram() const { return problem.auto_scan ? problem.auto_scan->max_program : 0.0; }
  void joinFirst() {
    joined = joinInOrder(*p.scene, runs, segments, maxProgram(), moves, run_order, &known);
  }
  // A search of the same runs in `order` (not joined yet).
  OrderSearch inOrder(const SegmentOrder& order) const {
    OrderSearch o{problem, p, trajectories, moves, segments, runs, {}, {}, {}};
    o.runs.order = order;
    arrange(p.scene->cell(), trajectories, p.path.path.own_durations, o.runs);
    return o;
  }
  // Another order's joined program taken when it is not worse; the moves it made learnt.
  void adopt(OrderSearch& other) {
    known.insert(known.end(), other.known.begin(), other.known.end());
    if (worseProgram(other.joined, joined)) return;
    runs = std::move(other.runs);
    joined = std::move(other.joined);
    run_order = std::move(other.run_order);
  }
  // The runs in `order` joined: kept when the program is better.
  void tryOrder(const SegmentOrder& order) {
    if (order == runs.order) return;
    pollCancel(problem.planning.termination.cancel);
    OrderSearch other = inOrder(order);
    other.joinFirst();
    adopt(other);
  }
};

// The program joined in the order of the shortest moves and in 2-opt's alone (the estimate
// misses the moves that must back off: either may join shorter), then in rounds ordered again
// with the moves made costed as they were (reorderSegments()), and with the table held
// (holdTable()): the held one when it drops no more passes and is shorter. Applies the held
// paths to `segs` when it is kept; `run_order` gets the kept program's order.
JoinedProgram joinBest(const ScanProblem& problem,
                       const PreparedScan& p,
                       const std::vector<kinematics::Trajectory>& trajectories,
                       OrderedRuns runs,
                       std::vector<Segment>& segs,
                       std::vector<ScanPlan::Run>& run_order,
                       ProgramTimes& held_times) {
  const kinematics::CellModel& cell = p.scene->cell();
  MoveSettings moves = moveSettings(problem);
  MoveCache cache;  // the joins share the moves they have in common
  moves.cache = &cache;
  OrderSearch search{problem, p, trajectories, moves, segs.size(), std::move(runs), {}, {}, {}};
  // Then 2-opt's order alone, its moves in common taken from the cache. (Each join plans its
  // moves on every core; two joins side by side would wait on the moves both need.)
  search.joinFirst();
  search.tryOrder(orderSegments(cell, search.runs.forwards, search.runs.fixed, {}, false));
  constexpr int kReorderRounds = 8;
  for (int round = 0; round < kReorderRounds && search.joined.times.detours > 0; ++round) {
    const SegmentOrder again = reorderSegments(cell, search.runs.forwards, search.runs.fixed,
                                               search.runs.order, search.known);
    if (again == search.runs.order) break;  // nothing learnt changes it
    search.tryOrder(again);
  }
  runs = std::move(search.runs);
  JoinedProgram joined = std::move(search.joined);
  run_order = std::move(search.run_order);
  OrderedRuns held_runs = runs;
  std::vector<ScanPlan::Run> held_order;
  std::vector<HeldPass> held = holdTable(problem, p, p.path.path.own_durations, segs, held_runs);
  if (held.empty()) return joined;
  JoinedProgram other =
      joinInOrder(*p.scene, held_runs, segs.size(), search.maxProgram(), moves, held_order);
  if (worseProgram(other, joined)) return joined;
  held_times.held = held.size();
  held_times.held_cost = applyHeld(problem, held, segs);
  run_order = std::move(held_order);
  return other;
}

}  // namespace

planner::Termination segmentBudget(const planner::Termination& whole,
                                   std::size_t samples,
                                   std::size_t path_samples) {
  const double share =
      static_cast<double>(samples) / static_cast<double>(std::max<std::size_t>(1, path_samples));
  planner::Termination t = whole;
  if (whole.max_iterations > 0) {
    const auto part =
        static_cast<std::size_t>(std::ceil(share * static_cast<double>(whole.max_iterations)));
    t.max_iterations = std::min(whole.max_iterations, std::max(kSegmentIterations, part));
  }
  if (whole.time_limit_s > 0.0)
    t.time_limit_s =
        std::min(whole.time_limit_s, std::max(kSegmentSeconds, share * whole.time_limit_s));
  return t;
}

std::string executableReason(const planner::TrajectoryBuild& build) {
  if (!build.ok) return build.reason;
  if (build.min_f > 0.0) return {};
  const auto& s = build.trajectory.samples[build.min_f_sample];
  return fmt::format(
      "time sample {} (t = {:.2f} s, table {:.2f} deg): f = 0 ({}) between the map's grid "
      "angles; a finer map.angle_step_deg resolves it",
      build.min_f_sample, s.t, toDeg(s.theta), s.limit);
}

planner::ConfigMap sliceMap(const planner::ConfigMap& map, std::size_t begin, std::size_t end) {
  planner::ConfigMap out;
  out.angles = map.angles;
  out.times.assign(map.times.begin() + static_cast<std::ptrdiff_t>(begin),
                   map.times.begin() + static_cast<std::ptrdiff_t>(end));
  out.branches = map.branches;
  const auto copy = [&](const auto& from, auto& to) {
    to.clear();
    to.reserve(map.branches.size() * map.angles.size() * (end - begin));
    for (std::size_t b = 0; b < map.branches.size(); ++b)
      for (std::size_t a = 0; a < map.angles.size(); ++a) {
        const auto row = from.begin() + static_cast<std::ptrdiff_t>(map.index(b, a, 0));
        to.insert(to.end(), row + static_cast<std::ptrdiff_t>(begin),
                  row + static_cast<std::ptrdiff_t>(end));
      }
  };
  copy(map.f, out.f);
  copy(map.joint, out.joint);
  copy(map.singularity, out.singularity);
  copy(map.clearance, out.clearance);
  copy(map.limit, out.limit);
  return out;
}

void planSegments(const ScanProblem& problem, const PlanOptions& options, ScanPlan& plan) {
  const PreparedScan& p = *plan.prepared;
  const auto ranges = kinematics::segmentRanges(p.path.path);
  std::vector<Segment> segs(ranges.size());
  for (std::size_t s = 0; s < ranges.size(); ++s) std::tie(segs[s].begin, segs[s].end) = ranges[s];
  const auto t = Clock::now();
  tbb::parallel_for(std::size_t{0}, segs.size(),
                    [&](std::size_t s) { planSegment(problem, p, options, segs[s]); });
  const double wall = since(t);
  std::vector<std::uint8_t> kept(segs.size(), 0);
  std::vector<kinematics::Trajectory> trajectories(segs.size());
  double trajectory_cpu = 0.0, all_cpu = 0.0;
  for (std::size_t s = 0; s < segs.size(); ++s) {
    trajectory_cpu += segs[s].trajectory_seconds;
    all_cpu += segs[s].choice.chosen.seconds + segs[s].trajectory_seconds;
    if (segs[s].build) {
      kept[s] = 1;
      trajectories[s] = segs[s].build->trajectory;
    } else {
      plan.dropped.emplace_back(s, segs[s].choice.chosen.result.reason);
    }
  }
  // Wall time split between the search and the trajectories as their CPU time splits.
  plan.times.trajectory = all_cpu > 0.0 ? wall * trajectory_cpu / all_cpu : 0.0;
  plan.times.plan = wall - plan.times.trajectory;
  if (std::find(kept.begin(), kept.end(), std::uint8_t{1}) == kept.end() ||
      (!p.auto_scan && !kept[0])) {
    plan.status = ScanStatus::kNoExecutablePath;
    plan.reason = segs.front().choice.chosen.result.reason;
    if (plan.reason.empty()) plan.reason = "no segment of the path can be planned";
    return;
  }
  const auto tj = Clock::now();
  // The hand-written path, when there is one, runs first.
  const std::size_t fixed = p.auto_scan && kept[0] && !problem.path.elements.empty() ? 1 : 0;
  const std::vector<double>& own = p.path.path.own_durations;
  OrderedRuns runs = orderedRuns(p.scene->cell(), trajectories, own, kept, fixed);
  ProgramTimes held;
  JoinedProgram joined =
      joinBest(problem, p, trajectories, std::move(runs), segs, plan.order, held);
  plan.dropped.insert(plan.dropped.end(), joined.dropped.begin(), joined.dropped.end());
  plan.choice = joinChoices(segs, kept);
  if (plan.choice.dp && plan.choice.chosen.method != "dp") plan.times.dp = plan.choice.dp->seconds;
  std::sort(plan.dropped.begin(), plan.dropped.end());
  planner::TrajectoryBuild build;
  build.ok = true;
  build.trajectory = std::move(joined.trajectory);
  build.min_f = 1.0;
  build.min_clearance = std::numeric_limits<double>::infinity();
  for (std::size_t s = 0; s < segs.size(); ++s) {
    if (!segs[s].build || std::isnan(joined.start_times[s])) continue;
    build.min_clearance = std::min(build.min_clearance, segs[s].build->min_clearance);
  }
  const auto& js = build.trajectory.samples;
  for (std::size_t k = 0; k < js.size(); ++k) {
    if (!std::isnan(js[k].f) && js[k].f < build.min_f) {
      build.min_f = js[k].f;
      build.min_f_sample = k;
    }
  }
  plan.trajectory = std::move(build);
  plan.program = joined.times;
  plan.program.held = held.held;
  plan.program.held_cost = held.held_cost;
  plan.times.trajectory += since(tj);
}

}  // namespace scanplan::pipeline
