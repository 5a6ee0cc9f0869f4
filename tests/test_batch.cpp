// `scanplan batch` end to end on the lightened demo (test::kLightDemo, simulation off, each case
// a fraction of a second): the small sweep, resume after an interruption, shards merged,
// failing cases as rows and the exit code they give, labelled PNG plots, the OMPL benchmark log
// through OMPL's own script (when installed), and sweep errors before anything runs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli/batch.h"
#include "cli/image_io.h"
#include "cli_support.h"
#include "test_support.h"

namespace {

using namespace scanplan;
using namespace scanplan::test;

const fs::path kDemoJob = fs::path(SCANPLAN_SOURCE_DIR) / "data/jobs/demo.yaml";

// The fixed settings of every case: the light demo, no simulation, and no refinement so that
// the DP gap compares grid paths with the grid optimum (refinement can take a path below DP's
// grid optimum, a negative gap).
std::string sweepHeader() {
  std::string text = fmt::format("jobs: ['{}']\nset:\n", kDemoJob.string());
  for (const std::string& o : kLightDemo) text += "  - '" + o + "'\n";
  text += "  - simulation.enabled=false\n  - planner.refine.enabled=false\n";
  return text;
}

// The small sweep: 2 planners x 3 horizons x 2 seeds = 12 cases on one map.
const std::string kSmallVary =
    "vary:\n"
    "  planner.method: [ray, dp]\n"
    "  planner.ray.horizon: [10, 15, 30]\n"
    "  planner.ompl.seed: {from: 1, to: 2, step: 1}\n";

// A row without its wall times and without map_reused (which case computes the map depends on
// which cases a run has left to do): what must not change between runs.
std::string stable(const cli::BatchRow& r) {
  std::string text = fmt::format("{} #{} {} r{} {} {} [{}]", r.case_id, r.index, r.job, r.repeat,
                                 r.method, r.status, r.reason);
  for (const auto& [k, v] : r.params) text += " " + k + "=" + v;
  for (std::size_t m = 0; m < cli::kFirstTimingMetric; ++m) {
    text += " " + (r.metrics[m] ? fmt::format("{}", *r.metrics[m]) : std::string("-"));
  }
  return text;
}

std::vector<std::string> stableRows(const fs::path& out) {
  std::vector<std::string> rows;
  for (const cli::BatchRow& r : cli::readBatchRows(out / "results.jsonl")) {
    rows.push_back(stable(r));
  }
  return rows;  // readBatchRows keeps the file's order: sorted by case order after a run
}

class Batch : public Cli {
 protected:
  fs::path writeSweep(const std::string& body) const {
    const fs::path file = dir_ / "sweep.yaml";
    writeFile(file, sweepHeader() + body);
    return file;
  }
  Result batch(const fs::path& sweep, const fs::path& out, std::vector<std::string> extra = {}) {
    std::vector<std::string> args{"batch", sweep.string(), "-o", out.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    return scanplan(args);
  }
};

TEST_F(Batch, SmallSweepGivesOneRowPerCaseWithTheDpGap) {
  const fs::path sweep = writeSweep(kSmallVary);
  const fs::path out = dir_ / "out";
  const Result run = batch(sweep, out, {"--jobs", "2"});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_TRUE(contains(run.out, "12 case(s): 12 run, 0 already done, 0 error(s); 1 map(s)"))
      << run.out;
  // The map's own time, then the whole run's: the map took part of it.
  double map_s = -1, all_s = -1;
  const std::size_t line = run.out.find("1 map(s) computed (");
  ASSERT_NE(line, std::string::npos) << run.out;
  ASSERT_EQ(std::sscanf(run.out.c_str() + line,
                        "1 map(s) computed (%lf s of map time); %lf s in all", &map_s, &all_s),
            2)
      << run.out;
  EXPECT_GT(map_s, 0.0);
  EXPECT_LE(map_s, all_s + 0.05);
  // Every map's time is in the rows (map_s of the row that computed it).
  double rows_map_s = 0.0;
  for (const cli::BatchRow& r : cli::readBatchRows(out / "results.jsonl")) {
    if (!r.map_reused) rows_map_s += r.metrics[cli::kFirstTimingMetric].value_or(0.0);
  }
  EXPECT_NEAR(map_s, rows_map_s, 0.051);
  EXPECT_TRUE(contains(run.out,
                       "\ntally      12 case(s): 12 planned, 0 no_path, 0 no_executable_path, 0 "
                       "invalid_trajectory, 0 error\n"))
      << run.out;

  const std::vector<cli::BatchRow> rows = cli::readBatchRows(out / "results.jsonl");
  ASSERT_EQ(rows.size(), 12u);
  int reused = 0;
  for (const cli::BatchRow& r : rows) {
    EXPECT_EQ(r.status, "planned") << stable(r);
    EXPECT_EQ(r.method, r.params.at(0).second);
    ASSERT_TRUE(r.metrics[4].has_value()) << "dp_gap_percent missing: " << stable(r);
    // DP is the optimum of the grid problem the unrefined planners solve: the gap is >= 0 (and
    // exactly 0 for DP itself, run on the same branch).
    EXPECT_GE(*r.metrics[4], 0.0) << stable(r);
    if (r.method == "dp") {
      EXPECT_NEAR(*r.metrics[4], 0.0, 1e-9) << stable(r);
    }
    reused += r.map_reused ? 1 : 0;
  }
  EXPECT_EQ(reused, 11) << "one map for all 12 cases";

  // CSV: a header and one line per case, a column per varied key.
  const std::string csv = readFile(out / "results.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 13);
  EXPECT_TRUE(csv.starts_with(
      "case_id,job,planner.method,planner.ray.horizon,planner.ompl.seed,repeat,method,status,"))
      << csv.substr(0, 200);
  for (const char* f :
       {"summary.md", "ompl_benchmark.log", "plots/J_s_vs_planner_ray_horizon.png",
        "plots/J_s_vs_planner_ray_horizon.svg", "plots/dp_gap_percent_vs_planner_method.png"}) {
    EXPECT_TRUE(fs::exists(out / f)) << f;
  }
  EXPECT_TRUE(tmpFiles(out).empty());
  // The PNG plots carry their text: a margin around the 720 x 480 data area with the title on
  // top, the y-axis title on the left and the legend on the right, all in dark pixels.
  const cli::RgbImage png = cli::decodePng(readFile(out / "plots/J_s_vs_planner_ray_horizon.png"));
  ASSERT_GT(png.width, 720 + 100);
  ASSERT_GT(png.height, 480 + 60);
  const auto dark = [&](int x0, int y0, int x1, int y1) {
    int n = 0;
    for (int y = y0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x) {
        const cli::Rgb c = png.at(x, y);
        n += c.r < 100 && c.g < 100 && c.b < 100 ? 1 : 0;
      }
    }
    return n;
  };
  EXPECT_GT(dark(0, 0, png.width, 30), 100) << "title";
  EXPECT_GT(dark(0, 60, 30, png.height - 60), 100) << "y-axis title";
  EXPECT_GT(dark(0, png.height - 30, png.width, png.height), 100) << "x-axis title";
  EXPECT_GT(dark(png.width - 80, 0, png.width, 200), 50) << "legend";
  // The SVG embeds the bare data area and labels it with SVG text.
  const std::string svg = readFile(out / "plots/J_s_vs_planner_ray_horizon.svg");
  EXPECT_TRUE(contains(svg, "href=\"data:image/png;base64,iVBORw0KGgo")) << svg.substr(0, 400);
  EXPECT_TRUE(contains(svg, ">J, objective (s) against planner.ray.horizon</text>"));
  const std::string log = readFile(out / "ompl_benchmark.log");
  EXPECT_TRUE(contains(log, "6 planners\n")) << log;  // 2 methods x 3 horizons, seeds are runs
  EXPECT_TRUE(contains(log, "\n2 runs\n")) << log;

  // `batch report` regenerates the summary from the results alone.
  fs::remove(out / "summary.md");
  const Result report = scanplan({"batch", "report", out.string()});
  ASSERT_EQ(report.exit_code, 0) << describe(report);
  EXPECT_TRUE(contains(readFile(out / "summary.md"), "| ray | 30 | 2 | 2 |"))
      << readFile(out / "summary.md");
}

TEST_F(Batch, ResumedRunEqualsAnUninterruptedOne) {
  const fs::path sweep = writeSweep(kSmallVary);
  const fs::path full = dir_ / "full";
  const Result whole = batch(sweep, full);
  ASSERT_EQ(whole.exit_code, 0) << describe(whole);

  // Interrupted in process after 5 cases, then resumed from the command line.
  const fs::path part = dir_ / "part";
  cli::BatchOptions options;
  options.sweep_file = sweep;
  options.out_dir = part;
  options.max_cases = 5;
  options.print = false;
  const cli::BatchStats first = cli::runBatchCases(options);
  EXPECT_EQ(first.ran, 5u);
  EXPECT_EQ(first.maps, 1u);
  EXPECT_GT(first.map_seconds, 0.0);
  EXPECT_LE(first.map_seconds, first.seconds);
  EXPECT_EQ(cli::readBatchRows(part / "results.jsonl").size(), 5u);
  // A rerun without --resume refuses to mix two batches.
  const Result refused = batch(sweep, part);
  EXPECT_EQ(refused.exit_code, 4) << describe(refused);
  EXPECT_TRUE(contains(refused.err, "--resume")) << refused.err;
  // A torn last line, as a kill mid-write leaves it.
  std::ofstream(part / "results.jsonl", std::ios::app) << "{\"case_id\": \"0123";
  const Result resumed = batch(sweep, part, {"--resume"});
  ASSERT_EQ(resumed.exit_code, 0) << describe(resumed);
  EXPECT_TRUE(contains(resumed.out, "12 case(s): 7 run, 5 already done")) << resumed.out;
  EXPECT_EQ(stableRows(part), stableRows(full));
  // Nothing left to run: no map, and the line says so (no map time for the batch's time).
  const Result again = batch(sweep, part, {"--resume"});
  ASSERT_EQ(again.exit_code, 0) << describe(again);
  EXPECT_TRUE(
      contains(again.out, "12 case(s): 0 run, 12 already done, 0 error(s); 0 map(s) computed; "))
      << again.out;
  EXPECT_TRUE(contains(again.out, " s in all\n")) << again.out;
  const std::string csv = readFile(part / "results.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 13) << csv;
}

TEST_F(Batch, ShardsMergedEqualTheUnshardedRun) {
  const fs::path sweep = writeSweep(kSmallVary);
  const fs::path full = dir_ / "full";
  ASSERT_EQ(batch(sweep, full).exit_code, 0);
  std::vector<std::string> merge{"batch", "merge"};
  std::size_t total = 0;
  for (int i = 1; i <= 3; ++i) {
    const fs::path out = dir_ / fmt::format("shard_{}", i);
    const Result run = batch(sweep, out, {"--shard", fmt::format("{}/3", i)});
    ASSERT_EQ(run.exit_code, 0) << describe(run);
    total += cli::readBatchRows(out / "results.jsonl").size();
    merge.push_back(out.string());
  }
  EXPECT_EQ(total, 12u) << "the shards are disjoint and cover the sweep";
  merge.insert(merge.end(), {"-o", (dir_ / "merged").string()});
  const Result merged = scanplan(merge);
  ASSERT_EQ(merged.exit_code, 0) << describe(merged);
  EXPECT_EQ(stableRows(dir_ / "merged"), stableRows(full));
  EXPECT_TRUE(fs::exists(dir_ / "merged" / "summary.md"));
}

// The shards through GNU parallel, as across hosts (README), merged: the unsharded run.
TEST_F(Batch, ShardsThroughGnuParallelEqualTheUnshardedRun) {
  if (std::system("command -v parallel >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "GNU parallel is not installed";
  }
  const fs::path sweep = writeSweep(kSmallVary);
  const fs::path full = dir_ / "full";
  ASSERT_EQ(batch(sweep, full).exit_code, 0);
  const std::string command = fmt::format(
      "parallel --halt now,fail=1 '{} batch {} -o {}/p_{{}} --jobs 1 --shard {{}}/3' ::: 1 2 3 "
      ">/dev/null 2>&1 && {} batch merge {}/p_1 {}/p_2 {}/p_3 -o {}/p_merged >/dev/null",
      SCANPLAN_BINARY, sweep.string(), dir_.string(), SCANPLAN_BINARY, dir_.string(), dir_.string(),
      dir_.string(), dir_.string());
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  EXPECT_EQ(stableRows(dir_ / "p_merged"), stableRows(full));
}

TEST_F(Batch, AFailingCaseIsARowNotTheEndOfTheBatch) {
  // Each value is valid on its own; together min >= max: that case fails when it is loaded.
  const fs::path sweep = writeSweep(
      "vary:\n  table.min_deg: [170]\n  table.max_deg: [160]\ncases:\n"
      "  - {planner.method: dp}\n");
  const fs::path out = dir_ / "out";
  const Result run = batch(sweep, out);
  // The whole batch runs and is written; a case with bad input makes the exit code 4 (bad
  // input), after the tally.
  EXPECT_EQ(run.exit_code, 4) << describe(run);
  EXPECT_TRUE(contains(run.out,
                       "\ntally      2 case(s): 1 planned, 0 no_path, 0 no_executable_path, 0 "
                       "invalid_trajectory, 1 error\n"))
      << run.out;
  EXPECT_TRUE(contains(run.err, "scanplan: error: 1 of 2 case(s) ended in status error;"))
      << run.err;
  const std::vector<cli::BatchRow> rows = cli::readBatchRows(out / "results.jsonl");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].status, "error");
  EXPECT_TRUE(contains(rows[0].reason, "table.max_deg")) << rows[0].reason;
  EXPECT_FALSE(contains(rows[0].reason, "internal error")) << rows[0].reason;
  EXPECT_EQ(rows[1].status, "planned") << rows[1].reason;
  EXPECT_EQ(rows[1].method, "dp");
  for (const char* f :
       {"results.csv", "summary.md", "ompl_benchmark.log", "plots/J_s_vs_planner_method.png"}) {
    EXPECT_TRUE(fs::exists(out / f)) << f;
  }
  // In the OMPL log the failed case is a run that did not solve, outcome 4 (error).
  const std::string log = readFile(out / "ompl_benchmark.log");
  EXPECT_TRUE(
      contains(log, "\noutcome|planned|no_path|no_executable_path|invalid_trajectory|error\n"))
      << log;
  EXPECT_TRUE(contains(log, "\n; 0; 4; ")) << log;  // no plan time, not solved, error
}

TEST_F(Batch, ExitCodeZeroWhenEveryCaseHasAnOutcomeEvenWithoutAPath) {
  // Half a degree per second is too slow to follow the rings: no path, an outcome, not an error.
  const fs::path sweep = writeSweep("vary:\n  table.max_speed_deg_s: [0.5, 30]\n");
  const fs::path out = dir_ / "out";
  const Result run = batch(sweep, out);
  EXPECT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_TRUE(contains(run.out,
                       "\ntally      2 case(s): 1 planned, 1 no_path, 0 no_executable_path, 0 "
                       "invalid_trajectory, 0 error\n"))
      << run.out;
  EXPECT_TRUE(run.err.empty()) << run.err;

  // A case that ended in an internal error (here: written into the results as a run would
  // write it) makes a resumed batch exit 1, as `plan` would: everything ran, something is a bug.
  std::string jsonl = readFile(out / "results.jsonl");
  const std::size_t at = jsonl.find("\"status\": \"planned\", \"reason\": \"\"");
  ASSERT_NE(at, std::string::npos) << jsonl;
  jsonl.replace(at, std::string("\"status\": \"planned\", \"reason\": \"\"").size(),
                "\"status\": \"error\", \"reason\": \"internal error: boom (please report this)\"");
  writeFile(out / "results.jsonl", jsonl);
  const Result resumed = batch(sweep, out, {"--resume"});
  EXPECT_EQ(resumed.exit_code, 1) << describe(resumed);
  EXPECT_TRUE(contains(resumed.out, "2 case(s): 0 run, 2 already done")) << resumed.out;
  EXPECT_TRUE(contains(resumed.out,
                       "0 planned, 1 no_path, 0 no_executable_path, 0 "
                       "invalid_trajectory, 1 error\n"))
      << resumed.out;
  EXPECT_TRUE(contains(resumed.err, "1 of 2 case(s) ended in status error, 1 of them internal"))
      << resumed.err;
}

// The OMPL benchmark log through OMPL's own ompl_benchmark_statistics (Debian: ompl-demos) into
// the Planner Arena database: every case a run of the right planner with its values.
TEST_F(Batch, OmplBenchmarkLogLoadsIntoThePlannerArenaDatabase) {
  if (std::system("command -v ompl_benchmark_statistics >/dev/null 2>&1") != 0 ||
      std::system("command -v python3 >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "ompl_benchmark_statistics (Debian package ompl-demos) is not installed";
  }
  const fs::path sweep = writeSweep(
      "vary:\n  planner.method: [ray, dp]\n  planner.ray.horizon: [10, 30]\n"
      "  planner.ompl.seed: [1, 2]\n");
  const fs::path out = dir_ / "out";
  const Result run = batch(sweep, out, {"--jobs", "2"});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  const fs::path db = dir_ / "results.db";
  const std::string script =
      fmt::format("cd {} && ompl_benchmark_statistics {} -d {} >stats_out.txt 2>stats_err.txt",
                  dir_.string(), (out / "ompl_benchmark.log").string(), db.string());
  ASSERT_EQ(std::system(script.c_str()), 0)
      << readFile(dir_ / "stats_out.txt") << readFile(dir_ / "stats_err.txt");
  EXPECT_FALSE(contains(readFile(dir_ / "stats_err.txt"), "Error"))
      << readFile(dir_ / "stats_err.txt");

  // The database as Planner Arena reads it, one line per run and a few counts.
  writeFile(dir_ / "query.py",
            "import sqlite3, sys\n"
            "c = sqlite3.connect(sys.argv[1])\n"
            "print('experiments', *c.execute('SELECT count(*), name, runcount FROM experiments')"
            ".fetchone())\n"
            "print('planners', c.execute('SELECT count(*) FROM plannerConfigs').fetchone()[0])\n"
            "print('outcomes', c.execute(\"SELECT count(*) FROM enums WHERE name = 'outcome'\")"
            ".fetchone()[0])\n"
            "for r in c.execute('SELECT p.name, r.time, r.solved, r.outcome, r.best_cost, r.min_f, "
            "r.planner_ompl_seed FROM runs r JOIN plannerConfigs p ON p.id = r.plannerid'):\n"
            "    print('run|%s|%.12g|%d|%d|%.12g|%.12g|%d' % r)\n");
  const std::string query = fmt::format("python3 {} {} >{} 2>&1", (dir_ / "query.py").string(),
                                        db.string(), (dir_ / "query.txt").string());
  ASSERT_EQ(std::system(query.c_str()), 0) << readFile(dir_ / "query.txt");
  std::istringstream lines(readFile(dir_ / "query.txt"));
  std::vector<std::string> runs, other;
  for (std::string line; std::getline(lines, line);) {
    (line.starts_with("run|") ? runs : other).push_back(line);
  }
  EXPECT_EQ(other, (std::vector<std::string>{"experiments 1 demo 2", "planners 4", "outcomes 5"}));

  // What each case should be: planner = method and the non-seed values, its runs the seeds.
  std::vector<std::string> expected;
  for (const cli::BatchRow& r : cli::readBatchRows(out / "results.jsonl")) {
    ASSERT_EQ(r.status, "planned");
    expected.push_back(fmt::format("run|{} planner.ray.horizon={}|{:.12g}|1|0|{:.12g}|{:.12g}|{}",
                                   r.method, r.params.at(1).second, *r.metrics[12], *r.metrics[0],
                                   *r.metrics[5], r.params.at(2).second));
  }
  ASSERT_EQ(expected.size(), 8u);
  std::sort(expected.begin(), expected.end());
  std::sort(runs.begin(), runs.end());
  EXPECT_EQ(runs, expected);
}

TEST_F(Batch, BadKeyInTheSweepFailsBeforeAnythingRuns) {
  const fs::path out = dir_ / "out";
  const Result key = batch(writeSweep("vary:\n  planner.ray.horizn: [10, 15]\n"), out);
  EXPECT_EQ(key.exit_code, 4) << describe(key);
  EXPECT_TRUE(contains(key.err, "vary.planner.ray.horizn")) << key.err;
  EXPECT_TRUE(contains(key.err, "horizn")) << key.err;
  EXPECT_FALSE(fs::exists(out)) << "nothing runs, nothing is written";

  const Result value = batch(writeSweep("vary:\n  planner.ray.horizon: [10, -3]\n"), out);
  EXPECT_EQ(value.exit_code, 4) << describe(value);
  EXPECT_TRUE(contains(value.err, "planner.ray.horizon")) << value.err;
  EXPECT_FALSE(fs::exists(out));

  const Result top = batch(writeSweep("varry:\n  planner.ray.horizon: [10]\n"), out);
  EXPECT_EQ(top.exit_code, 4) << describe(top);
  EXPECT_TRUE(contains(top.err, "varry: unknown key")) << top.err;

  const Result shard = batch(writeSweep(kSmallVary), out, {"--shard", "4/3"});
  EXPECT_EQ(shard.exit_code, 4) << describe(shard);
  EXPECT_TRUE(contains(shard.err, "--shard '4/3'")) << shard.err;
  EXPECT_FALSE(fs::exists(out));
}

// A results.jsonl row as a batch writes it (metrics in kBatchMetrics order, "null" when absent).
std::string jsonRow(int index,
                    const std::string& method,
                    const std::string& horizon,
                    const std::vector<std::string>& metrics) {
  std::string row = fmt::format(
      "{{\"case_id\": \"c{0}\", \"index\": {0}, \"job\": \"demo.yaml\", \"params\": "
      "{{\"planner.method\": \"{1}\", \"planner.ray.horizon\": \"{2}\"}}, \"repeat\": 0, "
      "\"method\": \"{1}\", \"status\": \"planned\", \"reason\": \"\"",
      index, method, horizon);
  for (std::size_t m = 0; m < cli::kBatchMetrics.size(); ++m) {
    row += fmt::format(", \"{}\": {}", cli::kBatchMetrics[m],
                       m < metrics.size() ? metrics[m] : std::string("null"));
  }
  return row + ", \"map_reused\": false}\n";
}

// `batch report` on values that make degenerate axes: J equal but for rounding (this died with
// std::bad_alloc in the tick code), horizons equal but for rounding, one value, huge values
// whose mean overflows, a metric no case has. Every plot is written and sane.
TEST_F(Batch, ReportSurvivesDegenerateValues) {
  const fs::path out = dir_ / "out";
  fs::create_directories(out);
  // J_s, cost_f_s, cost_omega_s, cost_alpha_s, dp_gap_percent, min_f, …, cycle_time_s, coverage,
  // map_s, plan_s.
  writeFile(out / "results.jsonl",
            jsonRow(0, "ray", "10",
                    {"25.46247875282346", "1", "1", "0", "0", "1e308", "null", "null", "null",
                     "109.4", "null", "2", "0.5"}) +
                jsonRow(1, "dp", "10.000000000000002",
                        {"25.462478752823472", "1", "1", "0", "0", "1e308", "null", "null", "null",
                         "109.4", "null", "2", "1e-300"}) +
                jsonRow(2, "dp", "10.000000000000002",
                        {"25.462478752823472", "1", "1", "0", "0", "-1e308", "null", "null", "null",
                         "109.4", "null", "2", "0"}));
  const Result report = scanplan({"batch", "report", out.string()});
  ASSERT_EQ(report.exit_code, 0) << describe(report);
  EXPECT_TRUE(contains(report.out, "tally      3 case(s): 3 planned")) << report.out;
  for (const char* stem :
       {"J_s_vs_planner_method", "J_s_vs_planner_ray_horizon", "min_f_vs_planner_ray_horizon",
        "plan_s_vs_planner_method", "cycle_time_s_vs_planner_ray_horizon"}) {
    SCOPED_TRACE(stem);
    const fs::path png = out / "plots" / (std::string(stem) + ".png");
    ASSERT_TRUE(fs::exists(png));
    const cli::RgbImage image = cli::decodePng(readFile(png));
    EXPECT_GT(image.width, 720);
    EXPECT_LT(image.width, 720 + 600) << "tick values stay short";
    EXPECT_LT(image.height, 480 + 300);
    const std::string svg = readFile(out / "plots" / (std::string(stem) + ".svg"));
    EXPECT_FALSE(contains(svg, "nan")) << svg.substr(0, 2000);
    EXPECT_FALSE(contains(svg, "inf")) << svg.substr(0, 2000);
    const auto ticks = std::count(svg.begin(), svg.end(), '\n');
    EXPECT_GT(ticks, 10);
    EXPECT_LT(ticks, 60) << "a few ticks per axis";
  }
  // The flat J axis is centred on the value: 25.46 ± 2.5, ticks 23 … 27.
  const std::string j = readFile(out / "plots/J_s_vs_planner_method.svg");
  EXPECT_TRUE(contains(j, ">25.0<") || contains(j, ">25<")) << j;
  // No case has coverage: no plot of it.
  EXPECT_FALSE(fs::exists(out / "plots/coverage_vs_planner_method.png"));

  // A single case, and then every metric of it null.
  writeFile(out / "results.jsonl", jsonRow(0, "ray", "10", {"25.5"}));
  const Result one = scanplan({"batch", "report", out.string()});
  ASSERT_EQ(one.exit_code, 0) << describe(one);
  EXPECT_TRUE(fs::exists(out / "plots/J_s_vs_planner_method.png"));
  writeFile(out / "results.jsonl", jsonRow(0, "ray", "10", {}));
  const Result none = scanplan({"batch", "report", out.string()});
  ASSERT_EQ(none.exit_code, 0) << describe(none);
}

}  // namespace
