#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "cli/app.h"
#include "cli/job.h"
#include "planner/config_map.h"

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

struct PlanOptions {
  std::filesystem::path job_file;
  std::filesystem::path out_dir;
};

struct CheckOptions {
  std::filesystem::path job_file;
  double table_deg = 0.0;
  std::string joints_deg;  ///< empty: use time_s
  double time_s = -1.0;
  bool json = false;
};

ExitCode runCheck(const CheckOptions& options);
ExitCode runPath(const PlanOptions& options);
ExitCode runMap(const PlanOptions& options);
/// The job's scan path (loads the part, casts rays for the standoff); errors name the job.
scanner::GeneratedPath generateScanPath(const JobSpec& job, const kinematics::CellModel& cell);
/// Path, maps and their files into `out`; returns the summary lines.
std::string buildAndWriteMaps(const JobSpec& job,
                              const kinematics::CellModel& cell,
                              const std::filesystem::path& out);
/// The map files of `scanplan map` (npy layers, json, images) into `dir`.
void writeMapOutputs(const std::filesystem::path& dir,
                     const JobSpec& job,
                     const planner::ConfigMap& map);
ExitCode runFk(const FkOptions& options);
ExitCode runIk(const IkOptions& options);
ExitCode runJobShow(const std::filesystem::path& job_file);
ExitCode runPlan(const PlanOptions& options);

/// Parses "a,b,c" into exactly `count` finite numbers; errors name the option.
std::vector<double> parseNumberList(const std::string& text,
                                    std::size_t count,
                                    const std::string& option,
                                    const std::string& what);

}  // namespace scanplan::cli
