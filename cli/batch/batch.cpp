// `scanplan batch`: sweep files, case expansion, running cases in parallel with map reuse,
// the results files, summary, plots, shard merge and the OMPL benchmark log.
#include "cli/batch/batch.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <sstream>
#include <string_view>
#include <tuple>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <yaml-cpp/yaml.h>

#include "cli/plot/bitmap_font.h"
#include "cli/commands/commands.h"
#include "cli/io/output.h"
#include "cli/plot/image_io.h"
#include "cli/config/job.h"
#include "cli/planning.h"
#include "cli/verify.h"
#include "collision/scene.h"
#include "kinematics/error.h"
#include "kinematics/units.h"
#include "planner/trajectory_builder.h"

namespace scanplan::cli {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

std::uint64_t fnv1a(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (const char c : text) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ull;
  }
  return h;
}

constexpr std::size_t kJ = 0, kCostF = 1, kCostOmega = 2, kCostAlpha = 3, kGap = 4, kMinF = 5,
                      kClearance = 6, kOmega = 7, kAlpha = 8, kCycle = 9, kCoverage = 10,
                      kMapS = 11, kPlanS = 12, kDpS = 13, kValidationS = 14, kSimulationS = 15;

// ---- the sweep file -------------------------------------------------------------------------

std::string where(const fs::path& file, const YAML::Node& node) {
  const YAML::Mark m = node.Mark();
  return m.line >= 0 ? fmt::format("{}:{}:{}", file.string(), m.line + 1, m.column + 1)
                     : file.string();
}

// A value as --set takes it: scalars as written, lists and maps as flow YAML.
std::string valueText(const YAML::Node& node) {
  if (node.IsScalar()) return node.Scalar();
  YAML::Emitter out;
  out.SetMapFormat(YAML::Flow);
  out.SetSeqFormat(YAML::Flow);
  out << node;
  return out.c_str();
}

std::string numberText(double v) {
  const double rounded = std::round(v);
  if (std::abs(v - rounded) < 1e-9 * std::max(1.0, std::abs(v))) v = rounded;
  return fmt::format("{}", v);
}

// A list of values, or a range {from, to, step}; `field` names it in errors (vary.KEY, seeds).
std::vector<std::string> valueList(const fs::path& file,
                                   const std::string& field,
                                   const YAML::Node& node) {
  const std::string at = fmt::format("{}: {}", where(file, node), field);
  std::vector<std::string> values;
  if (node.IsSequence()) {
    for (const YAML::Node& v : node) values.push_back(valueText(v));
  } else if (node.IsMap()) {
    const auto number = [&](const char* name, std::optional<double> fallback) {
      const YAML::Node n = node[name];
      if (!n) {
        if (fallback) return *fallback;
        throw InputError(
            fmt::format("{}: a range needs '{}': expected {{from, to, step}}", at, name));
      }
      try {
        const double v = n.as<double>();
        if (std::isfinite(v)) return v;
      } catch (const YAML::Exception&) {
      }
      throw InputError(
          fmt::format("{}.{}: '{}': expected a finite number", at, name, valueText(n)));
    };
    for (const auto& kv : node) {
      const auto name = kv.first.as<std::string>();
      if (name != "from" && name != "to" && name != "step") {
        throw InputError(fmt::format("{}: unknown key '{}': expected from, to, step", at, name));
      }
    }
    const double from = number("from", {}), to = number("to", {}), step = number("step", 1.0);
    if (!(step > 0.0) || to < from) {
      throw InputError(fmt::format("{}: from {} to {} step {}: expected step > 0 and to >= from",
                                   at, from, to, step));
    }
    const auto n = static_cast<std::size_t>(std::floor((to - from) / step + 1e-9)) + 1;
    if (n > 100000) throw InputError(fmt::format("{}: {} values: expected at most 100000", at, n));
    for (std::size_t i = 0; i < n; ++i) {
      values.push_back(numberText(from + static_cast<double>(i) * step));
    }
  } else {
    values.push_back(valueText(node));
  }
  if (values.empty()) throw InputError(at + ": an empty list: expected at least one value");
  return values;
}

std::string caseId(const std::string& job, const std::vector<std::string>& overrides, int repeat) {
  std::vector<std::string> sorted = overrides;
  std::sort(sorted.begin(), sorted.end());
  std::string text = job + "\n";
  for (const std::string& o : sorted) text += o + "\n";
  text += std::to_string(repeat);
  return fmt::format("{:016x}", fnv1a(text));
}

// ---- results files --------------------------------------------------------------------------

