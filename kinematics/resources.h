#pragma once
// What this process may still allocate: the limit every stage whose memory grows with its input
// checks its estimate against, besides its own named limit.
#include <cstddef>
#include <string>

namespace scanplan::kinematics {

/// Bytes this process can still allocate: the smaller of the memory the kernel reports available
/// (MemAvailable in /proc/meminfo) and the headroom under the address-space limit (RLIMIT_AS, as
/// `ulimit -v` sets it, less the process's present virtual size). SIZE_MAX when neither is known.
std::size_t availableMemoryBytes();

/// "N MB" (one decimal) for messages.
std::string megabytes(double bytes);

}  // namespace scanplan::kinematics
