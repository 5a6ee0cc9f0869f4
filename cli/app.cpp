#include "cli/app.h"

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <exception>
#include <memory>
#include <optional>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <scanplan/config/text.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/planner/registry.h>
#include "cli/batch/batch.h"
#include "cli/commands/commands.h"
#include "cli/completion.h"

namespace scanplan::cli {
namespace {

void addRobotSource(CLI::App& cmd, RobotSource& source) {
  auto* robot = cmd.add_option("--robot", source.robot_file,
                               "Robot file (YAML), or a URDF (.urdf: base_link to tool0)");
  auto* job = cmd.add_option("--job", source.job_file, "Job file: use its robot (and scanner)");
  robot->excludes(job);
  cmd.callback([robot, job] {
    if (robot->count() + job->count() == 0) {
      throw CLI::RequiredError("--robot or --job");
    }
  });
}

// The `%*` of the log pattern: the message with invisible characters made visible, as in errors.
class VisibleMessage : public spdlog::custom_flag_formatter {
 public:
  void format(const spdlog::details::log_msg& msg,
              const std::tm& /*time*/,
              spdlog::memory_buf_t& dest) override {
    const std::string text = visibleText(std::string(msg.payload.data(), msg.payload.size()));
    dest.append(text.data(), text.data() + text.size());
  }
  [[nodiscard]] std::unique_ptr<custom_flag_formatter> clone() const override {
    return std::make_unique<VisibleMessage>();
  }
};

void setUpLogging(int verbosity) {
  auto logger = spdlog::stderr_color_mt("scanplan");
  auto formatter = std::make_unique<spdlog::pattern_formatter>();
  formatter->add_flag<VisibleMessage>('*').set_pattern("scanplan: %^%l%$: %*");
  logger->set_formatter(std::move(formatter));
  logger->set_level(verbosity > 0   ? spdlog::level::debug
                    : verbosity < 0 ? spdlog::level::err
                                    : spdlog::level::info);
  spdlog::set_default_logger(logger);
}

// Input files are checked here, not by CLI11's ExistingFile: a missing or
// unreadable file is bad input (exit 4), named like every other input error,
// not a usage error (exit 2).
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

// --quiet: the summary a command prints on stdout goes to /dev/null for the
// command's run; errors (and stdout again afterwards) are untouched.
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

// What the command printed reached standard output, or the run is an error: a summary, a JSON
// document or a job lost to a full disk or a closed descriptor must not look like success.
ExitCode withStdoutWritten(ExitCode code) {
  errno = 0;
  const bool flushed = std::fflush(stdout) == 0;
  const int error = errno;
  if (flushed && !std::ferror(stdout)) return code;
  std::fprintf(stderr,
               "scanplan: error: standard output: cannot be written%s%s: what the "
               "command printed there is incomplete\n",
               error != 0 ? ": " : "",
               error != 0 ? std::error_code(error, std::generic_category()).message().c_str() : "");
  return code == ExitCode::kOk ? ExitCode::kInput : code;
}

void addOverrides(CLI::App& cmd, std::vector<std::string>& overrides) {
  cmd.add_option("--set", overrides,
                 "Override a job value, as if the file said so: key.path=value "
                 "(repeatable), e.g. "
                 "--set planner.ray.horizon=20 --set scan.paths[0].height_mm=60")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false);
}

constexpr const char* kTrajectoryHelp =
    "Trajectory: a trajectory CSV (trajectory.csv from plan, or written by "
    "hand with its "
    "columns) or a program from plan or export (scan.v2, .src, .mod, .script)";

// Every command's options and CLI11 handle: the add*Command()s fill it in,
// parse() sets it, the checks and dispatch() read it. Neither copied nor moved:
// CLI11 holds pointers into it.
struct Commands {
  int verbose = 0;
  bool quiet = false;
  PlanArguments plan;
  CLI::App* plan_cmd = nullptr;
  VerifyOptions validate;
  CLI::App* validate_cmd = nullptr;
  VerifyOptions simulate;
  CLI::App* simulate_cmd = nullptr;
  VerifyOptions export_options;
  CLI::App* export_cmd = nullptr;
  PlanArguments path;
  CLI::App* path_cmd = nullptr;
  PlanArguments map;
  CLI::App* map_cmd = nullptr;
  std::filesystem::path show_file;
  std::vector<std::string> show_overrides;
  CLI::App* show_cmd = nullptr;
  CLI::App* schema_cmd = nullptr;
  std::string completion_shell;
  CLI::App* completion_cmd = nullptr;
  BatchOptions batch;
  CLI::App* batch_cmd = nullptr;
  std::filesystem::path batch_report_dir;
  CLI::App* batch_report_cmd = nullptr;
  std::vector<std::filesystem::path> merge_inputs;
  std::filesystem::path merge_out;
  CLI::App* batch_merge_cmd = nullptr;
  CheckOptions check;
  CLI::App* check_cmd = nullptr;
  WatchCommandOptions watch;
  CLI::App* watch_cmd = nullptr;
  CLI::Option* check_joints = nullptr;
  CLI::Option* check_time = nullptr;
  FkOptions fk;
  CLI::App* fk_cmd = nullptr;
  IkOptions ik;
  CLI::App* ik_cmd = nullptr;
  CLI::Option* ik_trans = nullptr;
  CLI::Option* ik_matrix = nullptr;
  RobotImportOptions robot_import;
  CLI::App* robot_import_cmd = nullptr;
  RobotCheckOptions robot_check;
  CLI::App* robot_check_cmd = nullptr;

