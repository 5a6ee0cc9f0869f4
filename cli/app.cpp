#include "cli/app.h"

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <exception>
#include <string>
#include <utility>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include "cli/batch/batch.h"
#include "cli/commands/commands.h"
#include "kinematics/error.h"

namespace scanplan::cli {
namespace {

void addRobotSource(CLI::App& cmd, RobotSource& source) {
  auto* robot = cmd.add_option("--robot", source.robot_file, "Robot file (YAML)");
  auto* job = cmd.add_option("--job", source.job_file, "Job file: use its robot (and scanner)");
  robot->excludes(job);
  cmd.callback([robot, job] {
    if (robot->count() + job->count() == 0) {
      throw CLI::RequiredError("--robot or --job");
    }
  });
}

void setUpLogging(int verbosity) {
  auto logger = spdlog::stderr_color_mt("scanplan");
  logger->set_pattern("scanplan: %^%l%$: %v");
  logger->set_level(verbosity > 0   ? spdlog::level::debug
                    : verbosity < 0 ? spdlog::level::err
                                    : spdlog::level::info);
  spdlog::set_default_logger(logger);
}

// Input files are checked here, not by CLI11's ExistingFile: a missing or unreadable file is bad
// input (exit 4), named like every other input error, not a usage error (exit 2).
void requireInput(const std::filesystem::path& path, const char* what, bool folder = false) {
  if (path.empty()) return;
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) {
    throw InputError(fmt::format("{}: {} does not exist", path.string(), what));
  }
  if (folder && !std::filesystem::is_directory(status)) {
    throw InputError(fmt::format("{}: is not a folder: expected the {}", path.string(), what));
  }
  if (!folder && std::filesystem::is_directory(status)) {
    throw InputError(fmt::format("{}: is a folder: expected the {}", path.string(), what));
  }
  if (::access(path.c_str(), folder ? (R_OK | X_OK) : R_OK) != 0) {
    throw InputError(fmt::format("{}: {} cannot be read: {}", path.string(), what,
                                 std::error_code(errno, std::generic_category()).message()));
  }
}

// --quiet: the summary a command prints on stdout goes to /dev/null for the command's run;
// errors (and stdout again afterwards) are untouched.
class SilencedStdout {
 public:
  explicit SilencedStdout(bool silence) {
    if (!silence) return;
    std::fflush(stdout);
    const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (null < 0) return;
    saved_ = ::dup(STDOUT_FILENO);
    if (saved_ >= 0) ::dup2(null, STDOUT_FILENO);
    ::close(null);
  }
  ~SilencedStdout() {
    if (saved_ < 0) return;
    std::fflush(stdout);
    ::dup2(saved_, STDOUT_FILENO);
    ::close(saved_);
  }
  SilencedStdout(const SilencedStdout&) = delete;
  SilencedStdout& operator=(const SilencedStdout&) = delete;

 private:
  int saved_ = -1;
};

void addOverrides(CLI::App& cmd, std::vector<std::string>& overrides) {
  cmd.add_option("--set", overrides,
                 "Override a job value, as if the file said so: key.path=value (repeatable), e.g. "
                 "--set planner.ray.horizon=20 --set scan.paths[0].height_mm=60")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false);
}

}  // namespace

