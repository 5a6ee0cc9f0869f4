// `scanplan plan`: the job from part to plan — scan path, configuration maps, the table-angle
// path (docs/design.md §5), the 7-DOF trajectory, and the report.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <optional>

#include <sstream>

#include <fmt/format.h>

#include <scanplan/collision/scene.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/pipeline/plan_scan.h>
#include <scanplan/pipeline/setups.h>
#include <scanplan/planner/trajectory_builder.h>
#include <scanplan/programs/programs.h>
#include "cli/commands/commands.h"
#include "cli/commands/plan_folder.h"
#include "cli/io/output.h"
#include "cli/io/program_files.h"
#include "cli/io/replay_html.h"
#include "cli/plot/cell_figure.h"
#include "cli/plot/image_io.h"
#include "cli/report/plan_report.h"
#include "cli/report/plan_summary.h"
#include "cli/report/sensor_report.h"
#include "cli/report/simulation_files.h"
#include "cli/report/verify_report.h"

namespace scanplan::cli {

namespace {

using Clock = std::chrono::steady_clock;

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
                     const std::vector<std::string>& labels,
                     const WriteSettings& settings) {
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
              std::move(lines), settings);
}

// `run` (a pipeline call) with the options of the command line and a progress line on a
// terminal; its input errors name the job file.
template <class Run>
auto runPipeline(const config::JobSpec& job, const PlanArguments& options, Run&& run) {
  Progress map("map"), passes("auto (candidate passes)");
  pipeline::PlanOptions po;
  po.method = options.planner;
  po.compare = options.compare;
  po.refine = options.refine;
  try {
    return run(po, [&](std::string_view stage, std::size_t d, std::size_t n) {
      (stage == "auto" ? passes : map)(d, n);
    });
  } catch (const InputError& e) {
    throw InputError(job.source.string() + ": " + e.what());
  }
}

// configmap_path.png/.svg: the chosen path and, with --compare, every other planner's.
void writeChoiceFigure(const std::filesystem::path& out,
                       const pipeline::ScanPlan& plan,
                       const WriteSettings& settings = {}) {
  const pipeline::PathChoice& c = plan.choice;
  std::vector<std::pair<std::string, std::vector<double>>> drawn{{c.chosen.method, c.theta}};
  std::vector<std::string> labels{
      fmt::format("{}{} J {:.2f} s", c.chosen.method, c.refine ? " + refine" : "", c.terms.total)};
  for (const pipeline::PlannerOutcome& o : c.others) {
    if (!o.result.solved()) continue;
    drawn.emplace_back(o.method, o.result.theta);
    labels.push_back(fmt::format("{} J {:.2f} s", o.method, o.result.terms.total));
  }
  // On a joint-wrap sheet the path was planned on the sheet's f (its joint's window scored,
  // cells near the window's edges closed): that is the map to draw it over.
  if (c.sheet_map) {
    writePathFigure(out, *c.sheet_map, 0, drawn, labels, settings);
  } else {
    writePathFigure(out, plan.prepared->map, c.chosen.result.branch, drawn, labels, settings);
  }
}

// cell.png: the cell at the closest approach to the cell (else half-way), as the replay shows it.
RgbImage cellFigure(const pipeline::ReplayScene& scene, const std::string& job_name) {
  std::size_t frame = scene.frames.size() / 2;
  std::string what = "half-way";
  if (!scene.closest.empty()) {
    const double t = scene.closest.front().t;
    for (std::size_t i = 0; i < scene.frames.size(); ++i) {
      if (std::abs(scene.frames[i].t - t) < std::abs(scene.frames[frame].t - t)) frame = i;
    }
    what = fmt::format("closest approach, {} - {} {:.1f} mm", scene.closest.front().a,
                       scene.closest.front().b, 1000.0 * scene.closest.front().distance);
  }
  return cellPicture(scene, frame, fmt::format("Cell of job {} ({})", job_name, what));
}

// OUT/replay.html and cell.png, and the summary line.
std::string writeReplay(const std::filesystem::path& out,
                        const config::JobSpec& job,
                        const pipeline::ScanProblem& problem,
                        const pipeline::ScanPlan& plan,
                        const WriteSettings& settings) {
  const pipeline::ReplayScene scene = pipeline::replayScene(problem.cell, problem.part, plan);
  writePng(out / "cell.png", cellFigure(scene, job.name), settings.views);
  const std::optional<std::string> html = replayHtml(scene, job.name);
  if (!html) {
    return "replay     cell.png; replay.html not written: three.js is not installed "
           "(./bootstrap.sh installs it from npm)\n";
  }
  writeFileAtomically(out / "replay.html", *html);
  return fmt::format(
      "replay     replay.html: the cell over {} frames of the motion, {} of the cloud's {} "
      "points, open it in a browser; cell.png: the cell at the closest approach\n",
      scene.frames.size(), scene.cloud.size(), scene.cloud_total);
}

