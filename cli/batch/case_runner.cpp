// One case of a batch: the map bundle its job needs (shared by the cases with the same map key)
// and the `plan` pipeline after the map, as a result row.
#include <cmath>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli/batch/batch_internal.h"
#include "cli/commands/commands.h"
#include "cli/config/job.h"
#include "cli/planning.h"
#include "cli/verify.h"
#include "collision/scene.h"
#include "kinematics/units.h"
#include "planner/trajectory_builder.h"

namespace scanplan::cli::detail {

namespace {

std::vector<kinematics::IkBranch> mapBranches(const JobSpec& job) {
  if (job.map.branch != "auto") return {*parseBranch(job.map.branch)};
  std::vector<kinematics::IkBranch> all;
  for (int i = 0; i < 8; ++i) all.push_back(kinematics::IkBranch::fromIndex(i));
  return all;
}

}  // namespace

std::unique_ptr<MapBundle> buildBundle(const JobSpec& job) {
  auto bundle = std::make_unique<MapBundle>(job);
  bundle->context = buildPath(job, bundle->cell);
  bundle->scene = std::make_unique<collision::Scene>(bundle->cell, clearanceConfig(job));
  planner::MapRequest request;
  request.angle_step = deg(job.map.angle_step_deg);
  request.branches = mapBranches(job);
  request.memory_limit_bytes = static_cast<std::size_t>(job.map.memory_limit_mb * 1024.0 * 1024.0);
  const auto start = Clock::now();
  bundle->map = planner::buildConfigMap(*bundle->scene, constraintSettings(job),
                                        bundle->context.generated.path, request, {});
  bundle->map_seconds = since(start);
  return bundle;
}

// The settings that change the map: the job without its planner, validation, simulation and
// output sections, the scanner's measurement noise (simulation only; `seeds:` sets its seed) and
// the name. Cases with the same key share one map.
std::string mapKey(const JobSpec& job) {
  JobSpec copy = job;
  copy.name.clear();
  copy.scanner.noise = NoiseSpec{};
  copy.planner = PlannerSpec{};
  copy.validation = ValidationSpec{};
  copy.simulation = SimulationSpec{};
  copy.outputs = OutputsSpec{};
  return job.source.string() + "#" + jobHash(copy);
}

BatchRow rowFor(const SweepCase& c) {
  BatchRow row;
  row.index = c.index;
  row.case_id = c.id;
  row.job = c.job;
  row.params = c.params;
  row.seed = c.seed;
  row.repeat = c.repeat;
  return row;
}

// The `plan` pipeline after the map (cli/commands/plan.cpp), without its files.
void planCase(const JobSpec& job, const MapBundle& bundle, BatchRow& row) {
  using Status = planner::PlanResult::Status;
  auto& m = row.metrics;
  m[kMapS] = bundle.map_seconds;
  const planner::ConfigMap& map = bundle.map;
  const kinematics::ScanPath& path = bundle.context.generated.path;
  double trajectory_s = 0.0;
  std::optional<planner::TrajectoryBuild> candidate;
  // As in `plan`: a path is accepted only when the arm can follow it with f > 0 throughout.
  const auto check = [&](std::size_t b, const std::vector<double>& theta) -> std::string {
    const auto t = Clock::now();
    candidate = planner::buildTrajectory(*bundle.scene, constraintSettings(job), path, theta,
                                         map.branches[b]);
    trajectory_s += since(t);
    if (!candidate->ok) return candidate->reason;
    if (!(candidate->min_f > 0.0)) return "f = 0 between the map's grid angles";
    return {};
  };
  const auto t0 = Clock::now();
  const PlanningOutcome planning = planJob(map, job, job.planner.method, false, false, check);
  const double planning_s = since(t0) - trajectory_s;
  row.method = planning.chosen.method;
  // planJob also ran the DP yardstick on the chosen branch (planner.dp_gap): its time is dp_s,
  // not the planner's. With method dp the yardstick is the chosen result itself: nothing more ran.
  if (planning.dp && row.method != "dp") m[kDpS] = planning.dp->seconds;
  m[kPlanS] = planning_s - m[kDpS].value_or(0.0);
  if (planning.dp && planning.dp->status == Status::kSolved) {
    if (const auto gap = planning.dpGap()) m[kGap] = 100.0 * *gap;
  }
  if (!planning.solved()) {
    row.status = planning.rejected.empty() ? "no_path" : "no_executable_path";
    row.reason = planning.chosen.result.reason;
    return;
  }
  const planner::ObjectiveTerms& t = planning.terms;
  m[kJ] = t.total;
  m[kCostF] = t.cost_f;
  m[kCostOmega] = t.cost_omega;
  m[kCostAlpha] = t.cost_alpha;
  m[kOmega] = toDeg(t.max_abs_omega);
  m[kAlpha] = toDeg(t.max_abs_alpha);
  m[kCycle] = map.times.back() - map.times.front();
  const planner::TrajectoryBuild& trajectory = *candidate;  // the accepted branch's
  m[kMinF] = trajectory.min_f;
  if (std::isfinite(trajectory.min_clearance)) m[kClearance] = toMm(trajectory.min_clearance);
  if (job.validation.enabled) {
    const auto tv = Clock::now();
    const planner::ValidationReport validation =
        planner::validateTrajectory(*bundle.scene, trajectory.trajectory, validationSettings(job));
    m[kValidationS] = since(tv);
    if (!validation.valid) {
      row.status = "invalid_trajectory";
      row.reason = fmt::format("validation found {} violation(s)", validation.violations.size());
      return;
    }
  }
  if (job.simulation.enabled) {
    const auto ts = Clock::now();
    const SimulationRun simulation =
        simulateTrajectory(job, bundle.cell, bundle.context.part.mesh, trajectory.trajectory);
    m[kSimulationS] = since(ts);
    m[kCoverage] = simulation.coverage.covered_fraction;
  }
  row.status = "planned";
}

}  // namespace scanplan::cli::detail