int run(int argc, char** argv) {
  static const char* const kTrajectoryHelp =
      "Trajectory: a trajectory CSV (trajectory.csv from plan, or written by hand with its "
      "columns) or a V+ program (scan.v2 from plan or export)";
  CLI::App app{
      "scanplan — scanning path planner for a 6-axis arm with a laser line scanner and a rotary "
      "table.\nUnits at the command line: mm and degrees."};
  app.set_version_flag("--version", std::string("scanplan ") + SCANPLAN_VERSION);
  app.require_subcommand(1);
  // Options of the app are also taken after the subcommand (`scanplan plan -q …`): every
  // subcommand, added below, inherits this.
  app.fallthrough();
  int verbose = 0;
  bool quiet = false;
  app.add_flag("-v,--verbose", verbose,
               "Also log on stderr the files each command reads, the --set overrides applied and "
               "how long the command took");
  app.add_flag("-q,--quiet", quiet,
               "Errors only: no summary or warnings (what job show, check, fk, ik and --json "
               "print is the result, and still printed)");

  PlanOptions plan;
  auto* plan_cmd = app.add_subcommand(
      "plan",
      "Run a job end to end: scan path, configuration maps, table-angle plan on every IK "
      "branch, validation of the motion, robot programs and the scan simulation, all into OUT");
  plan_cmd->add_option("job", plan.job_file, "Job file (YAML)")->required();
  plan_cmd->add_option("-o,--out", plan.out_dir, "Output folder (created)")->required();
  plan_cmd
      ->add_option(
          "--planner", plan.planner,
          "Table-angle search: ray (Ray Shooting), dp (exact optimum on the grid) or ompl; "
          "default: the job's planner.method")
      ->check(CLI::IsMember({"ray", "dp", "ompl"}));
  plan_cmd->add_flag("--compare", plan.compare,
                     "Also run the other planners on the chosen branch: J side by side, every path "
                     "drawn in configmap_path.png");
  plan_cmd->add_flag("--refine", plan.refine,
                     "Refine the path with NLopt even when the job turns it off: refinement is on "
                     "by default (the job's planner.refine.enabled), this overrides a false");
  addOverrides(*plan_cmd, plan.overrides);

  VerifyOptions validate;
  auto* validate_cmd = app.add_subcommand(
      "validate",
      "Prove a trajectory executable: joint limits, joint and table speeds, table acceleration, "
      "and collisions along the whole motion (continuous check); exit 3 when it is not");
  validate_cmd->add_option("job", validate.job_file, "Job file (YAML)")->required();
  validate_cmd->add_option("-t,--trajectory", validate.trajectory_file, kTrajectoryHelp)
      ->required();
  validate_cmd->add_option("-o,--out", validate.out_dir, "Also write OUT/validation.json");
  validate_cmd->add_flag("--json", validate.json, "Print JSON instead of text");
  addOverrides(*validate_cmd, validate.overrides);

  VerifyOptions simulate;
  auto* simulate_cmd = app.add_subcommand(
      "simulate",
      "Simulate the laser scanner along a trajectory: the expected point cloud and how much of "
      "the part it covers");
  simulate_cmd->add_option("job", simulate.job_file, "Job file (YAML)")->required();
  simulate_cmd->add_option("-t,--trajectory", simulate.trajectory_file, kTrajectoryHelp)
      ->required();
  simulate_cmd->add_option("-o,--out", simulate.out_dir, "Output folder (created)")->required();
  addOverrides(*simulate_cmd, simulate.overrides);

  VerifyOptions export_options;
  auto* export_cmd = app.add_subcommand(
      "export",
      "Write robot programs for a trajectory: V+, KRL, RAPID, URScript or the CSV interchange");
  export_cmd->add_option("job", export_options.job_file, "Job file (YAML)")->required();
  export_cmd->add_option("-t,--trajectory", export_options.trajectory_file, kTrajectoryHelp)
      ->required();
  export_cmd->add_option("-o,--out", export_options.out_dir, "Output folder (created)")->required();
  export_cmd->add_option("-f,--format", export_options.formats,
                         "Comma-separated: vplus, krl, rapid, urscript, csv (default: the job's "
                         "outputs.programs)");
  addOverrides(*export_cmd, export_options.overrides);

  PlanOptions path;
  auto* path_cmd = app.add_subcommand(
      "path", "Generate the scan path: OUT/path.csv and a picture of it around the part");
  path_cmd->add_option("job", path.job_file, "Job file (YAML)")->required();
  path_cmd->add_option("-o,--out", path.out_dir, "Output folder (created)")->required();
  addOverrides(*path_cmd, path.overrides);

  PlanOptions map;
  auto* map_cmd = app.add_subcommand(
      "map", "Build the configuration maps over table angle x time: npy layers, json, images");
  map_cmd->add_option("job", map.job_file, "Job file (YAML)")->required();
  map_cmd->add_option("-o,--out", map.out_dir, "Output folder (created)")->required();
  addOverrides(*map_cmd, map.overrides);

  auto* job_cmd = app.add_subcommand("job", "Inspect job files");
  job_cmd->require_subcommand(1);
  std::filesystem::path show_file;
  auto* show_cmd = job_cmd->add_subcommand(
      "show", "Print the fully resolved job as YAML: every default filled in, robot inline");
  show_cmd->add_option("job", show_file, "Job file (YAML)")->required();
  std::vector<std::string> show_overrides;
  addOverrides(*show_cmd, show_overrides);

  BatchOptions batch;
  auto* batch_cmd = app.add_subcommand(
      "batch",
      "Run a sweep of settings over many cases: one result row per case in OUT/results.csv and "
      "results.jsonl, summary.md, plots, an OMPL benchmark log");
  batch_cmd->add_option("sweep", batch.sweep_file, "Sweep file (YAML)");
  batch_cmd->add_option("-o,--out", batch.out_dir, "Output folder (created)");
  batch_cmd->add_option("-j,--jobs", batch.jobs, "Threads in all (default: every core)")
      ->check(CLI::PositiveNumber);
  batch_cmd->add_option("--shard", batch.shard, "Run only slice I of N (1-based), e.g. 2/8")
      ->type_name("I/N");
  batch_cmd->add_flag("--resume", batch.resume, "Skip the cases OUT/results.jsonl already has");
  std::filesystem::path batch_report_dir;
  auto* batch_report_cmd = batch_cmd->add_subcommand(
      "report", "Regenerate summary.md, plots/ and ompl_benchmark.log from OUT/results.jsonl");
  batch_report_cmd->add_option("out", batch_report_dir, "Batch output folder")->required();
  std::vector<std::filesystem::path> merge_inputs;
  std::filesystem::path merge_out;
  auto* batch_merge_cmd =
      batch_cmd->add_subcommand("merge", "Merge the results of shard runs into one folder");
  batch_merge_cmd->add_option("inputs", merge_inputs, "Batch output folders")->required();
  batch_merge_cmd->add_option("-o,--out", merge_out, "Output folder (created)")->required();

  CheckOptions check;
  auto* check_cmd = app.add_subcommand(
      "check", "Score one pose: every constraint factor, every pair's clearance, collision");
  check_cmd->add_option("job", check.job_file, "Job file (YAML)")->required();
  check_cmd->add_option("--table", check.table_deg, "Table angle, degrees")->required();
  auto* check_joints = check_cmd->add_option(
      "--joints", check.joints_deg,
      "Six joint angles in degrees: j1,…,j6 (write --joints=-10,… when j1 is negative)");
  auto* check_time = check_cmd->add_option("--time", check.time_s,
                                           "A time on the job's scan path, s: the pose is solved "
                                           "by IK (the job's map.branch, or the best)");
  check_joints->excludes(check_time);
  check_cmd->add_flag("--json", check.json, "Print JSON instead of text");
  addOverrides(*check_cmd, check.overrides);

  FkOptions fk;
  auto* fk_cmd =
      app.add_subcommand("fk", "Forward kinematics: flange (and sensor) pose for joints");
  addRobotSource(*fk_cmd, fk.source);
  fk_cmd
      ->add_option("--joints", fk.joints_deg,
                   "Six joint angles in degrees: j1,j2,j3,j4,j5,j6 "
                   "(write --joints=-10,… when j1 is negative)")
      ->required();
  fk_cmd->add_flag("--json", fk.json, "Print JSON instead of text");

  IkOptions ik;
  auto* ik_cmd =
      app.add_subcommand("ik", "Inverse kinematics: every joint solution for a flange pose");
  addRobotSource(*ik_cmd, ik.source);
  auto* trans = ik_cmd->add_option("--trans", ik.trans,
                                   "Flange pose as V+ TRANS: x,y,z (mm), y,p,r (deg, ZYZ' Euler)");
  auto* matrix = ik_cmd->add_option("--matrix", ik.matrix,
                                    "Flange pose as a 4x4 matrix: 16 numbers, row-major, mm");
  trans->excludes(matrix);
  ik_cmd->add_flag("--within-limits", ik.within_limits_only,
                   "List only solutions inside the joint limits");
  ik_cmd->add_flag("--json", ik.json, "Print JSON instead of text");

  // An example per command, run from the repository root on the bundled data (the tests run each
  // one's file names against the repository).
  const std::vector<std::pair<CLI::App*, std::vector<const char*>>> examples{
      {plan_cmd,
       {"scanplan plan data/jobs/demo.yaml -o out/demo",
        "scanplan plan data/jobs/demo.yaml -o out/dp --planner dp --compare"}},
      {validate_cmd, {"scanplan validate data/jobs/demo.yaml -t out/demo/trajectory.csv"}},
      {simulate_cmd,
       {"scanplan simulate data/jobs/demo.yaml -t out/demo/trajectory.csv -o out/sim"}},
      {export_cmd,
       {"scanplan export data/jobs/demo.yaml -t out/demo/trajectory.csv -o out/prg -f vplus,krl"}},
      {path_cmd, {"scanplan path data/jobs/demo.yaml -o out/path"}},
      {map_cmd, {"scanplan map data/jobs/demo.yaml -o out/map --set map.angle_step_deg=5"}},
      {show_cmd, {"scanplan job show data/jobs/demo.yaml --set scan.dt_s=0.2"}},
      {batch_cmd,
       {"scanplan batch data/sweeps/planners.yaml -o out/sweep",
        "scanplan batch data/sweeps/planners.yaml -o out/shard_2 --shard 2/4 --resume"}},
      {batch_report_cmd, {"scanplan batch report out/sweep"}},
      {batch_merge_cmd, {"scanplan batch merge out/shard_1 out/shard_2 -o out/sweep"}},
      {check_cmd,
       {"scanplan check data/jobs/demo.yaml --table 30 --joints=-20,-40,120,0,40,0",
        "scanplan check data/jobs/demo.yaml --table 40 --time 5 --json",
        "scanplan check data/jobs/demo.yaml --table 30 --joints=-20,-40,120,0,40,0 --set "
        "constraints.clearance.d_high_mm=60"}},
      {fk_cmd, {"scanplan fk --robot data/robots/viper_s650.yaml --joints 0,-90,180,0,90,0"}},
      {ik_cmd, {"scanplan ik --robot data/robots/viper_s650.yaml --trans 450,0,695,0,90,0"}},
  };
  for (const auto& [cmd, lines] : examples) {
    std::string footer = lines.size() > 1 ? "Examples:" : "Example:";
    for (const char* line : lines) footer += std::string("\n  ") + line;
    cmd->footer(footer);
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    std::string message = e.what();
    const auto known =
        app.get_subcommands([&](CLI::App* sub) { return argc > 1 && sub->check_name(argv[1]); });
    if (argc > 1 && argv[1][0] != '-' && known.empty()) {
      message =
          std::string("unknown command '") + argv[1] +
          "'; expected one of: plan, batch, validate, simulate, export, path, map, check, job, fk, "
          "ik";
    }
    std::fprintf(
        stderr,
        "scanplan: error: %s\nRun 'scanplan --help' (or 'scanplan COMMAND --help') for usage.\n",
        message.c_str());
    return static_cast<int>(ExitCode::kUsage);
  }
  if (check_cmd->parsed() && check_joints->count() + check_time->count() == 0) {
    std::fprintf(stderr, "scanplan: error: check needs --joints or --time\n");
    return static_cast<int>(ExitCode::kUsage);
  }
  if (batch_cmd->parsed() && !batch_report_cmd->parsed() && !batch_merge_cmd->parsed() &&
      (batch.sweep_file.empty() || batch.out_dir.empty())) {
    std::fprintf(stderr, "scanplan: error: batch needs a sweep file and -o OUT\n");
    return static_cast<int>(ExitCode::kUsage);
  }
  if (ik_cmd->parsed() && trans->count() + matrix->count() == 0) {
    std::fprintf(stderr, "scanplan: error: ik needs --trans or --matrix\n");
    return static_cast<int>(ExitCode::kUsage);
  }

  setUpLogging(quiet ? -1 : verbose);
  const auto start = std::chrono::steady_clock::now();
  try {
    if (plan_cmd->parsed()) requireInput(plan.job_file, "job file");
    if (path_cmd->parsed()) requireInput(path.job_file, "job file");
    if (map_cmd->parsed()) requireInput(map.job_file, "job file");
    if (check_cmd->parsed()) requireInput(check.job_file, "job file");
    if (show_cmd->parsed()) requireInput(show_file, "job file");
    for (const auto& [cmd, options] :
         {std::pair{validate_cmd, &validate}, std::pair{simulate_cmd, &simulate},
          std::pair{export_cmd, &export_options}}) {
      if (!cmd->parsed()) continue;
      requireInput(options->job_file, "job file");
      requireInput(options->trajectory_file, "trajectory file");
    }
    for (const auto& [cmd, source] :
         {std::pair{fk_cmd, &fk.source}, std::pair{ik_cmd, &ik.source}}) {
      if (!cmd->parsed()) continue;
      requireInput(source->robot_file, "robot file");
      requireInput(source->job_file, "job file");
    }
    if (batch_report_cmd->parsed()) {
      requireInput(batch_report_dir, "batch output folder", true);
    } else if (batch_merge_cmd->parsed()) {
      for (const auto& dir : merge_inputs) requireInput(dir, "batch output folder", true);
    } else if (batch_cmd->parsed()) {
      requireInput(batch.sweep_file, "sweep file");
    }
    spdlog::debug("scanplan {}: {}", SCANPLAN_VERSION, fmt::join(argv, argv + argc, " "));

    // What these commands print on stdout is a summary of the files they write (or, for
    // validate without --json, of the verdict the exit code gives): --quiet drops it.
    const bool summary_only = plan_cmd->parsed() || path_cmd->parsed() || map_cmd->parsed() ||
                              simulate_cmd->parsed() || export_cmd->parsed() ||
                              batch_cmd->parsed() || (validate_cmd->parsed() && !validate.json);
    const SilencedStdout silenced(quiet && summary_only);
    ExitCode code = ExitCode::kOk;
    if (plan_cmd->parsed()) code = runPlan(plan);
    if (validate_cmd->parsed()) code = runValidate(validate);
    if (simulate_cmd->parsed()) code = runSimulate(simulate);
    if (export_cmd->parsed()) code = runExport(export_options);
    if (show_cmd->parsed()) code = runJobShow(show_file, show_overrides);
    if (check_cmd->parsed()) code = runCheck(check);
    if (path_cmd->parsed()) code = runPath(path);
    if (map_cmd->parsed()) code = runMap(map);
    if (fk_cmd->parsed()) code = runFk(fk);
    if (ik_cmd->parsed()) code = runIk(ik);
    if (batch_report_cmd->parsed()) {
      code = runBatchReport(batch_report_dir);
    } else if (batch_merge_cmd->parsed()) {
      code = runBatchMerge(merge_inputs, merge_out);
    } else if (batch_cmd->parsed()) {
      code = runBatch(batch);
    }
    spdlog::debug("done in {:.2f} s, exit code {}",
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
                  static_cast<int>(code));
    return static_cast<int>(code);
  } catch (const InputError& e) {
    std::fprintf(stderr, "scanplan: error: %s\n", e.what());
    return static_cast<int>(ExitCode::kInput);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scanplan: internal error: %s (please report this)\n", e.what());
    return static_cast<int>(ExitCode::kInternal);
  }
}

}  // namespace scanplan::cli