  Commands() = default;
  Commands(const Commands&) = delete;
  Commands& operator=(const Commands&) = delete;
};

void addAppOptions(CLI::App& app, Commands& c) {
  app.set_version_flag("--version", std::string("scanplan ") + SCANPLAN_VERSION);
  app.require_subcommand(1);
  // Options of the app are also taken after the subcommand (`scanplan plan -q
  // …`): every subcommand, added below, inherits this.
  app.fallthrough();
  app.add_flag("-v,--verbose", c.verbose,
               "Also log on stderr the files each command reads, the --set "
               "overrides applied and "
               "how long the command took");
  app.add_flag("-q,--quiet", c.quiet,
               "Errors only: no summary or warnings (what job show, check, fk, "
               "ik and --json "
               "print is the result, and still printed)");
}

void addPlanCommand(CLI::App& app, Commands& c) {
  PlanArguments& plan = c.plan;
  auto* cmd = c.plan_cmd =
      app.add_subcommand("plan",
                         "Run a job end to end: scan path, configuration maps, "
                         "table-angle plan on every IK "
                         "branch, validation of the motion, robot programs and the scan "
                         "simulation, all into OUT");
  cmd->add_option("job", plan.job_file, "Job file (YAML)")->required();
  cmd->add_option("-o,--out", plan.out_dir, "Output folder (created)")->required();
  cmd->add_option("--planner", plan.planner,
                  "Table-angle search: ray (Ray Shooting), dp (exact optimum "
                  "on the grid) or ompl; "
                  "default: the job's planner.method")
      ->check(CLI::IsMember(planner::plannerNames()));
  cmd->add_flag("--compare", plan.compare,
                "Also run the other planners on the chosen branch: J side by "
                "side, every path "
                "drawn in configmap_path.png");
  cmd->add_flag("--refine", plan.refine,
                "Refine the path with NLopt even when the job turns it off: refinement "
                "is on "
                "by default (the job's planner.refine.enabled), this overrides a false");
  cmd->add_option("--setups", plan.setups,
                  "2: with scan.auto, also plan a second program with the part turned onto "
                  "another face it rests on, for the area that faces the table; its files go "
                  "to OUT/setup2, the combined coverage into the summary and report.json")
      ->check(CLI::Range(1, 2));
  cmd->add_flag("--json", plan.json,
                "Print the result as one JSON document on stdout instead of the text summary: "
                "report.json's content with out_dir, exit_code and the summary's lines");
  addOverrides(*cmd, plan.overrides);
}

void addValidateCommand(CLI::App& app, Commands& c) {
  VerifyOptions& validate = c.validate;
  auto* cmd = c.validate_cmd =
      app.add_subcommand("validate",
                         "Prove a trajectory executable: joint limits, joint and "
                         "table speeds, table acceleration, "
                         "and collisions along the whole motion (continuous check); "
                         "exit 3 when it is not");
  cmd->add_option("job", validate.job_file, "Job file (YAML)")->required();
  cmd->add_option("-t,--trajectory", validate.trajectory_file, kTrajectoryHelp)->required();
  cmd->add_option("-o,--out", validate.out_dir, "Also write OUT/validation.json");
  cmd->add_flag("--json", validate.json, "Print JSON instead of text");
  addOverrides(*cmd, validate.overrides);
}

void addSimulateCommand(CLI::App& app, Commands& c) {
  VerifyOptions& simulate = c.simulate;
  auto* cmd = c.simulate_cmd =
      app.add_subcommand("simulate",
                         "Simulate the laser scanner along a trajectory: the expected "
                         "point cloud and how much of "
                         "the part it covers");
  cmd->add_option("job", simulate.job_file, "Job file (YAML)")->required();
  cmd->add_option("-t,--trajectory", simulate.trajectory_file, kTrajectoryHelp)->required();
  cmd->add_option("-o,--out", simulate.out_dir, "Output folder (created)")->required();
  addOverrides(*cmd, simulate.overrides);
}

void addExportCommand(CLI::App& app, Commands& c) {
  VerifyOptions& export_options = c.export_options;
  auto* cmd = c.export_cmd =
      app.add_subcommand("export",
                         "Write robot programs for a trajectory: V+, KRL, RAPID, "
                         "URScript or the CSV interchange");
  cmd->add_option("job", export_options.job_file, "Job file (YAML)")->required();
  cmd->add_option("-t,--trajectory", export_options.trajectory_file, kTrajectoryHelp)->required();
  cmd->add_option("-o,--out", export_options.out_dir, "Output folder (created)")->required();
  cmd->add_option("-f,--format", export_options.formats,
                  "Comma-separated: vplus, krl, rapid, urscript, csv (default: the job's "
                  "outputs.programs)");
  addOverrides(*cmd, export_options.overrides);
}

// `path` and `map`: a job file and an output folder.
CLI::App* addJobToFolderCommand(CLI::App& app,
                                const char* name,
                                const char* description,
                                PlanArguments& options) {
  auto* cmd = app.add_subcommand(name, description);
  cmd->add_option("job", options.job_file, "Job file (YAML)")->required();
  cmd->add_option("-o,--out", options.out_dir, "Output folder (created)")->required();
  addOverrides(*cmd, options.overrides);
  return cmd;
}

void addJobCommand(CLI::App& app, Commands& c) {
  auto* job_cmd = app.add_subcommand("job", "Inspect job files");
  job_cmd->require_subcommand(1);
  auto* cmd = c.show_cmd = job_cmd->add_subcommand("show",
                                                   "Print the fully resolved job as YAML: "
                                                   "every default filled in, robot inline");
  cmd->add_option("job", c.show_file, "Job file (YAML)")->required();
  addOverrides(*cmd, c.show_overrides);
  c.schema_cmd = job_cmd->add_subcommand(
      "schema",
      "Print a JSON Schema (draft-07) of the job file on stdout: every key, its type, range "
      "and choices; unknown keys refused. For editors (VS Code's YAML extension: "
      "# yaml-language-server: $schema=job.schema.json) and scripts");
}

void addBatchCommand(CLI::App& app, Commands& c) {
  BatchOptions& batch = c.batch;
  auto* cmd = c.batch_cmd =
      app.add_subcommand("batch",
                         "Run a sweep of settings over many cases: one result row per "
                         "case in OUT/results.csv and "
                         "results.jsonl, summary.md, plots, an OMPL benchmark log");
  cmd->add_option("sweep", batch.sweep_file, "Sweep file (YAML)");
  cmd->add_option("-o,--out", batch.out_dir, "Output folder (created)");
  cmd->add_option("-j,--jobs", batch.jobs, "Threads in all (default: every core; at most 1024)")
      ->check(CLI::Range(1, 1024));
  cmd->add_option("--shard", batch.shard, "Run only slice I of N (1-based), e.g. 2/8")
      ->type_name("I/N");
  cmd->add_flag("--resume", batch.resume, "Skip the cases OUT/results.jsonl already has");
  c.batch_report_cmd =
      cmd->add_subcommand("report",
                          "Regenerate summary.md, plots/ and ompl_benchmark.log from "
                          "OUT/results.jsonl");
  c.batch_report_cmd->add_option("out", c.batch_report_dir, "Batch output folder")->required();
  c.batch_merge_cmd =
      cmd->add_subcommand("merge", "Merge the results of shard runs into one folder");
  c.batch_merge_cmd->add_option("inputs", c.merge_inputs, "Batch output folders")->required();
  c.batch_merge_cmd->add_option("-o,--out", c.merge_out, "Output folder (created)")->required();
}

void addCheckCommand(CLI::App& app, Commands& c) {
  CheckOptions& check = c.check;
  auto* cmd = c.check_cmd = app.add_subcommand("check",
                                               "Score one pose: every constraint factor, "
                                               "every pair's clearance, collision");
  cmd->add_option("job", check.job_file, "Job file (YAML)")->required();
  cmd->add_option("--table", check.table_deg, "Table angle, degrees")->required();
  c.check_joints = cmd->add_option("--joints", check.joints_deg,
                                   "Six joint angles in degrees: j1,…,j6 (write "
                                   "--joints=-10,… when j1 is negative)");
  c.check_time = cmd->add_option("--time", check.time_s,
                                 "A time on the job's scan path, s: the pose is solved "
                                 "by IK (the job's map.branch, or the best)");
  c.check_joints->excludes(c.check_time);
  cmd->add_flag("--json", check.json, "Print JSON instead of text");
  addOverrides(*cmd, check.overrides);
}

void addWatchCommand(CLI::App& app, Commands& c) {
  WatchCommandOptions& w = c.watch;
  auto* cmd = c.watch_cmd = app.add_subcommand(
      "watch",
      "Predictive collision watch: read measured joint positions (a log, or standard input "
      "line by line), predict the motion (joint or Cartesian) and warn before bodies meet");
  cmd->add_option("job", w.job_file, "Job file (YAML): the cell, robot and clearance pairs")
      ->required();
  cmd->add_option("--log", w.log_file,
                  "CSV of t_s,table_deg,j1_deg,…,j6_deg (a header names the columns; "
                  "trajectory.csv reads as it is); without it, standard input");
  cmd->add_option("--horizon-s", w.horizon_s, "How far ahead to predict, s")->capture_default_str();
  cmd->add_option("--step-s", w.step_s, "Time between predicted poses, s")->capture_default_str();
  cmd->add_option("--warn-distance-mm", w.warn_distance_mm,
                  "Warn when bodies getting closer are predicted within this distance, mm")
      ->capture_default_str();
  cmd->add_option("--stop-distance-mm", w.stop_distance_mm,
                  "Exit with code 5 as soon as bodies getting closer are predicted within this "
                  "distance within --stop-time-s, mm (0: contact)");
  cmd->add_option("--stop-time-s", w.stop_time_s,
                  "How far ahead a stop-distance breach calls for a stop: the time the robot "
                  "needs to brake, s")
      ->capture_default_str();
  cmd->add_option("--window", w.window, "Samples the motion model is fitted on")
      ->capture_default_str();
  cmd->add_option("--repeat-s", w.repeat_s, "Print a lasting warning again after this long, s")
      ->capture_default_str();
  addOverrides(*cmd, w.overrides);
}

void addFkCommand(CLI::App& app, Commands& c) {
  FkOptions& fk = c.fk;
  auto* cmd = c.fk_cmd =
      app.add_subcommand("fk", "Forward kinematics: flange (and sensor) pose for joints");
  addRobotSource(*cmd, fk.source);
  cmd->add_option("--joints", fk.joints_deg,
                  "Six joint angles in degrees: j1,j2,j3,j4,j5,j6 "
                  "(write --joints=-10,… when j1 is negative)")
      ->required();
  cmd->add_flag("--json", fk.json, "Print JSON instead of text");
}

void addIkCommand(CLI::App& app, Commands& c) {
  IkOptions& ik = c.ik;
  auto* cmd = c.ik_cmd =
      app.add_subcommand("ik", "Inverse kinematics: every joint solution for a flange pose");
  addRobotSource(*cmd, ik.source);
  c.ik_trans = cmd->add_option("--trans", ik.trans,
                               "Flange pose as V+ TRANS: x,y,z (mm), y,p,r (deg, ZYZ' Euler)");
  c.ik_matrix = cmd->add_option("--matrix", ik.matrix,
                                "Flange pose as a 4x4 matrix: 16 numbers, row-major, mm");
  c.ik_trans->excludes(c.ik_matrix);
  cmd->add_flag("--within-limits", ik.within_limits_only,
                "List only solutions inside the joint limits");
  cmd->add_flag("--json", ik.json, "Print JSON instead of text");
}

void addRobotCheckCommand(CLI::App& robot_cmd, Commands& c) {
  RobotCheckOptions& o = c.robot_check;
  auto* cmd = c.robot_check_cmd = robot_cmd.add_subcommand(
      "check",
      "Sample random configurations within the joint limits and list the link pairs that collide "
      "in all, in >= 95% or in none of them; suggest allowed_collisions for the robot file (pairs "
      "that overlap by design, as MoveIt's setup assistant does)");
  cmd->add_option("robot", o.robot_file, "Robot file (YAML) or URDF")->required();
  cmd->add_option("--samples", o.samples, "Random configurations")
      ->check(CLI::Range(std::size_t{1}, std::size_t{10000000}))
      ->capture_default_str();
  cmd->add_option("--seed", o.seed, "Seed of the random configurations")->capture_default_str();
  cmd->add_flag("--json", o.json, "Print JSON instead of text");
}

void addRobotCommand(CLI::App& app, Commands& c) {
  auto* robot_cmd =
      app.add_subcommand("robot", "Robot files: import a URDF, survey the links' self-collisions");
  robot_cmd->require_subcommand(1);
  config::UrdfRobotSource& s = c.robot_import.source;
  auto* cmd = c.robot_import_cmd = robot_cmd->add_subcommand(
      "import",
      "Write the robot file (YAML) of a URDF's 6-axis ortho-parallel arm: DH rows from the "
      "joints between --base-link and --tip-link (fixed joints folded in), OPW parameters derived "
      "from them and checked, limits and speeds from <limit>, collision geometry from <collision>");
  cmd->add_option("urdf", s.urdf, "URDF file")->required();
  cmd->add_option("-o,--out", c.robot_import.out_file, "Robot file to write (YAML)")->required();
  cmd->add_option("--base-link", s.base_link,
                  "The link at DH frame 0: origin on the J1 axis, z along it")
      ->capture_default_str();
  cmd->add_option("--tip-link", s.tip_link,
                  "The flange link (DH frame 6): origin on the J6 axis, z along it")
      ->capture_default_str();
  cmd->add_option("--package-path", s.package_path,
                  "A folder holding ROS packages (PKG/…) for package://PKG/… mesh URIs "
                  "(repeatable; searched before SCANPLAN_PACKAGE_PATH)")
      ->allow_extra_args(false);
  cmd->add_option("--opw-parameters", s.opw_parameters,
                  "A ROS-Industrial opw_kinematics parameter YAML (m, rad) for the IK, checked "
                  "against the chain (default: derived from it)");
  cmd->add_option("--name", s.name, "Robot name (default: the URDF's <robot name>)");
  cmd->add_option("--controller", s.controller,
                  "The controller, for the programs plan writes: adept_vplus, kuka_krl, "
                  "abb_rapid, ur_script or none")
      ->check(CLI::IsMember(config::kControllers))
      ->capture_default_str();
  addRobotCheckCommand(*robot_cmd, c);
}

// An example per command, run from the repository root on the bundled data (the
// tests run each one's file names against the repository).
void addExamples(const Commands& c) {
  const std::vector<std::pair<CLI::App*, std::vector<const char*>>> examples{
      {c.plan_cmd,
       {"scanplan plan data/jobs/demo.yaml -o out/demo",
        "scanplan plan data/jobs/demo.yaml -o out/dp --planner dp --compare",
        "scanplan plan data/jobs/demo.yaml -o out/two --setups 2"}},
      {c.validate_cmd, {"scanplan validate data/jobs/demo.yaml -t out/demo/trajectory.csv"}},
      {c.simulate_cmd,
       {"scanplan simulate data/jobs/demo.yaml -t out/demo/trajectory.csv -o "
        "out/sim"}},
      {c.export_cmd,
       {"scanplan export data/jobs/demo.yaml -t out/demo/trajectory.csv -o "
        "out/prg -f vplus,csv"}},
      {c.path_cmd, {"scanplan path data/jobs/demo.yaml -o out/path"}},
      {c.map_cmd,
       {"scanplan map data/jobs/demo.yaml -o out/map --set "
        "map.angle_step_deg=5"}},
      {c.show_cmd, {"scanplan job show data/jobs/demo.yaml --set scan.dt_s=0.2"}},
      {c.schema_cmd, {"scanplan job schema > job.schema.json"}},
      {c.completion_cmd,
       {"source <(scanplan completion bash)",
        "scanplan completion bash > ~/.local/share/bash-completion/completions/scanplan"}},
      {c.batch_cmd,
       {"scanplan batch data/sweeps/planners.yaml -o out/sweep",
        "scanplan batch data/sweeps/planners.yaml -o out/shard_2 --shard 2/4 "
        "--resume"}},
      {c.batch_report_cmd, {"scanplan batch report out/sweep"}},
      {c.batch_merge_cmd, {"scanplan batch merge out/shard_1 out/shard_2 -o out/sweep"}},
      {c.check_cmd,
       {"scanplan check data/jobs/demo.yaml --table 30 "
        "--joints=-20,-40,120,0,40,0",
        "scanplan check data/jobs/demo_rings.yaml --table 40 --time 5 --json",
        "scanplan check data/jobs/demo.yaml --table 30 "
        "--joints=-20,-40,120,0,40,0 --set "
        "constraints.clearance.d_high_mm=60"}},
      {c.watch_cmd,
       {"scanplan watch data/jobs/demo_rings.yaml --log out/rings/trajectory.csv --window 5",
        "my_robot_reader | scanplan watch data/jobs/demo_rings.yaml --stop-distance-mm 5"}},
      {c.fk_cmd,
       {"scanplan fk --robot data/robots/viper_s650.yaml --joints "
        "0,-90,180,0,90,0"}},
      {c.ik_cmd,
       {"scanplan ik --robot data/robots/viper_s650.yaml --trans "
        "450,0,695,0,90,0"}},
      {c.robot_import_cmd,
       {"scanplan robot import data/robots/urdf/kuka_kr6_r700_sixx.urdf -o kr6_r700.yaml "
        "--controller kuka_krl",
        "scanplan robot import data/robots/urdf/abb_irb2400.urdf -o irb2400.yaml "
        "--opw-parameters data/robots/urdf/abb_irb2400_opw.yaml"}},
      {c.robot_check_cmd,
       {"scanplan robot check data/robots/viper_s650.yaml",
        "scanplan robot check data/robots/urdf/abb_irb2400.urdf --samples 20000 --json"}},
  };
  for (const auto& [cmd, lines] : examples) {
    std::string footer = lines.size() > 1 ? "Examples:" : "Example:";
    for (const char* line : lines) footer += std::string("\n  ") + line;
    cmd->footer(footer);
  }
}

void addCommands(CLI::App& app, Commands& c) {
  addAppOptions(app, c);
  addPlanCommand(app, c);
  addValidateCommand(app, c);
  addSimulateCommand(app, c);
  addExportCommand(app, c);
  c.path_cmd = addJobToFolderCommand(app, "path",
                                     "Generate the scan path: OUT/path.csv and "
                                     "a picture of it around the part",
                                     c.path);
  c.map_cmd = addJobToFolderCommand(app, "map",
                                    "Build the configuration maps over table "
                                    "angle x time: npy layers, json, images",
                                    c.map);
  addJobCommand(app, c);
  addBatchCommand(app, c);
  addCheckCommand(app, c);
  addWatchCommand(app, c);
  addFkCommand(app, c);
  addIkCommand(app, c);
  addRobotCommand(app, c);
  c.completion_cmd = app.add_subcommand(
      "completion",
      "Print a shell completion script for bash or zsh: source <(scanplan completion bash)");
  c.completion_cmd->add_option("shell", c.completion_shell, "bash or zsh")
      ->required()
      ->check(CLI::IsMember({"bash", "zsh"}));
  addExamples(c);
}

// The subcommands of `app`, by name.
std::vector<std::string> subcommandNames(CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    names.push_back(sub->get_name());
  }
  return names;
}

