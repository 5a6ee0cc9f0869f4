#include "cli/io/trajectory_file.h"

#include <fstream>
#include <sstream>
#include <string>

#include <fmt/format.h>

#include <scanplan/kinematics/error.h>
#include <scanplan/programs/programs.h>

namespace scanplan::cli {

namespace {

constexpr std::uintmax_t kMaxTrajectoryBytes = std::uintmax_t{1} << 30;  // 1 GB

std::string readWhole(const std::filesystem::path& file) {
  std::error_code ec;
  const auto status = std::filesystem::status(file, ec);
  if (!std::filesystem::exists(status)) {
    throw InputError(fmt::format("{}: file does not exist", file.string()));
  }
  // A pipe or a device would be read without end (a FIFO waits, /dev/zero fills the memory).
  if (!std::filesystem::is_regular_file(status)) {
    throw InputError(fmt::format(
        "{}: is not a regular file (a directory, pipe or device): expected a trajectory file",
        file.string()));
  }
  const std::uintmax_t size = std::filesystem::file_size(file, ec);
  if (!ec && size > kMaxTrajectoryBytes) {
    throw InputError(fmt::format("{}: is {} MB: expected a trajectory file of at most {} MB",
                                 file.string(), size >> 20, kMaxTrajectoryBytes >> 20));
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(fmt::format("{}: cannot be read", file.string()));
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

kinematics::Trajectory loadTrajectoryFile(const std::filesystem::path& file,
                                          const kinematics::RobotModel* robot) {
  const std::string text = readWhole(file);
  const auto format = programs::programFormatOfFile(file.filename().string());
  if (format && *format != programs::ProgramFormat::kCsv) {
    return programs::atStepTimes(programs::readProgram(text, *format, file.string(), robot));
  }
  const bool vplus = text.rfind(".PROGRAM", 0) == 0 || text.find("\n.PROGRAM") != std::string::npos;
  return vplus ? programs::readVplusProgram(text, file.string(), robot)
               : kinematics::parseTrajectoryCsv(text, file.string());
}

}  // namespace scanplan::cli
