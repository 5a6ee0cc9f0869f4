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
#include <yaml-cpp/yaml.h>

#include "cli/batch/batch.h"
#include "cli/batch/batch_internal.h"
#include "cli/io/output.h"
#include "kinematics/error.h"

namespace scanplan::cli {

namespace fs = std::filesystem;

namespace detail {
namespace {

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
    jsonl += jsonLine(r);
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
  const std::string json = jsonLine(row), csv = csvLine(row, keys_);
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

}  // namespace scanplan::cli
