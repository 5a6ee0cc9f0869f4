// `scanplan batch` end to end on the lightened demo (test::kLightDemo, simulation off, each case
// a fraction of a second): a small sweep with seeds, the planner's and the DP
// yardstick's times, resume after a batch killed mid-run, shards merged, failing cases as rows
// and the exit code they give, labelled PNG plots read back, the OMPL benchmark log through
// OMPL's own script (when installed), and sweep errors before anything runs.
#include <gtest/gtest.h>

#include <signal.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <scanplan/config/job.h>
#include "cli/batch/batch.h"
#include "cli/plot/image_io.h"
#include "cli_support.h"
#include "image_support.h"
#include "test_support.h"
#include "tests/io_support.h"

namespace {

using namespace scanplan;
using namespace scanplan::test;

const fs::path kDemoJob = fs::path(SCANPLAN_SOURCE_DIR) / "data/jobs/demo_rings.yaml";

// The fixed settings of every case: the light demo, no simulation, no refinement so that the DP
// gap compares grid paths with the grid optimum (refinement can take a path below DP's grid
// optimum, a negative gap), and an OMPL search of 2000 iterations (0.1 s a case here, where the
// default 10000 takes 1.1 s): seeds 1, 2 and 3 all solve with 2000, one of the three with 1000.
std::string sweepHeader(const std::vector<std::string>& set = {}) {
  std::string text = fmt::format("jobs: ['{}']\nset:\n", kDemoJob.string());
  for (const std::string& o : kLightDemo) text += "  - '" + o + "'\n";
  text +=
      "  - simulation.enabled=false\n  - planner.refine.enabled=false\n"
      "  - planner.ompl.max_iterations=2000\n";
  for (const std::string& o : set) text += "  - '" + o + "'\n";
  return text;
}

// A small sweep: 2 planners x 3 horizons x 2 seeds, each twice (repeats) = 24 cases
// on one map. The horizon is ray's only: OMPL's runs at the three horizons are re-runs too.
const std::string kSmallSweep =
    "vary:\n"
    "  planner.method: [ray, ompl]\n"
    "  planner.ray.horizon: [10, 15, 30]\n"
    "seeds: [1, 2]\n"
    "repeats: 2\n";

// 12 quick cases (ray and DP take no seed; the seeds make distinct cases all the same) for the
// tests of resume and shards.
const std::string kQuickSweep =
    "vary:\n"
    "  planner.method: [ray, dp]\n"
    "  planner.ray.horizon: [10, 15, 30]\n"
    "seeds: {from: 1, to: 2}\n";

// What a case gave: its planner, outcome and every number but the wall times.
std::string outcome(const cli::BatchRow& r) {
  std::string text = fmt::format("{} {} [{}]", r.method, r.status, r.reason);
  for (std::size_t m = 0; m < cli::kFirstTimingMetric; ++m) {
    text += " " + (r.metrics[m] ? fmt::format("{}", *r.metrics[m]) : std::string("-"));
  }
  return text;
}

// A row without its wall times and without map_reused (which case computes the map depends on
// which cases a run has left to do): what must not change between runs.
std::string stable(const cli::BatchRow& r) {
  std::string text =
      fmt::format("{} #{} {} s{} r{} {}", r.case_id, r.index, r.job,
                  r.seed ? std::to_string(*r.seed) : std::string("-"), r.repeat, outcome(r));
  for (const auto& [k, v] : r.params) text += " " + k + "=" + v;
  return text;
}

std::string param(const cli::BatchRow& r, const std::string& key) {
  for (const auto& [k, v] : r.params) {
    if (k == key) return v;
  }
  return {};
}

std::optional<double> metric(const cli::BatchRow& r, const char* name) {
  const auto* it = std::find_if(cli::kBatchMetrics.begin(), cli::kBatchMetrics.end(),
                                [&](const char* m) { return std::string(m) == name; });
  EXPECT_NE(it, cli::kBatchMetrics.end()) << name;
  if (it == cli::kBatchMetrics.end()) return std::nullopt;
  return r.metrics[static_cast<std::size_t>(it - cli::kBatchMetrics.begin())];
}

// The tick labels of an axis ('x' or 'y') that a figure's SVG lists in its <desc>.
std::vector<std::string> svgTicks(const std::string& svg, char axis) {
  const std::string key = std::string("; ") + axis + " ticks: ";
  const std::size_t at = svg.find(key, svg.find("<desc>"));
  EXPECT_NE(at, std::string::npos) << svg.substr(0, 600);
  if (at == std::string::npos) return {};
  const std::size_t end = svg.find_first_of(";<", at + key.size());
  std::vector<std::string> ticks;
  std::size_t from = at + key.size();
  while (from < end) {
    const std::size_t comma = std::min(svg.find(", ", from), end);
    ticks.push_back(svg.substr(from, comma - from));
    from = comma + 2;
  }
  return ticks;
}

// Whether `p` is `colour` up to antialiasing at a line's edge (sum of channel differences).
bool near(const cli::Rgb& p, const cli::Rgb& colour) {
  constexpr int kTolerance = 60;
  return std::abs(p.r - colour.r) + std::abs(p.g - colour.g) + std::abs(p.b - colour.b) <=
         kTolerance;
}

// Whether a pixel within 1 px of (x, y) is `colour` (up to antialiasing).
bool nearPixel(const cli::RgbImage& image, double x, double y, const cli::Rgb& colour) {
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      const int px = static_cast<int>(std::floor(x)) + dx,
                py = static_cast<int>(std::floor(y)) + dy;
      if (px >= 0 && py >= 0 && px < image.width && py < image.height &&
          near(image.at(px, py), colour)) {
        return true;
      }
    }
  }
  return false;
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
  fs::path writeSweep(const std::string& body, const std::vector<std::string>& set = {}) const {
    const fs::path file = dir_ / "sweep.yaml";
    writeFile(file, sweepHeader(set) + body);
    return file;
  }
  static std::vector<std::string> args(const fs::path& sweep,
                                       const fs::path& out,
                                       const std::vector<std::string>& extra) {
    std::vector<std::string> a{"batch", sweep.string(), "-o", out.string()};
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  }
  Result batch(const fs::path& sweep, const fs::path& out, std::vector<std::string> extra = {}) {
    return scanplan(args(sweep, out, extra));
  }
  // Starts a batch in the background (output to files in the scratch folder): its process id.
  pid_t startBatch(const fs::path& sweep, const fs::path& out, std::vector<std::string> extra) {
    return spawnScanplan(args(sweep, out, extra), dir_ / "killed_out.txt", dir_ / "killed_err.txt");
  }
};