// sensors.csv when the cell has sensors (the validation evaluated them); returns their summary
// lines.
std::string writeSensorOutputs(const std::filesystem::path& out, const pipeline::ScanPlan& plan) {
  if (!plan.validation || !plan.validation->sensors) return {};
  const collision::Scene& scene = *plan.prepared->scene;
  writeFileAtomically(out / "sensors.csv", sensorsCsv(scene, *plan.validation->sensors));
  return sensorsSummary(scene, *plan.validation->sensors);
}

// The outputs of a valid plan: trajectory.csv, the programs, the simulation's and the
// certificate's files; returns their summary lines (`second`: of the second setup, which does
// not suggest another).
std::string writePlannedOutputs(const std::filesystem::path& out,
                                const config::JobSpec& job,
                                const pipeline::ScanProblem& problem,
                                const pipeline::ScanPlan& plan,
                                bool second = false,
                                const WriteSettings& settings = {}) {
  const kinematics::Trajectory& trajectory = plan.trajectory->trajectory;
  writeFileAtomically(out / "trajectory.csv", kinematics::trajectoryToCsv(trajectory));
  const std::string programs = writePrograms(out / "programs", "programs/", job, problem.cell,
                                             trajectory, job.outputs.programs, true);
  if (plan.simulation) writeSimulationOutputs(out, job, problem.part, *plan.simulation, settings);
  if (plan.certificate) {
    writeCertificateOutputs(out, problem.part, plan.simulation->sampling, *plan.certificate,
                            settings);
    writeCoverageCurve(out, plan.coverage_curve, plan.program.total, settings);
  }
  const std::string replay = writeReplay(out, job, problem, plan, settings);
  const std::string sensors = writeSensorOutputs(out, plan);
  std::string summary = choiceSummary(plan);
  if (plan.validation) summary += validationSummary(*plan.validation);
  summary += sensors;
  summary += programs;
  summary += replay;
  if (plan.simulation) summary += simulationSummary(*plan.simulation);
  if (plan.certificate) summary += certificateSummary(*plan.certificate, !second);
  summary += curveSummary(plan);
  return summary;
}

// --setups 2: the second setup's files in DIR/setup2 (its program and report) and the coverage of
// both setups together.
struct SecondSetupRun {
  Json json = Json::object();  // report.json's `setups`
  std::string summary;
  bool ok = true;
};

SecondSetupRun writeSecondSetup(const std::filesystem::path& out,
                                const std::filesystem::path& shown,
                                const config::JobSpec& job,
                                const pipeline::SecondSetupPlan& second) {
  SecondSetupRun r;
  if (!second.setup) {
    r.summary = fmt::format("setup 2    not planned: {}\n", second.why_not);
    r.json["setups"] = {{"second", {{"status", "not_planned"}, {"reason", second.why_not}}}};
    return r;
  }
  const pipeline::ScanPlan& plan = second.plan;
  const std::filesystem::path dir = out / "setup2";
  std::filesystem::create_directories(dir);
  Json json = {{"turn", second.setup->turn},
               {"gain", second.setup->gain},
               {"status", std::string(pipeline::scanStatusName(plan.status))},
               {"folder", "setup2"}};
  r.summary = fmt::format(
      "setup 2    the part {}: {:.1f}% of its area faced the table and comes into view\n",
      second.setup->turn, 100.0 * second.setup->gain);
  if (plan.prepared->auto_scan) r.summary += autoScanSummary(*plan.prepared->auto_scan);
  if (second.combined) {
    writeChoiceFigure(dir, plan);
    r.summary += writePlannedOutputs(dir, job, *second.problem, plan, true);
    const pipeline::CombinedCoverage& c = *second.combined;
    r.summary += fmt::format(
        "setups     both: {:.1f}% of the part's area covered; {:.1f}% scannable in one setup or "
        "the other, {:.1f}% of that covered (setup 2's files in {})\n",
        100.0 * c.area_fraction, 100.0 * c.scannable_fraction, 100.0 * c.covered_of_scannable,
        (shown / "setup2").string());
    json["combined"] = {{"area_fraction", c.area_fraction},
                        {"scannable_fraction", c.scannable_fraction},
                        {"covered_of_scannable", c.covered_of_scannable}};
  } else {
    r.ok = false;
    r.summary += fmt::format("setup 2    NOT PLANNED ({}): {}\n",
                             pipeline::scanStatusName(plan.status), plan.reason);
  }
  writeFileAtomically(dir / "report.json",
                      planReportJson(job, second.problem->cell, plan, plan.times));
  r.json["setups"] = {{"second", json}};
  return r;
}