std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (c == '\n') {
      out += "\\n";
    } else if (static_cast<unsigned char>(c) < 0x20) {
      out += fmt::format("\\u{:04x}", static_cast<int>(c));
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string numberOrEmpty(const std::optional<double>& v, const char* empty) {
  return v && std::isfinite(*v) ? fmt::format("{}", *v) : std::string(empty);
}

std::string jsonLine(const BatchRow& row) {
  std::string out = fmt::format("{{\"case_id\": {}, \"index\": {}, \"job\": {}, \"params\": {{",
                                jsonString(row.case_id), row.index, jsonString(row.job));
  for (std::size_t i = 0; i < row.params.size(); ++i) {
    out += fmt::format("{}{}: {}", i ? ", " : "", jsonString(row.params[i].first),
                       jsonString(row.params[i].second));
  }
  out += fmt::format(
      "}}, \"seed\": {}, \"repeat\": {}, \"method\": {}, \"status\": {}, \"reason\": {}",
      row.seed ? std::to_string(*row.seed) : std::string("null"), row.repeat,
      jsonString(row.method), jsonString(row.status), jsonString(row.reason));
  for (std::size_t m = 0; m < kBatchMetrics.size(); ++m) {
    out += fmt::format(", \"{}\": {}", kBatchMetrics[m], numberOrEmpty(row.metrics[m], "null"));
  }
  out += fmt::format(", \"map_reused\": {}}}\n", row.map_reused ? "true" : "false");
  return out;
}

std::string csvField(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (const char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string csvHeader(const std::vector<std::string>& keys) {
  std::string out = "case_id,job";
  for (const std::string& k : keys) out += "," + csvField(k);
  out += ",seed,repeat,method,status,reason";
  for (const char* m : kBatchMetrics) out += fmt::format(",{}", m);
  return out + ",map_reused\n";
}

std::string paramValue(const BatchRow& row, const std::string& key) {
  for (const auto& [k, v] : row.params) {
    if (k == key) return v;
  }
  return {};
}

std::string csvLine(const BatchRow& row, const std::vector<std::string>& keys) {
  std::string out = row.case_id + "," + csvField(row.job);
  for (const std::string& k : keys) out += "," + csvField(paramValue(row, k));
  out += fmt::format(",{},{},{},{},{}", row.seed ? std::to_string(*row.seed) : std::string(),
                     row.repeat, csvField(row.method), csvField(row.status), csvField(row.reason));
  for (const auto& v : row.metrics) out += "," + numberOrEmpty(v, "");
  return out + (row.map_reused ? ",true\n" : ",false\n");
}

// The varied keys of a set of rows, in order of first appearance.
std::vector<std::string> rowKeys(const std::vector<BatchRow>& rows) {
  std::vector<std::string> keys;
  for (const BatchRow& r : rows) {
    for (const auto& [k, v] : r.params) {
      if (std::find(keys.begin(), keys.end(), k) == keys.end()) keys.push_back(k);
    }
  }
  return keys;
}

void sortRows(std::vector<BatchRow>& rows) {
  std::sort(rows.begin(), rows.end(), [](const BatchRow& a, const BatchRow& b) {
    return std::tie(a.index, a.case_id) < std::tie(b.index, b.case_id);
  });
}

// Both results files, complete and sorted, written atomically.
void writeResults(const fs::path& out,
                  const std::vector<BatchRow>& rows,
                  const std::vector<std::string>& keys) {
  std::string csv = csvHeader(keys), jsonl;
  for (const BatchRow& r : rows) {
    csv += csvLine(r, keys);
    jsonl += jsonLine(r);
  }
  writeFileAtomically(out / "results.jsonl", jsonl);
  writeFileAtomically(out / "results.csv", csv);
}

// Appends rows as cases finish (from any worker thread).
class RowSink {
 public:
  RowSink(const fs::path& out, std::vector<std::string> keys)
      : keys_(std::move(keys)),
        csv_(out / "results.csv", std::ios::binary | std::ios::app),
        jsonl_(out / "results.jsonl", std::ios::binary | std::ios::app) {
    if (!csv_ || !jsonl_) {
      throw InputError(fmt::format("{}: cannot append to the results files", out.string()));
    }
  }
  void append(const BatchRow& row) {
    const std::string json = jsonLine(row), csv = csvLine(row, keys_);
    const std::lock_guard<std::mutex> lock(mutex_);
    jsonl_ << json << std::flush;
    csv_ << csv << std::flush;
  }

 private:
  std::vector<std::string> keys_;
  std::mutex mutex_;
  std::ofstream csv_, jsonl_;
};

// ---- running a case -------------------------------------------------------------------------

// Everything a case needs that depends only on the map-relevant part of the job.
struct MapBundle {
  explicit MapBundle(const JobSpec& job) : cell(buildCell(job)) {}
  kinematics::CellModel cell;
  PathContext context;
  std::unique_ptr<collision::Scene> scene;
  planner::ConfigMap map;
  double map_seconds = 0.0;
};

std::vector<kinematics::IkBranch> mapBranches(const JobSpec& job) {
  if (job.map.branch != "auto") return {*parseBranch(job.map.branch)};
  std::vector<kinematics::IkBranch> all;
  for (int i = 0; i < 8; ++i) all.push_back(kinematics::IkBranch::fromIndex(i));
  return all;
}

std::unique_ptr<MapBundle> buildBundle(const JobSpec& job) {
  auto bundle = std::make_unique<MapBundle>(job);
  bundle->context = buildPath(job, bundle->cell);
  bundle->scene = std::make_unique<collision::Scene>(bundle->cell, clearanceConfig(job));
  planner::MapRequest request;
  request.angle_step = deg(job.map.angle_step_deg);
  request.branches = mapBranches(job);
  request.memory_limit_bytes = static_cast<std::size_t>(job.map.memory_limit_mb * 1024.0 * 1024.0);
  const auto start = Clock::now();
  bundle->map = planner::buildConfigMap(*bundle->scene, constraintSettings(job),
                                        bundle->context.generated.path, request, {});
  bundle->map_seconds = since(start);
  return bundle;
}

// The settings that change the map: the job without its planner, validation, simulation and
// output sections, the scanner's measurement noise (simulation only; `seeds:` sets its seed) and
// the name. Cases with the same key share one map.
std::string mapKey(const JobSpec& job) {
  JobSpec copy = job;
  copy.name.clear();
  copy.scanner.noise = NoiseSpec{};
  copy.planner = PlannerSpec{};
  copy.validation = ValidationSpec{};
  copy.simulation = SimulationSpec{};
  copy.outputs = OutputsSpec{};
  return job.source.string() + "#" + jobHash(copy);
}

BatchRow rowFor(const SweepCase& c) {
  BatchRow row;
  row.index = c.index;
  row.case_id = c.id;
  row.job = c.job;
  row.params = c.params;
  row.seed = c.seed;
  row.repeat = c.repeat;
  return row;
}

// The `plan` pipeline after the map (cli/commands/plan.cpp), without its files.
void planCase(const JobSpec& job, const MapBundle& bundle, BatchRow& row) {
  using Status = planner::PlanResult::Status;
  auto& m = row.metrics;
  m[kMapS] = bundle.map_seconds;
  const planner::ConfigMap& map = bundle.map;
  const kinematics::ScanPath& path = bundle.context.generated.path;
  double trajectory_s = 0.0;
  std::optional<planner::TrajectoryBuild> candidate;
  // As in `plan`: a path is accepted only when the arm can follow it with f > 0 throughout.
  const auto check = [&](std::size_t b, const std::vector<double>& theta) -> std::string {
    const auto t = Clock::now();
    candidate = planner::buildTrajectory(*bundle.scene, constraintSettings(job), path, theta,
                                         map.branches[b]);
    trajectory_s += since(t);
    if (!candidate->ok) return candidate->reason;
    if (!(candidate->min_f > 0.0)) return "f = 0 between the map's grid angles";
    return {};
  };
  const auto t0 = Clock::now();
  const PlanningOutcome planning = planJob(map, job, job.planner.method, false, false, check);
  const double planning_s = since(t0) - trajectory_s;
  row.method = planning.chosen.method;
  // planJob also ran the DP yardstick on the chosen branch (planner.dp_gap): its time is dp_s,
  // not the planner's. With method dp the yardstick is the chosen result itself: nothing more ran.
  if (planning.dp && row.method != "dp") m[kDpS] = planning.dp->seconds;
  m[kPlanS] = planning_s - m[kDpS].value_or(0.0);
  if (planning.dp && planning.dp->status == Status::kExact) {
    if (const auto gap = planning.dpGap()) m[kGap] = 100.0 * *gap;
  }
  if (!planning.solved()) {
    row.status = planning.rejected.empty() ? "no_path" : "no_executable_path";
    row.reason = planning.chosen.result.reason;
    return;
  }
  const planner::ObjectiveTerms& t = planning.terms;
  m[kJ] = t.total;
  m[kCostF] = t.cost_f;
  m[kCostOmega] = t.cost_omega;
  m[kCostAlpha] = t.cost_alpha;
  m[kOmega] = toDeg(t.max_abs_omega);
  m[kAlpha] = toDeg(t.max_abs_alpha);
  m[kCycle] = map.times.back() - map.times.front();
  const planner::TrajectoryBuild& trajectory = *candidate;  // the accepted branch's
  m[kMinF] = trajectory.min_f;
  if (std::isfinite(trajectory.min_clearance)) m[kClearance] = toMm(trajectory.min_clearance);
  if (job.validation.enabled) {
    const auto tv = Clock::now();
    const planner::ValidationReport validation =
        planner::validateTrajectory(*bundle.scene, trajectory.trajectory, validationSettings(job));
    m[kValidationS] = since(tv);
    if (!validation.valid) {
      row.status = "invalid_trajectory";
      row.reason = fmt::format("validation found {} violation(s)", validation.violations.size());
      return;
    }
  }
  if (job.simulation.enabled) {
    const auto ts = Clock::now();
    const SimulationRun simulation =
        simulateTrajectory(job, bundle.cell, bundle.context.part.mesh, trajectory.trajectory);
    m[kSimulationS] = since(ts);
    m[kCoverage] = simulation.coverage.covered_fraction;
  }
  row.status = "planned";
}

// The reason of an error row: an InputError's message as it is; anything else is a bug, marked
// as `scanplan` marks it (the batch's exit code tells the two apart, also after --resume).
constexpr std::string_view kInternalPrefix = "internal error: ";
std::string errorReason(const std::exception& e) {
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

// ---- report: summary, plots, OMPL log ---------------------------------------------------------

bool isSeedKey(const std::string& key) {
  const std::size_t dot = key.rfind('.');
  return key.substr(dot == std::string::npos ? 0 : dot + 1).find("seed") != std::string::npos;
}

// A setting: the job and the varied values except seeds (runs of a setting differ by seed and
// repeat only).
std::string settingOf(const BatchRow& row, const std::vector<std::string>& keys) {
  std::string text = row.job;
  for (const std::string& k : keys) {
    if (!isSeedKey(k)) text += " " + k + "=" + paramValue(row, k);
  }
  return text;
}

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

std::string summaryMarkdown(const std::vector<BatchRow>& rows,
                            const std::vector<std::string>& keys,
                            const std::vector<std::string>& figures) {
  std::map<std::string, int> statuses;
  for (const BatchRow& r : rows) ++statuses[r.status];
  std::string md = "# scanplan batch summary\n\n";
  md += fmt::format("{} case(s):", rows.size());
  for (const auto& [s, n] : statuses) md += fmt::format(" {} {},", n, s);
  md.back() = '\n';
  md +=
      "\nMeans per setting (over seeds and repeats; J and its gap over planned cases only). Plan "
      "is the planner's own time, DP the DP yardstick's on top of it (none when the planner is "
      "DP).\n\n";
  md += "| job |";
  std::vector<std::string> shown;
  for (const std::string& k : keys) {
    if (!isSeedKey(k)) shown.push_back(k);
  }
  for (const std::string& k : shown) md += " " + k + " |";
  md +=
      " cases | planned | J (s) | DP gap (%) | min f | cycle (s) | coverage | plan (s) | DP (s) | "
      "map (s) |\n|---|";
  for (std::size_t i = 0; i < shown.size(); ++i) md += "---|";
  md += "---|---|---|---|---|---|---|---|---|---|\n";
  std::vector<std::string> order;
  std::map<std::string, std::vector<const BatchRow*>> groups;
  for (const BatchRow& r : rows) {
    const std::string s = settingOf(r, keys);
    if (!groups.count(s)) order.push_back(s);
    groups[s].push_back(&r);
  }
  for (const std::string& s : order) {
    const auto& group = groups[s];
    Mean j, gap, minf, cycle, coverage, plan, dp, map;
    int planned = 0;
    for (const BatchRow* r : group) {
      planned += r->status == "planned" ? 1 : 0;
      j.add(r->metrics[kJ]);
      gap.add(r->metrics[kGap]);
      minf.add(r->metrics[kMinF]);
      cycle.add(r->metrics[kCycle]);
      coverage.add(r->metrics[kCoverage]);
      plan.add(r->metrics[kPlanS]);
      dp.add(r->metrics[kDpS]);
      map.add(r->metrics[kMapS]);
    }
    md += "| " + group.front()->job + " |";
    for (const std::string& k : shown) md += " " + paramValue(*group.front(), k) + " |";
    md += fmt::format(" {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n", group.size(), planned,
                      j.text(), gap.text("{:.2f}"), minf.text(), cycle.text(), coverage.text(),
                      plan.text("{:.3f}"), dp.text("{:.3f}"), map.text("{:.2f}"));
  }
  const std::vector<const BatchRow*> failed = [&] {
    std::vector<const BatchRow*> out;
    for (const BatchRow& r : rows) {
      if (r.status != "planned") out.push_back(&r);
    }
    return out;
  }();
  if (!failed.empty()) {
    md += "\nCases without a plan:\n\n";
    for (const BatchRow* r : failed) {
      md += fmt::format("- `{}` {}: {}\n", r->case_id, r->status, r->reason);
    }
  }
  if (!figures.empty()) {
    md += "\nFigures (each metric against each varied value, one colour per planner):\n\n";
    for (const std::string& f : figures) md += fmt::format("- [{0}](plots/{0}.svg)\n", f);
  }
  return md;
}

std::string fileStem(const std::string& text) {
  std::string out;
  for (const char c : text) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return out;
}

std::optional<double> numberOf(const std::string& text) {
  try {
    std::size_t used = 0;
    const double v = std::stod(text, &used);
    if (used == text.size() && std::isfinite(v)) return v;
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

// A metric's name on an axis, with its unit.
std::string metricLabel(std::size_t metric) {
  switch (metric) {
    case kJ:
      return "J, objective (s)";
    case kCostF:
      return "J's f term (s)";
    case kCostOmega:
      return "J's omega term (s)";
    case kCostAlpha:
      return "J's alpha term (s)";
    case kGap:
      return "DP gap (%)";
    case kMinF:
      return "min f along the path";
    case kClearance:
      return "min clearance (mm)";
    case kOmega:
      return "max table speed (deg/s)";
    case kAlpha:
      return "max table acceleration (deg/s²)";
    case kCycle:
      return "cycle time (s)";
    case kCoverage:
      return "coverage (fraction of the part's area)";
    case kMapS:
      return "map time (s)";
    case kPlanS:
      return "plan time (s)";
    case kDpS:
      return "DP yardstick time (s)";
    case kValidationS:
      return "validation time (s)";
    case kSimulationS:
      return "simulation time (s)";
    default:
      return kBatchMetrics[metric];
  }
}

std::string base64(const std::string& bytes) {
  static constexpr char kDigits[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    std::uint32_t v = static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i])) << 16;
    if (i + 1 < bytes.size())
      v |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i + 1])) << 8;
    if (i + 2 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 2]);
    out += kDigits[(v >> 18) & 63];
    out += kDigits[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kDigits[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kDigits[v & 63] : '=';
  }
  return out;
}

// One metric against one varied value: a point per case, a line through each planner's means;
// categorical values are placed at 0, 1, 2, … and the planners side by side at each.
// Returns false when no case has the metric.
bool writePlot(const fs::path& dir,
               const std::string& stem,
               const std::vector<BatchRow>& rows,
               const std::string& key,
               std::size_t metric) {
  std::vector<std::string> values;  // distinct values of `key`, in order of appearance
  bool numeric = true;
  for (const BatchRow& r : rows) {
    const std::string v = paramValue(r, key);
    if (std::find(values.begin(), values.end(), v) == values.end()) values.push_back(v);
    numeric = numeric && numberOf(v).has_value();
  }
  if (numeric) {
    std::sort(values.begin(), values.end(), [](const std::string& a, const std::string& b) {
      return *numberOf(a) < *numberOf(b);
    });
  }
  std::vector<std::string> methods;
  for (const BatchRow& r : rows) {
    if (std::find(methods.begin(), methods.end(), r.method) == methods.end()) {
      methods.push_back(r.method);
    }
  }
  const auto position = [&](const std::string& v) {
    if (numeric) return *numberOf(v);
    return static_cast<double>(std::find(values.begin(), values.end(), v) - values.begin());
  };
  // Padded axis ranges; values equal up to rounding (e.g. the same J from two planners) make a
  // flat range, centred on the value (axisRange), never one with ticks 1e-14 apart.
  const std::pair<double, double> x_range =
      axisRange(position(values.front()), position(values.back()));
  const double x0 = x_range.first, x1 = x_range.second;
  const double spread = (x1 - x0) * 0.012;  // planners side by side at one value
  double lowest = std::numeric_limits<double>::infinity(), highest = -lowest;
  for (const BatchRow& r : rows) {
    if (r.metrics[metric] && std::isfinite(*r.metrics[metric])) {
      lowest = std::min(lowest, *r.metrics[metric]);
      highest = std::max(highest, *r.metrics[metric]);
    }
  }
  if (!std::isfinite(lowest)) return false;
  const std::pair<double, double> y_range = axisRange(lowest, highest);
  const double y0 = y_range.first, y1 = y_range.second;
  constexpr int kW = 720, kH = 480;
  RgbImage image = RgbImage::filled(kW, kH, {255, 255, 255});
  const auto px = [&](double x) { return (x - x0) / (x1 - x0) * kW; };
  const auto py = [&](double y) { return (1.0 - (y - y0) / (y1 - y0)) * kH; };
  // Light grid lines at the ticks the axes get.
  constexpr Rgb kGrid{225, 225, 225};
  for (const double v : niceTicks(y0, y1).values) drawLine(image, 0, py(v), kW, py(v), kGrid, 1);
  std::vector<double> x_grid;
  if (numeric) {
    x_grid = niceTicks(x0, x1).values;
  } else {
    for (std::size_t i = 0; i < values.size(); ++i) x_grid.push_back(static_cast<double>(i));
  }
  for (const double v : x_grid) drawLine(image, px(v), 0, px(v), kH, kGrid, 1);
  std::vector<std::pair<Rgb, std::string>> legend;  // the planners (the SVG's legend)
  for (std::size_t mi = 0; mi < methods.size(); ++mi) {
    const Rgb colour = batchPlannerColour(methods[mi]);
    const double offset =
        (static_cast<double>(mi) - 0.5 * static_cast<double>(methods.size() - 1)) * spread;
    std::vector<std::pair<double, double>> means;
    for (const std::string& v : values) {
      Mean mean;
      for (const BatchRow& r : rows) {
        if (r.method != methods[mi] || paramValue(r, key) != v) continue;
        mean.add(r.metrics[metric]);
        if (r.metrics[metric] && std::isfinite(*r.metrics[metric])) {
          const double x = px(position(v) + offset), y = py(*r.metrics[metric]);
          drawLine(image, x - 3, y - 3, x + 3, y + 3, colour, 2);
          drawLine(image, x - 3, y + 3, x + 3, y - 3, colour, 2);
        }
      }
      // The mean of huge values can overflow: no point then (drawLine skips non-finite ends).
      if (mean.n) means.emplace_back(px(position(v) + offset), py(mean.sum / mean.n));
    }
    for (std::size_t i = 1; i < means.size(); ++i) {
      drawLine(image, means[i - 1].first, means[i - 1].second, means[i].first, means[i].second,
               colour, 2);
    }
    // In the legend when it has a value here (a planner whose cases all failed has none).
    if (!means.empty()) {
      legend.emplace_back(colour, methods[mi].empty() ? std::string("(none)") : methods[mi]);
    }
  }
  const std::string x_name = key.empty() ? std::string("all cases") : key;
  FigureLabels text;
  text.title = metricLabel(metric) + " against " + x_name;
  text.x_label = x_name;
  text.y_label = metricLabel(metric);
  text.x0 = x0;
  text.x1 = x1;
  text.y0 = y0;
  text.y1 = y1;
  if (!numeric) {
    text.categories = key.empty() ? std::vector<std::string>{"all"} : values;
    for (std::string& c : text.categories) {
      if (c.empty()) c = "(not set)";  // an explicit case without this key
    }
  }
  // A swatch and name per planner, then what the marks mean.
  constexpr Rgb kGreyText{90, 90, 90};
  for (const auto& [colour, name] : legend) text.legend.push_back({colour, name});
  text.legend.push_back({kGreyText, "case", LegendEntry::Mark::kCross, kGreyText, 10});
  text.legend.push_back({kGreyText, "mean", LegendEntry::Mark::kLine, kGreyText});
  writePng(dir / (stem + ".png"), labelFigure(image, text).image);
  // The SVG: the same data raster, embedded, with the axes and text as SVG text.
  SvgFigure figure;
  figure.png_file = "data:image/png;base64," + base64(encodePng(image));
  figure.png_width = kW;
  figure.png_height = kH;
  figure.title = text.title;
  figure.x_label = x_name;
  if (!numeric && !key.empty()) {
    figure.x_label += " (";
    for (std::size_t i = 0; i < values.size(); ++i) {
      figure.x_label += fmt::format("{}{} = {}", i ? ", " : "", i,
                                    values[i].empty() ? std::string("(not set)") : values[i]);
    }
    figure.x_label += ")";
  }
  figure.y_label = text.y_label;
  figure.x_min = x0;
  figure.x_max = x1;
  figure.y_min = y0;
  figure.y_max = y1;
  figure.legend = legend;
  writeFileAtomically(dir / (stem + ".svg"), svgFigure(figure));
  return true;
}

// OMPL's benchmark log (ompl/doc/markdown/benchmark.md, "The benchmark logfile format"), as
// ompl_benchmark_statistics.py reads it into the database Planner Arena shows. The script reads
// one experiment per file: one log per base job (the OMPL "problem"), a "planner" per setting
// of that job (its seeds and repeats are the planner's runs).

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

// "batch      13 case(s): 13 run, 0 already done, 0 error(s); 1 map(s) computed (2.2 s of map
// time); 8.5 s in all": the map time is the maps' own, the last time the whole run's.
std::string batchLine(const BatchStats& s, const std::string& shard) {
  return fmt::format(
      "batch      {} case(s){}: {} run, {} already done, {} error(s); {} map(s) computed{}; {:.1f} "
      "s in all",
      s.cases, shard.empty() ? "" : " in shard " + shard, s.ran, s.skipped, s.failed, s.maps,
      s.maps ? fmt::format(" ({:.1f} s of map time)", s.map_seconds) : "", s.seconds);
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

}  // namespace

// ---- public -----------------------------------------------------------------------------------

Rgb batchPlannerColour(const std::string& method) {
  if (method == "dp") return categoryColour(4);    // blue, as in `plan`'s figures
  if (method == "ompl") return categoryColour(2);  // bluish green
  if (method == "ray") return categoryColour(5);   // vermillion
  return categoryColour(7);
}

bool inShard(const std::string& id, int shard, int count) {
  return fnv1a(id) % static_cast<std::uint64_t>(count) == static_cast<std::uint64_t>(shard - 1);
}

Sweep loadSweep(const fs::path& file) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(file.string());
  } catch (const YAML::BadFile&) {
    throw InputError(file.string() + ": cannot read the sweep file");
  } catch (const YAML::Exception& e) {
    throw InputError(
        fmt::format("{}:{}:{}: {}", file.string(), e.mark.line + 1, e.mark.column + 1, e.msg));
  }
  if (!root.IsMap()) throw InputError(file.string() + ": expected a mapping (jobs, vary, …)");
  for (const auto& kv : root) {
    const auto key = kv.first.as<std::string>();
    if (key != "jobs" && key != "set" && key != "vary" && key != "cases" && key != "seeds" &&
        key != "repeats") {
      throw InputError(
          fmt::format("{}: {}: unknown key; expected one of: jobs, set, vary, cases, seeds, "
                      "repeats",
                      where(file, kv.first), key));
    }
  }
  const auto strings = [&](const char* key) {
    std::vector<std::string> out;
    const YAML::Node n = root[key];
    if (!n) return out;
    if (n.IsScalar()) return std::vector<std::string>{n.Scalar()};
    if (!n.IsSequence()) {
      throw InputError(fmt::format("{}: {}: expected a list of strings", where(file, n), key));
    }
    for (const YAML::Node& v : n) {
      if (!v.IsScalar()) {
        throw InputError(fmt::format("{}: {}: expected a string", where(file, v), key));
      }
      out.push_back(v.Scalar());
    }
    return out;
  };
  Sweep sweep;
  sweep.file = file;
  const std::vector<std::string> jobs = strings("jobs");
  if (jobs.empty()) throw InputError(file.string() + ": jobs: missing: expected the job file(s)");
  const std::vector<std::string> fixed = strings("set");
  int repeats = 1;
  if (const YAML::Node n = root["repeats"]) {
    try {
      repeats = n.as<int>();
    } catch (const YAML::Exception&) {
      repeats = 0;
    }
    if (repeats < 1) {
      throw InputError(
          fmt::format("{}: repeats: '{}': expected an integer >= 1", where(file, n), valueText(n)));
    }
  }

  // The seeds: every case runs once per seed, with the seed in each of the job's seed keys.
  if (const YAML::Node n = root["seeds"]) {
    for (const std::string& v : valueList(file, "seeds", n)) {
      const std::optional<double> seed = numberOf(v);
      if (!seed || *seed != std::round(*seed) || *seed < 0.0 || *seed > 2147483647.0) {
        throw InputError(fmt::format("{}: seeds: '{}': expected an integer from 0 to 2147483647",
                                     where(file, n), v));
      }
      const int value = static_cast<int>(*seed);
      if (std::find(sweep.seeds.begin(), sweep.seeds.end(), value) != sweep.seeds.end()) {
        throw InputError(fmt::format("{}: seeds: {} is listed twice", where(file, n), value));
      }
      sweep.seeds.push_back(value);
    }
  }

  // The grid (last key fastest), then the explicit cases.
  std::vector<std::pair<std::string, std::vector<std::string>>> grid;
  if (const YAML::Node vary = root["vary"]) {
    if (!vary.IsMap()) throw InputError(where(file, vary) + ": vary: expected key: [values]");
    for (const auto& kv : vary) {
      const auto key = kv.first.as<std::string>();
      grid.emplace_back(key, valueList(file, key, kv.second));
      sweep.keys.push_back(key);
    }
  }
  std::vector<std::vector<std::pair<std::string, std::string>>> settings;
  if (!grid.empty()) {
    std::vector<std::size_t> at(grid.size(), 0);
    while (true) {
      std::vector<std::pair<std::string, std::string>> s;
      for (std::size_t k = 0; k < grid.size(); ++k)
        s.emplace_back(grid[k].first, grid[k].second[at[k]]);
      settings.push_back(std::move(s));
      std::size_t k = grid.size();
      while (k > 0 && ++at[k - 1] == grid[k - 1].second.size()) at[--k] = 0;
      if (k == 0) break;
    }
  }
  std::size_t explicit_count = 0;
  if (const YAML::Node cases = root["cases"]) {
    explicit_count = cases.size();
    if (!cases.IsSequence()) throw InputError(where(file, cases) + ": cases: expected a list");
    for (const YAML::Node& c : cases) {
      if (!c.IsMap()) {
        throw InputError(where(file, c) + ": cases: expected a mapping key: value per case");
      }
      std::vector<std::pair<std::string, std::string>> s;
      for (const auto& kv : c) {
        const auto key = kv.first.as<std::string>();
        s.emplace_back(key, valueText(kv.second));
        if (std::find(sweep.keys.begin(), sweep.keys.end(), key) == sweep.keys.end()) {
          sweep.keys.push_back(key);
        }
      }
      settings.push_back(std::move(s));
    }
  }
  if (settings.empty()) settings.emplace_back();
  // A seed key set elsewhere too would be overridden by the seeds, case by case: refused.
  if (!sweep.seeds.empty()) {
    const auto seedKey = [](std::string key) {
      key.erase(std::remove_if(key.begin(), key.end(),
                               [](char c) { return std::isspace(static_cast<unsigned char>(c)); }),
                key.end());
      return std::any_of(kJobSeedKeys.begin(), kJobSeedKeys.end(),
                         [&](const char* k) { return key == k; });
    };
    const auto refuse = [&](const std::string& what) {
      throw InputError(fmt::format(
          "{}: seeds and {} both set a seed: seeds sets every seed key of the job ({}, {}) "
          "case by case; give the seeds in one place",
          file.string(), what, kJobSeedKeys[0], kJobSeedKeys[1]));
    };
    for (const std::string& o : fixed) {
      if (seedKey(o.substr(0, o.find('=')))) refuse(fmt::format("set ('{}')", o));
    }
    for (const std::string& k : sweep.keys) {
      if (seedKey(k)) refuse(fmt::format("vary or cases ({})", k));
    }
  }
  const auto seedOverrides = [](int seed) {
    std::vector<std::string> out;
    for (const char* k : kJobSeedKeys) out.push_back(fmt::format("{}={}", k, seed));
    return out;
  };

  // Every value on every job before anything runs: a bad key or value names itself here.
  const auto check = [&](const fs::path& job, const std::vector<std::string>& overrides,
                         const std::string& what) {
    try {
      loadJob(job, overrides);
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: {}: {}", file.string(), what, e.what()));
    }
  };
  std::vector<fs::path> job_files;
  for (const std::string& j : jobs) {
    fs::path p = fs::path(j).is_absolute() ? fs::path(j) : file.parent_path() / j;
    if (!fs::is_regular_file(p)) {
      throw InputError(
          fmt::format("{}: jobs: '{}': no such file ({})", file.string(), j, p.string()));
    }
    check(p, fixed, "set");
    for (const int seed : sweep.seeds) {
      std::vector<std::string> o = fixed;
      for (std::string& s : seedOverrides(seed)) o.push_back(std::move(s));
      check(p, o, fmt::format("seeds: {}", seed));
    }
    for (const auto& [key, values] : grid) {
      for (const std::string& v : values) {
        std::vector<std::string> o = fixed;
        o.push_back(key + "=" + v);
        check(p, o, "vary." + key);
      }
    }
    job_files.push_back(std::move(p));
  }

  std::vector<std::optional<int>> seeds(sweep.seeds.begin(), sweep.seeds.end());
  if (seeds.empty()) seeds.emplace_back();  // the jobs' own seeds
  std::set<std::string> seen;
  for (std::size_t j = 0; j < jobs.size(); ++j) {
    for (const auto& s : settings) {
      for (const std::optional<int>& seed : seeds) {
        for (int r = 0; r < repeats; ++r) {
          SweepCase c;
          c.job = jobs[j];
          c.job_file = job_files[j];
          c.params = s;
          c.seed = seed;
          c.repeat = r;
          c.overrides = fixed;
          for (const auto& [k, v] : s) c.overrides.push_back(k + "=" + v);
          if (seed) {
            for (std::string& o : seedOverrides(*seed)) c.overrides.push_back(std::move(o));
          }
          c.id = caseId(c.job, c.overrides, r);
          if (!seen.insert(c.id).second) continue;  // an explicit case the grid already has
          c.index = sweep.cases.size();
          sweep.cases.push_back(std::move(c));
        }
      }
    }
  }
  // The explicit cases, whole, on each job (a grid case may still fail in combination: a row).
  for (const fs::path& job : job_files) {
    for (std::size_t s = 0; s < explicit_count; ++s) {
      std::vector<std::string> o = fixed;
      for (const auto& [k, v] : settings[settings.size() - explicit_count + s]) {
        o.push_back(k + "=" + v);
      }
      check(job, o, fmt::format("cases[{}]", s));
    }
  }
  return sweep;
}