// The long options ("--planner") of `app` and, for a subcommand, of the app above it.
std::vector<std::string> optionNames(CLI::App& app) {
  std::vector<std::string> names;
  for (CLI::App* a = &app; a != nullptr; a = a->get_parent()) {
    for (const CLI::Option* o : a->get_options()) {
      for (const std::string& n : o->get_lnames()) names.push_back("--" + n);
    }
  }
  return names;
}

// A usage error made helpful: an unknown command or option names what was meant ("did you
// mean 'plan'?") and what there is. Empty when the error is of another kind.
std::string usageHint(CLI::App& app, int argc, char** argv) {
  CLI::App* at = &app;  // the deepest command the arguments name
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("-", 0) == 0) {
      const std::string name = arg.substr(0, arg.find('='));
      const std::vector<std::string> options = optionNames(*at);
      if (name.rfind("--", 0) != 0 ||
          std::find(options.begin(), options.end(), name) != options.end()) {
        continue;
      }
      const std::string near = config::suggestKey(name, options);
      return fmt::format("unknown option '{}' for '{}'{}", name,
                         at == &app ? std::string("scanplan") : at->get_name(),
                         near.empty() ? "" : "; did you mean '" + near + "'?");
    }
    const auto named = at->get_subcommands([&](CLI::App* sub) { return sub->check_name(arg); });
    if (!named.empty()) {
      at = named.front();
      continue;
    }
    const std::vector<std::string> commands = subcommandNames(*at);
    if (commands.empty() || at->get_require_subcommand_min() == 0) continue;  // a positional
    const std::string near = config::suggestKey(arg, commands);
    const std::string where = at == &app ? "command" : at->get_name() + " command";
    return fmt::format("unknown {} '{}'{} (expected one of: {})", where, arg,
                       near.empty() ? "" : "; did you mean '" + near + "'?",
                       fmt::join(commands, ", "));
  }
  if (at != &app && at->get_require_subcommand_min() > 0) {
    return fmt::format("'{}' needs a command: {}", at->get_name(),
                       fmt::join(subcommandNames(*at), ", "));
  }
  return "";
}

