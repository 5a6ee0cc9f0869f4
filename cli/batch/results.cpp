// The rows of a batch and its results files: results.csv and results.jsonl, written whole
// (sorted, atomically) or appended as cases finish, and read back (--resume, report, merge).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <exception>
#include <fstream>
#include <limits>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include <fmt/format.h>

#include <scanplan/kinematics/error.h>
#include "cli/batch/batch.h"
#include "cli/batch/batch_internal.h"
#include "cli/io/json.h"
#include "cli/io/output.h"

namespace scanplan::cli {

namespace fs = std::filesystem;

namespace detail {
namespace {

Json rowJson(const BatchRow& row) {
  Json params = Json::object();
  for (const auto& [k, v] : row.params) params[k] = v;
  Json json = {{"case_id", row.case_id},
               {"index", row.index},
               {"job", row.job},
               {"params", std::move(params)},
               {"seed", row.seed ? Json(*row.seed) : Json(nullptr)},
               {"repeat", row.repeat},
               {"method", row.method},
               {"status", row.status},
               {"reason", row.reason}};
  for (std::size_t m = 0; m < kBatchMetrics.size(); ++m) {
    const std::optional<double>& v = row.metrics[m];
    json[kBatchMetrics[m]] = v && std::isfinite(*v) ? Json(*v) : Json(nullptr);
  }
  json["map_reused"] = row.map_reused;
  return json;
}

// What is wrong with a results.jsonl row that is not one a batch writes.
struct BadRow : std::runtime_error {
  using std::runtime_error::runtime_error;
};

[[noreturn]] void badMember(const char* key, const Json& value, const char* expected) {
  throw BadRow(fmt::format("\"{}\": {}: expected {}", key, clipForMessage(value.dump()), expected));
}

const Json& member(const Json& row, const char* key) {
  const auto it = row.find(key);
  if (it == row.end()) throw BadRow(fmt::format("no \"{}\"", key));
  return *it;
}

std::string stringOf(const Json& row, const char* key) {
  const Json& v = member(row, key);
  if (!v.is_string()) badMember(key, v, "a string");
  return v.get<std::string>();
}

// Checked before any cast: a fraction or 1e300 in an integer field would be cut or overflow.
std::int64_t integerOf(const Json& v, const char* key, std::int64_t lo, std::int64_t hi) {
  const char* expected = "an integer in range";
  if (!v.is_number_integer()) badMember(key, v, expected);
  if (v.is_number_unsigned()) {
    if (v.get<std::uint64_t>() > static_cast<std::uint64_t>(hi)) badMember(key, v, expected);
    return static_cast<std::int64_t>(v.get<std::uint64_t>());
  }
  const auto i = v.get<std::int64_t>();
  if (i < lo || i > hi) badMember(key, v, expected);
  return i;
}

// A line of results.jsonl as JSON; a key twice in one object throws BadRow (nlohmann would keep
// the last value silently, and a hand-merged row could then report another case's figures).
Json parseRow(const std::string& line) {
  std::vector<std::set<std::string>> keys;  // one per object being read
  return Json::parse(line, [&keys](int /*depth*/, Json::parse_event_t event, Json& parsed) {
    if (event == Json::parse_event_t::object_start) keys.emplace_back();
    if (event == Json::parse_event_t::object_end) keys.pop_back();
    if (event == Json::parse_event_t::key &&
        !keys.back().insert(parsed.get<std::string>()).second) {
      throw BadRow(fmt::format("the key \"{}\" appears twice in one object: expected each once",
                               clipForMessage(parsed.get<std::string>())));
    }
    return true;
  });
}

// A row of results.jsonl, every field of the type a batch writes; throws BadRow otherwise.
BatchRow rowOf(const Json& json) {
  if (!json.is_object()) throw BadRow("not a JSON object");
  constexpr std::int64_t kIntMax = std::numeric_limits<int>::max();
  BatchRow r;
  r.case_id = stringOf(json, "case_id");
  r.index = static_cast<std::size_t>(
      integerOf(member(json, "index"), "index", 0, std::numeric_limits<std::int64_t>::max()));
  r.job = stringOf(json, "job");
  const Json& params = member(json, "params");
  if (!params.is_object()) badMember("params", params, "an object of strings");
  for (const auto& [k, v] : params.items()) {
    if (!v.is_string()) badMember("params", params, "an object of strings");
    r.params.emplace_back(k, v.get<std::string>());
  }
  if (const auto seed = json.find("seed"); seed != json.end() && !seed->is_null()) {
    r.seed = static_cast<int>(integerOf(*seed, "seed", -kIntMax, kIntMax));
  }
  r.repeat = static_cast<int>(integerOf(member(json, "repeat"), "repeat", 0, kIntMax));
  r.method = stringOf(json, "method");
  r.status = stringOf(json, "status");
  if (std::find(kBatchStatuses.begin(), kBatchStatuses.end(), r.status) == kBatchStatuses.end()) {
    badMember("status", member(json, "status"), "a batch status (planned, no_path, …, error)");
  }
  r.reason = stringOf(json, "reason");
  for (std::size_t m = 0; m < kBatchMetrics.size(); ++m) {
    const auto v = json.find(kBatchMetrics[m]);
    if (v == json.end() || v->is_null()) continue;
    if (!v->is_number()) badMember(kBatchMetrics[m], *v, "a number or null");
    r.metrics[m] = v->get<double>();
  }
  const Json& reused = member(json, "map_reused");
  if (!reused.is_boolean()) badMember("map_reused", reused, "true or false");
  r.map_reused = reused.get<bool>();
  return r;
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

std::string csvLine(const BatchRow& row, const std::vector<std::string>& keys) {
  std::string out = row.case_id + "," + csvField(row.job);
  for (const std::string& k : keys) out += "," + csvField(paramValue(row, k));
  out += fmt::format(",{},{},{},{},{}", row.seed ? std::to_string(*row.seed) : std::string(),
                     row.repeat, csvField(row.method), csvField(row.status), csvField(row.reason));
  for (const auto& v : row.metrics) out += "," + numberOrEmpty(v, "");
  return out + (row.map_reused ? ",true\n" : ",false\n");
}

}  // namespace

std::string paramValue(const BatchRow& row, const std::string& key) {
  for (const auto& [k, v] : row.params) {
    if (k == key) return v;
  }
  return {};
}

std::string numberOrEmpty(const std::optional<double>& v, const char* empty) {
  return v && std::isfinite(*v) ? fmt::format("{}", *v) : std::string(empty);
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

bool isSeedKey(const std::string& key) {
  const std::size_t dot = key.rfind('.');
  return key.substr(dot == std::string::npos ? 0 : dot + 1).find("seed") != std::string::npos;
}

std::string fileStem(const std::string& text) {
  std::string out;
  for (const char c : text) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return out;
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
    jsonl += jsonLine(rowJson(r));
  }
  writeFileAtomically(out / "results.jsonl", jsonl);
  writeFileAtomically(out / "results.csv", csv);
}

RowSink::RowSink(const fs::path& out, std::vector<std::string> keys)
    : keys_(std::move(keys)),
      csv_(out / "results.csv", std::ios::binary | std::ios::app),
      jsonl_(out / "results.jsonl", std::ios::binary | std::ios::app) {
  if (!csv_ || !jsonl_) {
    throw InputError(fmt::format("{}: cannot append to the results files", out.string()));
  }
}

void RowSink::append(const BatchRow& row) {
  const std::string json = jsonLine(rowJson(row)), csv = csvLine(row, keys_);
  const std::lock_guard<std::mutex> lock(mutex_);
  jsonl_ << json << std::flush;
  csv_ << csv << std::flush;
}

}  // namespace detail

std::vector<BatchRow> readBatchRows(const fs::path& jsonl) {
  std::ifstream in(jsonl, std::ios::binary);
  if (!in) throw InputError(fmt::format("{}: cannot be read", jsonl.string()));
  std::vector<BatchRow> rows;
  std::string line;
  for (std::size_t number = 1; std::getline(in, line); ++number) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    // A kill while a row is appended leaves it without its '\n' (and its end): skipped. Any
    // other line that is not a row means the file is not a batch's, and a report of it would
    // silently leave cases out.
    const bool torn = in.eof() && line.front() == '{';
    std::string what;
    try {
      rows.push_back(detail::rowOf(detail::parseRow(line)));
      continue;
    } catch (const Json::parse_error& e) {
      if (torn) break;
      what = fmt::format("not JSON (a syntax error at byte {}): expected a JSON object", e.byte);
    } catch (const detail::BadRow& e) {
      what = e.what();
    }
    throw InputError(fmt::format(
        "{}:{}: {}; each line is a row as `scanplan batch` writes it (an object with case_id, "
        "index, job, params, seed, repeat, method, status, reason, the metrics, map_reused)",
        jsonl.string(), number, what));
  }
  return rows;
}

}  // namespace scanplan::cli
