// The rows of a batch and its results files: results.csv and results.jsonl, written whole
// (sorted, atomically) or appended as cases finish, and read back (--resume, report, merge).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <exception>
#include <fstream>
#include <mutex>
#include <string>
#include <tuple>

#include <fmt/format.h>

#include "cli/batch/batch.h"
#include "cli/batch/batch_internal.h"
#include "cli/io/json.h"
#include "cli/io/output.h"
#include "kinematics/error.h"

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

// A row of results.jsonl; throws Json::exception when a field is missing or of another type.
BatchRow rowOf(const Json& json) {
  BatchRow r;
  r.case_id = json.at("case_id").get<std::string>();
  r.index = json.at("index").get<std::size_t>();
  r.job = json.at("job").get<std::string>();
  for (const auto& [k, v] : json.at("params").items())
    r.params.emplace_back(k, v.get<std::string>());
  if (const auto seed = json.find("seed"); seed != json.end() && !seed->is_null()) {
    r.seed = seed->get<int>();
  }
  r.repeat = json.at("repeat").get<int>();
  r.method = json.at("method").get<std::string>();
  r.status = json.at("status").get<std::string>();
  r.reason = json.at("reason").get<std::string>();
  for (std::size_t m = 0; m < kBatchMetrics.size(); ++m) {
    const auto v = json.find(kBatchMetrics[m]);
    if (v != json.end() && !v->is_null()) r.metrics[m] = v->get<double>();
  }
  r.map_reused = json.at("map_reused").get<bool>();
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
  std::vector<BatchRow> rows;
  std::ifstream in(jsonl, std::ios::binary);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line.back() != '}') continue;  // torn by an interruption
    try {
      rows.push_back(detail::rowOf(Json::parse(line)));
    } catch (const Json::exception&) {
      continue;
    }
  }
  return rows;
}

}  // namespace scanplan::cli
