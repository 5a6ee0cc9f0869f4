#pragma once
// `scanplan batch`: a sweep of planner settings over many cases — the cases of a sweep file,
// run in parallel with each configuration map computed once, one result row per case
// (results.csv, results.jsonl), a summary with plots and an OMPL benchmark log.

#include <array>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cli/io/exit_code.h"
#include "cli/plot/image_io.h"

namespace scanplan::cli {

/// The keys of a job that seed a random generator: a sweep's `seeds:` sets all of them.
inline constexpr std::array<const char*, 2> kJobSeedKeys = {"planner.ompl.seed",
                                                            "scanner.noise.seed"};

/// One case of a sweep: a base job, its overrides, the seed and the repeat number.
struct SweepCase {
  std::size_t index = 0;  ///< position in the sweep's deterministic case order
  std::string id;         ///< stable hash of (job as written, sorted overrides, repeat), hex
  std::string job;        ///< the base job as the sweep file writes it
  std::filesystem::path job_file;                           ///< resolved against the sweep file
  std::vector<std::pair<std::string, std::string>> params;  ///< the varied values (key, value)
  std::optional<int> seed;  ///< the sweep's `seeds:` value (in every kJobSeedKeys), if it has any
  int repeat = 0;
  /// `set`, the varied values, then the seed keys, as for --set.
  std::vector<std::string> overrides;
};

/// A parsed and expanded sweep file.
struct Sweep {
  std::filesystem::path file;
  std::vector<std::string> keys;  ///< the varied keys, in the file's order (one column each)
  std::vector<int> seeds;         ///< `seeds:`, in the file's order (empty: the jobs' own)
  std::vector<SweepCase> cases;
};

/// Reads a sweep file and expands its cases; every varied value is checked on every base job
/// through loadJob() first, so a bad key or value is an InputError before anything runs.
Sweep loadSweep(const std::filesystem::path& file);

/// Case `id` belongs to shard `shard` (1-based) of `count`: stable, whatever else the sweep has.
bool inShard(const std::string& id, int shard, int count);

/// The numbers of a result row, in column order (kBatchMetrics).
/// `plan_s` is the chosen planner's own time; `dp_s` that of the DP yardstick run on the chosen
/// branch in addition (planner.dp_gap), empty when none ran: with method dp the planner is the
/// yardstick, and its time is plan_s.
inline constexpr std::array<const char*, 16> kBatchMetrics = {"J_s",
                                                              "cost_f_s",
                                                              "cost_omega_s",
                                                              "cost_alpha_s",
                                                              "dp_gap_percent",
                                                              "min_f",
                                                              "min_clearance_mm",
                                                              "max_omega_deg_s",
                                                              "max_alpha_deg_s2",
                                                              "cycle_time_s",
                                                              "coverage",
                                                              "map_s",
                                                              "plan_s",
                                                              "dp_s",
                                                              "validation_s",
                                                              "simulation_s"};
/// Index of the first timing column: wall times vary run to run, everything before does not.
inline constexpr std::size_t kFirstTimingMetric = 11;

/// The statuses of a case, in this order in the tally and in the OMPL log's `outcome` enum.
/// All but `error` are outcomes of a case that ran; `error` is a case that could not run to
/// one (bad input in combination, or an internal error: its reason says which).
inline constexpr std::array<const char*, 5> kBatchStatuses = {
    "planned", "no_path", "no_executable_path", "invalid_trajectory", "error"};

/// One row of results.csv / results.jsonl.
struct BatchRow {
  std::size_t index = 0;
  std::string case_id;
  std::string job;
  std::vector<std::pair<std::string, std::string>> params;
  std::optional<int> seed;  ///< the sweep's seed (`seeds:`), if it has any
  int repeat = 0;
  std::string method;  ///< the planner that ran (the resolved planner.method)
  std::string status;  ///< planned | no_path | no_executable_path | invalid_trajectory | error
  std::string reason;
  std::array<std::optional<double>, kBatchMetrics.size()> metrics{};
  bool map_reused = false;
};

struct BatchOptions {
  std::filesystem::path sweep_file;
  std::filesystem::path out_dir;
  int jobs = 0;            ///< threads in all (cases and the work inside them); 0: every core
  std::string shard;       ///< "I/N" (1 ≤ I ≤ N) or empty for all cases
  bool resume = false;     ///< skip the cases results.jsonl already has
  bool reuse_maps = true;  ///< false: every case computes its own map (benchmarks)
  bool report = true;      ///< write summary.md, plots and the OMPL log at the end
  bool print = true;       ///< print the summary lines on stdout
};

struct BatchStats {
  std::size_t cases = 0;    ///< in this shard
  std::size_t skipped = 0;  ///< already in results.jsonl (--resume)
  std::size_t ran = 0;
  std::size_t failed = 0;    ///< status error
  std::size_t maps = 0;      ///< maps computed
  double map_seconds = 0.0;  ///< wall time computing those maps (the sum over them)
  double seconds = 0.0;      ///< wall time of the whole run: sweep, cases, results and report
  /// Every row of the results (this run's and those --resume kept), by kBatchStatuses.
  std::array<std::size_t, kBatchStatuses.size()> statuses{};
  /// Rows with status error whose reason is an internal error (a bug), not bad input.
  std::size_t internal_errors = 0;
};

/// Runs the cases of the sweep into options.out_dir; rows are appended as cases finish.
BatchStats runBatchCases(const BatchOptions& options);
/// runBatchCases with the summary lines. The whole batch always runs and is written; the exit
/// code: kOk when every case ran to an outcome (planned, no_path, no_executable_path,
/// invalid_trajectory), kInput when some case ended in status error through bad input,
/// kInternal when some case ended in an internal error (as `plan` would have exited).
ExitCode runBatch(const BatchOptions& options);
/// Regenerates summary.md, plots/ and the OMPL benchmark log(s) from OUT/results.jsonl.
ExitCode runBatchReport(const std::filesystem::path& out_dir);
/// Merges the results of shard runs into `out_dir` (a case in several inputs is kept once).
ExitCode runBatchMerge(const std::vector<std::filesystem::path>& inputs,
                       const std::filesystem::path& out_dir);

/// The rows of a results.jsonl (a torn last line from an interrupted run is skipped). Throws
/// InputError naming the file and the line when any other line is not a row a batch writes.
std::vector<BatchRow> readBatchRows(const std::filesystem::path& jsonl);

/// A planner's colour in the batch plots (its crosses and the line through its means).
Rgb batchPlannerColour(const std::string& method);

}  // namespace scanplan::cli