std::vector<BatchRow> readBatchRows(const fs::path& jsonl) {
  std::vector<BatchRow> rows;
  std::ifstream in(jsonl, std::ios::binary);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line.back() != '}') continue;  // torn by an interruption
    try {
      const YAML::Node n = YAML::Load(line);
      BatchRow r;
      r.case_id = n["case_id"].as<std::string>();
      r.index = n["index"].as<std::size_t>();
      r.job = n["job"].as<std::string>();
      for (const auto& kv : n["params"]) {
        r.params.emplace_back(kv.first.as<std::string>(), kv.second.as<std::string>());
      }
      if (const YAML::Node seed = n["seed"]; seed && !seed.IsNull()) r.seed = seed.as<int>();
      r.repeat = n["repeat"].as<int>();
      r.method = n["method"].as<std::string>();
      r.status = n["status"].as<std::string>();
      r.reason = n["reason"].as<std::string>();
      for (std::size_t m = 0; m < kBatchMetrics.size(); ++m) {
        const YAML::Node v = n[kBatchMetrics[m]];
        if (v && !v.IsNull()) r.metrics[m] = v.as<double>();
      }
      r.map_reused = n["map_reused"].as<bool>();
      rows.push_back(std::move(r));
    } catch (const YAML::Exception&) {
      continue;
    }
  }
  return rows;
}

