#include "pipeline/auto_scan.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <cstdlib>

#include <fmt/format.h>

#include "collision/clearance.h"
#include "kinematics/error.h"
#include "kinematics/units.h"
#include "planner/config_map.h"
#include "scanner/pass_selection.h"
#include "scanner/scan_passes.h"
#include "scanner/simulator.h"

namespace scanplan::pipeline {

namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

int raysPerProfile(const ScanProblem& p) {
  return p.simulation ? p.simulation->scanner.rays_per_profile : 200;
}

scanner::PassSettings passSettings(const ScanProblem& p) {
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
  return s;
}

// Can the arm follow `pass` (R frame) with the table at one angle (strips) or turning with the
// head (spins) on one IK branch, f > 0 at 60 poses evenly in time along it? Table angles every 10°.
class ReachCheck {
 public:
  ReachCheck(const ScanProblem& problem, const collision::Scene& scene)
      : problem_(problem), scene_(scene), evaluator_(scene),
        branches_(mapBranches(problem.map)),
        angles_(planner::mapAngles(problem.cell.table, deg(10.0))) {}

  bool operator()(const scanner::ScanPass& pass) {
    const kinematics::CellModel& cell = problem_.cell;
    const Eigen::Isometry3d X_PR = cell.part.X_RP.inverse();
    const std::vector<Timed> poses = timedPoses(pass);
    for (const double theta0 : angles_) {
      std::vector<bool> alive(branches_.size(), true);
      bool any = true;
      for (std::size_t k = 0; k < poses.size() && any; ++k) {
        const double theta = theta0 - poses[k].turn;
        const auto solutions = cell.robot.ik(cell.flangeTarget(theta, X_PR * poses[k].X_RS));
        any = false;
        for (std::size_t b = 0; b < branches_.size(); ++b) {
          if (!alive[b]) continue;
          alive[b] = planner::scoreCell(scene_, problem_.constraints, evaluator_, solutions,
                                        branches_[b], theta, false)
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
  // 60 poses evenly in time along the pass, between its keys as the path will interpolate them.
  static std::vector<Timed> timedPoses(const scanner::ScanPass& pass) {
    constexpr int kPoses = 60;
    std::vector<Timed> out;
    std::size_t k = 0;
    for (int i = 0; i < kPoses; ++i) {
      const double t = pass.t.front() + pass.duration() * i / (kPoses - 1);
      while (k + 2 < pass.t.size() && pass.t[k + 1] < t) ++k;
      const double span = pass.t[k + 1] - pass.t[k];
      const double s = span > 0.0 ? std::clamp((t - pass.t[k]) / span, 0.0, 1.0) : 0.0;
      Timed pose{kinematics::interpolatePose(pass.X_RS[k], pass.X_RS[k + 1], s), 0.0};
      if (pass.kind == scanner::PassKind::kSpin)
        pose.turn = pass.azimuth[k] + s * (pass.azimuth[k + 1] - pass.azimuth[k]) - pass.azimuth.front();
      out.push_back(pose);
    }
    return out;
  }

  const ScanProblem& problem_;
  const collision::Scene& scene_;
  collision::ClearanceEvaluator evaluator_;
  std::vector<kinematics::IkBranch> branches_;
  std::vector<double> angles_;
};

// The scanning stretches of the hand-written path as passes (R frame).
std::vector<scanner::ScanPass> givenPasses(const kinematics::ScanPath& given, const Eigen::Isometry3d& X_RP) {
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
scanner::TransferSphere transferSphere(const ScanProblem& p, const kinematics::TriangleMesh& part_R) {
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

// Appends `keys` (R frame, times from 0) to the element after `offset` s, skipping the first.
void append(scanner::FileSpec& out,
            const std::vector<Eigen::Isometry3d>& X_RS,
            const std::vector<double>& t,
            bool scanning,
            const Eigen::Isometry3d& X_PR) {
  const double offset = out.samples.empty() ? 0.0 : out.samples.back().t;
  for (std::size_t k = out.samples.empty() ? 0 : 1; k < X_RS.size(); ++k)
    out.samples.push_back({offset + t[k] - t.front(), X_PR * X_RS[k], scanning && k > 0});
}

}  // namespace

double autoPointSpacing(const AutoScanSettings& settings,
                        const scanner::LaserOptics& optics,
                        int rays_per_profile) {
  if (settings.point_spacing > 0.0) return settings.point_spacing;
  const scanner::LaserWindow w = scanner::laserWindow(optics);
  return 2.0 * w.halfWidth(0.5 * (w.z_min + w.z_max)) / std::max(1, rays_per_profile - 1);
}

AutoScanPlan planAutoScan(const ScanProblem& problem,
                          const collision::Scene& scene,
                          const kinematics::ScanPath& given,
                          const std::function<void(std::size_t, std::size_t)>& progress) {
  const auto start = Clock::now();
  const AutoScanSettings& settings = *problem.auto_scan;
  const scanner::PassSettings pass_settings = passSettings(problem);
  const kinematics::RotaryTableModel& table = problem.cell.table;
  const scanner::PartOnTable part(problem.part, problem.cell.part.X_RP, {table.radius, table.height});
  const scanner::AreaSampling sampling = scanner::sampleArea(part.part(), settings.sample_spacing, 400'000);
  const scanner::SampleIndex index(sampling);

  AutoScanPlan plan;
  AutoScanReport& report = plan.report;
  report.samples = sampling.samples.size();
  report.sample_spacing = std::sqrt(sampling.area_per_sample);
  std::vector<std::uint8_t> counts = scanner::facesTable(sampling, Eigen::Isometry3d::Identity(),
                                                         settings.max_incidence, pass_settings.window.z_max);
  for (auto& c : counts) c = c ? 0 : 1;

  std::vector<scanner::ScanPass> passes = givenPasses(given, problem.cell.part.X_RP);
  const std::size_t given_count = passes.size();
  std::vector<scanner::ScanPass> candidates = scanner::candidatePasses(part, pass_settings);
  passes.insert(passes.end(), std::make_move_iterator(candidates.begin()),
                std::make_move_iterator(candidates.end()));
  scanner::evaluatePasses(passes, part, pass_settings, index, progress);
  report.candidates = passes.size() - given_count;

  std::vector<std::uint8_t> covered(sampling.samples.size(), 0);
  for (std::size_t p = 0; p < given_count; ++p)
    for (std::uint32_t i : passes[p].covers) covered[i] = 1;
  std::vector<scanner::ScanPass> auto_passes(passes.begin() + static_cast<std::ptrdiff_t>(given_count), passes.end());

  ReachCheck reach(problem, scene);
  if (std::getenv("SCANPLAN_DEBUG_AUTO")) {
    std::vector<std::uint8_t> any(counts.size(), 0), reachable(counts.size(), 0);
    std::size_t nr = 0;
    for (auto& p : auto_passes) {
      for (auto i : p.covers) any[i] = 1;
      const bool ok = reach(p);
      nr += ok;
      if (ok) for (auto i : p.covers) reachable[i] = 1;
      else fmt::print("unreachable: {}\n", p.label);
    }
    std::size_t a = 0, r = 0, c = 0;
    for (std::size_t i = 0; i < counts.size(); ++i) { c += counts[i]; a += counts[i] && any[i]; r += counts[i] && reachable[i]; }
    if (FILE* f = std::fopen("/tmp/uncovered.xyz", "w")) {
      for (std::size_t i = 0; i < counts.size(); ++i)
        if (counts[i] && !any[i]) { const auto& q = sampling.samples[i]; std::fprintf(f, "%g %g %g %g %g %g\n", q.p.x(), q.p.y(), q.p.z(), q.n.x(), q.n.y(), q.n.z()); }
      std::fclose(f);
    }
    fmt::print("DEBUG counted {} any {} reachable {} ({} reachable passes)\n", c, double(a)/c, double(r)/c, nr);
  }
  scanner::CoverSettings cover;
  cover.target = settings.target_coverage;
  cover.max_passes = settings.max_passes;
  const scanner::CoverResult chosen = scanner::greedyCover(
      auto_passes, counts, covered, cover,
      [&](std::size_t p) { return reach(auto_passes[p]); },
      [&] { return since(start) < settings.time_budget; });
  report.counted = chosen.counted;
  report.stop = chosen.stop;
  for (std::size_t p : chosen.rejected) report.unreachable.push_back(auto_passes[p].label);
  const double counted = std::max<double>(1.0, static_cast<double>(chosen.counted));
  report.planned_fraction = static_cast<double>(chosen.covered_counted) / counted;
  std::size_t given_covered = 0;
  for (std::size_t i = 0; i < counts.size(); ++i) given_covered += (counts[i] && covered[i]) ? 1u : 0u;
  report.given_fraction = static_cast<double>(given_covered) / counted;
  if (chosen.chosen.empty()) {
    if (given_count == 0)
      throw InputError("scan.auto: no reachable pass sees the part: expected a part within the "
                       "scanner's view and the arm's reach (see the map's limits)");
    report.seconds = since(start);
    return plan;
  }

  const scanner::TransferSphere sphere = transferSphere(problem, part.part());
  std::optional<Eigen::Isometry3d> at;
  if (!given.samples.empty()) at = problem.cell.part.X_RP * given.samples.back().X_PS;
  const std::vector<scanner::TourStep> tour = scanner::orderPasses(auto_passes, chosen.chosen, at, sphere);
  report.transfer_time = scanner::tourTransferTime(auto_passes, tour, at, sphere);

  // The gain of each pass in the order chosen (the tour reorders them).
  std::vector<double> gain(auto_passes.size(), 0.0);
  {
    std::vector<std::uint8_t> seen = covered;
    for (std::size_t p : chosen.chosen) {
      std::size_t n = 0;
      for (std::uint32_t i : auto_passes[p].covers) {
        if (counts[i] && !seen[i]) ++n;
        seen[i] = 1;
      }
      gain[p] = static_cast<double>(n) / counted;
    }
  }
  const Eigen::Isometry3d X_PR = problem.cell.part.X_RP.inverse();
  for (const scanner::TourStep& step : tour) {
    const scanner::ScanPass pass = scanner::stepPass(auto_passes, step);
    if (at) {
      const scanner::Move move = scanner::transferMove(*at, pass.X_RS.front(), sphere);
      if (plan.element.samples.empty()) plan.element.samples.push_back({0.0, X_PR * *at, false});
      append(plan.element, move.X_RS, move.t, false, X_PR);
    }
    const double begin = plan.element.samples.empty() ? 0.0 : plan.element.samples.back().t;
    append(plan.element, pass.X_RS, pass.t, true, X_PR);
    report.passes.push_back({scanner::passKindName(pass.kind), pass.label, begin, pass.duration(),
                             gain[step.pass]});
    report.scan_time += pass.duration();
    at = pass.X_RS.back();
  }
  if (const char* tt = std::getenv("SCANPLAN_DEBUG_T")) {
    const double want = std::atof(tt);
    fmt::print("element {} samples, {} .. {}\n", plan.element.samples.size(), plan.element.samples.front().t, plan.element.samples.back().t);
    collision::ClearanceEvaluator ev(scene);
    for (const auto& smp : plan.element.samples) {
      if (std::abs(smp.t - want) > 0.5) continue;
      fmt::print("sample at {}\n", smp.t);
      std::string line = fmt::format("t {:.2f}:", smp.t);
      for (double th = 0; th < 360; th += 10) {
        const auto sol = problem.cell.robot.ik(problem.cell.flangeTarget(deg(th), smp.X_PS));
        float best = 0;
        for (const auto& b : mapBranches(problem.map)) best = std::max(best, planner::scoreCell(scene, problem.constraints, ev, sol, b, deg(th), false).f);
        line += fmt::format(" {:.2f}", best);
      }
      fmt::print("{}\n", line);
    }
  }
  report.seconds = since(start);
  return plan;
}

}  // namespace scanplan::pipeline
