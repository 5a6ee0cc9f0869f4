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

// The method of a row's planner.
std::string methodOf(const BatchRow& r) {
  if (!r.method.empty()) return r.method;
  const std::string v = paramValue(r, "planner.method");  // a case that failed to load
  return v.empty() ? std::string("none") : v;
}

// Whether a planner of `method` reads `key`: another planner's settings (planner.ray.* on an
// OMPL run) do not label it.
bool usedBy(const std::string& method, const std::string& key) {
  for (const char* planner : {"ray", "dp", "ompl"}) {
    if (key.rfind(std::string("planner.") + planner + ".", 0) == 0) return method == planner;
  }
  return true;
}

// The rows grouped by planner: its method and the non-seed values it was given (those it uses).
struct PlannerGroups {
  std::vector<std::string> order;  // the planner names, in the order of their first row
  std::map<std::string, std::vector<const BatchRow*>> planners;
  std::map<std::string, std::vector<std::string>> settings;  // "key = value" lines
};

PlannerGroups groupByPlanner(const std::vector<const BatchRow*>& rows,
                             const std::vector<std::string>& keys) {
  PlannerGroups groups;
  for (const BatchRow* r : rows) {
    std::string name = methodOf(*r);
    std::vector<std::string> common{"planner.method = " + methodOf(*r)};
    for (const std::string& k : keys) {
      const std::string v = paramValue(*r, k);
      if (isSeedKey(k) || k == "planner.method" || v.empty() || !usedBy(methodOf(*r), k)) continue;
      name += " " + k + "=" + v;
      common.push_back(k + " = " + v);
    }
    for (char& c : name) {
      if (c == '\n' || c == '\r') c = ' ';
    }
    if (!groups.planners.count(name)) {
      groups.order.push_back(name);
      groups.settings[name] = common;
    }
    groups.planners[name].push_back(r);
  }
  return groups;
}

// The seeds as run properties, key → database type (numeric ones only: the database types them).
std::vector<std::pair<std::string, const char*>> seedColumns(
    const std::vector<const BatchRow*>& rows, const std::vector<std::string>& keys) {
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
  return seeds;
}

// Wall time spent: planning (the DP yardstick too), validation and simulation of every case,
// and each map once.
double wallTimeSpent(const std::vector<const BatchRow*>& rows) {
  double total = 0.0;
  for (const BatchRow* r : rows) {
    for (const std::size_t m : {kPlanS, kDpS, kValidationS, kSimulationS}) {
      total += r->metrics[m].value_or(0.0);
    }
    if (!r->map_reused) total += r->metrics[kMapS].value_or(0.0);
  }
  return total;
}

// The runs per planner when every planner has the same number, else 0.
std::size_t runsPerPlanner(const PlannerGroups& groups) {
  std::size_t runs = groups.planners.empty() ? 0 : groups.planners.at(groups.order.front()).size();
  for (const auto& [name, group] : groups.planners) {
    if (group.size() != runs) runs = 0;
  }
  return runs;
}

std::string hostName() {
  char host[256] = "localhost";
  ::gethostname(host, sizeof host - 1);
  host[sizeof host - 1] = '\0';
  return host[0] ? host : "localhost";
}

std::string localDateNow() {
  const std::time_t now = std::time(nullptr);
  std::tm local{};
  ::localtime_r(&now, &local);
  char date[64] = "unknown";
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S", &local);
  return date;
}

// The OMPL "problem": the base job's file stem, without white space.
std::string experimentName(const std::string& job) {
  std::string experiment = fs::path(job).stem().string();
  for (char& c : experiment) {
    if (std::isspace(static_cast<unsigned char>(c))) c = '_';
  }
  return experiment.empty() ? "scanplan_batch" : experiment;
}

// The log's lines up to the planners: the experiment, its description, the run settings, the
// enum type and the number of planners.
std::string logHeader(const std::vector<const BatchRow*>& rows, const PlannerGroups& groups) {
  const std::size_t runs = runsPerPlanner(groups);
  const double total = wallTimeSpent(rows);
  std::string log = fmt::format("scanplan version {}\n", SCANPLAN_VERSION);
  log += fmt::format("Experiment {}\n", experimentName(rows.front()->job));
  log += fmt::format("Running on {}\n", hostName());
  log += fmt::format("Starting at {}\n", localDateNow());  // when this log was written
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
  log += fmt::format("{} planners\n", groups.order.size());
  return log;
}

