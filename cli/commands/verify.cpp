// `scanplan validate` and `scanplan simulate`: a trajectory (from `plan`, or written by hand)
// proven executable, and the scan it would produce.
#include <cstdio>
#include <sstream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <scanplan/collision/scene.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/pipeline/simulation.h>
#include <scanplan/planner/validation.h>
#include <scanplan/programs/programs.h>
#include "cli/commands/commands.h"
#include "cli/io/output.h"
#include "cli/io/program_files.h"
#include "cli/io/trajectory_file.h"
#include "cli/report/sensor_report.h"
#include "cli/report/simulation_files.h"
#include "cli/report/verify_report.h"

namespace scanplan::cli {

namespace {

// The trajectory file (CSV or a program, its timing read with the cell's robot), at least two
// samples.
kinematics::Trajectory loadTrajectory(const std::filesystem::path& file,
                                      const kinematics::CellModel& cell) {
  kinematics::Trajectory t = loadTrajectoryFile(file, &cell.robot);
  if (t.samples.size() < 2) {
    throw InputError(
        fmt::format("{}: {} sample(s): expected at least 2", file.string(), t.samples.size()));
  }
  spdlog::debug("trajectory {}: {} samples over {:.2f} s", file.string(), t.samples.size(),
                t.samples.back().t - t.samples.front().t);
  return t;
}

// `run` (a stage on the trajectory) with its input errors naming the trajectory file: what
// those stages refuse is the trajectory's size (its duration at the frame rate, its motion).
template <class Run>
auto onTrajectory(const std::filesystem::path& file, const Run& run) {
  try {
    return run();
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", file.string(), e.what()));
  }
}

// OUT (when given) apart from every input: the job's files and the trajectory.
void checkOut(const VerifyOptions& options, const config::JobSpec& job) {
  if (options.out_dir.empty()) return;
  std::vector<std::filesystem::path> inputs = config::jobInputFiles(job);
  inputs.push_back(options.trajectory_file);
  checkOutputApartFromInputs(options.out_dir, inputs);
}

}  // namespace

ExitCode runValidate(const VerifyOptions& options) {
  const config::JobSpec job = config::loadJob(options.job_file, options.overrides);
  checkOut(options, job);
  const kinematics::CellModel cell = config::buildCell(job);
  const kinematics::Trajectory trajectory = loadTrajectory(options.trajectory_file, cell);
  const collision::Scene scene(cell, config::clearanceConfig(job));
  const planner::ValidationReport report = onTrajectory(options.trajectory_file, [&] {
    return planner::validateTrajectory(scene, trajectory, config::validationSettings(job));
  });
  Json doc = {{"format", "scanplan validation report 1"},
              {"job", job.name},
              {"job_hash", config::jobHash(job)},
              {"trajectory", options.trajectory_file.string()},
              {"frame_rate_hz", job.scanner.frame_rate_hz},
              {"validation", validationJson(report)}};
  if (report.sensors) doc["sensors"] = sensorsJson(scene, *report.sensors);
  const std::string json = jsonDocument(doc);
  if (options.json) {
    std::fputs(json.c_str(), stdout);
  } else {
    std::string text = validationSummary(report, 50);
    if (report.sensors) text += sensorsSummary(scene, *report.sensors);
    std::fputs(text.c_str(), stdout);
  }
  if (!options.out_dir.empty()) {
    OutputStage stage(options.out_dir, {"validation.json", "sensors.csv"});
    writeFileAtomically(stage.dir() / "validation.json", json);
    if (report.sensors) {
      writeFileAtomically(stage.dir() / "sensors.csv", sensorsCsv(scene, *report.sensors));
    }
    stage.commit();
  }
  return report.valid ? ExitCode::kOk : ExitCode::kNoPlan;
}

ExitCode runSimulate(const VerifyOptions& options) {
  const config::JobSpec job = config::loadJob(options.job_file, options.overrides);
  checkOut(options, job);
  const kinematics::CellModel cell = config::buildCell(job);
  const kinematics::LoadedMesh part = config::loadPart(job, cell);
  const kinematics::Trajectory trajectory = loadTrajectory(options.trajectory_file, cell);
  OutputStage stage(options.out_dir, {"cloud.ply", "coverage.ply", "cloud.png", "simulation.json",
                                      "profiles/profile_*", "sensors.csv"});
  const pipeline::SimulationRun run = onTrajectory(options.trajectory_file, [&] {
    return pipeline::simulateTrajectory(cell, part.mesh, config::laserOptics(job),
                                        config::simulationSettings(job, cell), trajectory);
  });
  writeSimulationOutputs(stage.dir(), job, part.mesh, run);
  Json json = {{"format", "scanplan simulation report 1"},
               {"job", job.name},
               {"job_hash", config::jobHash(job)},
               {"trajectory", options.trajectory_file.string()},
               {"simulation", simulationJson(run)}};
  std::string sensor_lines;
  if (!cell.sensors.empty()) {
    // The sensors at the validation's poses: the trajectory every frame period.
    const collision::Scene scene(cell, config::clearanceConfig(job));
    const collision::SensorEvaluation sensors = onTrajectory(options.trajectory_file, [&] {
      const kinematics::Trajectory dense =
          planner::densify(trajectory, config::validationSettings(job).sample_dt);
      return collision::evaluateSensors(scene, dense.samples);
    });
    writeFileAtomically(stage.dir() / "sensors.csv", sensorsCsv(scene, sensors));
    json["sensors"] = sensorsJson(scene, sensors);
    sensor_lines = sensorsSummary(scene, sensors);
  }
  writeFileAtomically(stage.dir() / "simulation.json", jsonDocument(json));
  stage.commit();
  std::string text = simulationSummary(run) + sensor_lines;
  text += fmt::format("wrote      {}: cloud.ply, coverage.ply, cloud.png, simulation.json{}{}\n",
                      options.out_dir.string(), run.profile_images.empty() ? "" : ", profiles/",
                      sensor_lines.empty() ? "" : ", sensors.csv");
  std::fputs(text.c_str(), stdout);
  return ExitCode::kOk;
}

ExitCode runExport(const VerifyOptions& options) {
  const config::JobSpec job = config::loadJob(options.job_file, options.overrides);
  checkOut(options, job);
  const kinematics::CellModel cell = config::buildCell(job);
  const kinematics::Trajectory trajectory = loadTrajectory(options.trajectory_file, cell);
  std::vector<std::string> formats = job.outputs.programs;
  if (!options.formats.empty()) {
    formats.clear();
    std::stringstream list(options.formats);
    std::string name;
    while (std::getline(list, name, ',')) {
      if (!programs::parseProgramFormat(name)) {
        throw InputError(fmt::format("--format '{}': expected a comma-separated list of {}", name,
                                     fmt::join(programs::programFormatNames(), ", ")));
      }
      formats.push_back(name);
    }
  }
  OutputStage stage(options.out_dir, {});  // replaces the programs it writes, keeps the rest
  const std::string summary =
      writePrograms(stage.dir(), options.out_dir.string(), job, cell, trajectory, formats);
  stage.commit();
  std::fputs(summary.c_str(), stdout);
  return ExitCode::kOk;
}

}  // namespace scanplan::cli
