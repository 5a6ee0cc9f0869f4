#include <scanplan/pipeline/auto_scan.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <optional>

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <scanplan/collision/clearance.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/ptp_move.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/pipeline/cancel.h>
#include <scanplan/pipeline/program_moves.h>
#include <scanplan/pipeline/simulation.h>
#include <scanplan/planner/config_map.h>
#include <scanplan/scanner/pass_selection.h>
#include <scanplan/scanner/scan_passes.h>
#include <scanplan/scanner/scannability.h>
#include <scanplan/scanner/set_cover.h>
#include <scanplan/scanner/simulator.h>

namespace scanplan::pipeline {

namespace {

using Clock = std::chrono::steady_clock;

constexpr std::size_t kMaxSamples = 400'000;  // evaluation samples at most (memory, time)
constexpr std::size_t kMaxAimed = 600;        // witnesses aimed at, at most
constexpr double kTargetMargin = 0.01;        // planned coverage over the target (see below)
constexpr double kMeasuredMargin = 0.0003;    // measured coverage kept over the target (below)
// Planned coverage over the target when the first cover measures less than the target.
constexpr std::array<double, 2> kRetryMargins{0.02, 0.03};
constexpr double kMaxStations = 5e6;  // probed strip stations of the candidates
// The set-cover programme's search (improveCover): nodes, model size, and a time limit that is
// only a safety net (the node and size limits decide, so the answer does not depend on speed).
constexpr std::size_t kCoverNodes = 200;
constexpr std::size_t kCoverNonzeros = 200'000;
constexpr double kCoverSeconds = 60.0;

double since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The automatic scan's progress over its steps: each step reports its own (done, total) into its
// share of the whole (in thousandths), and every report first polls the cancel flag (throws
// Cancelled). The shares follow the steps' wall times on the demo housing.
class Steps {
 public:
  // Where each step ends, as a share of the whole.
  static constexpr double kCandidates = 0.12;  // the general passes made and evaluated
  static constexpr double kStrips = 0.18;      // the aimed strips
  static constexpr double kArcs = 0.26;        // the aimed glances and arcs made
  static constexpr double kAimed = 0.49;       // ... and evaluated
  static constexpr double kReach = 0.56;       // the reach checks
  static constexpr double kGreedy = 0.57;      // the greedy cover
  static constexpr double kCover = 0.86;       // the set cover's programme
  static constexpr double kMeasured = 0.98;    // the chosen passes measured; then the tour

  Steps(const std::atomic<bool>* cancel, const std::function<void(std::size_t, std::size_t)>& out)
      : cancel_(cancel), out_(out) {}

  void poll() const { pollCancel(cancel_); }

  // The whole is done up to `fraction`.
  void at(double fraction) const {
    poll();
    if (out_)
      out_(static_cast<std::size_t>(std::lround(fraction * static_cast<double>(kWhole))), kWhole);
  }

  // The step from `from` to `to` of the whole, as a (done, total) report.
  std::function<void(std::size_t, std::size_t)> step(double from, double to) const {
    return [this, from, to](std::size_t done, std::size_t total) {
      const double share =
          static_cast<double>(done) / static_cast<double>(std::max<std::size_t>(1, total));
      at(from + (to - from) * std::min(1.0, share));
    };
  }

 private:
  static constexpr std::size_t kWhole = 1000;
  const std::atomic<bool>* cancel_;
  const std::function<void(std::size_t, std::size_t)>& out_;
};

int raysPerProfile(const ScanProblem& p) {
  return p.simulation ? p.simulation->scanner.rays_per_profile : 200;
}

// The largest d_low of the pairs between the scanner and the part or the table: the margin the
// housing keeps from them.
double housingMargin(const collision::Scene& scene) {
  double margin = 0.0;
  const auto& bodies = scene.bodies();
  for (const collision::PairInfo& pair : scene.pairs()) {
    const auto& a = bodies[static_cast<std::size_t>(pair.a)];
    const auto& b = bodies[static_cast<std::size_t>(pair.b)];
    const bool scanner =
        a.motion == collision::BodyMotion::kScanner || b.motion == collision::BodyMotion::kScanner;
    const bool table_side =
        a.motion == collision::BodyMotion::kTable || b.motion == collision::BodyMotion::kTable;
    if (scanner && table_side) margin = std::max(margin, pair.thresholds.d_low);
  }
  return margin;
}

// The housing's shapes as boxes in S (their tessellations' bounds).
std::vector<Eigen::AlignedBox3d> housingBoxes(const ScanProblem& p, double margin) {
  std::vector<Eigen::AlignedBox3d> boxes;
  for (const kinematics::Shape& shape : p.cell.scanner.body) {
    const kinematics::TriangleMesh m = kinematics::shapeSurface(shape);
    Eigen::AlignedBox3d box = m.bounds();
    box.min().array() -= margin;
    box.max().array() += margin;
    boxes.push_back(box);
  }
  return boxes;
}

scanner::PassSettings passSettings(const ScanProblem& p, const collision::Scene& scene) {
  const AutoScanSettings& a = *p.auto_scan;
  scanner::PassSettings s;
  s.window = scanner::laserWindow(p.optics);
  s.cameras = scanner::cameraCentres(
      p.optics, p.simulation ? p.simulation->scanner.cameras : scanner::CameraRule::kPositive);
  s.max_incidence = a.max_incidence;
  s.point_spacing = autoPointSpacing(a, p.optics, raysPerProfile(p));
  s.frame_rate = p.simulation ? p.simulation->frame_rate_hz : 100.0;
  const kinematics::RotaryTableModel& table = p.cell.table;
  // A spin turns the table a whole revolution; leave a fifth of its speed for the planner.
  s.max_spin_rate = table.continuous ? 0.8 * (table.max_speed > 0.0 ? table.max_speed : 0.5) : 0.0;
  // A spin's rate changes only as fast as half the table's acceleration limit: the planner keeps
  // the other half.
  if (table.max_accel > 0.0) s.max_spin_accel = 0.5 * table.max_accel;
  s.housing = housingBoxes(p, housingMargin(scene));
  return s;
}

// Can the arm follow `pass` (R frame), backed off along the laser to the transfer sphere before
// and after it, with the table at one angle (strips) or turning with the head (spins) on one IK
// branch, f > 0 at its keys, every 0.25 s between and every 20 mm on the legs? Table angles
// every 10°. (A spin the tour turns to start elsewhere keeps its legs' shape in the world only
// when the sphere's centre is on the table axis; off it, they differ a little.)
class ReachCheck {
 public:
  ReachCheck(const ScanProblem& problem,
             const collision::Scene& scene,
             const scanner::TransferSphere& sphere)
      : problem_(problem),
        scene_(scene),
        sphere_(sphere),
        branches_(mapBranches(problem.map)),
        evaluator_(scene, branches_.size()),
        angles_(planner::mapAngles(problem.cell.table, deg(10.0))) {}

