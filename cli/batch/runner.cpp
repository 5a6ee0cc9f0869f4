// Running a batch: the cases of this shard that results.jsonl does not have yet (--resume), in
// parallel on --jobs threads, the cases that share a map one after the other map by map.
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <scanplan/config/job.h>
#include <scanplan/kinematics/error.h>
#include "cli/batch/batch.h"
#include "cli/batch/batch_internal.h"
#include "cli/commands/commands.h"
#include "cli/io/output.h"

namespace scanplan::cli {

namespace fs = std::filesystem;
using namespace detail;  // this file runs what the others of cli/batch/ define

namespace {

std::pair<int, int> parseShard(const std::string& text) {
  int shard = 0, count = 0;
  char slash = 0, extra = 0;
  std::istringstream in(text);
  if (!(in >> shard >> slash >> count) || slash != '/' || (in >> extra) || count < 1 || shard < 1 ||
      shard > count) {
    throw InputError(fmt::format("--shard '{}': expected I/N with 1 <= I <= N, e.g. 2/8", text));
  }
  return {shard, count};
}

// "batch      13 case(s): 13 run, 0 already done, 0 error(s); 1 map(s) computed (2.2 s of map
// time); 8.5 s in all": the map time is the maps' own, the last time the whole run's.
std::string batchLine(const BatchStats& s, const std::string& shard) {
  return fmt::format(
      "batch      {} case(s){}: {} run, {} already done, {} error(s); {} map(s) computed{}; {:.1f} "
      "s in all",
      s.cases, shard.empty() ? "" : " in shard " + shard, s.ran, s.skipped, s.failed, s.maps,
      s.maps ? fmt::format(" ({:.1f} s of map time)", s.map_seconds) : "", s.seconds);
}

// The results files at the start of a run: new and empty, or (--resume) the rows of an earlier
// run of this sweep and shard, sorted; returns the ids of the cases they have.
std::set<std::string> startResults(const BatchOptions& options,
                                   const Sweep& sweep,
                                   int shard,
                                   int shards) {
  const fs::path& out = options.out_dir;
  std::set<std::string> done;
  if (std::error_code ec; !fs::exists(out / "results.jsonl", ec)) {
    writeResults(out, {}, sweep.keys);
    return done;
  }
  if (!options.resume) {
    throw InputError(fmt::format(
        "{}: has results.jsonl already: add --resume to finish that batch, or choose another "
        "folder",
        out.string()));
  }
  std::vector<BatchRow> rows = readBatchRows(out / "results.jsonl");
  // Every row must be a case of this sweep (and shard): rows of another sweep would be mixed
  // into this one's results without a word.
  std::set<std::string> ours;
  for (const SweepCase& c : sweep.cases) {
    if (inShard(c.id, shard, shards)) ours.insert(c.id);
  }
  std::size_t foreign = 0;
  const BatchRow* example = nullptr;
  for (const BatchRow& r : rows) {
    if (ours.count(r.case_id)) continue;
    ++foreign;
    if (!example) example = &r;
  }
  if (example) {
    std::string values;
    for (const auto& [k, v] : example->params) values += fmt::format(", {}={}", k, v);
    throw InputError(fmt::format(
        "{}: {} of its {} row(s) are not cases of {}{} (e.g. case {}: {}{}{}): the sweep or "
        "the shard changed since that batch ran; resume with them as they were, or write to "
        "another folder",
        (out / "results.jsonl").string(), foreign, rows.size(), options.sweep_file.string(),
        options.shard.empty() ? "" : " shard " + options.shard, example->case_id, example->job,
        values, example->seed ? fmt::format(", seed {}", *example->seed) : ""));
  }
  sortRows(rows);
  for (const BatchRow& r : rows) done.insert(r.case_id);
  writeResults(out, rows, sweep.keys);  // drops a torn last line; the CSV matches again
  return done;
}

// The maps a run computed: how many, and the wall time computing them.
struct MapTally {
  std::atomic<std::size_t> count{0};
  double seconds = 0.0;
};

// The cases of one map key: the map once, then the cases on it in parallel.
template <typename Finish>
void runGroup(const std::vector<std::size_t>& group,
              const std::vector<const SweepCase*>& todo,
              const std::vector<std::optional<config::JobSpec>>& jobs,
              const Finish& finish,
              MapTally& maps) {
  std::unique_ptr<MapBundle> bundle;
  std::string bundle_error;
  try {
    bundle = buildBundle(*jobs[group.front()]);
    ++maps.count;
    maps.seconds += bundle->map_seconds;  // maps are built one after the other
  } catch (const std::exception& e) {
    bundle_error = errorReason(e);
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, group.size(), 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t g = r.begin(); g != r.end(); ++g) {
                        const std::size_t i = group[g];
                        BatchRow row = rowFor(*todo[i]);
                        row.method = jobs[i]->planner.method;
                        row.map_reused = g > 0;
                        if (bundle) {
                          isolate(row, [&] { planCase(*jobs[i], *bundle, row); });
                        } else {
                          row.status = "error";
                          row.reason = bundle_error;
                        }
                        finish(row);
                      }
                    });
}