// Parses the command line; on a usage error (or --help, --version) prints it
// and returns the exit code.
std::optional<int> parseArguments(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    // Unknown words (and a missing subcommand) get a hint; a bad value keeps CLI11's message.
    const bool unknown = dynamic_cast<const CLI::ExtrasError*>(&e) != nullptr ||
                         dynamic_cast<const CLI::RequiredError*>(&e) != nullptr;
    const std::string hint = unknown ? usageHint(app, argc, argv) : std::string();
    std::fprintf(stderr,
                 "scanplan: error: %s\nRun 'scanplan --help' (or 'scanplan "
                 "COMMAND --help') for usage.\n",
                 visibleText(hint.empty() ? std::string(e.what()) : hint).c_str());
    return static_cast<int>(ExitCode::kUsage);
  }
  return std::nullopt;
}

// The usage errors CLI11 cannot express: one of two options, or the arguments
// of a command without subcommand. Printed; false when there is one.
bool checkChoices(const Commands& c) {
  const char* error = nullptr;
  if (c.check_cmd->parsed() && c.check_joints->count() + c.check_time->count() == 0) {
    error = "check needs --joints or --time";
  } else if (c.batch_cmd->parsed() && !c.batch_report_cmd->parsed() &&
             !c.batch_merge_cmd->parsed() &&
             (c.batch.sweep_file.empty() || c.batch.out_dir.empty())) {
    error = "batch needs a sweep file and -o OUT";
  } else if (c.ik_cmd->parsed() && c.ik_trans->count() + c.ik_matrix->count() == 0) {
    error = "ik needs --trans or --matrix";
  }
  if (error == nullptr) return true;
  std::fprintf(stderr, "scanplan: error: %s\n", error);
  return false;
}

