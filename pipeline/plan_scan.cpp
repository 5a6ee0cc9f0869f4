#include <scanplan/pipeline/plan_scan.h>

#include <atomic>
#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/pipeline/auto_scan.h>
#include <scanplan/pipeline/no_path.h>
#include <scanplan/pipeline/segment_plan.h>
#include <scanplan/scanner/raycaster.h>

namespace scanplan::pipeline {

namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void require(bool ok, const std::string& field, const std::string& what) {
  if (!ok) throw InputError("problem: " + field + ": " + what);
}

bool positive(double v) { return std::isfinite(v) && v > 0.0; }

// Validation and simulation of the accepted trajectory.
void proveAndSimulate(const ScanProblem& problem, const PreparedScan& prepared, ScanPlan& plan) {
  const kinematics::Trajectory& trajectory = plan.trajectory->trajectory;
  if (problem.validation) {
    const auto t = Clock::now();
    plan.validation = planner::validateTrajectory(*prepared.scene, trajectory, *problem.validation);
    plan.times.validation = since(t);
    if (!plan.validation->valid) {
      plan.status = ScanStatus::kInvalidTrajectory;
      plan.reason =
          fmt::format("validation found {} violation(s)", plan.validation->violations.size());
      return;
    }
  }
  pollCancel(problem.planning.termination.cancel);
  if (problem.simulation) {
    plan.simulation =
        simulateTrajectory(problem.cell, problem.part, problem.optics, *problem.simulation,
                           trajectory, problem.planning.termination.cancel);
    plan.times.simulation = plan.simulation->seconds;
    if (prepared.auto_scan && !prepared.auto_scan->classes.empty()) {
      plan.certificate =
          certify(plan.simulation->sampling, plan.simulation->area, *prepared.auto_scan);
      plan.coverage_curve = coverageCurve(*plan.certificate, plan.simulation->area);
    }
  }
  plan.status = ScanStatus::kPlanned;
}

// The automatic scan's settings, named as the problem's fields.
void checkAutoScan(const AutoScanSettings& a) {
  require(positive(a.max_incidence) && a.max_incidence < deg(90.0), "auto_scan.max_incidence",
          fmt::format("{} rad: expected an angle in (0, 90) deg", a.max_incidence));
  require(std::isfinite(a.point_spacing) && a.point_spacing >= 0.0, "auto_scan.point_spacing",
          fmt::format("{} m: expected 0 (from the optics) or a spacing > 0", a.point_spacing));
  require(positive(a.target_coverage) && a.target_coverage <= 1.0, "auto_scan.target_coverage",
          fmt::format("{}: expected a fraction in (0, 1]", a.target_coverage));
  require(a.max_passes >= 1, "auto_scan.max_passes", "0: expected at least 1");
  require(positive(a.time_budget), "auto_scan.time_budget", "expected > 0 s");
  require(positive(a.sample_spacing), "auto_scan.sample_spacing", "expected > 0 m");
  require(std::isfinite(a.max_program) && a.max_program >= 0.0, "auto_scan.max_program",
          fmt::format("{} s: expected 0 (no limit) or a time > 0 s", a.max_program));
}

// Appends a pass (part-frame keys, times from 0) to `path` as a segment of its own, sampled every
// path.dt: n steps over its duration rounded up to whole steps (a little slower, never faster),
// the first sample one step after the path's last. Its own duration is kept beside the path:
// the program runs it in that time where the axes allow.
void appendSegment(kinematics::ScanPath& path, const scanner::FileSpec& pass) {
  const auto& keys = pass.samples;
  const double duration = keys.back().t - keys.front().t;
  const auto n = static_cast<std::size_t>(std::max(1.0, std::ceil(duration / path.dt - 1e-9)));
  const double t0 = path.samples.empty() ? 0.0 : path.samples.back().t + path.dt;
  if (!path.samples.empty()) path.breaks.push_back(path.samples.size());
  path.own_durations.push_back(duration);
  std::size_t k = 0;
  for (std::size_t i = 0; i <= n; ++i) {
    const double t = duration * static_cast<double>(i) / static_cast<double>(n);
    while (k + 2 < keys.size() && keys[k + 1].t - keys.front().t < t) ++k;
    const auto& a = keys[k];
    const auto& b = keys[std::min(k + 1, keys.size() - 1)];
    const double span = b.t - a.t;
    const double u = span > 0.0 ? std::clamp((t - (a.t - keys.front().t)) / span, 0.0, 1.0) : 0.0;
    path.samples.push_back({t0 + path.dt * static_cast<double>(i),
                            kinematics::interpolatePose(a.X_PS, b.X_PS, u), true});
  }
}

// The hand-written elements (if any), then the automatic passes, each a segment of the path.
void autoPath(const ScanProblem& problem,
              const collision::Scene& scene,
              const scanner::Raycaster& raycaster,
              const ProgressFn& progress,
              ScanPathResult& out) {
  if (!problem.path.elements.empty())
    out.path = scanner::generatePath(problem.path, problem.part, raycaster, out.window);
  out.path.path.dt = problem.path.dt;
  std::function<void(std::size_t, std::size_t)> auto_progress;
  if (progress)
    auto_progress = [&progress](std::size_t d, std::size_t n) { progress("auto", d, n); };
  AutoScanPlan plan = planAutoScan(problem, scene, out.path.path, auto_progress);
  out.auto_scan = std::move(plan.report);
  if (plan.passes.empty()) return;
  kinematics::ScanPath& path = out.path.path;
  const double start = path.samples.empty() ? 0.0 : path.samples.back().t + path.dt;
  path.own_durations.clear();  // the hand-written path's segments run at their samples' times
  for (const auto& [begin, end] : kinematics::segmentRanges(path))
    path.own_durations.push_back(path.samples[end - 1].t - path.samples[begin].t);
  double samples = static_cast<double>(path.samples.size());
  for (const scanner::FileSpec& pass : plan.passes)
    samples += std::ceil((pass.samples.back().t - pass.samples.front().t) / path.dt) + 1.0;
  if (!(samples <= static_cast<double>(scanner::kMaxPathSamples)))
    throw InputError(fmt::format(
        "scan.auto: the passes take {:.0f} samples every {} s: expected at most {} (the passes "
        "move at scan.auto.point_spacing_mm times the frame rate: raise it or scan.dt_s, or "
        "lower scan.auto.target_coverage)",
        samples, path.dt, scanner::kMaxPathSamples));
  for (std::size_t i = 0; i < plan.passes.size(); ++i) {
    const double begin = path.samples.empty() ? 0.0 : path.samples.back().t + path.dt;
    appendSegment(path, plan.passes[i]);
    out.auto_scan->passes[i].start_time = begin;
  }
  scanner::ElementReport report;
  report.kind = "auto";
  report.start_time = start;
  report.duration = path.samples.back().t - start;
  double own = 0.0;
  for (const scanner::FileSpec& pass : plan.passes)
    own += pass.samples.back().t - pass.samples.front().t;
  report.note = fmt::format(
      "{} passes, {:.1f} s of scanning at their own speed (the path's samples stand whole "
      "steps apart; the moves between the passes come after planning)",
      plan.passes.size(), own);
  out.path.elements.push_back(report);
}

}  // namespace

