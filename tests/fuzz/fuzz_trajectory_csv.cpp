// Trajectory files (`-t` of validate, simulate, export) as the CLI reads them:
// loadTrajectoryFile, which takes the CSV interchange format (or a V+ program).
#include <cstddef>
#include <cstdint>

#include "cli/io/trajectory_file.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace scanplan;
  const auto file = fuzz::writeInput("input/trajectory.csv", data, size);
  return fuzz::expectInputErrors([&] { (void)cli::loadTrajectoryFile(file); });
}