// The complete rows of a results.jsonl as it is being written (a row is complete with its '\n').
std::size_t completeRows(const fs::path& jsonl) {
  const std::string text = readFile(jsonl);
  std::size_t n = 0;
  for (std::size_t at = text.find("}\n"); at != std::string::npos; at = text.find("}\n", at + 1)) {
    ++n;
  }
  return n;
}

TEST_F(Batch, SmallSweepGivesOneRowPerCaseSeedAndRepeatWithTheDpGap) {
  const fs::path sweep = writeSweep(kSmallSweep);
  const fs::path out = dir_ / "out";
  const Result run = batch(sweep, out, {"--jobs", "2"});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_TRUE(contains(run.out, "24 case(s): 24 run, 0 already done, 0 error(s); 1 map(s)"))
      << "one map whatever the seed (scanner.noise.seed is the simulation's)\n"
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
    if (!r.map_reused) rows_map_s += metric(r, "map_s").value_or(0.0);
  }
  EXPECT_NEAR(map_s, rows_map_s, 0.051);
  EXPECT_TRUE(contains(run.out,
                       "\ntally      24 case(s): 24 planned, 0 no_path, 0 no_executable_path, 0 "
                       "invalid_trajectory, 0 error\n"))
      << run.out;

  const std::vector<cli::BatchRow> rows = cli::readBatchRows(out / "results.jsonl");
  ASSERT_EQ(rows.size(), 24u);
  int reused = 0;
  // Each case's outcome by planner, horizon, seed and repeat.
  std::map<std::tuple<std::string, std::string, int, int>, std::string> outcomes;
  for (const cli::BatchRow& r : rows) {
    SCOPED_TRACE(stable(r));
    EXPECT_EQ(r.status, "planned");
    EXPECT_EQ(r.method, param(r, "planner.method"));
    ASSERT_TRUE(r.seed.has_value());
    // DP is the optimum of the grid problem the unrefined planners solve: the gap is >= 0.
    ASSERT_TRUE(metric(r, "dp_gap_percent").has_value());
    EXPECT_GE(*metric(r, "dp_gap_percent"), 0.0);
    // The planner's time and, apart, the DP yardstick's (planner.dp_gap is on).
    ASSERT_TRUE(metric(r, "plan_s").has_value());
    EXPECT_GE(*metric(r, "plan_s"), 0.0);
    ASSERT_TRUE(metric(r, "dp_s").has_value());
    EXPECT_GT(*metric(r, "dp_s"), 0.0);
    outcomes[{r.method, param(r, "planner.ray.horizon"), *r.seed, r.repeat}] = outcome(r);
    reused += r.map_reused ? 1 : 0;
  }
  EXPECT_EQ(reused, 23) << "one map for all 24 cases";
  ASSERT_EQ(outcomes.size(), 24u) << "a case per planner, horizon, seed and repeat";
  // Ray takes no seed: the same at both. OMPL: a seed gives the same path at every repeat and
  // horizon (not OMPL's), and the two seeds give different paths.
  const auto of = [&](const char* method, const char* horizon, int seed, int repeat) {
    return outcomes[{method, horizon, seed, repeat}];
  };
  bool seeds_differ = false;
  for (const char* h : {"10", "15", "30"}) {
    for (const int repeat : {0, 1}) {
      EXPECT_EQ(of("ray", h, 1, repeat), of("ray", h, 2, repeat)) << h;
      for (const int seed : {1, 2}) {
        EXPECT_EQ(of("ompl", h, seed, repeat), of("ompl", "10", seed, 0))
            << "horizon " << h << ", seed " << seed << ", repeat " << repeat;
      }
    }
    seeds_differ = seeds_differ || of("ompl", h, 1, 0) != of("ompl", h, 2, 0);
  }
  EXPECT_TRUE(seeds_differ) << of("ompl", "10", 1, 0) << "\n" << of("ompl", "10", 2, 0);

  // CSV: a header and one line per case, a column per varied key, then the seed.
  const std::string csv = readFile(out / "results.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 25);
  EXPECT_TRUE(csv.starts_with(
      "case_id,job,planner.method,planner.ray.horizon,seed,repeat,method,status,reason,J_s,"))
      << csv.substr(0, 200);
  EXPECT_TRUE(contains(csv, ",map_s,plan_s,dp_s,validation_s,simulation_s,map_reused\n"))
      << csv.substr(0, 400);
  EXPECT_TRUE(fs::exists(out / "summary.md"));
  EXPECT_TRUE(fs::exists(out / "ompl_benchmark.log"));
  EXPECT_TRUE(tmpFiles(out).empty());

  // A plot of every metric that some case has, against each varied key; none of the others
  // (coverage and simulation time: no simulation).
  std::set<std::string> expected_plots, plots;
  for (std::size_t m = 0; m < cli::kBatchMetrics.size(); ++m) {
    const bool any = std::any_of(rows.begin(), rows.end(), [&](const cli::BatchRow& r) {
      return r.metrics[m] && std::isfinite(*r.metrics[m]);
    });
    if (!any) continue;
    for (const char* key : {"planner_method", "planner_ray_horizon"}) {
      for (const char* ext : {".png", ".svg"}) {
        expected_plots.insert(fmt::format("{}_vs_{}{}", cli::kBatchMetrics[m], key, ext));
      }
    }
  }
  EXPECT_EQ(expected_plots.size(), 14u * 2u * 2u) << "all but coverage and simulation_s";
  for (const auto& e : fs::directory_iterator(out / "plots")) {
    plots.insert(e.path().filename().string());
  }
  EXPECT_EQ(plots, expected_plots);
  EXPECT_TRUE(expected_plots.count("dp_s_vs_planner_method.png"));

  // The PNG plots carry their text: a margin around the 720 x 480 data area with the title on
  // top, the y-axis title on the left and the legend on the right, all in dark pixels.
  const std::string stem = "plots/J_s_vs_planner_ray_horizon";
  const std::string png_bytes = readFile(out / (stem + ".png"));
  const cli::RgbImage png = test::decodePng(png_bytes);
  ASSERT_GT(png.width, 720 + 100);
  ASSERT_GT(png.height, 480 + 60);
  EXPECT_GT(darkPixels(png, 0, 0, png.width, 30), 100) << "title";
  EXPECT_GT(darkPixels(png, 0, 60, 30, png.height - 60), 100) << "y-axis title";
  EXPECT_GT(darkPixels(png, 0, png.height - 30, png.width, png.height), 100) << "x-axis title";
  EXPECT_GT(darkPixels(png, png.width - 80, 0, png.width, 200), 50) << "legend";
  // The SVG is the same figure in vectors (no raster at all), its words in <title> and <desc>;
  // the PNG's 720 x 480 data area sits inside its black frame.
  const std::string svg = readFile(out / (stem + ".svg"));
  EXPECT_TRUE(contains(svg, "<title>J, objective (s) against planner.ray.horizon</title>"));
  EXPECT_FALSE(contains(svg, "<image"));
  const test::Crop area = test::plotArea(png);
  ASSERT_EQ(area.w, 720);
  ASSERT_EQ(area.h, 480);

  // Each case is a cross (x) in its planner's colour at its horizon and J, the planners side by
  // side: positions as writePlot computes them (horizons 10 … 30 padded by axisRange; ray, the
  // first planner in the rows, left of OMPL by 1.2 % of the axis).
  const auto [x0, x1] = cli::axisRange(10.0, 30.0);
  double j_lo = 1e300, j_hi = -1e300;
  for (const cli::BatchRow& r : rows) {
    j_lo = std::min(j_lo, *metric(r, "J_s"));
    j_hi = std::max(j_hi, *metric(r, "J_s"));
  }
  const auto [y0, y1] = cli::axisRange(j_lo, j_hi);
  const double spread = (x1 - x0) * 0.012;
  for (const char* method : {"ray", "ompl"}) {
    const cli::Rgb colour = cli::batchPlannerColour(method);
    int n = 0;
    for (int y = 0; y < area.h; ++y) {
      for (int x = 0; x < area.w; ++x) n += near(png.at(area.x + x, area.y + y), colour) ? 1 : 0;
    }
    EXPECT_GT(n, 100) << method << ": its crosses and line in its colour";
  }
  ASSERT_NE(cli::batchPlannerColour("ray"), cli::batchPlannerColour("ompl"));
  for (const cli::BatchRow& r : rows) {
    SCOPED_TRACE(stable(r));
    const double offset = (r.method == "ray" ? -0.5 : 0.5) * spread;
    const double horizon = std::stod(param(r, "planner.ray.horizon"));
    const double x = area.x + (horizon + offset - x0) / (x1 - x0) * area.w;
    const double y = area.y + (1.0 - (*metric(r, "J_s") - y0) / (y1 - y0)) * area.h;
    // The cross's four arms, 2 px out along the diagonals from its centre: a line through the
    // point (another case's mean line) covers two of them at most.
    int arms = 0;
    for (const auto& [dx, dy] : {std::pair{-2, -2}, {2, -2}, {-2, 2}, {2, 2}}) {
      arms += nearPixel(png, x + dx, y + dy, cli::batchPlannerColour(r.method)) ? 1 : 0;
    }
    EXPECT_GE(arms, 3) << "no cross at (" << x << ", " << y << ") of the data area";
  }

  const std::string log = readFile(out / "ompl_benchmark.log");
  // Ray at 3 horizons, OMPL once: planner.ray.horizon does not label OMPL's runs (it does not
  // read it), which makes OMPL's 12 runs (3 horizons x 2 seeds x 2 repeats) one planner's.
  EXPECT_TRUE(contains(log, "\n4 planners\n")) << log;
  EXPECT_FALSE(contains(log, "ompl planner.ray.horizon")) << log;
  EXPECT_TRUE(contains(log, "\nray planner.ray.horizon=10\n")) << log;
  EXPECT_TRUE(contains(log, "\ndp time REAL\n")) << log;
  EXPECT_TRUE(contains(log, "\nseed INTEGER\n")) << log;

  // `batch report` regenerates the summary and the plots from the results alone.
  fs::remove(out / "summary.md");
  fs::remove_all(out / "plots");
  const Result report = scanplan({"batch", "report", out.string()});
  ASSERT_EQ(report.exit_code, 0) << describe(report);
  const std::string summary = readFile(out / "summary.md");
  EXPECT_TRUE(contains(summary, "| ray | 30 | 4 | 4 |")) << summary;  // seeds and repeats
  EXPECT_TRUE(contains(summary, "| plan (s) | DP (s) |")) << summary;
  plots.clear();
  for (const auto& e : fs::directory_iterator(out / "plots")) {
    plots.insert(e.path().filename().string());
  }
  EXPECT_EQ(plots, expected_plots);
  EXPECT_EQ(readFile(out / (stem + ".png")), png_bytes) << "the same figure";
}

