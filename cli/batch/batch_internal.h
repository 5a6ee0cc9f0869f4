#pragma once
// The parts of `scanplan batch` shared between its files (cli/batch/*.cpp); not a public header.

#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include <scanplan/collision/scene.h>
#include <scanplan/config/job.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/pipeline/plan_scan.h>
#include <scanplan/planner/config_map.h>
#include "cli/batch/batch.h"
#include "cli/commands/commands.h"

namespace scanplan::cli::detail {

using Clock = std::chrono::steady_clock;

inline double since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

inline std::uint64_t fnv1a(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (const char c : text) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ull;
  }
  return h;
}

// Indices into BatchRow::metrics (kBatchMetrics).
constexpr std::size_t kJ = 0, kCostF = 1, kCostOmega = 2, kCostAlpha = 3, kGap = 4, kMinF = 5,
                      kClearance = 6, kOmega = 7, kAlpha = 8, kCycle = 9, kCoverage = 10,
                      kMapS = 11, kPlanS = 12, kDpS = 13, kValidationS = 14, kSimulationS = 15;

// ---- rows and the results files (results.cpp) -------------------------------------------------

/// The value of a varied key in a row; empty when the row has no such key.
std::string paramValue(const BatchRow& row, const std::string& key);
/// A finite number as fmt writes it (shortest round trip), else `empty`.
std::string numberOrEmpty(const std::optional<double>& v, const char* empty);
/// A number written whole (the text is a finite double and nothing else), else none.
std::optional<double> numberOf(const std::string& text);
/// A key ending in a name with "seed" (planner.ompl.seed, scanner.noise.seed).
bool isSeedKey(const std::string& key);
/// Letters and digits kept, everything else '_' (a file name).
std::string fileStem(const std::string& text);
/// The varied keys of a set of rows, in order of first appearance.
std::vector<std::string> rowKeys(const std::vector<BatchRow>& rows);
/// By case index, then case id.
void sortRows(std::vector<BatchRow>& rows);
/// Both results files, complete and sorted, written atomically.
void writeResults(const std::filesystem::path& out,
                  const std::vector<BatchRow>& rows,
                  const std::vector<std::string>& keys);

/// Appends rows as cases finish (from any worker thread).
class RowSink {
 public:
  RowSink(const std::filesystem::path& out, std::vector<std::string> keys);
  void append(const BatchRow& row);

 private:
  std::vector<std::string> keys_;
  std::mutex mutex_;
  std::ofstream csv_, jsonl_;
};

// ---- running a case (case_runner.cpp) ---------------------------------------------------------

// Everything a case needs that depends only on the map-relevant part of the job.
/// What the cases with the same map key share: the cell, the part mesh, the scan path and the
/// maps (pipeline::prepareScan()).
struct MapBundle {
  explicit MapBundle(const config::JobSpec& job) : cell(config::buildCell(job)) {}
  kinematics::CellModel cell;
  kinematics::TriangleMesh part;
  std::shared_ptr<const pipeline::PreparedScan> prepared;
  double map_seconds = 0.0;
};

std::unique_ptr<MapBundle> buildBundle(const config::JobSpec& job);
/// Cases with the same key share one map.
std::string mapKey(const config::JobSpec& job);
BatchRow rowFor(const SweepCase& c);
/// The `plan` pipeline after the map, without its files: fills the row's status and metrics.
void planCase(const config::JobSpec& job, const MapBundle& bundle, BatchRow& row);

// The reason of an error row: an InputError's message as it is; anything else is a bug, marked
// as `scanplan` marks it (the batch's exit code tells the two apart, also after --resume).
constexpr std::string_view kInternalPrefix = "internal error: ";
inline std::string errorReason(const std::exception& e) {
  if (dynamic_cast<const InputError*>(&e)) return e.what();
  return fmt::format("{}{} (please report this)", kInternalPrefix, e.what());
}

template <typename F>
void isolate(BatchRow& row, F&& work) {
  try {
    work();
  } catch (const std::exception& e) {
    row.status = "error";
    row.reason = errorReason(e);
  }
}

// ---- report: summary, plots, OMPL log (summary.cpp, plots.cpp, ompl_log.cpp, report.cpp) ------

struct Mean {
  double sum = 0.0;
  int n = 0;
  void add(const std::optional<double>& v) {
    if (v && std::isfinite(*v)) {
      sum += *v;
      ++n;
    }
  }
  std::string text(const char* format = "{:.4g}") const {
    return n ? fmt::format(fmt::runtime(format), sum / n) : std::string("–");
  }
};

/// summary.md: statuses, means per setting, the cases without a plan, links to `figures`.
std::string summaryMarkdown(const std::vector<BatchRow>& rows,
                            const std::vector<std::string>& keys,
                            const std::vector<std::string>& figures);

/// One metric against one varied value, as dir/stem.png and dir/stem.svg.
/// Returns false when no case has the metric.
bool writePlot(const std::filesystem::path& dir,
               const std::string& stem,
               const std::vector<BatchRow>& rows,
               const std::string& key,
               std::size_t metric);

/// The OMPL benchmark logs of a batch, file name → content.
std::vector<std::pair<std::string, std::string>> omplLogs(const std::vector<BatchRow>& rows,
                                                          const std::vector<std::string>& keys);

/// summary.md, plots/ and the OMPL logs of `rows` into `out`.
void writeReport(const std::filesystem::path& out, const std::vector<BatchRow>& rows);

/// Counts the rows by status (an unknown status counts as error).
void tally(const std::vector<BatchRow>& rows, BatchStats& stats);
/// "tally      13 case(s): 12 planned, 0 no_path, …, 1 error".
std::string tallyLine(const BatchStats& stats);

}  // namespace scanplan::cli::detail