BatchStats runBatchCases(const BatchOptions& options) {
  const auto start = Clock::now();
  const Sweep sweep = loadSweep(options.sweep_file);
  const auto [shard, shards] = options.shard.empty() ? std::pair{1, 1} : parseShard(options.shard);
  const fs::path& out = options.out_dir;
  const int threads = options.jobs > 0 ? options.jobs : tbb::info::default_concurrency();
  BatchStats stats;

  prepareOutputDir(out);
  std::set<std::string> done;
  if (fs::exists(out / "results.jsonl")) {
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
  } else {
    writeResults(out, {}, sweep.keys);
  }

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
  std::atomic<std::size_t> finished{0}, failed{0}, maps{0};
  double map_seconds = 0.0;
  const auto finish = [&](const BatchRow& row) {
    sink.append(row);
    if (row.status == "error") ++failed;
    progress(++finished, todo.size());
  };

  tbb::task_arena arena(threads);
  arena.execute([&] {
    // Each case's job, resolved in parallel; the cases sharing a map run together.
    std::vector<std::optional<JobSpec>> jobs(todo.size());
    std::vector<std::string> errors(todo.size());
    tbb::parallel_for(std::size_t{0}, todo.size(), [&](std::size_t i) {
      try {
        jobs[i] = loadJob(todo[i]->job_file, todo[i]->overrides);
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
      const std::string key = options.reuse_maps ? mapKey(*jobs[i]) : todo[i]->id;
      if (!groups.count(key)) keys.push_back(key);
      groups[key].push_back(i);
    }
    for (const std::string& key : keys) {
      const std::vector<std::size_t>& group = groups[key];
      std::unique_ptr<MapBundle> bundle;
      std::string bundle_error;
      try {
        bundle = buildBundle(*jobs[group.front()]);
        ++maps;
        map_seconds += bundle->map_seconds;  // maps are built one after the other
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
  });

  stats.ran = finished.load();
  stats.failed = failed.load();
  stats.maps = maps.load();
  stats.map_seconds = map_seconds;
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

ExitCode runBatchReport(const fs::path& out_dir) {
  if (!fs::is_regular_file(out_dir / "results.jsonl")) {
    throw InputError(out_dir.string() + ": no results.jsonl: expected the folder of a batch run");
  }
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
    if (!fs::is_regular_file(in / "results.jsonl")) {
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