std::vector<kinematics::IkBranch> mapBranches(const MapSettings& settings) {
  if (!settings.branches.empty()) return settings.branches;
  std::vector<kinematics::IkBranch> all;
  for (int i = 0; i < 8; ++i) all.push_back(kinematics::IkBranch::fromIndex(i));
  return all;
}

planner::MapRequest mapRequest(const MapSettings& settings) {
  planner::MapRequest request;
  request.angle_step = settings.angle_step;
  request.branches = mapBranches(settings);
  request.memory_limit_bytes = settings.memory_limit_bytes;
  return request;
}

void checkProblem(const ScanProblem& p) {
  require(!p.part.triangles.empty(), "part", "no triangles: expected a part mesh");
  require(!p.path.elements.empty() || p.auto_scan, "path.elements",
          "empty: expected at least one path element (ring, raster, waypoints or file) or "
          "auto_scan");
  if (p.auto_scan) checkAutoScan(*p.auto_scan);
  require(positive(p.path.dt), "path.dt", fmt::format("{}: expected a time step > 0 s", p.path.dt));
  require(positive(p.map.angle_step) && p.map.angle_step <= deg(90.0), "map.angle_step",
          fmt::format("{}: expected an angle step in (0, pi/2] rad", p.map.angle_step));
  const auto& names = planner::plannerNames();
  require(std::find(names.begin(), names.end(), p.planning.method) != names.end(),
          "planning.method", p.planning.method + ": expected ray, dp or ompl");
  require(positive(p.planning.objective.omega_max) && positive(p.planning.objective.alpha_max),
          "planning.objective", "table speed and acceleration bounds must be > 0");
  for (const auto& [name, k] :
       {std::pair{"planning.objective.k_omega", p.planning.objective.k_omega},
        std::pair{"planning.objective.k_alpha", p.planning.objective.k_alpha}})
    require(std::isfinite(k) && k >= 0.0, name, fmt::format("{}: expected a weight >= 0", k));
  const planner::RayShootingSettings& ray = p.planning.planners.ray;
  require(ray.horizon >= 1 && ray.horizon <= 1000, "planning.planners.ray.horizon",
          fmt::format("{}: expected 1 to 1000 samples", ray.horizon));
  require(ray.rays >= 1 && ray.starts >= 1, "planning.planners.ray",
          fmt::format("{} rays, {} starts: expected at least 1 of each", ray.rays, ray.starts));
  const double limit = p.planning.termination.time_limit_s;
  require(std::isfinite(limit) && limit >= 0.0, "planning.termination.time_limit_s",
          fmt::format("{}: expected a time >= 0 s (0: no limit)", limit));
  if (p.validation) {
    require(positive(p.validation->sample_dt), "validation.sample_dt", "expected > 0 s");
  }
  if (p.simulation) {
    require(positive(p.simulation->frame_rate_hz), "simulation.frame_rate_hz", "expected > 0");
  }
}