// The pipeline also runs the DP yardstick (planner.dp_gap): plan_s is the planner's time without
// it, dp_s the yardstick's. The yardstick is made slow here (a grid 8 times finer than the map's:
// 0.2 s against ray's 0.03 s on an idle machine), so that a plan_s that still held it would be
// larger than dp_s.
TEST_F(Batch, PlanTimeIsThePlannersOwnAndDpTimeTheYardsticks) {
  // DP on a grid fine enough to take several times Ray's time (~8× here; at 8 subdivisions the
  // step-major DP can finish before Ray), so that plan_s < dp_s tells the two apart.
  const fs::path sweep = writeSweep(
      "cases:\n  - {planner.method: ray}\n  - {planner.method: ray, planner.dp_gap: false}\n"
      "  - {planner.method: dp}\n",
      {"planner.dp.angle_subdivisions=16"});
  const fs::path out = dir_ / "out";
  const Result run = batch(sweep, out, {"--jobs", "1"});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  const std::vector<cli::BatchRow> rows = cli::readBatchRows(out / "results.jsonl");
  ASSERT_EQ(rows.size(), 3u);
  for (const cli::BatchRow& r : rows) {
    ASSERT_EQ(r.status, "planned") << stable(r);
    ASSERT_TRUE(metric(r, "plan_s").has_value()) << stable(r);
    EXPECT_GT(*metric(r, "plan_s"), 0.0) << stable(r);
  }
  const cli::BatchRow& ray = rows[0];
  ASSERT_TRUE(metric(ray, "dp_s").has_value());
  EXPECT_LT(*metric(ray, "plan_s"), *metric(ray, "dp_s"))
      << "plan_s holds ray only, not the DP yardstick";
  EXPECT_TRUE(metric(ray, "dp_gap_percent").has_value());
  // No yardstick without the gap; and with method dp the planner is the yardstick: its time is
  // plan_s, and dp_s is empty (nothing ran on top of it).
  EXPECT_FALSE(metric(rows[1], "dp_s").has_value()) << stable(rows[1]);
  EXPECT_FALSE(metric(rows[1], "dp_gap_percent").has_value()) << stable(rows[1]);
  EXPECT_FALSE(metric(rows[2], "dp_s").has_value()) << stable(rows[2]);
}