void requireInputs(const Commands& c) {
  if (c.plan_cmd->parsed()) requireInput(c.plan.job_file, "job file");
  if (c.path_cmd->parsed()) requireInput(c.path.job_file, "job file");
  if (c.map_cmd->parsed()) requireInput(c.map.job_file, "job file");
  if (c.check_cmd->parsed()) requireInput(c.check.job_file, "job file");
  if (c.watch_cmd->parsed()) {
    requireInput(c.watch.job_file, "job file");
    if (!c.watch.log_file.empty()) requireInput(c.watch.log_file, "log file");
  }
  if (c.show_cmd->parsed()) requireInput(c.show_file, "job file");
  for (const auto& [cmd, options] :
       {std::pair{c.validate_cmd, &c.validate}, std::pair{c.simulate_cmd, &c.simulate},
        std::pair{c.export_cmd, &c.export_options}}) {
    if (!cmd->parsed()) continue;
    requireInput(options->job_file, "job file");
    requireInput(options->trajectory_file, "trajectory file");
  }
  for (const auto& [cmd, source] :
       {std::pair{c.fk_cmd, &c.fk.source}, std::pair{c.ik_cmd, &c.ik.source}}) {
    if (!cmd->parsed()) continue;
    requireInput(source->robot_file, "robot file");
    requireInput(source->job_file, "job file");
  }
  if (c.robot_check_cmd->parsed()) requireInput(c.robot_check.robot_file, "robot file");
  if (c.robot_import_cmd->parsed()) {
    const config::UrdfRobotSource& s = c.robot_import.source;
    requireInput(s.urdf, "URDF file");
    requireInput(s.opw_parameters, "opw_parameters file");
    for (const auto& dir : s.package_path) requireInput(dir, "package folder", true);
  }
  if (c.batch_report_cmd->parsed()) {
    requireInput(c.batch_report_dir, "batch output folder", true);
  } else if (c.batch_merge_cmd->parsed()) {
    for (const auto& dir : c.merge_inputs) requireInput(dir, "batch output folder", true);
  } else if (c.batch_cmd->parsed()) {
    requireInput(c.batch.sweep_file, "sweep file");
  }
}

