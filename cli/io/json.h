#pragma once
// JSON output (reports, --json, results.jsonl) on nlohmann::json.

#include <string>

#include <nlohmann/json.hpp>

namespace scanplan::cli {

/// A JSON value whose objects keep their keys in insertion order.
using Json = nlohmann::ordered_json;

/// `json` as a document: two-space indentation and a final newline. Numbers in shortest
/// round-trip form, non-finite numbers as null; bytes that are not UTF-8 become U+FFFD.
std::string jsonDocument(const Json& json);

/// `json` on one line (compact) with a final newline, as a JSON Lines file holds it.
std::string jsonLine(const Json& json);

}  // namespace scanplan::cli
