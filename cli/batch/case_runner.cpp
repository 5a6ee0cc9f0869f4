// One case of a batch: the map bundle its job needs (shared by the cases with the same map key)
// and the `plan` pipeline after the map, as a result row.
#include <cmath>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include <scanplan/collision/scene.h>
#include <scanplan/config/job.h>
#include <scanplan/kinematics/units.h>
#include "cli/batch/batch_internal.h"
#include "cli/commands/commands.h"

namespace scanplan::cli::detail {

std::unique_ptr<MapBundle> buildBundle(const config::JobSpec& job) {
  auto bundle = std::make_unique<MapBundle>(job);
  bundle->part = config::loadPart(job, bundle->cell).mesh;
  try {
    bundle->prepared = pipeline::prepareScan(config::toProblem(job, bundle->cell, bundle->part));
  } catch (const InputError& e) {
    throw InputError(job.source.string() + ": " + e.what());
  }
  bundle->map_seconds = bundle->prepared->map_seconds;
  return bundle;
}

// The settings that change the map: the job without its planner, validation, simulation and
// output sections, the scanner's measurement noise (simulation only; `seeds:` sets its seed), its
// image-mode camera and laser sheet (simulation only) and the name. Cases with the same key share
// one map.
std::string mapKey(const config::JobSpec& job) {
  config::JobSpec copy = job;
  copy.name.clear();
  copy.scanner.noise = config::NoiseSpec{};
  copy.scanner.camera = config::CameraSpec{};
  copy.scanner.laser = config::LaserSpec{};
  copy.planner = config::PlannerSpec{};
  copy.validation = config::ValidationSpec{};
  copy.simulation = config::SimulationSpec{};
  copy.outputs = config::OutputsSpec{};
  return job.source.string() + "#" + config::jobHash(copy);
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

namespace {

// The path choice's numbers: J and its terms, the DP gap, the table's motion.
void choiceMetrics(const pipeline::ScanPlan& plan, BatchRow& row) {
  auto& m = row.metrics;
  const pipeline::PathChoice& c = plan.choice;
  // The DP yardstick on the chosen branch (planner.dp_gap) is dp_s, not the planner's time. With
  // method dp the yardstick is the chosen result itself: nothing more ran.
  if (c.dp && row.method != "dp") m[kDpS] = plan.times.dp;
  m[kPlanS] = plan.times.plan - m[kDpS].value_or(0.0);
  if (const auto gap = c.dpGap()) m[kGap] = 100.0 * *gap;
  if (!c.solved()) return;
  m[kJ] = c.terms.total;
  m[kCostF] = c.terms.cost_f;
  m[kCostOmega] = c.terms.cost_omega;
  m[kCostAlpha] = c.terms.cost_alpha;
  m[kOmega] = toDeg(c.terms.max_abs_omega);
  m[kAlpha] = toDeg(c.terms.max_abs_alpha);
  const planner::ConfigMap& map = plan.prepared->map;
  m[kCycle] = map.times.back() - map.times.front();
}

}  // namespace

// The `plan` pipeline after the map (pipeline::planPrepared), without its files.
void planCase(const config::JobSpec& job, const MapBundle& bundle, BatchRow& row) {
  auto& m = row.metrics;
  m[kMapS] = bundle.map_seconds;
  const pipeline::ScanPlan plan =
      pipeline::planPrepared(config::toProblem(job, bundle.cell, bundle.part), bundle.prepared);
  row.method = plan.choice.chosen.method;
  choiceMetrics(plan, row);
  row.status = std::string(pipeline::scanStatusName(plan.status));
  row.reason = plan.reason;
  if (plan.trajectory) {
    m[kMinF] = plan.trajectory->min_f;
    const double clearance = plan.trajectory->min_clearance;
    if (std::isfinite(clearance)) m[kClearance] = toMm(clearance);
  }
  if (plan.validation) m[kValidationS] = plan.times.validation;
  if (plan.simulation) {
    m[kSimulationS] = plan.times.simulation;
    m[kCoverage] = plan.simulation->area.covered_fraction;
  }
}

}  // namespace scanplan::cli::detail
