// The report of a batch (summary.md, plots/, the OMPL logs), the status tally, and `batch
// report` and `batch merge`, which rebuild them from results.jsonl.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include <scanplan/kinematics/error.h>
#include "cli/batch/batch.h"
#include "cli/batch/batch_internal.h"
#include "cli/io/output.h"

namespace scanplan::cli {

namespace fs = std::filesystem;

namespace detail {

void writeReport(const fs::path& out, const std::vector<BatchRow>& rows) {
  const std::vector<std::string> keys = rowKeys(rows);
  std::vector<std::string> figures;
  if (!rows.empty()) {
    const fs::path plots = out / "plots";
    fs::create_directories(plots);
    std::vector<std::string> axes = keys;
    if (axes.empty()) axes.push_back("");
    for (const std::string& key : axes) {
      // Every metric; writePlot skips one that no case has (e.g. coverage without simulation).
      for (std::size_t metric = 0; metric < kBatchMetrics.size(); ++metric) {
        const std::string stem =
            std::string(kBatchMetrics[metric]) + "_vs_" + (key.empty() ? "case" : fileStem(key));
        if (writePlot(plots, stem, rows, key, metric)) figures.push_back(stem);
      }
    }
  }
  writeFileAtomically(out / "summary.md", summaryMarkdown(rows, keys, figures));
  // The OMPL logs; those of an earlier report that this one does not write go (other jobs).
  const std::vector<std::pair<std::string, std::string>> logs = omplLogs(rows, keys);
  std::vector<fs::path> stale;
  for (const fs::directory_entry& e : fs::directory_iterator(out)) {
    const std::string name = e.path().filename().string();
    if (name.starts_with("ompl_benchmark") && name.ends_with(".log") &&
        std::none_of(logs.begin(), logs.end(), [&](const auto& l) { return l.first == name; })) {
      stale.push_back(e.path());
    }
  }
  for (const fs::path& f : stale) fs::remove(f);
  for (const auto& [file, log] : logs) writeFileAtomically(out / file, log);
}

// Counts the rows by status (an unknown status counts as error).
void tally(const std::vector<BatchRow>& rows, BatchStats& stats) {
  stats.statuses = {};
  stats.internal_errors = 0;
  for (const BatchRow& r : rows) {
    const auto* it = std::find_if(kBatchStatuses.begin(), kBatchStatuses.end(),
                                  [&](const char* s) { return r.status == s; });
    if (it == kBatchStatuses.end()) it = kBatchStatuses.end() - 1;
    ++stats.statuses[static_cast<std::size_t>(it - kBatchStatuses.begin())];
    if (r.status == "error" && r.reason.starts_with(kInternalPrefix)) ++stats.internal_errors;
  }
}

// "tally      13 case(s): 12 planned, 0 no_path, …, 1 error".
std::string tallyLine(const BatchStats& stats) {
  std::size_t total = 0;
  for (const std::size_t n : stats.statuses) total += n;
  std::string line = fmt::format("tally      {} case(s):", total);
  for (std::size_t i = 0; i < kBatchStatuses.size(); ++i) {
    line += fmt::format("{} {} {}", i ? "," : "", stats.statuses[i], kBatchStatuses[i]);
  }
  return line;
}

}  // namespace detail

using detail::rowKeys;
using detail::sortRows;
using detail::tally;
using detail::tallyLine;
using detail::writeReport;
using detail::writeResults;

ExitCode runBatchReport(const fs::path& out_dir) {
  if (!isRegularFile(out_dir / "results.jsonl")) {
    throw InputError(out_dir.string() + ": no results.jsonl: expected the folder of a batch run");
  }
  const OutputLock lock(out_dir);
  std::vector<BatchRow> rows = readBatchRows(out_dir / "results.jsonl");
  sortRows(rows);
  writeReport(out_dir, rows);
  std::printf("wrote      %s: summary.md, plots/, ompl_benchmark*.log (%zu case(s))\n",
              out_dir.string().c_str(), rows.size());
  BatchStats stats;
  tally(rows, stats);
  std::printf("%s\n", tallyLine(stats).c_str());
  return ExitCode::kOk;
}

ExitCode runBatchMerge(const std::vector<fs::path>& inputs, const fs::path& out_dir) {
  std::vector<BatchRow> rows;
  std::set<std::string> seen;
  // Shards of one sweep have the same columns (the sweep's varied keys): different ones mean
  // folders of different sweeps, whose rows must not be mixed.
  const auto header = [](const fs::path& dir) {
    std::ifstream csv(dir / "results.csv");
    std::string line;
    std::getline(csv, line);
    return line;
  };
  const std::string columns = inputs.empty() ? std::string() : header(inputs.front());
  for (const fs::path& in : inputs) {
    if (!isRegularFile(in / "results.jsonl")) {
      throw InputError(in.string() + ": no results.jsonl: expected the folder of a batch run");
    }
    if (const std::string h = header(in); h != columns) {
      throw InputError(
          fmt::format("{}: its columns differ from {}'s ({} vs {}): expected shards of one sweep",
                      (in / "results.csv").string(), inputs.front().string(),
                      h.empty() ? "none" : h, columns.empty() ? "none" : columns));
    }
    for (BatchRow& r : readBatchRows(in / "results.jsonl")) {
      if (seen.insert(r.case_id).second) rows.push_back(std::move(r));
    }
  }
  sortRows(rows);
  prepareOutputDir(out_dir);
  const OutputLock lock(out_dir);
  writeResults(out_dir, rows, rowKeys(rows));
  writeReport(out_dir, rows);
  std::printf("merged     %zu case(s) from %zu folder(s) into %s\n", rows.size(), inputs.size(),
              out_dir.string().c_str());
  BatchStats stats;
  tally(rows, stats);
  std::printf("%s\n", tallyLine(stats).c_str());
  return ExitCode::kOk;
}

}  // namespace scanplan::cli
