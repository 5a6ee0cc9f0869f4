// Job files as `scanplan job show` and `plan` read them: loadJob (beside the bundled jobs, so
// `robot: ../robots/…` and `part.mesh: ../parts/…` resolve), then the resolved job and its hash.
#include <cstddef>
#include <cstdint>

#include <scanplan/config/job.h>
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace scanplan;
  const auto file = fuzz::writeInput("jobs/fuzz_input.yaml", data, size);
  return fuzz::expectInputErrors([&] {
    const config::JobSpec job = config::loadJob(file);
    (void)config::jobToYaml(job);
    (void)config::jobHash(job);
  });
}
