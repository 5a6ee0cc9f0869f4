// Scan path files (`scan.paths[].type: file`): parsePathCsv, which the job's path request
// (config::pathRequest) calls with the file's text.
#include <cstddef>
#include <cstdint>

#include <scanplan/scanner/path_generators.h>
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace scanplan;
  return fuzz::expectInputErrors(
      [&] { (void)scanner::parsePathCsv(fuzz::text(data, size), "fuzz.csv"); });
}
