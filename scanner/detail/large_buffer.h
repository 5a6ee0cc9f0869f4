#pragma once
// Private to scanner/ (detail/ is not installed): room for vectors of millions of elements (a
// simulated cloud) backed by transparent huge pages where the kernel offers them. Each first
// touch of a fresh 4 KiB page is a page fault; a 200 MB cloud takes 50 000 of them, one after
// another in the serial part of a run, and on a virtual machine each costs microseconds (measured:
// half the simulation's time on the demo). 2 MiB pages make them 512 times fewer. Only advice:
// where the kernel gives no huge pages, nothing changes.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace scanplan::scanner::detail {

/// Advises huge pages for the whole 2 MiB pages within [data, data + bytes).
inline void adviseHugePages(void* data, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr std::uintptr_t kHuge = std::uintptr_t{1} << 21;
  const auto begin = (reinterpret_cast<std::uintptr_t>(data) + kHuge - 1) & ~(kHuge - 1);
  const auto end = (reinterpret_cast<std::uintptr_t>(data) + bytes) & ~(kHuge - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#else
  (void)data;
  (void)bytes;
#endif
}

/// Writes a byte in every page of v's room for elements [from, to) (clipped to its capacity,
/// none constructed there yet): the room's first-touch page faults are taken here, by the thread
/// that calls this, while the others work (measured on a virtual machine: 0.25 s of faults for
/// the demo's 173 MB cloud, which do not get faster on more threads).
template <class T>
void touchRoom(std::vector<T>& v, std::size_t from, std::size_t to) {
  constexpr std::size_t kPage = 4096;
  auto* base = reinterpret_cast<volatile unsigned char*>(v.data());
  const std::size_t end = std::min(to, v.capacity()) * sizeof(T);
  for (std::size_t at = std::max(from, v.size()) * sizeof(T); at < end;
       at = (at / kPage + 1) * kPage)
    base[at] = 0;
}

/// v.reserve(n), the new room advised huge pages when it moved.
template <class T>
void reserveLarge(std::vector<T>& v, std::size_t n) {
  if (n <= v.capacity()) return;
  v.reserve(n);
  adviseHugePages(v.data(), v.capacity() * sizeof(T));
}

}  // namespace scanplan::scanner::detail