namespace {

void throwIfCancelled(const ScanProblem& problem) {
  pollCancel(problem.planning.termination.cancel);
}

// `progress` that first polls the problem's cancel flag (throws Cancelled once it is set).
ProgressFn polling(const ScanProblem& problem, const ProgressFn& progress) {
  const std::atomic<bool>* cancel = problem.planning.termination.cancel;
  if (cancel == nullptr) return progress;
  return [cancel, progress](std::string_view stage, std::size_t done, std::size_t total) {
    pollCancel(cancel);
    if (progress) progress(stage, done, total);
  };
}

}  // namespace

ScanPathResult scanPath(const ScanProblem& problem,
                        const collision::Scene& scene,
                        const ProgressFn& report) {
  checkProblem(problem);
  throwIfCancelled(problem);
  const ProgressFn progress = polling(problem, report);
  ScanPathResult out;
  out.window = scanner::laserWindow(problem.optics);
  const scanner::Raycaster raycaster(problem.part);
  if (problem.auto_scan) {
    autoPath(problem, scene, raycaster, progress, out);
  } else {
    out.path = scanner::generatePath(problem.path, problem.part, raycaster, out.window);
  }
  return out;
}

std::shared_ptr<const PreparedScan> prepareScan(const ScanProblem& problem,
                                                const ProgressFn& report) {
  checkProblem(problem);
  const ProgressFn progress = polling(problem, report);
  auto prepared = std::make_shared<PreparedScan>();
  auto t = Clock::now();
  prepared->window = scanner::laserWindow(problem.optics);
  prepared->scene = std::make_unique<collision::Scene>(problem.cell, problem.clearance);
  ScanPathResult path = scanPath(problem, *prepared->scene, progress);
  prepared->path = std::move(path.path);
  prepared->auto_scan = std::move(path.auto_scan);
  prepared->path_seconds = since(t);
  throwIfCancelled(problem);
  const planner::MapRequest request = mapRequest(problem.map);
  t = Clock::now();
  planner::ProgressFn map_progress;
  if (progress) map_progress = [&progress](std::size_t d, std::size_t n) { progress("map", d, n); };
  prepared->map = planner::buildConfigMap(*prepared->scene, problem.constraints,
                                          prepared->path.path, request, map_progress);
  prepared->map_seconds = since(t);
  return prepared;
}

