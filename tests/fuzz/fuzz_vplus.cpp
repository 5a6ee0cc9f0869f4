// V+ programs as trajectory files: readVplusProgram, which loadTrajectoryFile calls for a file
// with a .PROGRAM line (called directly, so that no mutation falls through to the CSV reader).
#include <cstddef>
#include <cstdint>

#include <scanplan/programs/programs.h>
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace scanplan;
  return fuzz::expectInputErrors(
      [&] { (void)programs::readVplusProgram(fuzz::text(data, size), "fuzz.v2"); });
}
