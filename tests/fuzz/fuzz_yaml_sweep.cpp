// Sweep files as `scanplan batch` reads them: loadSweep (beside the bundled sweeps, so
// `jobs: [../jobs/demo_rings.yaml]` resolves), which checks every value on every base job.
#include <cstddef>
#include <cstdint>

#include "cli/batch/batch.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace scanplan;
  const auto file = fuzz::writeInput("sweeps/fuzz_input.yaml", data, size);
  return fuzz::expectInputErrors([&] { (void)cli::loadSweep(file); });
}