  bool operator()(const scanner::ScanPass& pass) {
    const kinematics::CellModel& cell = problem_.cell;
    const Eigen::Isometry3d X_PR = cell.part.X_RP.inverse();
    const std::vector<Timed> poses = withLegs(timedPoses(pass));
    for (const double theta0 : angles_) {
      std::vector<bool> alive(branches_.size(), true);
      bool any = true;
      for (std::size_t k = 0; k < poses.size() && any; ++k) {
        const double theta = theta0 - poses[k].turn;
        const Eigen::Isometry3d X_BF = cell.flangeTarget(theta, X_PR * poses[k].X_RS);
        const auto solutions = cell.robot.ik(X_BF);
        evaluator_.beginCell(theta, X_BF);
        any = false;
        for (std::size_t b = 0; b < branches_.size(); ++b) {
          if (!alive[b]) continue;
          alive[b] = planner::scoreCell(scene_, problem_.constraints, evaluator_, b, solutions,
                                        branches_[b])
                         .f > 0.0f;
          any = any || alive[b];
        }
      }
      if (any) return true;
    }
    return false;
  }

 private:
  struct Timed {
    Eigen::Isometry3d X_RS;
    double turn = 0.0;  // rad the table turns with a spin's head by then
  };
  // The pass's keys and poses every 0.25 s between them (400 at most), as the path will
  // interpolate them: a corner between two sampled times can be the one pose that fails.
  static std::vector<Timed> timedPoses(const scanner::ScanPass& pass) {
    const int between = std::clamp(static_cast<int>(std::ceil(pass.duration() / 0.25)), 1, 400);
    std::vector<double> times(pass.t.begin(), pass.t.end());
    for (int i = 1; i < between; ++i)
      times.push_back(pass.t.front() + pass.duration() * i / between);
    std::sort(times.begin(), times.end());
    std::vector<Timed> out;
    std::size_t k = 0;
    for (const double t : times) {
      while (k + 2 < pass.t.size() && pass.t[k + 1] < t) ++k;
      const double span = pass.t[k + 1] - pass.t[k];
      const double s = span > 0.0 ? std::clamp((t - pass.t[k]) / span, 0.0, 1.0) : 0.0;
      Timed pose{kinematics::interpolatePose(pass.X_RS[k], pass.X_RS[k + 1], s), 0.0};
      if (pass.kind == scanner::PassKind::kSpin)
        pose.turn =
            pass.azimuth[k] + s * (pass.azimuth[k + 1] - pass.azimuth[k]) - pass.azimuth.front();
      out.push_back(pose);
    }
    return out;
  }

  // The pass's poses, then the legs to and from the sphere (each with the table where it is at
  // that end): f > 0 on a branch at all of them, in any order, so the pass's own poses, which
  // fail most often, go first.
  std::vector<Timed> withLegs(const std::vector<Timed>& poses) const {
    constexpr double kLegStep = 0.02;  // m
    std::vector<Timed> all = poses;
    for (const Timed& end : {poses.front(), poses.back()}) {
      const auto leg = scanner::backOffLeg(end.X_RS, sphere_, kLegStep);
      for (auto it = leg.begin() + 1; it != leg.end(); ++it) all.push_back({*it, end.turn});
    }
    return all;
  }