// What these commands print on stdout is a summary of the files they write (or,
// for validate without --json, of the verdict the exit code gives): --quiet
// drops it.
bool printsSummaryOnly(const Commands& c) {
  return (c.plan_cmd->parsed() && !c.plan.json) || c.path_cmd->parsed() || c.map_cmd->parsed() ||
         c.simulate_cmd->parsed() || c.export_cmd->parsed() || c.batch_cmd->parsed() ||
         c.robot_import_cmd->parsed() || (c.validate_cmd->parsed() && !c.validate.json);
}

ExitCode dispatch(const Commands& c) {
  ExitCode code = ExitCode::kOk;
  if (c.plan_cmd->parsed()) code = runPlan(c.plan);
  if (c.validate_cmd->parsed()) code = runValidate(c.validate);
  if (c.simulate_cmd->parsed()) code = runSimulate(c.simulate);
  if (c.export_cmd->parsed()) code = runExport(c.export_options);
  if (c.show_cmd->parsed()) code = runJobShow(c.show_file, c.show_overrides);
  if (c.schema_cmd->parsed()) code = runJobSchema();
  if (c.check_cmd->parsed()) code = runCheck(c.check);
  if (c.watch_cmd->parsed()) code = runWatch(c.watch);
  if (c.path_cmd->parsed()) code = runPath(c.path);
  if (c.map_cmd->parsed()) code = runMap(c.map);
  if (c.fk_cmd->parsed()) code = runFk(c.fk);
  if (c.ik_cmd->parsed()) code = runIk(c.ik);
  if (c.robot_import_cmd->parsed()) code = runRobotImport(c.robot_import);
  if (c.robot_check_cmd->parsed()) code = runRobotCheck(c.robot_check);
  if (c.batch_report_cmd->parsed()) {
    code = runBatchReport(c.batch_report_dir);
  } else if (c.batch_merge_cmd->parsed()) {
    code = runBatchMerge(c.merge_inputs, c.merge_out);
  } else if (c.batch_cmd->parsed()) {
    code = runBatch(c.batch);
  }
  return code;
}

}  // namespace

