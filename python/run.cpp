#include "python/run.h"

#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>

namespace py = pybind11;

namespace scanplan::python {

namespace {

// What the worker shares with the calling thread.
struct Shared {
  std::mutex mutex;
  std::condition_variable done_cv;
  bool done = false;
  std::exception_ptr error;
  bool reported = false;  // a report not yet handed to the progress callable
  std::string stage;
  double fraction = 0.0;
};

// Hands the latest report to `progress` (GIL held).
void deliver(Shared& shared, const py::object& progress) {
  std::string stage;
  double fraction = 0.0;
  {
    const std::lock_guard<std::mutex> lock(shared.mutex);
    if (!shared.reported) return;
    shared.reported = false;
    stage = shared.stage;
    fraction = shared.fraction;
  }
  if (!progress.is_none()) progress(stage, fraction);
}

}  // namespace

void runInterruptibly(
    const std::function<void(const std::atomic<bool>& cancel, const ReportFn& report)>& work,
    const py::object& progress) {
  Shared shared;
  std::atomic<bool> cancel{false};
  const ReportFn report = [&shared](std::string_view stage, std::size_t done, std::size_t total) {
    const std::lock_guard<std::mutex> lock(shared.mutex);
    shared.reported = true;
    shared.stage = stage;
    shared.fraction = total > 0 ? static_cast<double>(done) / static_cast<double>(total) : 1.0;
  };
  std::thread worker([&] {
    std::exception_ptr error;
    try {
      work(cancel, report);
    } catch (...) {
      error = std::current_exception();
    }
    const std::lock_guard<std::mutex> lock(shared.mutex);
    shared.error = error;
    shared.done = true;
    shared.done_cv.notify_all();
  });
  const auto wait = [&](std::chrono::milliseconds timeout) {
    const py::gil_scoped_release release;
    std::unique_lock<std::mutex> lock(shared.mutex);
    return shared.done_cv.wait_for(lock, timeout, [&] { return shared.done; });
  };
  while (!wait(std::chrono::milliseconds(50))) {
    if (PyErr_CheckSignals() != 0) {
      cancel = true;
      {
        const py::gil_scoped_release release;
        worker.join();
      }
      throw py::error_already_set();
    }
    try {
      deliver(shared, progress);
    } catch (...) {  // the callable raised: stop the work, then raise it
      cancel = true;
      {
        const py::gil_scoped_release release;
        worker.join();
      }
      throw;
    }
  }
  worker.join();
  deliver(shared, progress);
  if (shared.error) std::rethrow_exception(shared.error);
}

}  // namespace scanplan::python