// One pipeline: a batch case and `plan` with the same settings give the same numbers (both run
// pipeline::planPrepared on the maps of pipeline::prepareScan).
TEST_F(Batch, ACaseGivesTheNumbersOfPlanWithTheSameSettings) {
  const fs::path sweep = writeSweep("cases:\n  - {planner.method: ray}\n");
  const fs::path out = dir_ / "out";
  const Result run = batch(sweep, out, {"--jobs", "1"});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  const std::vector<cli::BatchRow> rows = cli::readBatchRows(out / "results.jsonl");
  ASSERT_EQ(rows.size(), 1u);
  ASSERT_EQ(rows[0].status, "planned") << stable(rows[0]);

  std::vector<std::string> plan_args{"plan", kDemoJob.string(), "-o", (dir_ / "plan").string()};
  for (const std::string& o : kLightDemo) plan_args.insert(plan_args.end(), {"--set", o});
  for (const char* o : {"simulation.enabled=false", "planner.refine.enabled=false",
                        "planner.ompl.max_iterations=2000", "planner.method=ray"}) {
    plan_args.insert(plan_args.end(), {"--set", o});
  }
  const Result plan = scanplan(plan_args);
  ASSERT_EQ(plan.exit_code, 0) << describe(plan);
  const auto report = nlohmann::json::parse(readFile(dir_ / "plan" / "report.json"));
  const cli::BatchRow& r = rows[0];
  EXPECT_EQ(metric(r, "J_s"), report["objective"]["J_s"].get<double>());
  EXPECT_EQ(metric(r, "cost_f_s"), report["objective"]["cost_f_s"].get<double>());
  EXPECT_EQ(metric(r, "dp_gap_percent"), report["dp_baseline"]["gap_percent"].get<double>());
  EXPECT_EQ(metric(r, "min_f"), report["path"]["min_f"].get<double>());
  EXPECT_EQ(metric(r, "min_clearance_mm"), report["path"]["min_clearance_mm"].get<double>());
  EXPECT_EQ(metric(r, "max_omega_deg_s"), report["path"]["max_abs_omega_deg_s"].get<double>());
}

