#pragma once
// A long library call run from Python: on a worker thread with the GIL released, Ctrl-C and the
// progress callable served on the calling thread.

#include <atomic>
#include <cstddef>
#include <functional>
#include <string>
#include <string_view>

#include <pybind11/pybind11.h>

namespace scanplan::python {

/// Where a run reports progress from (any thread): stage, done, total.
using ReportFn = std::function<void(std::string_view stage, std::size_t done, std::size_t total)>;

/// Runs `work(cancel, report)` on a worker thread. Every 50 ms, on the calling thread with the
/// GIL held, it checks for signals (Ctrl-C: `cancel` is set, the work is awaited, and
/// KeyboardInterrupt raised) and calls `progress(stage, fraction)` with the latest report when
/// there is a new one (`progress` may be None). An exception of the work is raised here.
void runInterruptibly(
    const std::function<void(const std::atomic<bool>& cancel, const ReportFn& report)>& work,
    const pybind11::object& progress);

}  // namespace scanplan::python
