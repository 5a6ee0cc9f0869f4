// Robot files as `scanplan fk --robot` reads them: loadRobotFile, then the kinematic model
// (OPW checked against DH).
#include <cstddef>
#include <cstdint>

#include <scanplan/config/robot_file.h>
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace scanplan;
  const auto file = fuzz::writeInput("robots_input.yaml", data, size);
  return fuzz::expectInputErrors([&] {
    const config::RobotSpec robot = config::loadRobotFile(file);
    (void)config::buildRobotModel(robot, file.string());
  });
}