// A real interruption: the batch killed (SIGKILL) between cases, then --resume runs the rest,
// and the results are those of a run never interrupted.
TEST_F(Batch, KilledBatchResumesToTheUninterruptedResult) {
  const fs::path sweep = writeSweep(kQuickSweep);
  const fs::path full = dir_ / "full";
  const Result whole = batch(sweep, full);
  ASSERT_EQ(whole.exit_code, 0) << describe(whole);
  const std::size_t cases = cli::readBatchRows(full / "results.jsonl").size();
  ASSERT_EQ(cases, 12u);

  // One case at a time, killed as soon as two rows are written (a case takes ~0.1 s here, so
  // ten are still to run; the batch has to be mid-run, checked below).
  const fs::path part = dir_ / "part";
  const pid_t pid = startBatch(sweep, part, {"--jobs", "1"});
  ASSERT_GT(pid, 0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  int status = 0;
  bool ended = false, late = false;
  while (completeRows(part / "results.jsonl") < 2) {
    if (::waitpid(pid, &status, WNOHANG) == pid) {
      ended = true;
      break;
    }
    if (std::chrono::steady_clock::now() > deadline) {
      late = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  if (!ended) {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &status, 0);
  }
  ASSERT_FALSE(late) << "no 2 rows after 60 s\n" << readFile(dir_ / "killed_err.txt");
  ASSERT_FALSE(ended) << "the batch ended before it was killed: exit "
                      << (WIFEXITED(status) ? WEXITSTATUS(status) : -1) << "\n"
                      << readFile(dir_ / "killed_out.txt") << readFile(dir_ / "killed_err.txt");
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
  const std::size_t done = cli::readBatchRows(part / "results.jsonl").size();
  ASSERT_GE(done, 2u);
  ASSERT_LT(done, cases) << "the kill came after the last case: make the sweep bigger";
  EXPECT_TRUE(readFile(dir_ / "killed_out.txt").empty()) << "killed before its summary lines";
  EXPECT_FALSE(fs::exists(part / "summary.md")) << "killed before its report";

  // A rerun without --resume refuses to mix two batches.
  const Result refused = batch(sweep, part);
  EXPECT_EQ(refused.exit_code, 4) << describe(refused);
  EXPECT_TRUE(contains(refused.err, "--resume")) << refused.err;
  // A torn last line, as a kill in the middle of a write leaves it.
  std::ofstream(part / "results.jsonl", std::ios::app) << "{\"case_id\": \"0123";
  const Result resumed = batch(sweep, part, {"--resume"});
  ASSERT_EQ(resumed.exit_code, 0) << describe(resumed);
  EXPECT_TRUE(
      contains(resumed.out, fmt::format("12 case(s): {} run, {} already done", cases - done, done)))
      << resumed.out;
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

// `seeds:` goes into every seed key of the job — each key of the resolved job named like a
// seed, not only the two known today — and makes a case per seed.
TEST_F(Batch, SeedsGoIntoEverySeedKeyOfTheJob) {
  const fs::path file = writeSweep(
      "vary:\n  planner.method: [ray, ompl]\nseeds: {from: 7, to: 107, step: 100}\n"
      "repeats: 2\n");
  const cli::Sweep sweep = cli::loadSweep(file);
  EXPECT_EQ(sweep.seeds, (std::vector<int>{7, 107}));
  ASSERT_EQ(sweep.cases.size(), 8u);  // 2 planners x 2 seeds x 2 repeats
  std::set<std::string> ids;
  for (const cli::SweepCase& c : sweep.cases) {
    SCOPED_TRACE(c.id);
    ASSERT_TRUE(c.seed.has_value());
    EXPECT_EQ(c.seed, c.index / 2 % 2 == 0 ? 7 : 107) << "planner, then seed, then repeat";
    EXPECT_EQ(c.repeat, static_cast<int>(c.index % 2));
    ids.insert(c.id);
    std::istringstream yaml(config::jobToYaml(config::loadJob(c.job_file, c.overrides)));
    int seeds = 0;
    for (std::string line; std::getline(yaml, line);) {
      const std::size_t colon = line.find(':');
      if (colon == std::string::npos || !contains(line.substr(0, colon), "seed")) continue;
      ++seeds;
      EXPECT_EQ(line.substr(colon + 1), fmt::format(" {}", *c.seed)) << line;
    }
    EXPECT_EQ(seeds, static_cast<int>(cli::kJobSeedKeys.size()));
  }
  EXPECT_EQ(ids.size(), 8u) << "a distinct case id per planner, seed and repeat";
}

// The sweep example of docs/commands.md, as written there: it loads (every value checked on the demo job)
// and expands to (2 planners x 3 horizons + 1 explicit case) x 3 seeds.
// The sweep example of docs/commands.md is the bundled data/sweeps/planners.yaml, word for word, and loads.
// A range whose step is tiny asks for more values than any integer holds: refused with the
// count, before it is cast (float-cast-overflow).
TEST_F(Batch, ARangeOfTooManyValuesIsRefusedWithItsCount) {
  for (const char* range : {"{from: 0, to: 1, step: 1e-300}", "{from: -1e9, to: 1e9, step: 1}"}) {
    const fs::path file = writeSweep(std::string("vary:\n  planner.ray.horizon: ") + range + "\n");
    try {
      cli::loadSweep(file);
      ADD_FAILURE() << range << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("expected at most 100000"), std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find("planner.ray.horizon"), std::string::npos) << e.what();
    }
  }
}

TEST_F(Batch, DocsSweepExampleIsTheBundledSweepAndLoads) {
  const std::string readme = readFile(sourceDir() / "docs" / "commands.md");
  const std::size_t section = readme.find("### `scanplan batch");
  ASSERT_NE(section, std::string::npos);
  const std::size_t begin = readme.find("```yaml\n", section);
  ASSERT_NE(begin, std::string::npos);
  const std::size_t end = readme.find("```\n", begin + 8);
  ASSERT_NE(end, std::string::npos);
  const fs::path bundled = sourceDir() / "data" / "sweeps" / "planners.yaml";
  EXPECT_EQ(readme.substr(begin + 8, end - begin - 8), readFile(bundled));
  const cli::Sweep sweep = cli::loadSweep(bundled);
  EXPECT_EQ(sweep.keys, (std::vector<std::string>{"planner.method", "planner.ray.horizon",
                                                  "planner.dp.angle_subdivisions"}));
  EXPECT_EQ(sweep.seeds, (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(sweep.cases.size(), 21u);  // (2 methods × 3 horizons + 1 dp case) × 3 seeds
}

TEST_F(Batch, ShardsMergedEqualTheUnshardedRun) {
  const fs::path sweep = writeSweep(kQuickSweep);
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

// The shards through GNU parallel, as across hosts (docs/commands.md), merged: the unsharded run.
TEST_F(Batch, ShardsThroughGnuParallelEqualTheUnshardedRun) {
  if (std::system("command -v parallel >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "GNU parallel is not installed";
  }
  const fs::path sweep = writeSweep(kQuickSweep);
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
  const std::string planned = "\"status\":\"planned\",\"reason\":\"\"";
  const std::size_t at = jsonl.find(planned);
  ASSERT_NE(at, std::string::npos) << jsonl;
  jsonl.replace(at, planned.size(),
                "\"status\":\"error\",\"reason\":\"internal error: boom (please report this)\"");
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
      "vary:\n  planner.method: [ray, dp]\n  planner.ray.horizon: [10, 30]\nseeds: [1, 2]\n");
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
            "r.seed, r.dp_time FROM runs r JOIN plannerConfigs p ON p.id = r.plannerid'):\n"
            "    dp = '-' if r[7] is None else '%.12g' % r[7]\n"
            "    print('run|%s|%.12g|%d|%d|%.12g|%.12g|%d|%s' % (r[:7] + (dp,)))\n");
  const std::string query = fmt::format("python3 {} {} >{} 2>&1", (dir_ / "query.py").string(),
                                        db.string(), (dir_ / "query.txt").string());
  ASSERT_EQ(std::system(query.c_str()), 0) << readFile(dir_ / "query.txt");
  std::istringstream lines(readFile(dir_ / "query.txt"));
  std::vector<std::string> runs, other;
  for (std::string line; std::getline(lines, line);) {
    (line.starts_with("run|") ? runs : other).push_back(line);
  }
  EXPECT_EQ(other,
            (std::vector<std::string>{"experiments 1 demo_rings -1", "planners 3", "outcomes 5"}));

  // What each case should be: planner = method and the non-seed values, its runs the seeds.
  std::vector<std::string> expected;
  for (const cli::BatchRow& r : cli::readBatchRows(out / "results.jsonl")) {
    ASSERT_EQ(r.status, "planned");
    const std::optional<double> dp_s = metric(r, "dp_s");
    // DP does not read planner.ray.horizon: its runs are one planner's, unlabelled by it (and
    // the experiment's run count is -1: the planners ran 2 and 4 times).
    const std::string label =
        r.method == "ray" ? " planner.ray.horizon=" + param(r, "planner.ray.horizon") : "";
    expected.push_back(fmt::format("run|{}{}|{:.12g}|1|0|{:.12g}|{:.12g}|{}|{}", r.method, label,
                                   *metric(r, "plan_s"), *metric(r, "J_s"), *metric(r, "min_f"),
                                   *r.seed,
                                   dp_s ? fmt::format("{:.12g}", *dp_s) : std::string("-")));
  }
  ASSERT_EQ(expected.size(), 8u);
  std::sort(expected.begin(), expected.end());
  std::sort(runs.begin(), runs.end());
  EXPECT_EQ(runs, expected);
}

// --resume after the sweep changed: the old rows are not this sweep's cases, and would be mixed
// into its results. Refused before anything runs; the folder is left as it was.
TEST_F(Batch, ResumingAChangedSweepIsRefused) {
  const fs::path out = dir_ / "out";
  ASSERT_EQ(batch(writeSweep("vary:\n  planner.ray.horizon: [10, 15]\n"), out).exit_code, 0);
  const std::string before = readFile(out / "results.jsonl");
  const Result changed =
      batch(writeSweep("vary:\n  planner.ray.horizon: [10, 20]\n"), out, {"--resume"});
  EXPECT_EQ(changed.exit_code, 4) << describe(changed);
  EXPECT_TRUE(contains(changed.err, "1 of its 2 row(s) are not cases of")) << changed.err;
  EXPECT_TRUE(contains(changed.err, "planner.ray.horizon=15")) << changed.err;
  EXPECT_EQ(readFile(out / "results.jsonl"), before);
  // The same sweep resumes (nothing left to run).
  const Result same =
      batch(writeSweep("vary:\n  planner.ray.horizon: [10, 15]\n"), out, {"--resume"});
  EXPECT_EQ(same.exit_code, 0) << describe(same);
  EXPECT_TRUE(contains(same.out, "2 case(s): 0 run, 2 already done")) << same.out;
}

// Folders of two different sweeps (other varied keys) are not shards of one: merge refuses them
// and writes nothing.
TEST_F(Batch, MergingFoldersOfDifferentSweepsIsRefused) {
  const fs::path a = dir_ / "a", b = dir_ / "b", merged = dir_ / "merged";
  ASSERT_EQ(batch(writeSweep("vary:\n  planner.ray.horizon: [10]\n"), a).exit_code, 0);
  ASSERT_EQ(batch(writeSweep("vary:\n  planner.ray.rays: [11]\n"), b).exit_code, 0);
  const Result run = scanplan({"batch", "merge", a.string(), b.string(), "-o", merged.string()});
  EXPECT_EQ(run.exit_code, 4) << describe(run);
  EXPECT_TRUE(contains(run.err, "columns differ")) << run.err;
  EXPECT_TRUE(contains(run.err, (b / "results.csv").string())) << run.err;
  EXPECT_FALSE(fs::exists(merged / "results.jsonl"));
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

  // A list as a key and a repeated key were "internal error".
  const Result list_key = batch(writeSweep("vary:\n  [planner.method]: [ray]\n"), out);
  EXPECT_EQ(list_key.exit_code, 4) << describe(list_key);
  EXPECT_TRUE(contains(list_key.err, "vary: a list used as a key")) << list_key.err;
  const Result repeated =
      batch(writeSweep("vary:\n  planner.method: [ray]\n  planner.method: [dp]\n"), out);
  EXPECT_EQ(repeated.exit_code, 4) << describe(repeated);
  EXPECT_TRUE(contains(repeated.err, "vary: planner.method: given twice")) << repeated.err;
  EXPECT_FALSE(fs::exists(out));

  const Result top = batch(writeSweep("varry:\n  planner.ray.horizon: [10]\n"), out);
  EXPECT_EQ(top.exit_code, 4) << describe(top);
  EXPECT_TRUE(contains(top.err, "varry: unknown key")) << top.err;

  const Result shard = batch(writeSweep(kQuickSweep), out, {"--shard", "4/3"});
  EXPECT_EQ(shard.exit_code, 4) << describe(shard);
  EXPECT_TRUE(contains(shard.err, "--shard '4/3'")) << shard.err;
  EXPECT_FALSE(fs::exists(out));

  const Result seed = batch(writeSweep("seeds: [1, 2.5]\n"), out);
  EXPECT_EQ(seed.exit_code, 4) << describe(seed);
  EXPECT_TRUE(contains(seed.err, "seeds: '2.5': expected an integer from 0 to 2147483647"))
      << seed.err;
  const Result twice = batch(writeSweep("seeds: [1, 2, 1]\n"), out);
  EXPECT_EQ(twice.exit_code, 4) << describe(twice);
  EXPECT_TRUE(contains(twice.err, "seeds: 1 is listed twice")) << twice.err;
  // A seed key varied or set as well would be overridden by the seeds: refused.
  const Result varied = batch(writeSweep("vary:\n  planner.ompl.seed: [1, 2]\nseeds: [3]\n"), out);
  EXPECT_EQ(varied.exit_code, 4) << describe(varied);
  EXPECT_TRUE(contains(varied.err, "seeds and vary or cases (planner.ompl.seed) both set a seed"))
      << varied.err;
  const Result set = batch(writeSweep("seeds: [3]\n", {"scanner.noise.seed=4"}), out);
  EXPECT_EQ(set.exit_code, 4) << describe(set);
  EXPECT_TRUE(contains(set.err, "seeds and set ('scanner.noise.seed=4') both set a seed"))
      << set.err;
  EXPECT_FALSE(fs::exists(out));
}

// Found by fuzzing (tests/fuzz, yaml_sweep): `repeats: 2000000000` or a grid of three 100-value
// ranges expanded billions of cases (out of memory), and 2 000 seeds loaded the job 2 000 times
// (minutes). The size is now refused from the lists' lengths before anything is expanded, and
// the seeds cost two loads (the smallest and the largest) however many there are.
TEST_F(Batch, HugeSweepsAreRefusedBeforeTheyAreExpanded) {
  const auto load = [&](const std::string& body) {
    return [this, body] { cli::loadSweep(writeSweep(body)); };
  };
  EXPECT_TRUE(throwsInputError(
      load("repeats: 2000000000\n"),
      {"sweep.yaml", "2e+09 cases", "2000000000 repeat(s)", "expected at most 100000"}));
  EXPECT_TRUE(throwsInputError(
      load("vary:\n  planner.ray.horizon: {from: 1, to: 100}\n"
           "  planner.ray.rays: {from: 1, to: 100}\n  planner.ray.starts: {from: 1, to: 100}\n"),
      {"1e+06 cases", "1e+06 setting(s)", "expected at most 100000"}));
  EXPECT_TRUE(throwsInputError(load("vary:\n  planner.ray.horizon: {from: 1, to: 400}\n"),
                               {"load the job(s) 401 times", "400 varied value(s)",
                                "expected at most 300; split the sweep"}));
  const cli::Sweep seeds = cli::loadSweep(writeSweep("seeds: {from: 1, to: 2000}\n"));
  EXPECT_EQ(seeds.cases.size(), 2000u);
  EXPECT_TRUE(throwsInputError(load("seeds: [1, 2, -3]\n"), {"seeds: '-3'"}));
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
    const cli::RgbImage image = test::decodePng(readFile(png));
    EXPECT_GT(image.width, 720);
    EXPECT_LT(image.width, 720 + 600) << "tick values stay short";
    EXPECT_LT(image.height, 480 + 300);
    const std::string svg = readFile(out / "plots" / (std::string(stem) + ".svg"));
    EXPECT_FALSE(contains(svg, "nan")) << svg.substr(0, 2000);
    EXPECT_FALSE(contains(svg, "inf")) << svg.substr(0, 2000);
    const std::vector<std::string> x_ticks = svgTicks(svg, 'x'), y_ticks = svgTicks(svg, 'y');
    EXPECT_GE(x_ticks.size(), 1u);
    EXPECT_LE(x_ticks.size(), 15u) << "a few ticks per axis";
    EXPECT_GE(y_ticks.size(), 3u);
    EXPECT_LE(y_ticks.size(), 15u) << "a few ticks per axis";
  }
  // The flat J axis is centred on the value: 25.46 ± 2.5, ticks 23 … 27.
  const std::vector<std::string> j =
      svgTicks(readFile(out / "plots/J_s_vs_planner_method.svg"), 'y');
  EXPECT_TRUE(std::count(j.begin(), j.end(), "25.0") + std::count(j.begin(), j.end(), "25") == 1)
      << fmt::format("{}", fmt::join(j, ", "));
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

// Robustness catalogue: `batch report` and `batch merge` skipped lines that are not
// rows, and rows of the wrong types, without a word (exit 0): the report left cases out.
TEST_F(Batch, ResultLinesThatAreNotRowsAreRefusedNamingTheLine) {
  const fs::path jsonl = dir_ / "results.jsonl";
  const std::string good = jsonRow(0, "ray", "10", {"25.5"});
  const auto fails = [&](const std::string& text, std::initializer_list<std::string> parts) {
    writeFile(jsonl, text);
    return throwsInputError([&] { cli::readBatchRows(jsonl); }, parts);
  };
  EXPECT_TRUE(
      fails(good + "\x01garbage\n" + good, {"results.jsonl:2: not JSON", "each line is a row"}));
  EXPECT_TRUE(fails("{\"case_id\": 5, \"J_s\": \"x\"}\n",
                    {"results.jsonl:1: \"case_id\": 5: expected a string"}));
  EXPECT_TRUE(fails("{}\n", {"results.jsonl:1: no \"case_id\""}));
  std::string huge_index = good;
  huge_index.replace(huge_index.find("\"index\": 0"), 10, "\"index\": 1e300");
  EXPECT_TRUE(fails(huge_index, {"\"index\": 1e+300: expected an integer"}));
  std::string bad_metric = good;
  bad_metric.replace(bad_metric.find("25.5"), 4, "\"x\"");
  EXPECT_TRUE(fails(bad_metric, {"\"J_s\": \"x\": expected a number or null"}));
  // A key twice (a hand-merged row): nlohmann keeps the last value; refused, naming the key, at
  // the top and inside params.
  std::string twice = good;
  twice.replace(twice.rfind('}'), 1, ", \"status\": \"error\"}");
  EXPECT_TRUE(fails(twice, {"results.jsonl:1: the key \"status\" appears twice"}));
  std::string twice_param = good;
  twice_param.replace(twice_param.find("\"params\": {"), 11,
                      "\"params\": {\"a\": \"1\", \"a\": \"2\"");
  EXPECT_TRUE(fails(twice_param, {"results.jsonl:1: the key \"a\" appears twice"}));

  // A torn last line (a kill while a row is appended) is skipped, the rows before it kept.
  writeFile(jsonl, good + "{\"case_id\": \"01");
  EXPECT_EQ(cli::readBatchRows(jsonl).size(), 1u);
  writeFile(jsonl, good + "garbage");
  EXPECT_TRUE(throwsInputError([&] { cli::readBatchRows(jsonl); }, {"results.jsonl:2:"}));

  const Result report = scanplan({"batch", "report", dir_.string()});
  EXPECT_EQ(report.exit_code, 4) << describe(report);
  EXPECT_TRUE(contains(report.err, "results.jsonl:2:")) << report.err;
}

// Robustness catalogue: repeats: 1000000000 ran out of memory making the cases
// (an internal error), and a range with a tiny step overflowed its count and ran one case.
TEST_F(Batch, HugeSweepsAreRefusedBeforeTheCasesAreMade) {
  for (const auto& [body, expect] :
       {std::pair<std::string, std::string>{"repeats: 1000000000\n", "repeats"},
        {"vary:\n  planner.k_omega: {from: 0, to: 1, step: 1e-300}\n", "expected at most 100000"},
        {"vary:\n  planner.ray.horizon: {from: 1, to: 1000, step: 1}\n"
         "  planner.ray.rays: {from: 1, to: 1000, step: 1}\n  planner.k_omega: [1, 2]\n",
         "cases"}}) {
    SCOPED_TRACE(body);
    EXPECT_TRUE(test::throwsInputError([&] { cli::loadSweep(writeSweep(body)); }, {expect}));
  }
}

// A sweep of two YAML documents would run the first only: refused before anything runs, naming
// the file and where the second starts. A leading `---` is one document, as before.
TEST_F(Batch, ASecondYamlDocumentInTheSweepIsRefusedNamingWhereItStarts) {
  const std::string text = sweepHeader() + kQuickSweep;
  const auto lines = std::count(text.begin(), text.end(), '\n');
  EXPECT_TRUE(throwsInputError(
      [&] { cli::loadSweep(writeSweep(kQuickSweep + "---\nrepeats: 2\n")); },
      {"sweep.yaml:" + std::to_string(lines + 1) + ":1: a second YAML document starts here",
       "expected one YAML document"}));
  const fs::path lead = dir_ / "lead.yaml";
  writeFile(lead, "---\n" + text);
  EXPECT_EQ(cli::loadSweep(lead).cases.size(), 12u);
}

// Found by fuzzing in CI (yaml_sweep): a job path the OS cannot look at (a name over 255
// bytes: ENAMETOOLONG) threw std::filesystem_error from the existence check, an internal error.
TEST_F(Batch, AJobPathTheSystemCannotLookAtIsNoSuchFile) {
  const std::string name(300, 'j');
  const fs::path file = dir_ / "long.yaml";
  writeFile(file, "jobs: ['./" + name + "/demo.yaml']\n");
  EXPECT_TRUE(throwsInputError([&] { cli::loadSweep(file); },
                               {"long.yaml", "jobs: './jjjj", "(312 characters)", "no such file"}));
}

}  // namespace
