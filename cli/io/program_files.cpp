#include "cli/io/program_files.h"

#include <algorithm>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/shape.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/programs/programs.h>
#include "cli/io/output.h"

namespace scanplan::cli {

namespace {

// The summary's word on the formats against the robot's controller: a warning for another
// vendor's language (its joint values are this robot's, not that vendor's), a note when the
// robot file names no controller.
std::string controllerNote(const config::RobotSpec& robot,
                           const std::vector<std::string>& formats) {
  const std::vector<std::string> foreign = config::foreignPrograms(robot, formats);
  if (!foreign.empty()) {
    const std::string warning =
        fmt::format("{} {} not the language of robot '{}' (controller {}, writes {})",
                    fmt::join(foreign, ", "), foreign.size() == 1 ? "is" : "are", robot.name,
                    robot.controller, config::controllerProgramFormat(robot.controller));
    spdlog::warn("programs: {}", warning);
    return "; WARNING: " + warning;
  }
  if (config::controllerProgramFormat(robot.controller).empty()) {
    return fmt::format("; robot '{}' names no controller (controller: none)", robot.name);
  }
  return "";
}

// The scanner's centre of gravity when the job does not give it: the centre of its housing's
// bounding box, or the laser frame's origin without a housing (flange frame, m).
Eigen::Vector3d defaultCog(const kinematics::CellModel& cell) {
  Eigen::AlignedBox3d box;
  for (const kinematics::Shape& shape : cell.scanner.body) {
    for (const Eigen::Vector3d& v : kinematics::shapeSurface(shape).vertices) box.extend(v);
  }
  const Eigen::Vector3d centre =
      box.isEmpty() ? Eigen::Vector3d(Eigen::Vector3d::Zero()) : Eigen::Vector3d(box.center());
  return cell.scanner.X_FS * centre;
}

}  // namespace

programs::ProgramOptions programOptions(const config::JobSpec& job,
                                        const kinematics::CellModel& cell) {
  programs::ProgramOptions options;
  options.name = job.outputs.program_name;
  options.job = job.name;
  options.table_max_speed = deg(job.table.max_speed_deg_s);
  options.tool = cell.scanner.X_FS;
  options.payload_kg = job.scanner.mass_kg;
  options.payload_cog =
      job.scanner.cog_given
          ? Eigen::Vector3d(job.scanner.cog_mm[0], job.scanner.cog_mm[1], job.scanner.cog_mm[2]) /
                1000.0
          : defaultCog(cell);
  options.trigger.output = job.outputs.trigger.output;
  options.trigger.on_at_scan_start = job.outputs.trigger.on_at_scan_start;
  options.trigger.rapid_signal = job.outputs.trigger.rapid_signal;
  options.table_endless = job.table.continuous;
  options.servo_period = job.outputs.servo_period_s;
  return options;
}

std::string writePrograms(const std::filesystem::path& dir,
                          const std::string& shown_as,
                          const config::JobSpec& job,
                          const kinematics::CellModel& cell,
                          const kinematics::Trajectory& trajectory,
                          const std::vector<std::string>& formats,
                          bool skip_refused) {
  const programs::ProgramOptions options = programOptions(job, cell);
  std::vector<std::string> written, refused;
  double max_percent = 0.0;
  std::size_t over = 0;
  for (const std::string& name : formats) {
    const auto format = programs::parseProgramFormat(name);
    if (!format)
      throw InputError(fmt::format("program format '{}': expected one of {}", name,
                                   fmt::join(programs::programFormatNames(), ", ")));
    programs::ProgramFiles files;
    try {
      files = programs::writeProgram(trajectory, cell.robot, *format, options);
    } catch (const InputError& e) {
      if (!skip_refused) throw;
      spdlog::warn("programs: {} not written: {}", name, e.what());
      refused.push_back(fmt::format("{} NOT written ({})", name, e.what()));
      continue;
    }
    for (const auto& [file, content] : files.files) {
      writeFileAtomically(dir / file, content);
      written.push_back(file);
    }
    max_percent = std::max(max_percent, files.max_speed_percent);
    over = std::max(over, files.over_speed_segments);
  }
  const std::string not_written =
      refused.empty() ? std::string() : fmt::format("; {}", fmt::join(refused, "; "));
  if (written.empty()) {
    return refused.empty() ? "programs   none (outputs.programs is empty)\n"
                           : "programs   none written" + not_written + "\n";
  }
  return fmt::format(
      "programs   {}: {}; fastest step {:.0f}% of an axis's max speed (joints, table){}{}{}\n",
      shown_as, fmt::join(written, ", "), max_percent,
      over == 0
          ? std::string()
          : fmt::format(", {} step(s) need more than 100% (marked WARNING, run slower)", over),
      controllerNote(job.robot, formats), not_written);
}

}  // namespace scanplan::cli