// A plan with a trajectory the validation did not refuse: the one that gets programs.
bool hasValidTrajectory(const pipeline::ScanPlan& plan) {
  return plan.trajectory && plan.status != pipeline::ScanStatus::kInvalidTrajectory;
}

}  // namespace

std::string writePlanOutputs(const std::filesystem::path& dir,
                             const config::JobSpec& job,
                             const pipeline::ScanProblem& problem,
                             const pipeline::ScanPlan& plan,
                             const WriteSettings& settings) {
  const pipeline::PreparedScan& prepared = *plan.prepared;
  writePathOutputs(dir, problem.cell, problem.part, prepared.path.path, settings);
  writeMapOutputs(dir, job, prepared.map, settings);
  if (!plan.trajectory) return {};
  writeChoiceFigure(dir, plan, settings);
  if (plan.status == pipeline::ScanStatus::kInvalidTrajectory) {
    // Kept for inspection under a name no robot-side tool picks up as the plan.
    writeFileAtomically(dir / "trajectory_invalid.csv",
                        kinematics::trajectoryToCsv(plan.trajectory->trajectory));
    writeSensorOutputs(dir, plan);
    return {};
  }
  return writePlannedOutputs(dir, job, problem, plan, false, settings);
}

// Everything `plan` may write into its output folder: on each run, what it does not write again
// is removed (no trajectory.csv or program of an earlier run beside a new report).
// What `plan` writes into OUT, relative to it (OutputStage's `owned`): its files, the programs
// of any language under the job's program name, the profile images, and the same in setup2/.
std::vector<std::string> planOutputs(const config::JobSpec& job) {
  std::vector<std::string> top{
      "job.yaml",     "report.json",       "trajectory.csv",    "trajectory_invalid.csv",
      "path.csv",     "path.png",          "configmap*",        "cloud.ply",
      "coverage.ply", "cloud.png",         "uncovered.ply",     "certificate.png",
      "replay.html",  "cell.png",          "coverage_time.png", "coverage_time.svg",
      "sensors.csv",  "profiles/profile_*"};
  for (const std::string& file : programs::programFileNames(job.outputs.program_name))
    top.push_back("programs/" + file);
  std::vector<std::string> owned = top;
  for (const std::string& name : top) owned.push_back("setup2/" + name);
  return owned;
}

// The command's result on stdout: the text summary, or with --json one JSON document (the
// report, the output folder and the summary's lines).
ExitCode printPlanResult(const PlanArguments& options,
                         const std::string& summary,
                         Json report,
                         ExitCode code) {
  if (!options.json) {
    std::fputs(summary.c_str(), stdout);
    return code;
  }
  Json lines = Json::array();
  std::istringstream in(summary);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  Json doc = {{"out_dir", options.out_dir.string()},
              {"exit_code", static_cast<int>(code)},
              {"summary", lines}};
  if (report.is_object()) doc.update(report);
  std::fputs(jsonDocument(doc).c_str(), stdout);
  return code;
}

namespace {

// The summary's "wrote" line of a planned, valid run (`dir`: the staged folder, `shown`: OUT).
std::string wroteLine(const std::filesystem::path& dir,
                      const std::filesystem::path& shown,
                      const pipeline::ScanPlan& plan,
                      bool second_setup) {
  return fmt::format(
      "wrote      {}: job.yaml, trajectory.csv, programs/, report.json, configmap_path.png/.svg, "
      "{}{}\n",
      shown.string(),
      std::string(plan.simulation ? "cloud.ply, coverage.ply, cloud.png, " : "") +
          (plan.simulation && !plan.simulation->profile_images.empty() ? "profiles/, " : "") +
          (std::filesystem::exists(dir / "replay.html") ? "replay.html, " : "") + "cell.png, " +
          (plan.certificate ? "uncovered.ply, certificate.png, coverage_time.png/.svg, " : "") +
          (plan.validation && plan.validation->sensors ? "sensors.csv, " : "") +
          (second_setup ? "setup2/, " : ""),
      kMapFilesNote);
}

// The summary lines of a plan without a valid trajectory: why, and what was written.
std::string notPlannedSummary(const std::filesystem::path& shown, const pipeline::ScanPlan& plan) {
  if (!plan.trajectory) {
    return fmt::format("plan       {} ({}): {}\n",
                       plan.choice.chosen.budget_ended ? "NOT SOLVED IN THE BUDGET" : "NO PATH",
                       plan.choice.chosen.method, plan.reason) +
           fmt::format("wrote      {}: job.yaml, report.json, {}\n", shown.string(), kMapFilesNote);
  }
  std::string summary = validationSummary(*plan.validation);
  const bool sensors = plan.validation->sensors.has_value();
  if (sensors) summary += sensorsSummary(*plan.prepared->scene, *plan.validation->sensors);
  summary += fmt::format(
      "plan       NOT VALID: the planned motion breaks the {} above\n"
      "wrote      {}: job.yaml, trajectory_invalid.csv, {}report.json, "
      "configmap_path.png/.svg, {}\n",
      sensors ? "limits or sensor rules" : "limits", shown.string(), sensors ? "sensors.csv, " : "",
      kMapFilesNote);
  return summary;
}

}  // namespace

