// Sweep files: reading one, checking every value it varies on every base job, and expanding its
// cases (the grid, the explicit cases, seeds and repeats) in a deterministic order.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <scanplan/config/detail/yaml_reader.h>
#include <scanplan/config/job.h>
#include <scanplan/kinematics/error.h>
#include "cli/batch/batch.h"
#include "cli/batch/batch_internal.h"
#include "cli/io/output.h"

namespace scanplan::cli {

namespace fs = std::filesystem;

namespace {

using detail::fnv1a;
using detail::numberOf;

std::string where(const fs::path& file, const YAML::Node& node) {
  const YAML::Mark m = node.Mark();
  return m.line >= 0 ? fmt::format("{}:{}:{}", file.string(), m.line + 1, m.column + 1)
                     : file.string();
}

// A mapping's key as text: a plain scalar, once per mapping (yaml-cpp keeps the first of
// repeated keys and converts a list key by throwing: both were an "internal error").
std::string keyText(const fs::path& file,
                    const YAML::Node& key,
                    const std::string& in,
                    std::set<std::string>& seen) {
  if (!key.IsScalar() || key.Scalar().empty()) {
    throw InputError(where(file, key) + ": " + in + ": a " +
                     (key.IsSequence() ? "list"
                      : key.IsMap()    ? "mapping"
                                       : "null") +
                     " used as a key: expected a plain key name");
  }
  const std::string text = key.Scalar();
  if (!seen.insert(text).second) {
    throw InputError(where(file, key) + ": " + in + ": " + text +
                     ": given twice: expected each key once");
  }
  return text;
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
    std::set<std::string> seen;
    for (const auto& kv : node) {
      const auto name = keyText(file, kv.first, field, seen);
      if (name != "from" && name != "to" && name != "step") {
        throw InputError(fmt::format("{}: unknown key '{}': expected from, to, step", at, name));
      }
    }
    const double from = number("from", {}), to = number("to", {}), step = number("step", 1.0);
    if (!(step > 0.0) || to < from) {
      throw InputError(fmt::format("{}: from {} to {} step {}: expected step > 0 and to >= from",
                                   at, from, to, step));
    }
    // Counted in double first: a tiny step makes more values than any integer holds.
    const double count = std::floor((to - from) / step + 1e-9) + 1.0;
    if (!(count <= 100000.0)) {
      throw InputError(
          fmt::format("{}: from {} to {} step {}: {:.3g} values: expected at most 100000", at, from,
                      to, step, count));
    }
    const auto n = static_cast<std::size_t>(count);
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

using Setting = std::vector<std::pair<std::string, std::string>>;

// docs/limits.md.
constexpr double kMaxSweepCases = 100000;
constexpr double kMaxSweepChecks = 300;

YAML::Node loadRoot(const fs::path& file) {
  config::requireYamlFile(file);
  const YAML::Node root = config::loadOneDocument(file);
  config::checkYamlSize(root, file.string());
  if (!root.IsMap()) throw InputError(file.string() + ": expected a mapping (jobs, vary, …)");
  std::set<std::string> top;
  for (const auto& kv : root) {
    const auto key = keyText(file, kv.first, "the sweep", top);
    if (key != "jobs" && key != "set" && key != "vary" && key != "cases" && key != "seeds" &&
        key != "repeats") {
      throw InputError(
          fmt::format("{}: {}: unknown key; expected one of: jobs, set, vary, cases, seeds, "
                      "repeats",
                      where(file, kv.first), key));
    }
  }
  return root;
}

std::vector<std::string> strings(const fs::path& file, const YAML::Node& root, const char* key) {
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
}

int readRepeats(const fs::path& file, const YAML::Node& root) {
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
  return repeats;
}

// The seeds: every case runs once per seed, with the seed in each of the job's seed keys.
std::vector<int> readSeeds(const fs::path& file, const YAML::Node& root) {
  std::vector<int> seeds;
  std::set<int> seen;
  if (const YAML::Node n = root["seeds"]) {
    for (const std::string& v : valueList(file, "seeds", n)) {
      const std::optional<double> seed = numberOf(v);
      if (!seed || *seed != std::round(*seed) || *seed < 0.0 || *seed > 2147483647.0) {
        throw InputError(fmt::format("{}: seeds: '{}': expected an integer from 0 to 2147483647",
                                     where(file, n), v));
      }
      const int value = static_cast<int>(*seed);
      if (!seen.insert(value).second) {
        throw InputError(fmt::format("{}: seeds: {} is listed twice", where(file, n), value));
      }
      seeds.push_back(value);
    }
  }
  return seeds;
}

// `vary:`, key by key in the file's order (its keys are appended to `keys`).
std::vector<std::pair<std::string, std::vector<std::string>>> readGrid(
    const fs::path& file, const YAML::Node& root, std::vector<std::string>& keys) {
  std::vector<std::pair<std::string, std::vector<std::string>>> grid;
  if (const YAML::Node vary = root["vary"]) {
    if (!vary.IsMap()) throw InputError(where(file, vary) + ": vary: expected key: [values]");
    std::set<std::string> seen;
    for (const auto& kv : vary) {
      const auto key = keyText(file, kv.first, "vary", seen);
      grid.emplace_back(key, valueList(file, key, kv.second));
      keys.push_back(key);
    }
  }
  return grid;
}

// Every combination of the grid's values, the last key fastest.
std::vector<Setting> expandGrid(
    const std::vector<std::pair<std::string, std::vector<std::string>>>& grid) {
  std::vector<Setting> settings;
  if (grid.empty()) return settings;
  std::vector<std::size_t> at(grid.size(), 0);
  while (true) {
    Setting s;
    for (std::size_t k = 0; k < grid.size(); ++k)
      s.emplace_back(grid[k].first, grid[k].second[at[k]]);
    settings.push_back(std::move(s));
    std::size_t k = grid.size();
    while (k > 0 && ++at[k - 1] == grid[k - 1].second.size()) at[--k] = 0;
    if (k == 0) break;
  }
  return settings;
}

// `cases:`, appended to `settings` (new keys to `keys`); returns how many there are.
std::size_t readCases(const fs::path& file,
                      const YAML::Node& root,
                      std::vector<std::string>& keys,
                      std::vector<Setting>& settings) {
  std::size_t explicit_count = 0;
  if (const YAML::Node cases = root["cases"]) {
    explicit_count = cases.size();
    if (!cases.IsSequence()) throw InputError(where(file, cases) + ": cases: expected a list");
    for (const YAML::Node& c : cases) {
      if (!c.IsMap()) {
        throw InputError(where(file, c) + ": cases: expected a mapping key: value per case");
      }
      Setting s;
      std::set<std::string> seen;
      for (const auto& kv : c) {
        const auto key = keyText(file, kv.first, "cases", seen);
        s.emplace_back(key, valueText(kv.second));
        if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
      }
      settings.push_back(std::move(s));
    }
  }
  return explicit_count;
}

// A seed key set elsewhere too would be overridden by the seeds, case by case: refused.
void refuseSeedConflicts(const fs::path& file,
                         const std::vector<std::string>& fixed,
                         const std::vector<std::string>& keys) {
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
  for (const std::string& k : keys) {
    if (seedKey(k)) refuse(fmt::format("vary or cases ({})", k));
  }
}

std::vector<std::string> seedOverrides(int seed) {
  std::vector<std::string> out;
  for (const char* k : kJobSeedKeys) out.push_back(fmt::format("{}={}", k, seed));
  return out;
}

// Loads the job with the overrides: a bad key or value names itself (`what`) in the sweep file.
void checkJob(const fs::path& file,
              const fs::path& job,
              const std::vector<std::string>& overrides,
              const std::string& what) {
  try {
    config::loadJob(job, overrides);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}: {}", file.string(), what, e.what()));
  }
}

// The smallest and the largest of `values` (nothing when empty).
std::vector<int> extremes(const std::vector<int>& values) {
  if (values.empty()) return {};
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  return *lo == *hi ? std::vector<int>{*lo} : std::vector<int>{*lo, *hi};
}

// The job files, resolved against the sweep file, each checked with `set`, each seed and each
// value of the grid before anything runs.
std::vector<fs::path> resolveJobs(
    const fs::path& file,
    const std::vector<std::string>& jobs,
    const std::vector<std::string>& fixed,
    const std::vector<int>& seeds,
    const std::vector<std::pair<std::string, std::vector<std::string>>>& grid) {
  std::vector<fs::path> job_files;
  for (const std::string& j : jobs) {
    fs::path p = fs::path(j).is_absolute() ? fs::path(j) : file.parent_path() / j;
    if (!isRegularFile(p)) {
      throw InputError(fmt::format("{}: jobs: '{}': no such file ({})", file.string(),
                                   clipForMessage(j), clipForMessage(p.string())));
    }
    checkJob(file, p, fixed, "set");
    // readSeeds took each seed from the seed keys' own range: the smallest and the largest
    // stand for all of them (one load each, however many seeds there are).
    for (const int seed : extremes(seeds)) {
      std::vector<std::string> o = fixed;
      for (std::string& s : seedOverrides(seed)) o.push_back(std::move(s));
      checkJob(file, p, o, fmt::format("seeds: {}", seed));
    }
    for (const auto& [key, values] : grid) {
      for (const std::string& v : values) {
        std::vector<std::string> o = fixed;
        o.push_back(key + "=" + v);
        checkJob(file, p, o, "vary." + key);
      }
    }
    job_files.push_back(std::move(p));
  }
  return job_files;
}

// The cases: job by job, setting by setting, seed by seed, repeat by repeat; a case the grid
// already has is not repeated by an explicit one.
void expandCases(Sweep& sweep,
                 const std::vector<std::string>& jobs,
                 const std::vector<fs::path>& job_files,
                 const std::vector<Setting>& settings,
                 const std::vector<std::string>& fixed,
                 int repeats) {
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
}

// The size of the sweep, from the lengths of its lists, refused before anything is expanded or
// loaded: the cases (a `repeats` or a grid product in the billions filled the memory) and the job
// loads that check its values (each takes milliseconds).
void refuseHugeSweep(const fs::path& file,
                     std::size_t jobs,
                     const std::vector<std::pair<std::string, std::vector<std::string>>>& grid,
                     const YAML::Node& root,
                     std::size_t seeds,
                     int repeats) {
  const YAML::Node explicit_cases = root["cases"];
  const double explicit_count = explicit_cases && explicit_cases.IsSequence()
                                    ? static_cast<double>(explicit_cases.size())
                                    : 0.0;
  double product = grid.empty() ? 0.0 : 1.0, values = 0.0;
  for (const auto& [key, list] : grid) {
    product *= static_cast<double>(list.size());
    values += static_cast<double>(list.size());
  }
  const double n_jobs = static_cast<double>(jobs), n_seeds = static_cast<double>(seeds);
  const double cases =
      n_jobs * std::max(1.0, product + explicit_count) * std::max(1.0, n_seeds) * repeats;
  if (cases > kMaxSweepCases) {
    throw InputError(fmt::format(
        "{}: {:.4g} cases ({} job(s) x {:.4g} setting(s) x {} seed(s) x {} repeat(s)): expected at "
        "most {:.0f} (vary, cases, seeds, repeats, jobs)",
        file.string(), cases, jobs, std::max(1.0, product + explicit_count),
        std::max<std::size_t>(seeds, 1), repeats, kMaxSweepCases));
  }
  const double loads = n_jobs * (1.0 + std::min(n_seeds, 2.0) + values + explicit_count);
  if (loads > kMaxSweepChecks) {
    throw InputError(fmt::format(
        "{}: checking every value would load the job(s) {:.0f} times ({} job(s) x (1 + {} for "
        "the seeds + {:.0f} varied value(s) + {:.0f} case(s))): expected at most {:.0f}; split "
        "the sweep",
        file.string(), loads, jobs, std::min<std::size_t>(seeds, 2), values, explicit_count,
        kMaxSweepChecks));
  }
}

}  // namespace

bool inShard(const std::string& id, int shard, int count) {
  return fnv1a(id) % static_cast<std::uint64_t>(count) == static_cast<std::uint64_t>(shard - 1);
}

Sweep loadSweep(const fs::path& file) {
  const YAML::Node root = loadRoot(file);
  Sweep sweep;
  sweep.file = file;
  const std::vector<std::string> jobs = strings(file, root, "jobs");
  if (jobs.empty()) throw InputError(file.string() + ": jobs: missing: expected the job file(s)");
  const std::vector<std::string> fixed = strings(file, root, "set");
  const int repeats = readRepeats(file, root);
  sweep.seeds = readSeeds(file, root);

  // The grid (last key fastest), then the explicit cases.
  const auto grid = readGrid(file, root, sweep.keys);
  refuseHugeSweep(file, jobs.size(), grid, root, sweep.seeds.size(), repeats);
  std::vector<Setting> settings = expandGrid(grid);
  const std::size_t explicit_count = readCases(file, root, sweep.keys, settings);
  if (settings.empty()) settings.emplace_back();
  if (!sweep.seeds.empty()) refuseSeedConflicts(file, fixed, sweep.keys);

  // Every value on every job before anything runs: a bad key or value names itself here.
  const std::vector<fs::path> job_files = resolveJobs(file, jobs, fixed, sweep.seeds, grid);
  expandCases(sweep, jobs, job_files, settings, fixed, repeats);
  // The explicit cases, whole, on each job (a grid case may still fail in combination: a row).
  for (const fs::path& job : job_files) {
    for (std::size_t s = 0; s < explicit_count; ++s) {
      std::vector<std::string> o = fixed;
      for (const auto& [k, v] : settings[settings.size() - explicit_count + s]) {
        o.push_back(k + "=" + v);
      }
      checkJob(file, job, o, fmt::format("cases[{}]", s));
    }
  }
  return sweep;
}

}  // namespace scanplan::cli
