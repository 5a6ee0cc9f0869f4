// `scanplan plan`: the job from part to plan — scan path, configuration maps, the table-angle
// path (DESIGN.md §5), the 7-DOF trajectory, and the report.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <optional>

#include <fmt/format.h>

#include "cli/commands/commands.h"
#include "cli/io/output.h"
#include "cli/plot/image_io.h"
#include "cli/planning.h"
#include "cli/verify.h"
#include "collision/scene.h"
#include "kinematics/error.h"
#include "kinematics/units.h"
#include "planner/trajectory_builder.h"

namespace scanplan::cli {

namespace {

using Clock = std::chrono::steady_clock;
using Status = planner::PlanResult::Status;

double since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

Rgb methodColour(const std::string& method) {
  if (method == "dp") return categoryColour(4);    // blue
  if (method == "ompl") return categoryColour(2);  // bluish green
  return categoryColour(5);                        // vermillion: ray
}

// The map of the chosen branch with each planner's path over it (Fig. 6 style).
void writePathFigure(const std::filesystem::path& dir,
                     const planner::ConfigMap& map,
                     std::size_t branch,
                     const std::vector<std::pair<std::string, std::vector<double>>>& paths,
                     const std::vector<std::string>& labels) {
  const double angle0 = map.angles.front();
  const double span = map.angles.size() > 1
                          ? (map.angles[1] - map.angles[0]) * static_cast<double>(map.angles.size())
                          : 1.0;
  const double nt = static_cast<double>(map.times.size());
  const double t0 = map.times.front(), t_span = map.times.back() - t0;
  constexpr double kBreak = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::pair<Rgb, std::string>> legend;
  std::vector<Overlay> lines;
  // Drawn in reverse so the chosen planner (first) ends on top.
  for (auto it = paths.rbegin(); it != paths.rend(); ++it) {
    const auto& [method, theta] = *it;
    Overlay& line = lines.emplace_back();
    line.colour = methodColour(method);
    line.width_px = it == paths.rend() - 1 ? 3.0 : 2.0;
    double last_u = 0.0;
    for (std::size_t k = 0; k < theta.size(); ++k) {
      double u = (theta[k] - angle0) / span;  // 0..1 over the grid, wrapped for a full turn
      u -= std::floor(u);
      // A jump across the grid's seam breaks the line.
      if (k > 0 && std::abs(u - last_u) > 0.5) line.points.emplace_back(kBreak, kBreak);
      last_u = u;
      line.points.emplace_back(t0 + (static_cast<double>(k) + 0.5) / nt * t_span,
                               toDeg(angle0 + u * span));
    }
    legend.insert(legend.begin(),
                  {line.colour, labels[static_cast<std::size_t>(paths.rend() - it - 1)]});
  }
  writeFigure(dir, "configmap_path", mapGreyImage(map, branch), map,
              "Table-angle path over the map f, " + map.branches[branch].words(), legend,
              std::move(lines));
}

void writeMatrixMm(JsonWriter& json, const std::string& key, const Eigen::Isometry3d& X) {
  json.beginArray(key);
  for (int r = 0; r < 4; ++r) {
    std::vector<double> row;
    for (int c = 0; c < 4; ++c) row.push_back(c == 3 && r < 3 ? toMm(X(r, c)) : X(r, c));
    json.beginArray();
    for (double v : row) json.element(v);
    json.endArray();
  }
  json.endArray();
}

void writeTerms(JsonWriter& json, const planner::ObjectiveTerms& t) {
  json.value("J_s", t.total);
  json.value("cost_f_s", t.cost_f);
  json.value("cost_omega_s", t.cost_omega);
  json.value("cost_alpha_s", t.cost_alpha);
}

struct PlanTimes {
  double path = 0, map = 0, plan = 0, trajectory = 0, validation = 0, simulation = 0, total = 0;
};

std::string reportJson(const JobSpec& job,
                       const kinematics::CellModel& cell,
                       const planner::ConfigMap& map,
                       const PlanningOutcome& planning,
                       const planner::TrajectoryBuild* trajectory,
                       const planner::ValidationReport* validation,
                       const SimulationRun* simulation,
                       const std::string& status,
                       const std::string& reason,
                       const PlanTimes& times) {
  JsonWriter json;
  json.beginObject();
  json.value("format", "scanplan plan report 1");
  json.value("job", job.name);
  json.value("job_hash", jobHash(job));
  json.value("status", status);
  if (!reason.empty()) json.value("reason", reason);
  const planner::PlanResult& chosen = planning.chosen.result;
  json.beginObject("planner");
  json.value("method", planning.chosen.method);
  json.value("seconds", planning.chosen.seconds);
  if (planning.solved()) json.value("branch", map.branches[chosen.branch].words());
  if (!chosen.detail.empty()) json.value("detail", chosen.detail);
  json.endObject();
  if (planning.solved()) {
    json.beginObject("objective");
    writeTerms(json, planning.terms);
    json.endObject();
    if (planning.refine) {
      json.beginObject("refine");
      json.value("improved", planning.refine->improved);
      json.value("J_before_s", planning.refine->before.total);
      json.value("J_after_s", planning.refine->after.total);
      json.value("seconds", planning.refine->seconds);
      json.value("evaluations", planning.refine->evaluations);
      json.value("algorithm", planning.refine->algorithm);
      json.value("stop_reason", planning.refine->stop_reason);
      json.endObject();
    }
    json.beginObject("path");
    json.value("samples", static_cast<int>(planning.theta.size()));
    json.value("cycle_time_s", map.times.back() - map.times.front());
    json.value("map_min_f", planning.terms.min_f);
    json.value("map_min_f_time_s", map.times[planning.terms.min_f_sample]);
    json.value("max_abs_omega_deg_s", toDeg(planning.terms.max_abs_omega));
    json.value("max_abs_alpha_deg_s2", toDeg(planning.terms.max_abs_alpha));
    json.value("omega_max_deg_s", job.table.max_speed_deg_s);
    json.value("alpha_max_deg_s2", job.table.max_accel_deg_s2);
    if (trajectory && trajectory->ok) {
      const auto& s = trajectory->trajectory.samples[trajectory->min_f_sample];
      json.value("min_f", trajectory->min_f);
      json.value("min_f_time_s", s.t);
      json.value("min_f_limit", s.limit);
      json.value("min_clearance_mm", toMm(trajectory->min_clearance));
    }
    json.endObject();
  }
  if (planning.dp) {
    json.beginObject("dp_baseline");
    json.value("status", planning.dp->status == Status::kSolved ? "solved" : "no_path");
    json.value("angle_subdivisions", planning.dp_subdivisions);
    json.value("seconds", planning.dp->seconds);
    if (planning.dp->status == Status::kSolved) json.value("J_s", planning.dp->terms.total);
    if (const auto gap = planning.dpGap()) json.value("gap_percent", 100.0 * *gap);
    json.endObject();
  }
  if (!planning.rejected.empty()) {
    json.beginArray("rejected");
    for (const auto& [b, why] : planning.rejected) {
      json.beginObject();
      json.value("branch", map.branches[b].words());
      json.value("reason", why);
      json.endObject();
    }
    json.endArray();
  }
  json.beginArray("branches");
  for (std::size_t b = 0; b < planning.chosen.branches.size(); ++b) {
    const planner::PlanResult& r = planning.chosen.branches[b];
    json.beginObject();
    json.value("branch", map.branches[b].words());
    json.value("status", r.status == Status::kSolved ? "solved" : "no_path");
    if (r.status == Status::kSolved) {
      json.value("J_s", r.terms.total);
    } else {
      json.value("reason", r.reason);
    }
    json.endObject();
  }
  json.endArray();
  if (!planning.others.empty()) {
    json.beginArray("compare");
    for (const PlannerOutcome& o : planning.others) {
      json.beginObject();
      json.value("method", o.method);
      json.value("status", o.result.status == Status::kSolved ? "solved" : "no_path");
      json.value("seconds", o.seconds);
      if (o.result.status == Status::kSolved) {
        writeTerms(json, o.result.terms);
      } else {
        json.value("reason", o.result.reason);
      }
      json.endObject();
    }
    json.endArray();
  }
  if (validation) writeValidationJson(json, "validation", *validation);
  if (simulation) writeSimulationJson(json, "simulation", *simulation);
  json.beginObject("times_s");
  json.value("path", times.path);
  json.value("map", times.map);
  json.value("plan", times.plan);
  json.value("trajectory", times.trajectory);
  json.value("validation", times.validation);
  json.value("simulation", times.simulation);
  json.value("total", times.total);
  json.endObject();
  json.beginObject("map");
  json.value("angles", static_cast<int>(map.angles.size()));
  json.value("samples", static_cast<int>(map.times.size()));
  json.value("angle_step_deg", job.map.angle_step_deg);
  json.value("dt_s", job.scan.dt_s);
  json.endObject();
  json.beginObject("cell");
  json.value("units", "4x4 homogeneous matrices, rotation unitless, translation in mm");
  writeMatrixMm(json, "X_WB", cell.X_WB);
  writeMatrixMm(json, "X_WA", cell.table.X_WA);
  writeMatrixMm(json, "X_RP", cell.part.X_RP);
  writeMatrixMm(json, "X_FS", cell.scanner.X_FS);
  json.endObject();
  json.endObject();
  return json.str();
}

}  // namespace

// Everything `plan` may write into its output folder: on each run, what it does not write again
// is removed (no trajectory.csv or program of an earlier run beside a new report).
const std::vector<std::string> kPlanOutputs{
    "job.yaml", "report.json", "trajectory.csv", "trajectory_invalid.csv", "programs", "path.csv",
    "path.png", "configmap*",  "cloud.ply",      "coverage.ply",           "cloud.png"};

ExitCode runPlan(const PlanOptions& options) {
  const auto start = Clock::now();
  const JobSpec job = loadJob(options.job_file, options.overrides);
  const kinematics::CellModel cell = buildCell(job);
  const kinematics::LoadedMesh part = loadPart(job, cell);
  const std::string method = options.planner.empty() ? job.planner.method : options.planner;

  std::string summary;
  summary += fmt::format("job        {} ({})\n", job.name, job.source.string());
  summary += fmt::format("robot      {}\n", cell.robot.name());
  summary += fmt::format(
      "table      radius {} mm, axis at ({:.1f}, {:.1f}, {:.1f}) mm, {}\n", job.table.radius_mm,
      toMm(cell.table.X_WA.translation().x()), toMm(cell.table.X_WA.translation().y()),
      toMm(cell.table.X_WA.translation().z()),
      job.table.continuous ? "continuous"
                           : fmt::format("{} … {} deg", job.table.min_deg, job.table.max_deg));
  const Eigen::Vector3d size = part.mesh.bounds().sizes() * kMToMm;
  summary += fmt::format("part       {}: {} triangles, {:.1f} x {:.1f} x {:.1f} mm, {}\n",
                         job.part.mesh.as_written, part.mesh.triangles.size(), size.x(), size.y(),
                         size.z(), part.mesh.isClosed() ? "closed" : "open (has holes)");
  OutputStage stage(options.out_dir, kPlanOutputs);
  const std::filesystem::path& out = stage.dir();
  writeFileAtomically(out / "job.yaml", jobToYaml(job));
  if (job.scan.paths.empty()) {
    stage.commit();
    summary += reachCheck(job, cell, part);
    summary += fmt::format("wrote      {}\n", (options.out_dir / "job.yaml").string());
    summary += "note       the job has no scan path (scan.paths): nothing to plan\n";
    std::fputs(summary.c_str(), stdout);
    return ExitCode::kOk;
  }

  PlanTimes times;
  auto t0 = Clock::now();
  const PathContext context = buildPath(job, cell);
  times.path = since(t0);
  const kinematics::ScanPath& path = context.generated.path;
  const collision::Scene scene(cell, clearanceConfig(job));
  const MapRun run = computeMap(job, scene, path);
  times.map = run.seconds;
  writePathOutputs(out, context);
  writeMapOutputs(out, job, run.map);
  summary += pathSummary(context) + mapSummary(run);

  // Each candidate path is turned into joint motion before it is accepted: the map scores every
  // cell on its own, but a path must also be followable continuously (joints such as J4 and J6
  // cannot wrap past their limits) and keep f > 0 between the grid angles.
  std::optional<planner::TrajectoryBuild> candidate;
  const auto check = [&](std::size_t b, const std::vector<double>& theta) -> std::string {
    const auto t = Clock::now();
    candidate =
        planner::buildTrajectory(scene, constraintSettings(job), path, theta, run.map.branches[b]);
    times.trajectory += since(t);
    if (!candidate->ok) return candidate->reason;
    if (!(candidate->min_f > 0.0)) {
      const auto& s = candidate->trajectory.samples[candidate->min_f_sample];
      return fmt::format(
          "time sample {} (t = {:.2f} s, table {:.2f} deg): f = 0 ({}) between the map's grid "
          "angles; a finer map.angle_step_deg resolves it",
          candidate->min_f_sample, s.t, toDeg(s.theta), s.limit);
    }
    return {};
  };
  t0 = Clock::now();
  const PlanningOutcome planning =
      planJob(run.map, job, method, options.compare, options.refine, check);
  times.plan = since(t0) - times.trajectory;
  const planner::ValidationReport* validated = nullptr;
  const SimulationRun* simulated = nullptr;
  const auto finish = [&](const std::string& status, const std::string& reason,
                          const planner::TrajectoryBuild* trajectory) {
    times.total = since(start);
    writeFileAtomically(out / "report.json",
                        reportJson(job, cell, run.map, planning, trajectory, validated, simulated,
                                   status, reason, times));
    stage.commit();
  };
  if (!planning.solved()) {
    finish(planning.rejected.empty() ? "no_path" : "no_executable_path",
           planning.chosen.result.reason, nullptr);
    summary += fmt::format("plan       NO PATH ({}): {}\n", method, planning.chosen.result.reason);
    summary += fmt::format("wrote      {}: job.yaml, report.json, {}\n", options.out_dir.string(),
                           kMapFilesNote);
    std::fputs(summary.c_str(), stdout);
    return ExitCode::kNoPlan;
  }
  const std::size_t branch = planning.chosen.result.branch;
  const planner::TrajectoryBuild& trajectory = *candidate;  // the accepted branch's, checked last
  std::vector<std::pair<std::string, std::vector<double>>> drawn{{method, planning.theta}};
  std::vector<std::string> labels{fmt::format(
      "{}{} J {:.2f} s", method, planning.refine ? " + refine" : "", planning.terms.total)};
  for (const PlannerOutcome& o : planning.others) {
    if (o.result.status != Status::kSolved) continue;
    drawn.emplace_back(o.method, o.result.theta);
    labels.push_back(fmt::format("{} J {:.2f} s", o.method, o.result.terms.total));
  }
  writePathFigure(out, run.map, branch, drawn, labels);

  // Prove the motion between the samples too, before anything goes to a robot.
  std::optional<planner::ValidationReport> validation;
  if (job.validation.enabled) {
    t0 = Clock::now();
    validation = planner::validateTrajectory(scene, trajectory.trajectory, validationSettings(job));
    times.validation = since(t0);
    validated = &*validation;
  }
  if (validation && !validation->valid) {
    // Kept for inspection under a name no robot-side tool picks up as the plan.
    writeFileAtomically(out / "trajectory_invalid.csv",
                        kinematics::trajectoryToCsv(trajectory.trajectory));
    finish("invalid_trajectory",
           fmt::format("validation found {} violation(s)", validation->violations.size()),
           &trajectory);
    summary += validationSummary(*validation);
    summary += fmt::format(
        "plan       NOT VALID: the planned motion breaks the limits above\n"
        "wrote      {}: job.yaml, trajectory_invalid.csv, report.json, configmap_path.png/.svg, "
        "{}\n",
        options.out_dir.string(), kMapFilesNote);
    std::fputs(summary.c_str(), stdout);
    return ExitCode::kNoPlan;
  }
  writeFileAtomically(out / "trajectory.csv", kinematics::trajectoryToCsv(trajectory.trajectory));
  const std::string programs = writePrograms(out / "programs", "programs/", job, cell,
                                             trajectory.trajectory, job.outputs.programs);
  std::optional<SimulationRun> simulation;
  if (job.simulation.enabled) {
    t0 = Clock::now();
    simulation = simulateTrajectory(job, cell, part.mesh, trajectory.trajectory);
    writeSimulationOutputs(out, job, part.mesh, *simulation);
    times.simulation = since(t0);
    simulated = &*simulation;
  }
  finish("planned", "", &trajectory);

  const planner::ObjectiveTerms& t = planning.terms;
  summary += fmt::format(
      "plan       {} on {}: J = {:.3f} s (f {:.3f}, omega {:.3f}, alpha {:.3f}) in {:.2f} s\n",
      method, run.map.branches[branch].words(), t.total, t.cost_f, t.cost_omega, t.cost_alpha,
      planning.chosen.seconds);
  for (const auto& [b, why] : planning.rejected) {
    summary += fmt::format("  rejected {} (lower J): {}\n", run.map.branches[b].words(), why);
  }
  if (planning.refine) {
    summary += fmt::format("refine     J {:.3f} -> {:.3f} s ({})\n", planning.refine->before.total,
                           planning.refine->after.total,
                           planning.refine->improved ? "improved" : "kept the input");
  }
  if (const auto gap = planning.dpGap()) {
    summary += fmt::format("baseline   DP optimum J = {:.3f} s (grid {:.3g} deg): gap {:+.1f}%\n",
                           planning.dp->terms.total,
                           job.map.angle_step_deg / planning.dp_subdivisions, 100.0 * *gap);
  }
  for (const PlannerOutcome& o : planning.others) {
    summary += o.result.status == Status::kSolved
                   ? fmt::format("compare    {:<5} J = {:.3f} s in {:.2f} s\n", o.method,
                                 o.result.terms.total, o.seconds)
                   : fmt::format("compare    {:<5} no path: {}\n", o.method, o.result.reason);
  }
  const auto& worst = trajectory.trajectory.samples[trajectory.min_f_sample];
  summary += fmt::format(
      "trajectory {} samples over {:.1f} s; table |omega| <= {:.1f} deg/s, |alpha| <= {:.1f} "
      "deg/s^2; min f {:.3f} at t = {:.1f} s ({}); min clearance {}\n",
      trajectory.trajectory.samples.size(), trajectory.trajectory.duration(),
      toDeg(t.max_abs_omega), toDeg(t.max_abs_alpha), trajectory.min_f, worst.t, worst.limit,
      std::isfinite(trajectory.min_clearance)
          ? fmt::format("{:.1f} mm", toMm(trajectory.min_clearance))
          : std::string("beyond every d_high"));
  if (validation) summary += validationSummary(*validation);
  summary += programs;
  if (simulation) summary += simulationSummary(*simulation);
  summary += fmt::format(
      "wrote      {}: job.yaml, trajectory.csv, programs/, report.json, configmap_path.png/.svg, "
      "{}{}\n",
      options.out_dir.string(), simulation ? "cloud.ply, coverage.ply, cloud.png, " : "",
      kMapFilesNote);
  summary += fmt::format(
      "time       {:.1f} s (path {:.1f}, map {:.1f}, plan {:.1f}, trajectory {:.1f}, validation "
      "{:.1f}, simulation {:.1f})\n",
      since(start), times.path, times.map, times.plan, times.trajectory, times.validation,
      times.simulation);
  std::fputs(summary.c_str(), stdout);
  return ExitCode::kOk;
}

}  // namespace scanplan::cli
