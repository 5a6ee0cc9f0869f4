#include "cli/io/trajectory_file.h"

#include <fstream>
#include <sstream>
#include <string>

#include <fmt/format.h>

#include "cli/programs/programs.h"
#include "kinematics/error.h"

namespace scanplan::cli {

namespace {

std::string readWhole(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) {
    throw InputError(fmt::format("{}: file does not exist", file.string()));
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(fmt::format("{}: cannot be read", file.string()));
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

kinematics::Trajectory loadTrajectoryFile(const std::filesystem::path& file) {
  const std::string text = readWhole(file);
  const bool vplus = text.rfind(".PROGRAM", 0) == 0 || text.find("\n.PROGRAM") != std::string::npos;
  return vplus ? readVplusProgram(text, file.string())
               : kinematics::parseTrajectoryCsv(text, file.string());
}

}  // namespace scanplan::cli
