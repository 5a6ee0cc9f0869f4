#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <mutex>

#include <scanplan/config/job.h>
#include <scanplan/config/robot_urdf.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/pipeline/plan_scan.h>
#include <scanplan/planner/config_map.h>
#include "cli/io/exit_code.h"
#include "cli/plot/figure.h"
#include "cli/plot/map_figures.h"

namespace scanplan::cli {

/// Where a command gets its robot: a robot file, or the robot of a job.
struct RobotSource {
  std::filesystem::path robot_file;
  std::filesystem::path job_file;
};

struct FkOptions {
  RobotSource source;
  std::string joints_deg;  ///< "j1,…,j6"
  bool json = false;
};

struct IkOptions {
  RobotSource source;
  std::string trans;   ///< "x,y,z,y,p,r" (mm, V+ ZYZ' deg)
  std::string matrix;  ///< 16 numbers row-major, mm
  bool json = false;
  bool within_limits_only = false;
};

struct PlanArguments {
  std::filesystem::path job_file;
  std::filesystem::path out_dir;
  std::vector<std::string> overrides;  ///< --set key.path=value
  std::string planner;                 ///< --planner: empty = the job's planner.method
  bool compare = false;                ///< --compare: run every planner, draw every path
  bool refine = false;                 ///< --refine: NLopt refinement whatever the job says
  int setups = 1;                      ///< --setups 2: a second program, the part turned over
  bool json = false;                   ///< --json: the result as one JSON document on stdout
};

/// A progress line on stderr, only on a terminal (scripts and CI logs stay clean). Callable
/// from worker threads.
/// A progress line on stderr (a terminal only): the share done and, once the work has run a
/// few seconds, the time left at the rate so far.
class Progress {
 public:
  explicit Progress(std::string label);
  void operator()(std::size_t done, std::size_t total);

 private:
  std::string label_;
  bool enabled_;
  std::mutex mutex_;
  int last_ = -1;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

/// The part, the laser window and the generated scan path of a job.
struct PathContext {
  kinematics::LoadedMesh part;
  scanner::LaserWindow window;
  scanner::GeneratedPath generated;
  std::optional<pipeline::AutoScanReport> auto_scan;  ///< with scan.auto
};
/// Loads the part and generates the scan path; errors name the job.
PathContext buildPath(const config::JobSpec& job, const kinematics::CellModel& cell);

/// Link meshes over this many triangles in all make a map measured exactly slow.
inline constexpr std::size_t kHeavyLinkTriangles = 1000;
/// Warns (stderr) when the maps are to measure heavy link meshes exactly
/// (constraints.clearance.link_meshes: exact), naming the job and each link's triangles.
void warnSlowLinkMeshes(const config::JobSpec& job, const kinematics::CellModel& cell);
/// `validate` / `simulate`: a job and a trajectory file.
struct VerifyOptions {
  std::filesystem::path job_file;
  std::filesystem::path trajectory_file;
  std::filesystem::path out_dir;  ///< validate: optional
  std::vector<std::string> overrides;
  bool json = false;
  std::string formats;  ///< export: comma-separated program formats; empty = the job's
};
ExitCode runValidate(const VerifyOptions& options);
ExitCode runExport(const VerifyOptions& options);
ExitCode runSimulate(const VerifyOptions& options);

struct CheckOptions {
  std::filesystem::path job_file;
  double table_deg = 0.0;
  std::string joints_deg;  ///< empty: use time_s
  double time_s = -1.0;
  bool json = false;
  std::vector<std::string> overrides;  ///< --set key.path=value
};

ExitCode runCheck(const CheckOptions& options);

/// `scanplan watch`: the predictive collision watch over a stream of axis positions.
struct WatchCommandOptions {
  std::filesystem::path job_file;
  std::vector<std::string> overrides;
  std::filesystem::path log_file;  ///< empty: standard input, line by line
  double horizon_s = 1.0;
  double step_s = 0.02;
  double warn_distance_mm = 20.0;
  std::optional<double> stop_distance_mm;
  double stop_time_s = 0.2;
  std::size_t window = 25;
  double repeat_s = 0.5;  ///< a lasting warning is printed again after this long
};
ExitCode runWatch(const WatchCommandOptions& options);
ExitCode runPath(const PlanArguments& options);
ExitCode runMap(const PlanArguments& options);
/// The job's scan path (loads the part, casts rays for the standoff); errors name the job.
scanner::GeneratedPath generateScanPath(const config::JobSpec& job,
                                        const kinematics::CellModel& cell);
/// A configuration map and how long it took.
struct MapRun {
  planner::ConfigMap map;
  double seconds = 0.0;
};
/// The job's maps (every branch the job asks for) over the scan path, progress on a terminal.
MapRun computeMap(const config::JobSpec& job,
                  const collision::Scene& scene,
                  const kinematics::ScanPath& path);
/// path.csv and path.png into `dir`.
void writePathOutputs(const std::filesystem::path& dir,
                      const kinematics::CellModel& cell,
                      const kinematics::TriangleMesh& part,
                      const kinematics::ScanPath& path,
                      const WriteSettings& settings = {});
/// The file list of writePathOutputs() + writeMapOutputs(), for summaries.
extern const char* const kMapFilesNote;
/// Path, maps and their files into `out`; returns the summary lines.
std::string buildAndWriteMaps(const config::JobSpec& job,
                              const kinematics::CellModel& cell,
                              const std::filesystem::path& out);
/// The map files of `scanplan map` (npy layers, json, images) into `dir`.
void writeMapOutputs(const std::filesystem::path& dir,
                     const config::JobSpec& job,
                     const planner::ConfigMap& map,
                     const WriteSettings& settings = {});
/// `robot import`: a URDF in, the equivalent robot file out.
struct RobotImportOptions {
  config::UrdfRobotSource source;
  std::filesystem::path out_file;
};
ExitCode runRobotImport(const RobotImportOptions& options);
struct RobotCheckOptions {
  std::filesystem::path robot_file;  ///< robot YAML or URDF
  std::size_t samples = 10000;
  std::uint32_t seed = 1;
  bool json = false;
};
ExitCode runRobotCheck(const RobotCheckOptions& options);
ExitCode runFk(const FkOptions& options);
ExitCode runIk(const IkOptions& options);
/// `job schema`: the job file's JSON Schema on stdout.
ExitCode runJobSchema();
ExitCode runJobShow(const std::filesystem::path& job_file,
                    const std::vector<std::string>& overrides);
/// Without a scan path: can the sensor reach a pose above the part as the table turns?
std::string reachCheck(const config::JobSpec& job,
                       const kinematics::CellModel& cell,
                       const kinematics::LoadedMesh& part);
ExitCode runPlan(const PlanArguments& options);
/// Every file `plan` writes for `plan` into `dir` but job.yaml and report.json: the path and map
/// files; with a trajectory configmap_path.png/.svg; a valid one's trajectory.csv, programs,
/// simulation and certificate files (an invalid one's trajectory_invalid.csv). Returns the
/// summary lines of a valid plan's files (choice, validation, programs, simulation, certificate).
std::string writePlanOutputs(const std::filesystem::path& dir,
                             const config::JobSpec& job,
                             const pipeline::ScanProblem& problem,
                             const pipeline::ScanPlan& plan,
                             const WriteSettings& settings = {});

/// Parses "a,b,c" into exactly `count` finite numbers; errors name the option.
std::vector<double> parseNumberList(const std::string& text,
                                    std::size_t count,
                                    const std::string& option,
                                    const std::string& what);

}  // namespace scanplan::cli
