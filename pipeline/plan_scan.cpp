#include "pipeline/plan_scan.h"

#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include "kinematics/error.h"
#include "kinematics/units.h"
#include "pipeline/auto_scan.h"
#include "pipeline/no_path.h"
#include "scanner/raycaster.h"

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

// The map scores each cell on its own; a path must also be followable continuously (joints such
// as J4 and J6 cannot wrap past their limits) and keep f > 0 between the grid angles.
std::string executable(const planner::TrajectoryBuild& build) {
  if (!build.ok) return build.reason;
  if (build.min_f > 0.0) return {};
  const auto& s = build.trajectory.samples[build.min_f_sample];
  return fmt::format(
      "time sample {} (t = {:.2f} s, table {:.2f} deg): f = 0 ({}) between the map's grid "
      "angles; a finer map.angle_step_deg resolves it",
      build.min_f_sample, s.t, toDeg(s.theta), s.limit);
}

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
  if (problem.simulation) {
    plan.simulation = simulateTrajectory(problem.cell, problem.part, problem.optics,
                                         *problem.simulation, trajectory);
    plan.times.simulation = plan.simulation->seconds;
    if (prepared.auto_scan && !prepared.auto_scan->classes.empty())
      plan.certificate =
          certify(plan.simulation->sampling, plan.simulation->area, *prepared.auto_scan);
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
}

// The hand-written elements (if any), then the automatic passes as one more element.
void autoPath(const ScanProblem& problem,
              const collision::Scene& scene,
              const scanner::Raycaster& raycaster,
              const ProgressFn& progress,
              ScanPathResult& out) {
  if (!problem.path.elements.empty())
    out.path = scanner::generatePath(problem.path, problem.part, raycaster, out.window);
  std::function<void(std::size_t, std::size_t)> auto_progress;
  if (progress)
    auto_progress = [&progress](std::size_t d, std::size_t n) { progress("auto", d, n); };
  AutoScanPlan plan = planAutoScan(problem, scene, out.path.path, auto_progress);
  out.auto_scan = std::move(plan.report);
  if (plan.element.samples.empty()) return;
  scanner::PathRequest request = problem.path;
  request.elements.push_back(std::move(plan.element));
  out.path = scanner::generatePath(request, problem.part, raycaster, out.window);
  out.path.elements.back().kind = "auto";
  out.path.elements.back().note = fmt::format("{} passes", out.auto_scan->passes.size());
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
  require(positive(p.map.angle_step), "map.angle_step",
          fmt::format("{}: expected an angle step > 0 rad", p.map.angle_step));
  const auto& names = planner::plannerNames();
  require(std::find(names.begin(), names.end(), p.planning.method) != names.end(),
          "planning.method", p.planning.method + ": expected ray, dp or ompl");
  require(positive(p.planning.objective.omega_max) && positive(p.planning.objective.alpha_max),
          "planning.objective", "table speed and acceleration bounds must be > 0");
  if (p.validation) {
    require(positive(p.validation->sample_dt), "validation.sample_dt", "expected > 0 s");
  }
  if (p.simulation) {
    require(positive(p.simulation->frame_rate_hz), "simulation.frame_rate_hz", "expected > 0");
  }
}

ScanPathResult scanPath(const ScanProblem& problem,
                        const collision::Scene& scene,
                        const ProgressFn& progress) {
  checkProblem(problem);
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
                                                const ProgressFn& progress) {
  checkProblem(problem);
  auto prepared = std::make_shared<PreparedScan>();
  auto t = Clock::now();
  prepared->window = scanner::laserWindow(problem.optics);
  prepared->scene = std::make_unique<collision::Scene>(problem.cell, problem.clearance);
  ScanPathResult path = scanPath(problem, *prepared->scene, progress);
  prepared->path = std::move(path.path);
  prepared->auto_scan = std::move(path.auto_scan);
  prepared->path_seconds = since(t);
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
  const auto accept = [&](std::size_t b, const std::vector<double>& theta) {
    const auto t = Clock::now();
    plan.trajectory = planner::buildTrajectory(*p.scene, problem.constraints, p.path.path, theta,
                                               p.map.branches[b]);
    plan.times.trajectory += since(t);
    return executable(*plan.trajectory);
  };
  // Joint wrap: the sheets of a branch whose path a joint could not follow within its limits.
  const auto wrap_sheets = [&](std::size_t b) -> std::shared_ptr<const planner::WrapSheets> {
    if (!plan.trajectory || plan.trajectory->wrap_joint < 0) return nullptr;
    return std::make_shared<const planner::WrapSheets>(
        p.scene->cell(), problem.constraints, p.path.path, p.map, b, plan.trajectory->wrap_joint);
  };
  const auto t = Clock::now();
  plan.choice = choosePath(p.map, problem.planning, options, accept, wrap_sheets);
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
