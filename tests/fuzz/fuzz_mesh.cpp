// Mesh files through the guarded loader (kinematics::loadMesh: the file and header checks,
// then assimp). The first byte picks the format (its value modulo 4: STL, OBJ, PLY, OFF, the
// file's extension), the rest is the file.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include <scanplan/kinematics/mesh.h>
#include "tests/fuzz/fuzz_support.h"

// Debian's libassimp 5.2 leaks an importer structure (about 1.3 kB) when it gives up on some
// malformed PLY files; that is assimp's, not ours, and a scanplan process ends soon after.
// Leaks allocated by scanplan's own code (no assimp frame in their stack) are still reported.
extern "C" const char* __lsan_default_suppressions() { return "leak:libassimp.so\n"; }

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace scanplan;
  if (size == 0) return 0;
  static constexpr std::array<const char*, 4> kExtensions = {"stl", "obj", "ply", "off"};
  const std::string name = std::string("input/mesh.") + kExtensions[data[0] % 4];
  const auto file = fuzz::writeInput(name, data + 1, size - 1);
  return fuzz::expectInputErrors([&] { (void)kinematics::loadMesh(file); });
}
