#pragma once
// The plan folder: every file `scanplan plan -o OUT` writes for a planned job, and the summary
// lines that describe them. The command and the Python module's Plan.write() both write it.

#include <chrono>
#include <filesystem>
#include <string>

#include <scanplan/config/job.h>
#include <scanplan/pipeline/plan_scan.h>
#include <scanplan/pipeline/setups.h>
#include "cli/io/exit_code.h"

namespace scanplan::cli {

/// A planned job: the job as read, the problem planned, its plan and, with two setups, the
/// second setup's plan (planned only after a valid first plan).
struct PlannedJob {
  const config::JobSpec& job;
  const pipeline::ScanProblem& problem;
  const pipeline::ScanPlan& plan;
  const pipeline::SecondSetupPlan* second = nullptr;
  std::chrono::steady_clock::time_point start;  ///< when the run began (report.json's total)
};

/// What writing the folder gave.
struct PlanFolder {
  std::string summary;  ///< the summary lines from the plan on ("plan", "validation", "wrote")
  std::string report;   ///< report.json's text
  ExitCode code = ExitCode::kOk;  ///< kNoPlan when a setup has no valid program
};

/// Writes the plan folder's files into `dir` (an OutputStage's directory; `shown` is the OUT the
/// summary names), report.json last. job.yaml is the caller's.
PlanFolder writePlanFolder(const std::filesystem::path& dir,
                           const std::filesystem::path& shown,
                           const PlannedJob& planned);

/// The whole folder published atomically into `out_dir`: refused (InputError naming `option`)
/// when it is, holds or lies in an input of the job; staged, job.yaml and writePlanFolder(), then
/// committed (old or new files, never mixed).
PlanFolder publishPlanFolder(const std::filesystem::path& out_dir,
                             const PlannedJob& planned,
                             const std::string& option = "-o");

}  // namespace scanplan::cli
