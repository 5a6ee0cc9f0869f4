// report.json of `plan`: the plan's numbers, the planner's choice and why, the DP yardstick,
// validation, simulation, stage times and the cell's frames.
#include "cli/report/plan_report.h"

#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include <scanplan/kinematics/ptp_move.h>
#include <scanplan/kinematics/units.h>
#include "cli/io/json.h"
#include "cli/report/sensor_report.h"
#include "cli/report/verify_report.h"

namespace scanplan::cli {

namespace {

// A 4x4 homogeneous matrix, row by row; the translation in mm.
Json matrixMm(const Eigen::Isometry3d& X) {
  Json rows = Json::array();
  for (int r = 0; r < 4; ++r) {
    std::vector<double> row;
    for (int c = 0; c < 4; ++c) row.push_back(c == 3 && r < 3 ? toMm(X(r, c)) : X(r, c));
    rows.push_back(row);
  }
  return rows;
}

// The objective's terms, added to `json`.
void addTerms(Json& json, const planner::ObjectiveTerms& t) {
  json["J_s"] = t.total;
  json["cost_f_s"] = t.cost_f;
  json["cost_omega_s"] = t.cost_omega;
  json["cost_alpha_s"] = t.cost_alpha;
}

// A planner result's status as the report has always written it.
const char* resultStatus(const planner::PlanResult& r) { return r.solved() ? "solved" : "no_path"; }

Json plannerJson(const planner::ConfigMap& map, const pipeline::PathChoice& planning) {
  const planner::PlanResult& chosen = planning.chosen.result;
  Json json = {{"method", planning.chosen.method}, {"seconds", planning.chosen.seconds}};
  if (planning.solved()) json["branch"] = map.branches[chosen.branch].words();
  if (!chosen.detail.empty()) json["detail"] = chosen.detail;
  if (!planning.why_chosen.empty()) json["why_chosen"] = planning.why_chosen;
  return json;
}

Json refineJson(const planner::RefineResult& refine) {
  return {{"improved", refine.improved},       {"J_before_s", refine.before.total},
          {"J_after_s", refine.after.total},   {"seconds", refine.seconds},
          {"evaluations", refine.evaluations}, {"algorithm", refine.algorithm},
          {"stop_reason", refine.stop_reason}};
}

Json pathJson(const config::JobSpec& job,
              const planner::ConfigMap& map,
              const pipeline::PathChoice& planning,
              const planner::TrajectoryBuild* trajectory) {
  // The program's time: the trajectory's when there is one (with the moves between passes),
  // else the map's time axis.
  const double cycle =
      trajectory && !trajectory->trajectory.samples.empty()
          ? trajectory->trajectory.duration() - trajectory->trajectory.samples.front().t
          : map.times.back() - map.times.front();
  Json json = {{"samples", planning.theta.size()},
               {"cycle_time_s", cycle},
               {"map_min_f", planning.terms.min_f},
               {"map_min_f_time_s", map.times[planning.terms.min_f_sample]},
               {"max_abs_omega_deg_s", toDeg(planning.terms.max_abs_omega)},
               {"max_abs_alpha_deg_s2", toDeg(planning.terms.max_abs_alpha)},
               {"omega_max_deg_s", job.table.max_speed_deg_s},
               {"alpha_max_deg_s2", job.table.max_accel_deg_s2}};
  if (trajectory && trajectory->ok) {
    const auto& s = trajectory->trajectory.samples[trajectory->min_f_sample];
    json["min_f"] = trajectory->min_f;
    json["min_f_time_s"] = s.t;
    json["min_f_limit"] = s.limit;
    json["min_clearance_mm"] = toMm(trajectory->min_clearance);
  }
  return json;
}

Json dpJson(const pipeline::PathChoice& planning) {
  const planner::PlanResult& dp = *planning.dp;
  Json json = {{"status", resultStatus(dp)},
               {"angle_subdivisions", planning.dp_subdivisions},
               {"seconds", dp.seconds}};
  if (dp.solved()) json["J_s"] = dp.terms.total;
  if (const auto gap = planning.dpGap()) json["gap_percent"] = 100.0 * *gap;
  return json;
}

// The branches the chosen planner tried, and the planners it was compared with.
void addBranches(Json& json, const planner::ConfigMap& map, const pipeline::PathChoice& planning) {
  if (!planning.rejected.empty()) {
    Json rejected = Json::array();
    for (const auto& [b, why] : planning.rejected) {
      rejected.push_back({{"branch", map.branches[b].words()}, {"reason", why}});
    }
    json["rejected"] = std::move(rejected);
  }
  Json branches = Json::array();
  for (std::size_t b = 0; b < planning.chosen.branches.size(); ++b) {
    const planner::PlanResult& r = planning.chosen.branches[b];
    Json branch = {{"branch", map.branches[b].words()}, {"status", resultStatus(r)}};
    if (r.solved()) {
      branch["J_s"] = r.terms.total;
    } else {
      branch["reason"] = r.reason;
    }
    branches.push_back(std::move(branch));
  }
  json["branches"] = std::move(branches);
  if (planning.others.empty()) return;
  Json compare = Json::array();
  for (const pipeline::PlannerOutcome& o : planning.others) {
    Json other = {{"method", o.method}, {"status", resultStatus(o.result)}, {"seconds", o.seconds}};
    if (o.result.solved()) {
      addTerms(other, o.result.terms);
    } else {
      other["reason"] = o.result.reason;
    }
    compare.push_back(std::move(other));
  }
  json["compare"] = std::move(compare);
}

// The run's times, the map's size and the cell's frames.
void addSetup(Json& json,
              const config::JobSpec& job,
              const kinematics::CellModel& cell,
              const planner::ConfigMap& map,
              const pipeline::StageTimes& times) {
  json["times_s"] = {{"path", times.path},
                     {"map", times.map},
                     {"plan", times.plan},
                     {"trajectory", times.trajectory},
                     {"validation", times.validation},
                     {"simulation", times.simulation},
                     {"total", times.total}};
  json["map"] = {{"angles", map.angles.size()},
                 {"samples", map.times.size()},
                 {"angle_step_deg", job.map.angle_step_deg},
                 {"dt_s", job.scan.dt_s}};
  json["cell"] = {{"units", "4x4 homogeneous matrices, rotation unitless, translation in mm"},
                  {"X_WB", matrixMm(cell.X_WB)},
                  {"X_WA", matrixMm(cell.table.X_WA)},
                  {"X_RP", matrixMm(cell.part.X_RP)},
                  {"X_FS", matrixMm(cell.scanner.X_FS)}};
}

Json autoScanJson(const pipeline::AutoScanReport& r) {
  Json passes = Json::array();
  for (const auto& p : r.passes) {
    passes.push_back({{"kind", p.kind},
                      {"label", p.label},
                      {"start_s", p.start_time},
                      {"duration_s", p.duration},
                      {"gain", p.gain}});
  }
  return {
      {"candidates", r.candidates},
      {"aimed_candidates", r.aimed},
      {"unreachable_candidates", r.unreachable.size()},
      {"evaluation_samples", r.samples},
      {"sample_spacing_mm", toMm(r.sample_spacing)},
      {"planned_fraction", r.planned_fraction},
      {"given_fraction", r.given_fraction},
      {"stop", r.stop},
      {"scan_s", r.scan_time},
      {"transfer_estimate_s", r.transfer_time},
      {"cut",
       {{"scan_s", r.cut_time}, {"passes_left_out", r.cut_dropped}, {"passes_split", r.cut_split}}},
      {"pruned", {{"passes", r.pruned}, {"scan_s", r.pruned_time}}},
      {"covers_chosen_again", {{"tried", r.rechosen}, {"kept", r.rechosen_kept}}},
      {"measured_fraction", r.measured_fraction},
      {"seconds", r.seconds},
      {"set_cover",
       {{"greedy_s", r.greedy_cost},
        {"optimised_s", r.cover_cost},
        {"lower_bound_s", r.cover_bound},
        {"status", r.cover_status},
        {"seconds", r.cover_seconds}}},
      {"passes", passes}};
}

}  // namespace

std::string planReportJson(const config::JobSpec& job,
                           const kinematics::CellModel& cell,
                           const pipeline::ScanPlan& plan,
                           const pipeline::StageTimes& times,
                           const Json& extra) {
  const planner::ConfigMap& map = plan.prepared->map;
  const pipeline::PathChoice& planning = plan.choice;
  Json json;
  json["format"] = "scanplan plan report 1";
  json["job"] = job.name;
  json["job_hash"] = config::jobHash(job);
  json["status"] = std::string(pipeline::scanStatusName(plan.status));
  if (!plan.reason.empty()) json["reason"] = plan.reason;
  json["planner"] = plannerJson(map, planning);
  if (planning.solved()) {
    Json objective = Json::object();
    addTerms(objective, planning.terms);
    json["objective"] = std::move(objective);
    if (planning.refine) json["refine"] = refineJson(*planning.refine);
    json["path"] = pathJson(job, map, planning, plan.trajectory ? &*plan.trajectory : nullptr);
  }
  if (plan.trajectory) {
    Json dropped = Json::array();
    for (const auto& [segment, why] : plan.dropped)
      dropped.push_back({{"pass", segment + 1}, {"reason", why}});
    json["program"] = {{"total_s", plan.program.total},
                       {"scanning_s", plan.program.scanning},
                       {"moving_s", plan.program.moving},
                       {"moves", plan.program.moves},
                       {"backed_off_moves", plan.program.detours},
                       {"passes_table_held", plan.program.held},
                       {"table_held_J_s", plan.program.held_cost},
                       {"dropped_passes", dropped}};
    if (plan.program.moves > 0) {
      Json by_axis = Json::object();
      for (int j = 0; j < kinematics::kNumAxes; ++j)
        by_axis[j == 0 ? std::string("table") : "j" + std::to_string(j)] =
            plan.program.moving_by_axis(j);
      json["program"]["moves_set_by_axis_s"] = by_axis;
    }
  }
  if (!plan.coverage_curve.t.empty()) {
    const pipeline::CoverageCurve& c = plan.coverage_curve;
    Json curve = {{"t_s", c.t}, {"of_scannable", c.fraction}};
    for (const double share : {0.90, 0.95, 0.98}) {
      const auto t = c.timeTo(share);
      curve[fmt::format("time_to_{:.0f}_percent_s", 100.0 * share)] = t ? Json(*t) : Json();
    }
    json["coverage_curve"] = std::move(curve);
  }
  if (planning.dp) json["dp_baseline"] = dpJson(planning);
  addBranches(json, map, planning);
  if (plan.validation) json["validation"] = validationJson(*plan.validation);
  if (plan.validation && plan.validation->sensors && plan.prepared) {
    json["sensors"] = sensorsJson(*plan.prepared->scene, *plan.validation->sensors);
  }
  if (plan.simulation) json["simulation"] = simulationJson(*plan.simulation);
  if (plan.certificate) json["coverage"] = certificateJson(*plan.simulation, *plan.certificate);
  if (plan.prepared && plan.prepared->auto_scan)
    json["auto_scan"] = autoScanJson(*plan.prepared->auto_scan);
  addSetup(json, job, cell, map, times);
  if (extra.is_object())
    for (const auto& [key, value] : extra.items()) json[key] = value;
  return jsonDocument(json);
}

}  // namespace scanplan::cli
