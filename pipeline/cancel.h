#pragma once
// Cancelling a plan: the exception the pipeline's long work throws once its cancel flag
// (planner::Termination::cancel, set from any thread) is set.

#include <atomic>
#include <stdexcept>

namespace scanplan::pipeline {

/// Thrown by planScan(), prepareScan(), scanPath() and planPrepared() once the problem's
/// `planning.termination.cancel` is set, at the next point that polls it. The work polls it
/// every few tens of milliseconds: at every progress report of the automatic scan (each
/// candidate, aimed pass and reach check, the set cover's search steps) and of the maps, at
/// every table path and move between the passes, between the stages, and at OMPL's iterations.
struct Cancelled : std::runtime_error {
  Cancelled() : std::runtime_error("cancelled") {}
};

/// Throws Cancelled when `flag` is set; nullptr: never.
inline void pollCancel(const std::atomic<bool>* flag) {
  if (flag != nullptr && flag->load(std::memory_order_relaxed)) throw Cancelled();
}

}  // namespace scanplan::pipeline
