// Trajectory files (`-t` of validate, simulate, export) as the CLI reads them:
// loadTrajectoryFile, which takes the CSV interchange format (or a V+ program), read as the
// commands read it, with the job's robot (a V+ program's SPEED timed against its joint speeds),
// and as a library caller without one.
#include <cstddef>
#include <cstdint>

#include "cli/config/robot_file.h"
#include "cli/io/trajectory_file.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace scanplan;
  static const kinematics::RobotModel robot = [] {
    const auto file = fuzz::scratch() / "robots" / "viper_s650.yaml";
    return cli::buildRobotModel(cli::loadRobotFile(file), file.string());
  }();
  const auto file = fuzz::writeInput("input/trajectory.csv", data, size);
  fuzz::expectInputErrors([&] { (void)cli::loadTrajectoryFile(file, &robot); });
  return fuzz::expectInputErrors([&] { (void)cli::loadTrajectoryFile(file); });
}