  const ScanProblem& problem_;
  const collision::Scene& scene_;
  const scanner::TransferSphere& sphere_;
  std::vector<kinematics::IkBranch> branches_;
  collision::MapClearance evaluator_;
  std::vector<double> angles_;
};

// The scanning stretches of the hand-written path as passes (R frame).
std::vector<scanner::ScanPass> givenPasses(const kinematics::ScanPath& given,
                                           const Eigen::Isometry3d& X_RP) {
  std::vector<scanner::ScanPass> out;
  scanner::ScanPass run;
  const auto flush = [&] {
    if (run.X_RS.size() >= 2) out.push_back(run);
    run = {};
    run.kind = scanner::PassKind::kGiven;
  };
  flush();
  for (const auto& s : given.samples) {
    if (!s.scanning) {
      flush();
      continue;
    }
    run.t.push_back(s.t);
    run.X_RS.push_back(X_RP * s.X_PS);
  }
  flush();
  return out;
}

// The safe sphere: around the part's bounding sphere, grown by the head's reach from its laser
// origin (the housing) and a margin.
scanner::TransferSphere transferSphere(const ScanProblem& p,
                                       const kinematics::TriangleMesh& part_R) {
  Eigen::AlignedBox3d box = part_R.bounds();
  scanner::TransferSphere s;
  s.centre = box.center();
  double part = 0.0, head = 0.0;
  for (const Eigen::Vector3d& v : part_R.vertices) part = std::max(part, (v - s.centre).norm());
  for (const kinematics::Shape& shape : p.cell.scanner.body) {
    const kinematics::TriangleMesh m = kinematics::shapeSurface(shape);
    for (const Eigen::Vector3d& v : m.vertices) head = std::max(head, v.norm());
  }
  s.radius = part + head + 0.02;
  s.speed = p.path.transfer_speed;
  return s;
}

}  // namespace

double autoPointSpacing(const AutoScanSettings& settings,
                        const scanner::LaserOptics& optics,
                        int rays_per_profile) {
  if (settings.point_spacing > 0.0) return settings.point_spacing;
  const scanner::LaserWindow w = scanner::laserWindow(optics);
  return 2.0 * w.halfWidth(0.5 * (w.z_min + w.z_max)) / std::max(1, rays_per_profile - 1);
}

namespace {

// The certificate's first pass: classes and a witness pose per scannable sample.
std::vector<scanner::SampleClass> certify(const scanner::PartOnTable& part,
                                          const scanner::PassSettings& pass,
                                          const scanner::AreaSampling& sampling,
                                          std::vector<Eigen::Isometry3d>& witnesses) {
  scanner::ScannabilitySettings s;
  s.max_incidence = pass.max_incidence;
  s.window = pass.window;
  s.cameras = pass.cameras;
  s.housing = pass.housing;
  s.housing_spacing = pass.housing_spacing;
  s.directions = 48;  // bore walls are seen from few directions; 24 x 8 misses a few percent
  s.rolls = 12;
  return scanner::classifyScannability(sampling, part, s, &witnesses);
}

// The ±30 mm strips aimed at the scannable samples `reached` leaves out, in sample order, a
// sample an earlier strip covers getting none of its own; each appends its witness's sample to
// `aimed_at`. At most `limit`. The strips are made and evaluated in parallel batches, ahead of
// knowing whether an earlier strip of the batch covers their sample (then one is dropped): the
// result is the same as one by one. `report` gets the samples looked at of all.
std::vector<scanner::ScanPass> aimedStrips(
    const scanner::PartOnTable& part,
    const scanner::PassSettings& pass,
    const scanner::SampleIndex& index,
    const std::vector<scanner::SampleClass>& classes,
    const std::vector<Eigen::Isometry3d>& witnesses,
    std::vector<std::uint8_t>& reached,
    std::size_t limit,
    std::vector<std::size_t>& aimed_at,
    const std::function<void(std::size_t, std::size_t)>& report) {
  constexpr std::size_t kBatch = 16;
  std::vector<scanner::ScanPass> out;
  std::vector<std::size_t> batch;
  for (std::size_t i = 0; i < classes.size() && out.size() < limit;) {
    batch.clear();
    for (; i < classes.size() && batch.size() < kBatch; ++i)
      if (classes[i] == scanner::SampleClass::kScannable && !reached[i]) batch.push_back(i);
    std::vector<scanner::ScanPass> strips(batch.size());
    tbb::parallel_for(std::size_t{0}, batch.size(), [&](std::size_t k) {
      strips[k] = scanner::aimedPass(part, pass, witnesses[batch[k]], 0.03);
      if (!strips[k].X_RS.empty()) scanner::evaluatePass(strips[k], part, pass, index);
    });
    for (std::size_t k = 0; k < batch.size() && out.size() < limit; ++k) {
      if (reached[batch[k]]) continue;  // an earlier strip of this batch covers it
      reached[batch[k]] = 1;
      if (strips[k].X_RS.empty()) continue;
      for (std::uint32_t j : strips[k].covers) reached[j] = 1;
      if (strips[k].covers.empty()) continue;
      out.push_back(std::move(strips[k]));
      aimed_at.push_back(batch[k]);
    }
    report(i, classes.size());
  }
  return out;
}

// Aimed passes for the scannable samples no general candidate covers, each from its witness;
// a sample an aimed pass already covers gets none of its own. At most `limit` witnesses. Each
// witness gives a strip of ±30 mm and one of ±12 mm, and arcs of the table of at most 35°, 90°
// and a whole turn: the set cover takes the shortest that covers what is needed (a small pocket
// wants a glance, a bore on the axis a whole turn).
std::vector<scanner::ScanPass> aimedPasses(const scanner::PartOnTable& part,
                                           const scanner::PassSettings& pass,
                                           const scanner::SampleIndex& index,
                                           const std::vector<scanner::SampleClass>& classes,
                                           const std::vector<Eigen::Isometry3d>& witnesses,
                                           const std::vector<scanner::ScanPass>& general,
                                           std::size_t limit,
                                           const Steps& steps) {
  std::vector<std::uint8_t> reached(classes.size(), 0);
  for (const auto& p : general)
    for (std::uint32_t i : p.covers) reached[i] = 1;
  std::vector<std::size_t> aimed_at;
  std::vector<scanner::ScanPass> out =
      aimedStrips(part, pass, index, classes, witnesses, reached, limit, aimed_at,
                  steps.step(Steps::kCandidates, Steps::kStrips));
  // Per witness, in parallel (then in witness order): the short strip and the arcs.
  std::vector<std::vector<scanner::ScanPass>> per_witness(aimed_at.size());
  std::atomic<std::size_t> done{0};
  const auto report = steps.step(Steps::kStrips, Steps::kArcs);
  tbb::parallel_for(std::size_t{0}, aimed_at.size(), [&](std::size_t k) {
    const Eigen::Isometry3d& witness = witnesses[aimed_at[k]];
    scanner::ScanPass glance = scanner::aimedPass(part, pass, witness, 0.012);
    if (!glance.X_RS.empty()) per_witness[k].push_back(std::move(glance));
    // The same view held while the table turns: one pass for a band of such samples (a bore on
    // the axis, features repeated around it) where the strips would take one each.
    std::size_t stations = 0;  // of the last arc: a longer cap that fits no more adds nothing
    for (double arc : {0.6108652381980153, 1.5707963267948966, 6.283185307179586}) {
      scanner::ScanPass spin = scanner::aimedSpin(part, pass, witness, 0.35, arc);
      if (spin.X_RS.size() <= stations) break;
      stations = spin.X_RS.size();
      per_witness[k].push_back(std::move(spin));
    }
    report(++done, aimed_at.size());
  });
  std::vector<scanner::ScanPass> more;
  for (auto& passes : per_witness)
    for (auto& p : passes) more.push_back(std::move(p));
  scanner::evaluatePasses(more, part, pass, index, steps.step(Steps::kArcs, Steps::kAimed));
  for (auto& p : more)
    if (!p.covers.empty()) out.push_back(std::move(p));
  return out;
}

// Which passes the arm can follow (ReachCheck), in parallel.
std::vector<std::uint8_t> reachable(const ScanProblem& problem,
                                    const collision::Scene& scene,
                                    const scanner::TransferSphere& sphere,
                                    const std::vector<scanner::ScanPass>& passes,
                                    const std::function<void(std::size_t, std::size_t)>& report) {
  std::vector<std::uint8_t> ok(passes.size(), 0);
  tbb::enumerable_thread_specific<ReachCheck> checks(std::cref(problem), std::cref(scene),
                                                     std::cref(sphere));
  std::atomic<std::size_t> done{0};
  tbb::parallel_for(std::size_t{0}, passes.size(), [&](std::size_t p) {
    ok[p] = checks.local()(passes[p]) ? 1 : 0;
    report(++done, passes.size());
  });
  return ok;
}

// Scannable samples that some pass sees but no reachable one: out of the arm's reach.
void markOutOfReach(std::vector<scanner::SampleClass>& classes,
                    const std::vector<scanner::ScanPass>& passes,
                    const std::vector<std::uint8_t>& reach) {
  std::vector<std::uint8_t> seen(classes.size(), 0), open(classes.size(), 0);
  for (std::size_t p = 0; p < passes.size(); ++p) {
    for (std::uint32_t i : passes[p].covers) {
      seen[i] = 1;
      if (reach[p]) open[i] = 1;
    }
  }
  for (std::size_t i = 0; i < classes.size(); ++i) {
    if (classes[i] == scanner::SampleClass::kScannable && seen[i] && !open[i])
      classes[i] = scanner::SampleClass::kOutOfReach;
  }
}

// The program's passes in tour order (part frame), and their lines in the report.
void buildPasses(const ScanProblem& problem,
                 const std::vector<scanner::ScanPass>& passes,
                 const std::vector<scanner::TourStep>& tour,
                 const std::vector<double>& gain,
                 AutoScanPlan& plan) {
  const Eigen::Isometry3d X_PR = problem.cell.part.X_RP.inverse();
  for (const scanner::TourStep& step : tour) {
    const scanner::ScanPass pass = scanner::stepPass(passes, step);
    scanner::FileSpec keys;
    for (std::size_t k = 0; k < pass.X_RS.size(); ++k)
      keys.samples.push_back({pass.t[k] - pass.t.front(), X_PR * pass.X_RS[k], true});
    plan.passes.push_back(std::move(keys));
    plan.report.passes.push_back({scanner::passKindName(pass.kind), pass.label,
                                  plan.report.scan_time, pass.duration(), gain[step.pass]});
    plan.report.scan_time += pass.duration();
  }
}

// Each pass's share of the counted samples (`counted` of them), the passes taken in order.
std::vector<double> gains(const std::vector<scanner::ScanPass>& passes,
                          std::size_t counted_samples,
                          const std::vector<std::uint8_t>& counts,
                          std::vector<std::uint8_t> seen) {
  std::vector<double> gain(passes.size(), 0.0);
  const double counted = std::max<double>(1.0, static_cast<double>(counted_samples));
  for (std::size_t p = 0; p < passes.size(); ++p) {
    std::size_t n = 0;
    for (std::uint32_t i : passes[p].covers) {
      if (counts[i] && !seen[i]) ++n;
      seen[i] = 1;
    }
    gain[p] = static_cast<double>(n) / counted;
  }
  return gain;
}

// The time a typical move between passes takes on this cell (a pass's overhead in the cover):
// a point-to-point move turning the table and every joint by 30°, as the program makes it.
double moveOverhead(const ScanProblem& problem) {
  const kinematics::AxisLimits limits =
      kinematics::axisLimits(problem.cell.robot, problem.cell.table, MoveSettings{}.speed_scale,
                             MoveSettings{}.accel_time);
  const kinematics::AxisVector zero = kinematics::AxisVector::Zero();
  return kinematics::ptpDuration(zero, kinematics::AxisVector::Constant(deg(30.0)), zero, zero,
                                 limits);
}

// The greedy cover improved by the set-cover integer programme (scanner/set_cover.h): the same
// target at the least estimated time (each pass's scanning plus a move), over a pool of the
// greedy passes and half as many again of the reachable passes with the most counting samples per
// second besides. Deterministic: a node limit, and a model-size limit rather than a time limit
// decide how far it searches. The report keeps the greedy and optimised estimates and the
// proven lower bound.
void improveCover(const std::vector<scanner::ScanPass>& passes,
                  const std::vector<std::uint8_t>& counts,
                  const std::vector<std::uint8_t>& covered,
                  const std::vector<std::uint8_t>& reach,
                  const scanner::CoverSettings& cover,
                  const Steps& steps,
                  scanner::CoverResult& chosen,
                  AutoScanReport& report) {
  scanner::CoverProblem problem;
  problem.counts = counts;
  problem.covered = covered;
  problem.target = cover.target;
  std::vector<std::pair<double, std::size_t>> value;
  for (std::size_t p = 0; p < passes.size(); ++p) {
    problem.cost.push_back(passes[p].duration() + cover.pass_overhead);
    problem.covers.push_back(passes[p].covers);
    std::size_t n = 0;
    for (const std::uint32_t i : passes[p].covers) n += counts[i] && !covered[i] ? 1u : 0u;
    if (reach[p] && n > 0) value.push_back({-static_cast<double>(n) / problem.cost[p], p});
  }
  std::sort(value.begin(), value.end());
  problem.allowed.assign(passes.size(), 0);
  for (const std::size_t p : chosen.chosen) problem.allowed[p] = 1;
  for (std::size_t k = 0, added = 0; k < value.size() && 2 * added < chosen.chosen.size(); ++k) {
    if (problem.allowed[value[k].second]) continue;
    problem.allowed[value[k].second] = 1;
    ++added;
  }
  scanner::CoverLimits limits;
  limits.node_limit = kCoverNodes;
  limits.max_nonzeros = kCoverNonzeros;
  limits.poll = [&steps] { steps.poll(); };
  const scanner::CoverSolution best =
      scanner::solveCover(problem, chosen.chosen, kCoverSeconds, limits);
  report.greedy_cost = 0.0;
  for (const std::size_t p : chosen.chosen) report.greedy_cost += problem.cost[p];
  report.cover_cost = best.cost;
  report.cover_bound = best.lower_bound;
  report.cover_status = best.status;
  report.cover_seconds = best.seconds;
  if (!best.reached || !(best.cost < report.greedy_cost)) return;
  chosen.chosen = best.chosen;
  chosen.covered.assign(counts.size(), 0);
  for (std::size_t i = 0; i < covered.size(); ++i) chosen.covered[i] = covered[i];
  for (const std::size_t p : best.chosen)
    for (const std::uint32_t i : passes[p].covers) chosen.covered[i] = 1;
  chosen.covered_counted = 0;
  for (std::size_t i = 0; i < counts.size(); ++i)
    chosen.covered_counted += counts[i] && chosen.covered[i] ? 1u : 0u;
}

// The evaluation samples and their classes in the part frame, for the report.
void keepCertificate(const scanner::AreaSampling& sampling_R,
                     const Eigen::Isometry3d& X_RP,
                     std::vector<scanner::SampleClass> classes,
                     AutoScanReport& report) {
  const Eigen::Isometry3d X_PR = X_RP.inverse();
  report.sampling = sampling_R;
  for (auto& s : report.sampling.samples) {
    s.p = X_PR * s.p;
    s.n = X_PR.linear() * s.n;
  }
  report.classes = std::move(classes);
}

// The candidates' probing grows with the square of the part's size: a part in mm declared in m
// would run for hours. Refused beyond 5 million probed strip stations (a part about 2 m across).
void checkPartSize(const ScanProblem& problem, const scanner::PassSettings& pass) {
  std::vector<Eigen::Vector3d> part_R;
  part_R.reserve(problem.part.vertices.size());
  for (const Eigen::Vector3d& v : problem.part.vertices)
    part_R.push_back(problem.cell.part.X_RP * v);
  if (!(scanner::candidateStations(part_R, pass) <= kMaxStations)) {
    throw InputError(fmt::format(
        "part: {:.0f} mm across (its box diagonal) is too large to scan with a {:.0f} mm line: "
        "expected a part within about 2 m (check part.units and part.scale)",
        toMm(problem.part.bounds().diagonal().norm()), toMm(2.0 * pass.window.y_near)));
  }
}

// Every candidate: the general spins and strips, then passes aimed at what they miss; evaluated.
std::vector<scanner::ScanPass> candidates(const scanner::PartOnTable& part,
                                          const scanner::PassSettings& pass,
                                          const scanner::SampleIndex& index,
                                          const std::vector<scanner::SampleClass>& classes,
                                          const std::vector<Eigen::Isometry3d>& witnesses,
                                          const Steps& steps,
                                          std::size_t& aimed_count) {
  std::vector<scanner::ScanPass> passes = scanner::candidatePasses(part, pass);
  steps.poll();
  scanner::evaluatePasses(passes, part, pass, index, steps.step(0.0, Steps::kCandidates));
  std::vector<scanner::ScanPass> aimed =
      aimedPasses(part, pass, index, classes, witnesses, passes, kMaxAimed, steps);
  aimed_count = aimed.size();
  passes.insert(passes.end(), std::make_move_iterator(aimed.begin()),
                std::make_move_iterator(aimed.end()));
  return passes;
}

// The samples the hand-written path covers already.
std::vector<std::uint8_t> givenCoverage(const kinematics::ScanPath& given,
                                        const Eigen::Isometry3d& X_RP,
                                        const scanner::PartOnTable& part,
                                        const scanner::PassSettings& pass,
                                        const scanner::SampleIndex& index) {
  std::vector<scanner::ScanPass> passes = givenPasses(given, X_RP);
  scanner::evaluatePasses(passes, part, pass, index);
  std::vector<std::uint8_t> covered(index.sampling().samples.size(), 0);
  for (const auto& p : passes)
    for (std::uint32_t i : p.covers) covered[i] = 1;
  return covered;
}

// The radius the simulated cloud's area coverage is measured with, m (pipeline/simulation.cpp).
double coverageRadius(const ScanProblem& p, const scanner::PassSettings& pass) {
  return p.simulation ? coverageSpacing(*p.simulation, p.optics) : pass.point_spacing;
}

// The chosen passes as the scanner will measure them (scanner::measurePass: every profile, the
// whole fan, on the area samples and radius the simulated cloud's coverage is judged by), cut to
// what the others do not cover, split where a stretch that adds nothing takes longer than a
// typical move, then whole pieces left out while the measured coverage stays at the job's target
// and a margin. Fills the report's cut and measured figures; the pieces' covers are over
// `measured.fine`.
struct MeasuredCut {
  scanner::AreaSampling fine;        ///< the simulation's area samples (R frame)
  std::vector<std::uint8_t> counts;  ///< per fine sample: counts toward the target
  std::vector<std::uint8_t> given;   ///< per fine sample: covered by the given paths
  std::vector<scanner::ScanPass> pieces;
};

// The pieces left out whole (scanner::pruneToGoal, each costing its scanning and a typical
// move) while the measured coverage of the counting fine samples, the given paths' included,
// stays at the job's target and kMeasuredMargin. Fills the report's measured figures. The
// simulated cloud has covered at least what was measured on every bench part (0.03–0.23 % more,
// tests/bench/README.md): its passes run where they were measured, and its certificate counts as
// scannable no area sample the measuring does not; the margin is for the profiles falling at
// other instants and the joints interpolated between the trajectory's samples.
std::vector<scanner::ScanPass> prunedPieces(const ScanProblem& problem,
                                            std::vector<scanner::ScanPass> pieces,
                                            const scanner::CoverSettings& cover,
                                            const MeasuredCut& m,
                                            AutoScanReport& report) {
  std::size_t counted = 0, given = 0;
  std::vector<std::uint8_t> open(m.counts.size(), 0);
  for (std::size_t i = 0; i < m.counts.size(); ++i) {
    counted += m.counts[i] ? 1u : 0u;
    given += (m.counts[i] && m.given[i]) ? 1u : 0u;
    open[i] = (m.counts[i] && !m.given[i]) ? 1 : 0;
  }
  const double goal = std::min(1.0, problem.auto_scan->target_coverage + kMeasuredMargin);
  const double open_n = static_cast<double>(counted - given);
  const double open_goal =
      open_n > 0.0
          ? std::clamp((goal * static_cast<double>(counted) - static_cast<double>(given)) / open_n,
                       0.0, 1.0)
          : 0.0;
  std::vector<double> cost(pieces.size());
  for (std::size_t k = 0; k < pieces.size(); ++k)
    cost[k] = pieces[k].duration() + cover.pass_overhead;
  const std::vector<std::size_t> kept = scanner::pruneToGoal(pieces, cost, open, open_goal);
  std::vector<scanner::ScanPass> out;
  std::vector<std::uint8_t> seen = m.given;
  report.pruned_time = 0.0;
  for (const scanner::ScanPass& p : pieces) report.pruned_time += p.duration();
  for (const std::size_t k : kept) {
    for (const std::uint32_t i : pieces[k].covers) seen[i] = 1;
    report.pruned_time -= pieces[k].duration();
    out.push_back(std::move(pieces[k]));
  }
  report.pruned = pieces.size() - out.size();
  std::size_t have = 0;
  for (std::size_t i = 0; i < seen.size(); ++i) have += (m.counts[i] && seen[i]) ? 1u : 0u;
  report.measured_fraction =
      counted > 0 ? static_cast<double>(have) / static_cast<double>(counted) : 0.0;
  return out;
}

MeasuredCut measuredCut(const ScanProblem& problem,
                        const scanner::PartOnTable& part,
                        const scanner::PassSettings& pass_settings,
                        const scanner::SampleIndex& index,
                        const std::vector<scanner::SampleClass>& classes,
                        const std::vector<std::uint8_t>& covered,
                        const std::vector<scanner::ScanPass>& passes,
                        const scanner::CoverResult& chosen,
                        const scanner::CoverSettings& cover,
                        const Steps& steps,
                        AutoScanReport& report) {
  MeasuredCut out;
  const double radius = coverageRadius(problem, pass_settings);
  const std::size_t most = problem.simulation ? problem.simulation->max_area_samples : 200'000;
  out.fine = scanner::sampleArea(part.part(), 2.0 * radius, most);
  const scanner::SampleIndex fine(out.fine);
  std::vector<scanner::ScanPass> whole(chosen.chosen.size());
  std::atomic<std::size_t> done{0};
  const auto progress = steps.step(Steps::kCover, Steps::kMeasured);
  tbb::parallel_for(std::size_t{0}, whole.size(), [&](std::size_t k) {
    whole[k] = passes[chosen.chosen[k]];
    scanner::measurePass(whole[k], part, pass_settings, fine, raysPerProfile(problem), radius);
    progress(++done, whole.size());
  });
  // A fine sample counts as its nearest evaluation sample does, or when a pass measures it (as
  // the certificate counts the simulated cloud's samples).
  const std::size_t n = out.fine.samples.size();
  out.counts.assign(n, 0);
  out.given.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t near = index.nearest(out.fine.samples[i].p);
    out.counts[i] = classes[near] == scanner::SampleClass::kScannable ? 1 : 0;
    out.given[i] = covered[near];
  }
  for (const scanner::ScanPass& pass : whole)
    for (const std::uint32_t i : pass.covers) out.counts[i] = 1;
  std::vector<std::size_t> all(whole.size());
  for (std::size_t k = 0; k < all.size(); ++k) all[k] = k;
  scanner::CutPasses cut =
      scanner::cutToCover(whole, all, out.counts, out.given, cover.pass_overhead);
  report.cut_time = cut.cut_time;
  report.cut_dropped = cut.dropped;
  report.cut_split = cut.split;
  out.pieces = prunedPieces(problem, std::move(cut.passes), cover, out, report);
  return out;
}

void reportCover(const scanner::CoverResult& chosen,
                 const std::vector<std::uint8_t>& counts,
                 const std::vector<std::uint8_t>& given,
                 AutoScanReport& report) {
  report.counted = chosen.counted;
  report.stop = chosen.stop;
  const double counted = std::max<double>(1.0, static_cast<double>(chosen.counted));
  report.planned_fraction = static_cast<double>(chosen.covered_counted) / counted;
  std::size_t given_covered = 0;
  for (std::size_t i = 0; i < counts.size(); ++i)
    given_covered += (counts[i] && given[i]) ? 1u : 0u;
  report.given_fraction = static_cast<double>(given_covered) / counted;
}

// The set cover's target (the job's with a margin), pass limit and estimate of a move.
scanner::CoverSettings coverSettings(const ScanProblem& problem) {
  const AutoScanSettings& settings = *problem.auto_scan;
  scanner::CoverSettings cover;
  // A margin over the target: the evaluation samples are coarser than the area the cloud is
  // judged on, and the measured passes (measuredCut) then leave out what the target does not
  // need of the cover; with no margin, the measured coverage often falls short of the target.
  cover.target = std::min(1.0, settings.target_coverage + kTargetMargin);
  cover.max_passes = settings.max_passes;
  cover.pass_overhead = moveOverhead(problem);
  return cover;
}

// The measured pieces in tour order (scanner::orderPasses, from where the given paths end) as
// the plan's passes, each with its measured gain.
void addTour(const ScanProblem& problem,
             const MeasuredCut& measured,
             const kinematics::ScanPath& given,
             const scanner::TransferSphere& sphere,
             AutoScanPlan& plan) {
  std::vector<std::size_t> pieces(measured.pieces.size());
  for (std::size_t k = 0; k < pieces.size(); ++k) pieces[k] = k;
  std::optional<Eigen::Isometry3d> at;
  if (!given.samples.empty()) at = problem.cell.part.X_RP * given.samples.back().X_PS;
  const std::vector<scanner::TourStep> tour =
      scanner::orderPasses(measured.pieces, pieces, at, sphere);
  plan.report.transfer_time = scanner::tourTransferTime(measured.pieces, tour, at, sphere);
  const auto counted = static_cast<std::size_t>(
      std::count(measured.counts.begin(), measured.counts.end(), std::uint8_t{1}));
  buildPasses(problem, measured.pieces, tour,
              gains(measured.pieces, counted, measured.counts, measured.given), plan);
}

// The passes' selection for a cover's target: the greedy cover, then the integer programme.
struct Choosing {
  const ScanProblem& problem;
  const std::vector<scanner::ScanPass>& passes;
  const std::vector<std::uint8_t>& counts;
  const std::vector<std::uint8_t>& covered;
  const std::vector<std::uint8_t>& reach;
  Clock::time_point start;