// Runs the cases (inside the caller's task arena): each case's job, resolved in parallel; then
// the cases sharing a map together, map after map.
template <typename Finish>
void runCases(const std::vector<const SweepCase*>& todo,
              bool reuse_maps,
              const Finish& finish,
              MapTally& maps) {
  std::vector<std::optional<config::JobSpec>> jobs(todo.size());
  std::vector<std::string> errors(todo.size());
  tbb::parallel_for(std::size_t{0}, todo.size(), [&](std::size_t i) {
    try {
      jobs[i] = config::loadJob(todo[i]->job_file, todo[i]->overrides);
    } catch (const std::exception& e) {
      errors[i] = errorReason(e);
    }
  });
  std::vector<std::string> keys;
  std::map<std::string, std::vector<std::size_t>> groups;
  for (std::size_t i = 0; i < todo.size(); ++i) {
    if (!jobs[i]) {
      BatchRow row = rowFor(*todo[i]);
      row.status = "error";
      row.reason = errors[i];
      finish(row);
      continue;
    }
    const std::string key = reuse_maps ? mapKey(*jobs[i]) : todo[i]->id;
    if (!groups.count(key)) keys.push_back(key);
    groups[key].push_back(i);
  }
  for (const std::string& key : keys) runGroup(groups[key], todo, jobs, finish, maps);
}

// The sweep file, its base jobs and their files: OUT must not be, hold or lie inside any.
void checkOut(const fs::path& out, const Sweep& sweep) {
  std::vector<fs::path> inputs{sweep.file};
  std::set<fs::path> jobs;
  for (const SweepCase& c : sweep.cases) {
    if (!jobs.insert(c.job_file).second) continue;
    const std::vector<fs::path> files = config::jobInputFiles(config::loadJob(c.job_file));
    inputs.insert(inputs.end(), files.begin(), files.end());
  }
  checkOutputApartFromInputs(out, inputs);
}

}  // namespace

BatchStats runBatchCases(const BatchOptions& options) {
  const auto start = Clock::now();
  const Sweep sweep = loadSweep(options.sweep_file);
  checkOut(options.out_dir, sweep);
  const auto [shard, shards] = options.shard.empty() ? std::pair{1, 1} : parseShard(options.shard);
  const fs::path& out = options.out_dir;
  const int threads = options.jobs > 0 ? options.jobs : tbb::info::default_concurrency();
  BatchStats stats;

  prepareOutputDir(out);
  const OutputLock lock(out);  // results are appended as cases finish: one run per folder
  const std::set<std::string> done = startResults(options, sweep, shard, shards);
  std::vector<const SweepCase*> todo;
  for (const SweepCase& c : sweep.cases) {
    if (!inShard(c.id, shard, shards)) continue;
    ++stats.cases;
    if (done.count(c.id)) {
      ++stats.skipped;
    } else {
      todo.push_back(&c);
    }
  }

  RowSink sink(out, sweep.keys);
  Progress progress("batch");
  std::atomic<std::size_t> finished{0}, failed{0};
  MapTally maps;
  const auto finish = [&](const BatchRow& row) {
    sink.append(row);
    if (row.status == "error") ++failed;
    progress(++finished, todo.size());
  };
  tbb::task_arena arena(threads);
  arena.execute([&] { runCases(todo, options.reuse_maps, finish, maps); });

  stats.ran = finished.load();
  stats.failed = failed.load();
  stats.maps = maps.count.load();
  stats.map_seconds = maps.seconds;
  // Complete: both files rewritten sorted (a deterministic order whatever the threads did).
  std::vector<BatchRow> rows = readBatchRows(out / "results.jsonl");
  sortRows(rows);
  writeResults(out, rows, sweep.keys);
  if (options.report) writeReport(out, rows);
  tally(rows, stats);
  stats.seconds = since(start);
  return stats;
}

ExitCode runBatch(const BatchOptions& options) {
  const BatchStats s = runBatchCases(options);
  const std::size_t errors = s.statuses.back();
  if (options.print) {
    std::printf("%s\n", batchLine(s, options.shard).c_str());
    std::printf("wrote      %s: results.csv, results.jsonl%s\n", options.out_dir.string().c_str(),
                options.report ? ", summary.md, plots/, ompl_benchmark*.log" : "");
    std::printf("%s\n", tallyLine(s).c_str());
    std::fflush(stdout);
  }
  if (errors == 0) return ExitCode::kOk;
  std::fprintf(
      stderr,
      "scanplan: error: %zu of %zu case(s) ended in status error%s; every case ran and "
      "the results are written (reasons in %s)\n",
      errors, s.cases,
      s.internal_errors ? fmt::format(", {} of them internal", s.internal_errors).c_str() : "",
      (options.out_dir / "results.csv").string().c_str());
  return s.internal_errors ? ExitCode::kInternal : ExitCode::kInput;
}

}  // namespace scanplan::cli
