#pragma once
// A JSON Schema (draft-07) of a spec, written through the same describe() functions the reader
// uses, so the schema names exactly the keys, types, ranges and choices the reader accepts.
//
// describe() branches on values (a shape's type, an optional key's presence): the schema is the
// union of passes over every variant — has() answers no, then yes, then yes but for the keys
// that exclude others (kExclusiveKeys) — with a key required only where every pass requires it.
// SchemaOut reads (kReading) so that no optional field is skipped; it records and never fails.

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <nlohmann/json.hpp>

#include <scanplan/config/detail/yaml_reader.h>
#include <scanplan/config/spec.h>

namespace scanplan::config {

/// The prototypes a list item is described with: one per variant of its describe() branches.
template <class S>
std::vector<S> schemaVariants() {
  return {S{}};
}

/// Keys whose presence makes describe() skip others (an obstacle's corner_mm skips its shape's
/// keys): the third pass answers "absent" for them.
inline const std::vector<std::string> kExclusiveKeys = {"corner_mm"};

/// has()'s answer in a pass.
enum class SchemaPass { kAbsent, kPresent, kPresentButExclusive };

class SchemaOut {
 public:
  using Json = nlohmann::ordered_json;
  static constexpr bool kReading = true;

  explicit SchemaOut(SchemaPass pass) : pass_(pass) {
    schema_ = {{"type", "object"}, {"additionalProperties", false}, {"properties", Json::object()}};
  }

  bool has(const char* key) const {
    if (pass_ == SchemaPass::kAbsent) return false;
    return pass_ == SchemaPass::kPresent ||
           std::find(kExclusiveKeys.begin(), kExclusiveKeys.end(), key) == kExclusiveKeys.end();
  }
  void field(const char* key, double&, const Expect& e = {}) { put(key, number("number", e)); }
  void field(const char* key, int&, const Expect& e = {}) { put(key, number("integer", e)); }
  void field(const char* key, bool&, const Expect& = {}) { put(key, {{"type", "boolean"}}); }
  void field(const char* key, std::string&, const Expect& e = {}) { put(key, text(e)); }
  void field(const char* key, FilePath&, const Expect& = {}) {
    put(key, {{"type", "string"}, {"description", "a file, relative to this file's folder"}});
  }
  void field(const char* key, std::vector<std::string>&, const Expect& e = {}) {
    put(key, {{"type", "array"}, {"items", text(e)}, {"uniqueItems", true}});
  }
  void field(const char* key, std::vector<std::array<std::string, 2>>&, const Expect& = {}) {
    const Json pair = {
        {"type", "array"}, {"items", {{"type", "string"}}}, {"minItems", 2}, {"maxItems", 2}};
    put(key, {{"type", "array"}, {"items", pair}});
  }
  template <std::size_t N>
  void field(const char* key, std::array<double, N>&, const Expect& e = {}) {
    put(key, fixedArray(number("number", e), N));
  }
  template <std::size_t N>
  void field(const char* key, std::array<int, N>&, const Expect& e = {}) {
    put(key, fixedArray(number("integer", e), N));
  }
  void require(const char* key) { required_.push_back(key); }
  template <class S>
  void section(const char* key, S& spec) {
    put(key, of(spec, pass_));
  }
  template <class S>
  void list(const char* key, std::vector<S>&, std::size_t min_size, std::size_t max_size) {
    Json items;
    for (const S& variant : schemaVariants<S>()) items = merge(items, ofAll(variant));
    put(key, {{"type", "array"}, {"items", items}, {"minItems", min_size}, {"maxItems", max_size}});
  }
  void fail(const std::string&, const std::string&, const std::string&) const {}
  void finish() const {}
  YAML::Node node() const { return {}; }
  std::filesystem::path file() const { return {}; }
  std::shared_ptr<const OverrideOrigins> overrides() const { return nullptr; }

  /// The schema of `spec` described in one pass.
  template <class S>
  static Json of(S& spec, SchemaPass pass) {
    SchemaOut out(pass);
    describe(out, spec);
    return out.result();
  }
  /// Every pass merged.
  template <class S>
  static Json ofAll(const S& spec) {
    Json all;
    for (const SchemaPass pass :
         {SchemaPass::kAbsent, SchemaPass::kPresent, SchemaPass::kPresentButExclusive}) {
      S copy = spec;
      all = merge(all, of(copy, pass));
    }
    return all;
  }

  Json result() const {
    Json s = schema_;
    if (!required_.empty()) s["required"] = required_;
    return s;
  }

  /// The union of two object schemas' properties (recursively), the intersection of their
  /// required keys; `a` may be null.
  static Json merge(const Json& a, const Json& b) {
    if (a.is_null()) return b;
    if (!a.contains("properties") || !b.contains("properties")) return a;
    Json out = a;
    for (const auto& [key, value] : b["properties"].items()) {
      Json& mine = out["properties"][key];
      mine = mine.is_null() ? value : mergeValue(mine, value);
    }
    Json required = Json::array();
    if (a.contains("required") && b.contains("required")) {
      for (const Json& key : a["required"]) {
        for (const Json& other : b["required"]) {
          if (key == other) required.push_back(key);
        }
      }
    }
    out.erase("required");
    if (!required.empty()) out["required"] = required;
    return out;
  }

 private:
  static Json mergeValue(const Json& a, const Json& b) {
    if (a.contains("properties") && b.contains("properties")) return merge(a, b);
    const auto isArray = [](const Json& j) { return j.contains("type") && j["type"] == "array"; };
    if (isArray(a) && isArray(b) && a.contains("items") && b.contains("items")) {
      Json out = a;
      out["items"] = mergeValue(a["items"], b["items"]);
      return out;
    }
    return a;
  }

  static Json number(const char* type, const Expect& e) {
    Json s = {{"type", type}};
    if (std::isfinite(e.lo)) s[e.lo_open ? "exclusiveMinimum" : "minimum"] = e.lo;
    if (std::isfinite(e.hi)) s[e.hi_open ? "exclusiveMaximum" : "maximum"] = e.hi;
    return s;
  }
  // A text: one of the choices, or any scalar (YAML writes "auto" and 30 alike).
  static Json text(const Expect& e) {
    if (!e.choices.empty()) return {{"type", "string"}, {"enum", e.choices}};
    return {{"type", {"string", "number", "boolean"}}};
  }
  static Json fixedArray(const Json& item, std::size_t n) {
    return {{"type", "array"}, {"items", item}, {"minItems", n}, {"maxItems", n}};
  }
  void put(const char* key, const Json& value) {
    Json& slot = schema_["properties"][key];
    slot = slot.is_null() ? value : mergeValue(slot, value);
  }

  SchemaPass pass_;
  Json schema_;
  std::vector<std::string> required_;
};

}  // namespace scanplan::config