  scanner::CoverResult select(const scanner::CoverSettings& cover,
                              const Steps& steps,
                              AutoScanReport& report) const {
    const AutoScanSettings& settings = *problem.auto_scan;
    // With a time limit, a pass is taken only while the program's estimate (its passes and a
    // move before each) stays within it.
    double estimate = 0.0;
    const auto accept = [&](std::size_t p) {
      if (!reach[p]) return false;
      const double cost = passes[p].duration() + cover.pass_overhead;
      if (settings.max_program > 0.0 && estimate + cost > settings.max_program) return false;
      estimate += cost;
      return true;
    };
    scanner::CoverResult chosen = scanner::greedyCover(passes, counts, covered, cover, accept, [&] {
      steps.poll();
      return since(start) < settings.time_budget;
    });
    steps.at(Steps::kGreedy);
    if (settings.max_program <= 0.0 && chosen.stop == "target reached")
      improveCover(passes, counts, covered, reach, cover, steps, chosen, report);
    reportCover(chosen, counts, covered, report);
    return chosen;
  }
};

using Measure = std::function<MeasuredCut(
    const scanner::CoverResult&, const scanner::CoverSettings&, const Steps&, AutoScanReport&)>;

// Where the chosen passes measure less than the job's target (and kMeasuredMargin), the cover
// chosen again for the target + each of kRetryMargins in turn and measured, until one measures
// the target: that one is kept. When none does, the first stands: the target is then out of
// reach of covers that cost what it is worth (on the bench's 3 × 3 cavities 20 % more program
// for 0.7 % more area, still short). Not with a program time limit (its cover is the best within
// the limit).
void measureAgain(const Choosing& choosing,
                  const Measure& measure,
                  const Steps& steps,
                  AutoScanReport& report,
                  MeasuredCut& measured) {
  const AutoScanSettings& settings = *choosing.problem.auto_scan;
  const double goal = std::min(1.0, settings.target_coverage + kMeasuredMargin);
  if (settings.max_program > 0.0) return;
  const std::function<void(std::size_t, std::size_t)> none;
  const Steps quiet(choosing.problem.planning.termination.cancel, none);  // progress stays put
  scanner::CoverSettings cover = coverSettings(choosing.problem);
  for (const double margin : kRetryMargins) {
    if (report.measured_fraction >= goal - 1e-12) return;
    cover.target = std::min(1.0, settings.target_coverage + margin);
    AutoScanReport again = report;
    again.passes.clear();
    const scanner::CoverResult chosen = choosing.select(cover, quiet, again);
    if (chosen.chosen.empty()) return;
    MeasuredCut more = measure(chosen, cover, quiet, again);
    ++report.rechosen;
    if (again.measured_fraction >= goal - 1e-12) {
      again.rechosen = report.rechosen;
      again.rechosen_kept = true;
      report = std::move(again);
      measured = std::move(more);
    }
  }
  steps.poll();
}

}  // namespace