// A property of each run, as the log declares it and as a row gives its value.
enum class PropertyKind { kMetric, kSolved, kOutcome, kReused, kRepeat, kSweepSeed, kSeed };
struct Property {
  Property(std::string n, PropertyKind k, std::size_t m = 0, std::string seed_key = {})
      : name(std::move(n)), kind(k), metric(m), key(std::move(seed_key)) {}
  std::string name;  // with its type, as the log declares it
  PropertyKind kind;
  std::size_t metric;  // kBatchMetrics index (kMetric)
  std::string key;     // the seed key (kSeed)
};

std::vector<Property> runProperties(const std::vector<const BatchRow*>& rows,
                                    const std::vector<std::pair<std::string, const char*>>& seeds) {
  std::vector<Property> properties{
      {"time REAL", PropertyKind::kMetric, kPlanS},
      {"solved BOOLEAN", PropertyKind::kSolved},
      {"outcome ENUM", PropertyKind::kOutcome},
      {"best cost REAL", PropertyKind::kMetric, kJ},
      {"cost f REAL", PropertyKind::kMetric, kCostF},
      {"cost omega REAL", PropertyKind::kMetric, kCostOmega},
      {"cost alpha REAL", PropertyKind::kMetric, kCostAlpha},
      {"dp gap percent REAL", PropertyKind::kMetric, kGap},
      {"dp time REAL", PropertyKind::kMetric, kDpS},
      {"min f REAL", PropertyKind::kMetric, kMinF},
      {"solution clearance REAL", PropertyKind::kMetric, kClearance},
      {"max omega deg s REAL", PropertyKind::kMetric, kOmega},
      {"max alpha deg s2 REAL", PropertyKind::kMetric, kAlpha},
      {"cycle time REAL", PropertyKind::kMetric, kCycle},
      {"coverage REAL", PropertyKind::kMetric, kCoverage},
      {"map time REAL", PropertyKind::kMetric, kMapS},
      {"map reused BOOLEAN", PropertyKind::kReused},
      {"validation time REAL", PropertyKind::kMetric, kValidationS},
      {"simulation time REAL", PropertyKind::kMetric, kSimulationS},
      {"repeat INTEGER", PropertyKind::kRepeat},
  };
  if (std::any_of(rows.begin(), rows.end(), [](const BatchRow* r) { return r->seed; })) {
    properties.emplace_back("seed INTEGER", PropertyKind::kSweepSeed);
  }
  for (const auto& [key, type] : seeds) {
    properties.emplace_back(columnName(key) + " " + type, PropertyKind::kSeed, 0, key);
  }
  return properties;
}

std::string propertyValue(const Property& p, const BatchRow& r) {
  switch (p.kind) {
    case PropertyKind::kMetric:
      return numberOrEmpty(r.metrics[p.metric], "");
    case PropertyKind::kSolved:
      return r.status == "planned" ? "1" : "0";
    case PropertyKind::kOutcome: {
      const auto* it = std::find_if(kBatchStatuses.begin(), kBatchStatuses.end(),
                                    [&](const char* o) { return r.status == o; });
      if (it == kBatchStatuses.end()) --it;  // an unknown status: error
      return std::to_string(it - kBatchStatuses.begin());
    }
    case PropertyKind::kReused:
      return r.map_reused ? "1" : "0";
    case PropertyKind::kRepeat:
      return std::to_string(r.repeat);
    case PropertyKind::kSweepSeed:
      return r.seed ? std::to_string(*r.seed) : std::string();
    case PropertyKind::kSeed:
      return paramValue(r, p.key);
  }
  return {};
}

// One planner's block: its settings, the properties of each run and a line per run.
std::string plannerBlock(const std::string& name,
                         const std::vector<std::string>& settings,
                         const std::vector<const BatchRow*>& runs,
                         const std::vector<Property>& properties) {
  std::string log = name + "\n";
  log += fmt::format("{} common properties\n", settings.size());
  for (const std::string& s : settings) log += s + "\n";
  log += fmt::format("{} properties for each run\n", properties.size());
  for (const Property& p : properties) log += p.name + "\n";
  log += fmt::format("{} runs\n", runs.size());
  for (const BatchRow* r : runs) {
    for (const Property& p : properties) log += propertyValue(p, *r) + "; ";
    log += "\n";
  }
  log += ".\n";
  return log;
}

std::string omplLogOfJob(const std::vector<const BatchRow*>& rows,
                         const std::vector<std::string>& keys) {
  const PlannerGroups groups = groupByPlanner(rows, keys);
  const std::vector<Property> properties = runProperties(rows, seedColumns(rows, keys));
  std::string log = logHeader(rows, groups);
  for (const std::string& name : groups.order) {
    log += plannerBlock(name, groups.settings.at(name), groups.planners.at(name), properties);
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