int run(int argc, char** argv) {
  CLI::App app{
      "scanplan — scanning path planner for a 6-axis arm with a laser "
      "line scanner and a rotary "
      "table.\nUnits at the command line: mm and degrees."};
  Commands commands;
  addCommands(app, commands);
  if (const auto code = parseArguments(app, argc, argv)) return *code;
  if (!checkChoices(commands)) return static_cast<int>(ExitCode::kUsage);
  if (commands.completion_cmd->parsed()) {
    std::fputs(completionScript(app, commands.completion_shell).c_str(), stdout);
    return static_cast<int>(withStdoutWritten(ExitCode::kOk));
  }

  setUpLogging(commands.quiet ? -1 : commands.verbose);
  const auto start = std::chrono::steady_clock::now();
  try {
    requireInputs(commands);
    spdlog::debug("scanplan {}: {}", SCANPLAN_VERSION, fmt::join(argv, argv + argc, " "));
    ExitCode code = ExitCode::kOk;
    {
      const SilencedStdout silenced(commands.quiet && printsSummaryOnly(commands));
      code = dispatch(commands);
    }
    spdlog::debug("done in {:.2f} s, exit code {}",
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
                  static_cast<int>(code));
    return static_cast<int>(withStdoutWritten(code));
  } catch (const InputError& e) {
    std::fprintf(stderr, "scanplan: error: %s\n", e.what());
    return static_cast<int>(ExitCode::kInput);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scanplan: internal error: %s (please report this)\n",
                 visibleText(e.what()).c_str());
    return static_cast<int>(ExitCode::kInternal);
  }
}

}  // namespace scanplan::cli
