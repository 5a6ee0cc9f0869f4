// OMPL's benchmark log of a batch (ompl/doc/markdown/benchmark.md, "The benchmark logfile
// format"), as ompl_benchmark_statistics.py reads it into the database Planner Arena shows. The
// script reads one experiment per file: one log per base job (the OMPL "problem"), a "planner"
// per setting of that job (its seeds and repeats are the planner's runs).
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "cli/batch/batch_internal.h"

namespace scanplan::cli::detail {

namespace {

namespace fs = std::filesystem;

// A database column name: what the script makes of a property name (words joined by '_'),
// restricted to letters, digits and '_' so that its ALTER TABLE accepts it.
std::string columnName(const std::string& key) {
  std::string out;
  for (const char c : key) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return out;
}

bool isInteger(const std::string& text) {
  const std::optional<double> v = numberOf(text);
  return v && std::abs(*v) < 9e15 && *v == std::round(*v);
}

std::string omplLogOfJob(const std::vector<const BatchRow*>& rows,
                         const std::vector<std::string>& keys) {
  // The planner of a row: its method and the non-seed values it was given.
  const auto methodOf = [](const BatchRow& r) {
    if (!r.method.empty()) return r.method;
    const std::string v = paramValue(r, "planner.method");  // a case that failed to load
    return v.empty() ? std::string("none") : v;
  };
  std::vector<std::string> order;
  std::map<std::string, std::vector<const BatchRow*>> planners;
  std::map<std::string, std::vector<std::string>> settings;  // "key = value" lines
  for (const BatchRow* r : rows) {
    std::string name = methodOf(*r);
    std::vector<std::string> common{"planner.method = " + methodOf(*r)};
    for (const std::string& k : keys) {
      const std::string v = paramValue(*r, k);
      if (isSeedKey(k) || k == "planner.method" || v.empty()) continue;
      name += " " + k + "=" + v;
      common.push_back(k + " = " + v);
    }
    for (char& c : name) {
      if (c == '\n' || c == '\r') c = ' ';
    }
    if (!planners.count(name)) {
      order.push_back(name);
      settings[name] = common;
    }
    planners[name].push_back(r);
  }
  // The seeds as run properties (numeric ones: the database types them).
  std::vector<std::pair<std::string, const char*>> seeds;
  for (const std::string& k : keys) {
    if (!isSeedKey(k)) continue;
    bool integer = true, numeric = true, any = false;
    for (const BatchRow* r : rows) {
      const std::string v = paramValue(*r, k);
      if (v.empty()) continue;
      any = true;
      integer = integer && isInteger(v);
      numeric = numeric && numberOf(v).has_value();
    }
    if (any && numeric) seeds.emplace_back(k, integer ? "INTEGER" : "REAL");
  }

  // Wall time spent: planning (the DP yardstick too), validation and simulation of every case,
  // and each map once.
  double total = 0.0;
  for (const BatchRow* r : rows) {
    for (const std::size_t m : {kPlanS, kDpS, kValidationS, kSimulationS}) {
      total += r->metrics[m].value_or(0.0);
    }
    if (!r->map_reused) total += r->metrics[kMapS].value_or(0.0);
  }
  std::size_t runs = planners.empty() ? 0 : planners[order.front()].size();
  for (const auto& [name, group] : planners) {
    if (group.size() != runs) runs = 0;
  }
  char host[256] = "localhost";
  ::gethostname(host, sizeof host - 1);
  host[sizeof host - 1] = '\0';
  const std::time_t now = std::time(nullptr);
  std::tm local{};
  ::localtime_r(&now, &local);
  char date[64] = "unknown";
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S", &local);
  std::string experiment = fs::path(rows.front()->job).stem().string();
  for (char& c : experiment) {
    if (std::isspace(static_cast<unsigned char>(c))) c = '_';
  }

  std::string log = fmt::format("scanplan version {}\n", SCANPLAN_VERSION);
  log += fmt::format("Experiment {}\n", experiment.empty() ? "scanplan_batch" : experiment);
  log += fmt::format("Running on {}\n", host[0] ? host : "localhost");
  log += fmt::format("Starting at {}\n", date);  // when this log was written
  log += fmt::format(
      "<<<|\nscanplan batch of {}: the table angle over time planned on the job's configuration "
      "maps.\nPlanners are the settings of the sweep (planner.method and the varied values); "
      "their runs are the seeds and repeats.\nProperties: time = plan time (s, the planner's "
      "own), solved = planned (a path found, executable and valid), outcome, best cost = the "
      "objective J (s) and its terms (s), dp gap percent, dp time (s, the DP yardstick's, "
      "none when the planner is DP), min f, solution clearance (mm), max omega (deg/s), max "
      "alpha (deg/s^2), cycle time (s), coverage (fraction of the part's area), map, "
      "validation and simulation times (s), repeat, the seed. No time limit: 0 below.\n|>>>\n",
      rows.front()->job);
  log += "0 is the random seed\n";
  log += "0 seconds per run\n";
  log += "0 MB per run\n";
  if (runs) log += fmt::format("{} runs per planner\n", runs);
  log += fmt::format("{} seconds spent to collect the data\n", total);
  // The statuses as an enum, "outcome" (not OMPL's own "status" enum, so that a database holding
  // OMPL's logs too keeps both meanings).
  log += "1 enum type\noutcome";
  for (const char* o : kBatchStatuses) log += fmt::format("|{}", o);
  log += "\n";
  log += fmt::format("{} planners\n", order.size());

  enum class Kind { kMetric, kSolved, kOutcome, kReused, kRepeat, kSweepSeed, kSeed };
  struct Property {
    Property(std::string n, Kind k, std::size_t m = 0, std::string seed_key = {})
        : name(std::move(n)), kind(k), metric(m), key(std::move(seed_key)) {}
    std::string name;  // with its type, as the log declares it
    Kind kind;
    std::size_t metric;  // kBatchMetrics index (kMetric)
    std::string key;     // the seed key (kSeed)
  };
  std::vector<Property> properties{
      {"time REAL", Kind::kMetric, kPlanS},
      {"solved BOOLEAN", Kind::kSolved},
      {"outcome ENUM", Kind::kOutcome},
      {"best cost REAL", Kind::kMetric, kJ},
      {"cost f REAL", Kind::kMetric, kCostF},
      {"cost omega REAL", Kind::kMetric, kCostOmega},
      {"cost alpha REAL", Kind::kMetric, kCostAlpha},
      {"dp gap percent REAL", Kind::kMetric, kGap},
      {"dp time REAL", Kind::kMetric, kDpS},
      {"min f REAL", Kind::kMetric, kMinF},
      {"solution clearance REAL", Kind::kMetric, kClearance},
      {"max omega deg s REAL", Kind::kMetric, kOmega},
      {"max alpha deg s2 REAL", Kind::kMetric, kAlpha},
      {"cycle time REAL", Kind::kMetric, kCycle},
      {"coverage REAL", Kind::kMetric, kCoverage},
      {"map time REAL", Kind::kMetric, kMapS},
      {"map reused BOOLEAN", Kind::kReused},
      {"validation time REAL", Kind::kMetric, kValidationS},
      {"simulation time REAL", Kind::kMetric, kSimulationS},
      {"repeat INTEGER", Kind::kRepeat},
  };
  if (std::any_of(rows.begin(), rows.end(), [](const BatchRow* r) { return r->seed; })) {
    properties.emplace_back("seed INTEGER", Kind::kSweepSeed);
  }
  for (const auto& [key, type] : seeds) {
    properties.emplace_back(columnName(key) + " " + type, Kind::kSeed, 0, key);
  }
  const auto value = [](const Property& p, const BatchRow& r) -> std::string {
    switch (p.kind) {
      case Kind::kMetric:
        return numberOrEmpty(r.metrics[p.metric], "");
      case Kind::kSolved:
        return r.status == "planned" ? "1" : "0";
      case Kind::kOutcome: {
        const auto* it = std::find_if(kBatchStatuses.begin(), kBatchStatuses.end(),
                                      [&](const char* o) { return r.status == o; });
        if (it == kBatchStatuses.end()) --it;  // an unknown status: error
        return std::to_string(it - kBatchStatuses.begin());
      }
      case Kind::kReused:
        return r.map_reused ? "1" : "0";
      case Kind::kRepeat:
        return std::to_string(r.repeat);
      case Kind::kSweepSeed:
        return r.seed ? std::to_string(*r.seed) : std::string();
      case Kind::kSeed:
        return paramValue(r, p.key);
    }
    return {};
  };
  for (const std::string& name : order) {
    log += name + "\n";
    log += fmt::format("{} common properties\n", settings[name].size());
    for (const std::string& s : settings[name]) log += s + "\n";
    log += fmt::format("{} properties for each run\n", properties.size());
    for (const Property& p : properties) log += p.name + "\n";
    log += fmt::format("{} runs\n", planners[name].size());
    for (const BatchRow* r : planners[name]) {
      for (const Property& p : properties) log += value(p, *r) + "; ";
      log += "\n";
    }
    log += ".\n";
  }
  return log;
}

}  // namespace

// The OMPL logs of a batch, file name → content: ompl_benchmark.log for a sweep of one base
// job, ompl_benchmark_<i>_<job>.log (i = 1, 2, …) for each of several.
std::vector<std::pair<std::string, std::string>> omplLogs(const std::vector<BatchRow>& rows,
                                                          const std::vector<std::string>& keys) {
  std::vector<std::string> jobs;
  std::map<std::string, std::vector<const BatchRow*>> by_job;
  for (const BatchRow& r : rows) {
    if (!by_job.count(r.job)) jobs.push_back(r.job);
    by_job[r.job].push_back(&r);
  }
  std::vector<std::pair<std::string, std::string>> logs;
  for (std::size_t j = 0; j < jobs.size(); ++j) {
    const std::string file = jobs.size() == 1
                                 ? std::string("ompl_benchmark.log")
                                 : fmt::format("ompl_benchmark_{}_{}.log", j + 1,
                                               fileStem(fs::path(jobs[j]).stem().string()));
    logs.emplace_back(file, omplLogOfJob(by_job[jobs[j]], keys));
  }
  return logs;
}

}  // namespace scanplan::cli::detail