namespace {

// No path on any branch: per branch, why — a closed map explained (the time span, the constraint,
// the body pair or joint, what to change), else the planner's own reason.
std::string noPathReason(const ScanProblem& problem,
                         const PreparedScan& p,
                         const PlannerOutcome& outcome) {
  std::string text = outcome.method + " found no path on any branch:";
  for (std::size_t b = 0; b < p.map.branches.size(); ++b) {
    if (b >= outcome.branches.size()) break;
    std::string why = explainBlockedBranch(*p.scene, problem.constraints, p.path, p.map, b);
    if (why.empty()) why = outcome.branches[b].reason;
    if (why.empty()) continue;  // not planned (a fixed map.branch)
    text += fmt::format("\n  {}: {}", p.map.branches[b].words(), why);
  }
  return text;
}

}  // namespace

ScanPlan planPrepared(const ScanProblem& problem,
                      std::shared_ptr<const PreparedScan> prepared,
                      const PlanOptions& options) {
  ScanPlan plan;
  plan.prepared = std::move(prepared);
  const PreparedScan& p = *plan.prepared;
  plan.times.path = p.path_seconds;
  plan.times.map = p.map_seconds;
  throwIfCancelled(problem);
  if (!p.path.path.breaks.empty()) {
    planSegments(problem, options, plan);
    throwIfCancelled(problem);
    if (plan.trajectory) proveAndSimulate(problem, p, plan);
    return plan;
  }
  const auto accept = [&](std::size_t b, const std::vector<double>& theta) {
    const auto t = Clock::now();
    plan.trajectory = planner::buildTrajectory(*p.scene, problem.constraints, p.path.path, theta,
                                               p.map.branches[b]);
    plan.times.trajectory += since(t);
    return executableReason(*plan.trajectory);
  };
  // Joint wrap: the sheets of a branch whose path a joint could not follow within its limits.
  const auto wrap_sheets = [&](std::size_t b) -> std::shared_ptr<const planner::WrapSheets> {
    if (!plan.trajectory || plan.trajectory->wrap_joint < 0) return nullptr;
    return std::make_shared<const planner::WrapSheets>(
        p.scene->cell(), problem.constraints, p.path.path, p.map, b, plan.trajectory->wrap_joint);
  };
  const auto t = Clock::now();
  plan.choice = choosePath(p.map, problem.planning, options, accept, wrap_sheets);
  throwIfCancelled(problem);
  plan.times.plan = since(t) - plan.times.trajectory;
  if (plan.choice.dp && plan.choice.chosen.method != "dp") plan.times.dp = plan.choice.dp->seconds;
  if (!plan.choice.solved()) {
    plan.status =
        plan.choice.rejected.empty() ? ScanStatus::kNoPath : ScanStatus::kNoExecutablePath;
    plan.reason = plan.status == ScanStatus::kNoPath ? noPathReason(problem, p, plan.choice.chosen)
                                                     : plan.choice.chosen.result.reason;
    plan.trajectory.reset();
    return plan;
  }
  plan.program = programTimes(plan.trajectory->trajectory);
  proveAndSimulate(problem, p, plan);
  return plan;
}

ScanPlan planScan(const ScanProblem& problem,
                  const PlanOptions& options,
                  const ProgressFn& progress) {
  const auto start = Clock::now();
  ScanPlan plan = planPrepared(problem, prepareScan(problem, progress), options);
  plan.times.total = since(start);
  return plan;
}

}  // namespace scanplan::pipeline