AutoScanPlan planAutoScan(const ScanProblem& problem,
                          const collision::Scene& scene,
                          const kinematics::ScanPath& given,
                          const std::function<void(std::size_t, std::size_t)>& progress) {
  const auto start = Clock::now();
  const Steps steps(problem.planning.termination.cancel, progress);
  const AutoScanSettings& settings = *problem.auto_scan;
  const scanner::PassSettings pass_settings = passSettings(problem, scene);
  const kinematics::RotaryTableModel& table = problem.cell.table;
  const Eigen::Isometry3d& X_RP = problem.cell.part.X_RP;
  checkPartSize(problem, pass_settings);
  const scanner::PartOnTable part(problem.part, X_RP, {table.radius, table.height});
  const scanner::AreaSampling sampling =
      scanner::sampleArea(part.part(), settings.sample_spacing, kMaxSamples);
  const scanner::SampleIndex index(sampling);

  AutoScanPlan plan;
  AutoScanReport& report = plan.report;
  report.samples = sampling.samples.size();
  report.sample_spacing = std::sqrt(sampling.area_per_sample);
  std::vector<Eigen::Isometry3d> witnesses;
  std::vector<scanner::SampleClass> classes = certify(part, pass_settings, sampling, witnesses);
  const std::vector<std::uint8_t> covered = givenCoverage(given, X_RP, part, pass_settings, index);
  const std::vector<scanner::ScanPass> passes =
      candidates(part, pass_settings, index, classes, witnesses, steps, report.aimed);
  report.candidates = passes.size();

  const scanner::TransferSphere sphere = transferSphere(problem, part.part());
  const std::vector<std::uint8_t> reach =
      reachable(problem, scene, sphere, passes, steps.step(Steps::kAimed, Steps::kReach));
  for (std::size_t p = 0; p < passes.size(); ++p)
    if (!reach[p]) report.unreachable.push_back(passes[p].label);
  markOutOfReach(classes, passes, reach);
  std::vector<std::uint8_t> counts(classes.size());
  for (std::size_t i = 0; i < classes.size(); ++i)
    counts[i] = classes[i] == scanner::SampleClass::kScannable ? 1 : 0;
  const Choosing choosing{problem, passes, counts, covered, reach, start};
  const scanner::CoverSettings cover = coverSettings(problem);
  const scanner::CoverResult chosen = choosing.select(cover, steps, report);
  steps.at(Steps::kCover);
  keepCertificate(sampling, X_RP, classes, report);
  if (chosen.chosen.empty()) {
    if (given.samples.empty())
      throw InputError(
          "scan.auto: no reachable pass sees the part: expected a part within the "
          "scanner's view and the arm's reach (see the map's limits)");
    report.seconds = since(start);
    return plan;
  }
  const auto measure = [&](const scanner::CoverResult& c, const scanner::CoverSettings& cv,
                           const Steps& st, AutoScanReport& r) {
    return measuredCut(problem, part, pass_settings, index, classes, covered, passes, c, cv, st, r);
  };
  MeasuredCut measured = measure(chosen, cover, steps, report);
  measureAgain(choosing, measure, steps, report, measured);
  addTour(problem, measured, given, sphere, plan);
  steps.at(1.0);
  report.seconds = since(start);
  return plan;
}

}  // namespace scanplan::pipeline