PlanFolder writePlanFolder(const std::filesystem::path& dir,
                           const std::filesystem::path& shown,
                           const PlannedJob& planned) {
  const pipeline::ScanPlan& plan = planned.plan;
  PlanFolder r;
  const std::string written = writePlanOutputs(dir, planned.job, planned.problem, plan);
  Json setups = Json::object();
  if (!hasValidTrajectory(plan)) {
    r.summary = notPlannedSummary(shown, plan);
    r.code = ExitCode::kNoPlan;
  } else {
    r.summary = written;
    if (planned.second) {
      SecondSetupRun second = writeSecondSetup(dir, shown, planned.job, *planned.second);
      r.summary += second.summary;
      setups = std::move(second.json);
      if (!second.ok) r.code = ExitCode::kNoPlan;
    }
  }
  pipeline::StageTimes times = plan.times;
  times.total = since(planned.start);
  r.report = planReportJson(planned.job, planned.problem.cell, plan, times, setups);
  writeFileAtomically(dir / "report.json", r.report);
  if (hasValidTrajectory(plan)) r.summary += wroteLine(dir, shown, plan, setups.contains("setups"));
  return r;
}

PlanFolder publishPlanFolder(const std::filesystem::path& out_dir,
                             const PlannedJob& planned,
                             const std::string& option) {
  checkOutputApartFromInputs(out_dir, config::jobInputFiles(planned.job), option);
  OutputStage stage(out_dir, planOutputs(planned.job));
  writeFileAtomically(stage.dir() / "job.yaml", config::jobToYaml(planned.job));
  PlanFolder folder = writePlanFolder(stage.dir(), out_dir, planned);
  stage.commit();
  return folder;
}

ExitCode runPlan(const PlanArguments& options) {
  const auto start = Clock::now();
  const config::JobSpec job = config::loadJob(options.job_file, options.overrides);
  checkOutputApartFromInputs(options.out_dir, config::jobInputFiles(job));
  const kinematics::CellModel cell = config::buildCell(job);
  const kinematics::LoadedMesh part = config::loadPart(job, cell);
  std::string summary = cellSummary(job, cell, part);
  OutputStage stage(options.out_dir, planOutputs(job));
  writeFileAtomically(stage.dir() / "job.yaml", config::jobToYaml(job));
  if (job.scan.paths.empty() && !job.scan.auto_scan.enabled) {
    stage.commit();
    summary += reachCheck(job, cell, part);
    summary += fmt::format("wrote      {}\n", (options.out_dir / "job.yaml").string());
    summary += "note       the job has no scan path (scan.paths): nothing to plan\n";
    return printPlanResult(options, summary, {{"status", "no_scan_path"}}, ExitCode::kOk);
  }
  warnSlowLinkMeshes(job, cell);
  const pipeline::ScanProblem problem = config::toProblem(job, cell, part.mesh);
  const pipeline::ScanPlan plan = runPipeline(
      job, options, [&](const pipeline::PlanOptions& po, const pipeline::ProgressFn& progress) {
        return pipeline::planScan(problem, po, progress);
      });
  std::optional<pipeline::SecondSetupPlan> second;
  if (options.setups == 2 && hasValidTrajectory(plan)) {
    second = runPipeline(
        job, options, [&](const pipeline::PlanOptions& po, const pipeline::ProgressFn& progress) {
          return pipeline::planSecondSetup(problem, plan, po, progress);
        });
  }
  const pipeline::PreparedScan& prepared = *plan.prepared;
  summary += pathSummary(prepared.window, prepared.path);
  if (prepared.auto_scan) summary += autoScanSummary(*prepared.auto_scan);
  summary += linkMeshSummary(*prepared.scene) + mapSummary(prepared.map, prepared.map_seconds);
  const PlanFolder folder = writePlanFolder(
      stage.dir(), options.out_dir, {job, problem, plan, second ? &*second : nullptr, start});
  stage.commit();
  summary += folder.summary;
  if (hasValidTrajectory(plan)) {
    const pipeline::StageTimes& times = plan.times;
    summary += fmt::format(
        "time       {:.1f} s (path {:.1f}, map {:.1f}, plan {:.1f}, trajectory {:.1f}, "
        "validation {:.1f}, simulation {:.1f})\n",
        since(start), times.path, times.map, times.plan, times.trajectory, times.validation,
        times.simulation);
  }
  return printPlanResult(options, summary, options.json ? Json::parse(folder.report) : Json(),
                         folder.code);
}

}  // namespace scanplan::cli
