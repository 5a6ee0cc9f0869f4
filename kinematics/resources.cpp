#include <scanplan/kinematics/resources.h>

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>

namespace scanplan::kinematics {

namespace {

// MemAvailable, bytes; SIZE_MAX when the kernel does not say.
std::size_t memAvailable() {
  std::ifstream in("/proc/meminfo");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("MemAvailable:", 0) != 0) continue;
    std::istringstream words(line.substr(13));
    std::uint64_t kb = 0;
    if (words >> kb) return static_cast<std::size_t>(kb) * 1024;
  }
  return std::numeric_limits<std::size_t>::max();
}

// The headroom under RLIMIT_AS, bytes; SIZE_MAX without a limit.
std::size_t addressSpaceHeadroom() {
  rlimit limit{};
  if (::getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) {
    return std::numeric_limits<std::size_t>::max();
  }
  std::ifstream in("/proc/self/statm");
  std::uint64_t pages = 0;
  in >> pages;
  const auto used = static_cast<std::uint64_t>(pages) *
                    static_cast<std::uint64_t>(std::max(0L, ::sysconf(_SC_PAGESIZE)));
  return limit.rlim_cur > used ? static_cast<std::size_t>(limit.rlim_cur - used) : 0;
}

}  // namespace

std::size_t availableMemoryBytes() { return std::min(memAvailable(), addressSpaceHeadroom()); }

std::string megabytes(double bytes) {
  char text[64];
  std::snprintf(text, sizeof text, "%.1f MB", bytes / (1 << 20));
  return text;
}

}  // namespace scanplan::kinematics
