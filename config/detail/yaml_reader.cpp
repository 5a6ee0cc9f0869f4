#include <scanplan/config/detail/yaml_reader.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>

#include <fmt/format.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/parser.h>

#include <scanplan/kinematics/error.h>

namespace scanplan::config {
namespace {

std::string nodeText(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "(empty)";
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a list";
  return "a mapping";
}

// The choice a rejected text most likely means, for "did you mean": as for keys (adept →
// adept_vplus, ur_scrpit → ur_script), ignoring case, or the choice it is the last word of
// (vplus → adept_vplus).
std::string suggestChoice(const std::string& written, const std::vector<std::string>& choices) {
  std::string lower = written;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (std::string s = suggestKey(lower, choices); !s.empty()) return s;
  for (const std::string& c : choices) {
    if (c.size() > lower.size() + 1 && c.ends_with("_" + lower)) return c;
  }
  return "";
}

// What a text field expected, with the choice it most likely meant.
std::string expectedText(const Expect& expect, const std::string& written) {
  if (expect.choices.empty()) return "a text";
  std::string s = expect.describe("");
  if (const std::string hint = suggestChoice(written, expect.choices); !hint.empty()) {
    s += " (did you mean '" + hint + "'?)";
  }
  return s;
}

bool parseDouble(const std::string& text, double& out) {
  // YAML 1.2 spellings of the special values; they parse, then fail the finiteness check.
  if (text == ".nan" || text == ".NaN" || text == ".NAN" || text == "nan" || text == "NaN") {
    out = std::nan("");
    return true;
  }
  if (text == ".inf" || text == "+.inf" || text == ".Inf" || text == "inf") {
    out = HUGE_VAL;
    return true;
  }
  if (text == "-.inf" || text == "-.Inf" || text == "-inf") {
    out = -HUGE_VAL;
    return true;
  }
  const char* begin = text.data();
  const char* end = begin + text.size();
  if (begin != end && *begin == '+') ++begin;
  const auto [ptr, ec] = std::from_chars(begin, end, out);
  return ec == std::errc() && ptr == end && begin != end;
}

}  // namespace

void OverrideOrigins::add(const YAML::Node& node, const std::string& text) {
  if (!node.IsDefined()) return;
  nodes_.emplace_back(node, text);
  if (node.IsMap()) {
    for (auto it = node.begin(); it != node.end(); ++it) {
      add(it->first, text);
      add(it->second, text);
    }
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) add(node[i], text);
  }
}

const std::string* OverrideOrigins::find(const YAML::Node& node) const {
  if (!node.IsDefined()) return nullptr;
  for (const auto& [n, text] : nodes_) {
    if (n.is(node)) return &text;
  }
  return nullptr;
}

std::string Expect::describe(double v, const char* kind) const {
  if (v == 0.0 || !std::isfinite(v) || std::isnormal(v)) return describe(kind);
  return describe(kind) +
         ", and a normal one (this is a denormal, below 2.2e-308: arithmetic "
         "on it underflows)";
}

bool Expect::accepts(double v) const {
  // Not a normal number (a denormal such as 1e-320): arithmetic on it loses its precision and
  // underflows to 0, so it is refused where SI values are made.
  if (!std::isfinite(v) || (v != 0.0 && !std::isnormal(v))) return false;
  if (lo_open ? !(v > lo) : !(v >= lo)) return false;
  if (hi_open ? !(v < hi) : !(v <= hi)) return false;
  return true;
}

bool Expect::accepts(const std::string& v) const {
  return choices.empty() || std::find(choices.begin(), choices.end(), v) != choices.end();
}

std::string Expect::describe(const char* kind) const {
  if (!choices.empty()) {
    std::string s = "one of";
    for (std::size_t i = 0; i < choices.size(); ++i) s += (i ? ", " : " ") + choices[i];
    return s;
  }
  std::string s = fmt::format("a finite {}", kind);
  const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
  if (has_lo && has_hi) {
    s += fmt::format(" in {}{}, {}{}", lo_open ? "(" : "[", formatNumber(lo), formatNumber(hi),
                     hi_open ? ")" : "]");
  } else if (has_lo) {
    s += fmt::format(" {} {}", lo_open ? ">" : "≥", formatNumber(lo));
  } else if (has_hi) {
    s += fmt::format(" {} {}", hi_open ? "<" : "≤", formatNumber(hi));
  }
  return s;
}

namespace {

// Counts the nodes as a reader would visit them (an alias counts again each time it is used),
// stopping at the limits: the size and depth a document may have.
void countNodes(const YAML::Node& node,
                std::size_t depth,
                std::size_t& count,
                std::size_t& deepest) {
  ++count;
  deepest = std::max(deepest, depth);
  if (count > kMaxYamlNodes || depth > kMaxYamlDepth) return;
  if (node.IsSequence() || node.IsMap()) {
    for (auto it = node.begin(); it != node.end(); ++it) {
      if (node.IsMap()) {
        countNodes(it->second, depth + 1, count, deepest);
      } else {
        countNodes(*it, depth + 1, count, deepest);
      }
      if (count > kMaxYamlNodes || deepest > kMaxYamlDepth) return;
    }
  }
}

// Where a file's second YAML document starts; thrown to stop the parse there.
struct SecondDocument {
  YAML::Mark mark;
};

// Parser events seen only for where documents start: the second one ends the parse.
class DocumentStarts : public YAML::EventHandler {
 public:
  void OnDocumentStart(const YAML::Mark& mark) override {
    if (++documents_ > 1) throw SecondDocument{mark};
  }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&,
                const std::string&,
                YAML::anchor_t,
                const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&,
                       const std::string&,
                       YAML::anchor_t,
                       YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&,
                  const std::string&,
                  YAML::anchor_t,
                  YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}

 private:
  int documents_ = 0;
};

[[noreturn]] void failMalformed(const std::filesystem::path& file, const YAML::Exception& e) {
  throw InputError(fmt::format("{}:{}:{}: malformed YAML: {}", file.string(), e.mark.line + 1,
                               e.mark.column + 1, e.msg));
}

}  // namespace

void checkYamlSize(const YAML::Node& root, const std::string& where) {
  std::size_t count = 0, deepest = 0;
  countNodes(root, 0, count, deepest);
  if (count > kMaxYamlNodes) {
    throw InputError(fmt::format(
        "{}: the YAML expands to more than {} nodes (aliases count each time they are used): "
        "expected a job-sized document",
        where, kMaxYamlNodes));
  }
  if (deepest > kMaxYamlDepth) {
    throw InputError(fmt::format("{}: the YAML nests deeper than {} levels: expected a job", where,
                                 kMaxYamlDepth));
  }
}

void requireYamlFile(const std::filesystem::path& file) {
  std::error_code ec;
  const auto status = std::filesystem::status(file, ec);
  if (!std::filesystem::exists(status)) {
    throw InputError(fmt::format("{}: file does not exist", file.string()));
  }
  if (std::filesystem::is_directory(status)) {
    throw InputError(fmt::format("{}: is a directory, expected a YAML file", file.string()));
  }
  // A pipe or device would be read until it ends, which may be never.
  if (!std::filesystem::is_regular_file(status)) {
    throw InputError(
        fmt::format("{}: is not a regular file (a pipe, socket or device): expected a YAML file",
                    file.string()));
  }
  const auto bytes = std::filesystem::file_size(file, ec);
  if (!ec && bytes > kMaxYamlFileBytes) {
    throw InputError(fmt::format("{}: {} bytes: expected a YAML file of at most {} bytes",
                                 file.string(), bytes, kMaxYamlFileBytes));
  }
}

std::optional<YAML::Mark> secondDocumentStart(std::istream& in) {
  try {
    YAML::Parser parser(in);
    DocumentStarts starts;
    while (parser.HandleNextDocument(starts)) {
    }
  } catch (const SecondDocument& second) {
    return second.mark;
  }
  return std::nullopt;
}

YAML::Node loadOneDocument(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(fmt::format("{}: cannot be read", file.string()));
  // First only where documents start (no tree is built, so a file of many documents costs no
  // memory), then the one document itself.
  try {
    if (const auto second = secondDocumentStart(in)) {
      throw InputError(fmt::format(
          "{}:{}:{}: a second YAML document starts here: expected one YAML document (scanplan "
          "would read the first and drop the rest); join them by removing the document marker "
          "('---' or '...') between them",
          file.string(), second->line + 1, second->column + 1));
    }
  } catch (const YAML::Exception& e) {
    failMalformed(file, e);
  }
  in.clear();
  in.seekg(0);
  try {
    return YAML::Load(in);
  } catch (const YAML::Exception& e) {
    failMalformed(file, e);
  }
}

YAML::Node loadYamlFile(const std::filesystem::path& file) {
  requireYamlFile(file);
  YAML::Node root = loadOneDocument(file);
  checkYamlSize(root, file.string());
  if (!root.IsMap()) {
    throw InputError(
        fmt::format("{}: the file holds {}, expected a YAML mapping of keys", file.string(),
                    root.IsDefined() && !root.IsNull() ? nodeText(root) : std::string("nothing")));
  }
  return root;
}

YamlIn::YamlIn(YAML::Node node,
               std::string path,
               std::filesystem::path file,
               std::shared_ptr<const OverrideOrigins> overrides)
    : node_(std::move(node)),
      path_(std::move(path)),
      file_(std::move(file)),
      overrides_(std::move(overrides)) {
  // yaml-cpp accepts repeated keys (first wins) and any node as a key; a job file must not.
  std::vector<std::pair<std::string, YAML::Mark>> seen;
  for (auto it = node_.begin(); it != node_.end(); ++it) {
    const YAML::Mark mark = it->first.Mark();
    if (!it->first.IsScalar() || it->first.Tag() == "tag:yaml.org,2002:null" ||
        it->first.Scalar() == "~" || it->first.Scalar().empty()) {
      throw InputError(fmt::format("{}:{}:{}: {}: {} used as a key: expected a plain key name",
                                   file_.string(), mark.line + 1, mark.column + 1, fieldPath(""),
                                   nodeText(it->first)));
    }
    const std::string key = it->first.Scalar();
    for (const auto& [other, other_mark] : seen) {
      if (other == key) {
        throw InputError(fmt::format(
            "{}:{}:{}: {}: duplicate key (first given on line {}): expected each key once",
            file_.string(), mark.line + 1, mark.column + 1, fieldPath(key), other_mark.line + 1));
      }
    }
    seen.emplace_back(key, mark);
  }
}

std::string YamlIn::where(const YAML::Node& node) const {
  const YAML::Node& n = node.IsDefined() ? node : node_;
  // A value from the command line has no place in the file (and only a place in the override
  // text when it was a flow list or mapping): name the override.
  if (overrides_) {
    if (const std::string* text = overrides_->find(n)) return "--set " + *text;
  }
  const YAML::Mark m = n.Mark();
  if (m.is_null()) return file_.string();
  return fmt::format("{}:{}:{}", file_.string(), m.line + 1, m.column + 1);
}

std::string YamlIn::fieldPath(const std::string& key) const {
  if (key.empty()) return path_.empty() ? "(top level)" : path_;
  return path_.empty() ? key : path_ + "." + key;
}

bool YamlIn::has(const char* key) const {
  known_.emplace_back(key);
  const YAML::Node n = node_[key];
  if (n.IsDefined() && n.IsNull()) {
    fail(key, "empty value", "a value (or leave the key out to use the default)");
  }
  return n.IsDefined();
}

void YamlIn::require(const char* key) const {
  if (has(key)) return;
  // `hieght_mm: 70` for height_mm: the misspelt key is the user's mistake, not the missing one.
  // Whether that key is unknown is only certain once every field was asked for: finish().
  for (const auto& [k, n] : unknownKeys()) {
    if (suggestKey(k, {key}) == key) {
      missing_.emplace_back(key);
      return;
    }
  }
  missing(key);
}

void YamlIn::missing(const std::string& key) const {
  throw InputError(fmt::format("{}: {}: required field is missing", where(node_), fieldPath(key)));
}

std::vector<std::pair<std::string, YAML::Node>> YamlIn::unknownKeys() const {
  std::vector<std::pair<std::string, YAML::Node>> unknown;
  for (auto it = node_.begin(); it != node_.end(); ++it) {
    const std::string key = it->first.Scalar();
    if (std::find(known_.begin(), known_.end(), key) == known_.end()) {
      unknown.emplace_back(key, it->first);
    }
  }
  return unknown;
}

void YamlIn::unknownKey(const std::string& key,
                        const YAML::Node& key_node,
                        const std::string& suggestion) const {
  std::vector<std::string> sorted = known_;
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  throw InputError(
      fmt::format("{}: {}: unknown key{}; expected one of: {}", where(key_node), fieldPath(key),
                  suggestion.empty() ? "" : fmt::format(" (did you mean '{}'?)", suggestion),
                  fmt::join(sorted, ", ")));
}

void YamlIn::fail(const std::string& key,
                  const std::string& value,
                  const std::string& expected) const {
  // A required key was missing (next to a near miss): that came first.
  if (!missing_.empty()) missing(missing_.front());
  YAML::Node n = key.empty() ? node_ : node_[key];
  if (!key.empty() && (!n.IsDefined() || n.IsNull())) {
    // An empty value has no position of its own (yaml-cpp marks the next line): point at its key.
    for (auto it = node_.begin(); it != node_.end(); ++it) {
      if (it->first.Scalar() == key) n = it->first;
    }
  }
  throw InputError(
      fmt::format("{}: {}: {}: expected {}", where(n), fieldPath(key), value, expected));
}

namespace {

// No cell is a kilometre across, and the ray caster and the collision library work in float:
// lengths (keys in _mm) stay within ±1e6 mm, every other number within ±1e9, whatever a key's
// own range allows. Empty when `v` is within; else what to expect.
std::string beyondMagnitude(const std::string& key, double v) {
  const bool length = key.size() > 3 && key.compare(key.size() - 3, 3, "_mm") == 0;
  const double cap = length ? 1e6 : 1e9;
  if (std::abs(v) <= cap) return {};
  return fmt::format("a number within ±{} ({})", formatNumber(cap),
                     length ? "lengths in mm: a kilometre" : "a bound on every number");
}

}  // namespace

void YamlIn::field(const char* key, double& value, const Expect& expect) {
  if (!has(key)) return;
  const YAML::Node n = node_[key];
  double v = 0.0;
  if (!n.IsScalar() || !parseDouble(n.Scalar(), v)) {
    // "250 mm", "250mm": a number followed by a unit word.
    std::string hint;
    if (n.IsScalar()) {
      const std::string& text = n.Scalar();
      const std::size_t end = text.find_first_not_of("+-0123456789.eE");
      double leading = 0.0;
      if (end != std::string::npos && end > 0 && parseDouble(text.substr(0, end), leading) &&
          std::isalpha(static_cast<unsigned char>(text.back()))) {
        hint = fmt::format(" (write the number alone: the unit is part of the key name, {})", key);
      }
    }
    fail(key, nodeText(n) + " is not a number", expect.describe("number") + hint);
  }
  if (!expect.accepts(v)) fail(key, formatNumber(v), expect.describe(v, "number"));
  if (const std::string limit = beyondMagnitude(key, v); !limit.empty())
    fail(key, formatNumber(v), limit);
  value = v;
}

void YamlIn::field(const char* key, int& value, const Expect& expect) {
  if (!has(key)) return;
  const YAML::Node n = node_[key];
  double v = 0.0;
  if (!n.IsScalar() || !parseDouble(n.Scalar(), v)) {
    fail(key, nodeText(n) + " is not a number", expect.describe("integer"));
  }
  if (std::floor(v) != v || std::abs(v) > 1e9) {
    fail(key, nodeText(n) + " is not a whole number", expect.describe("integer"));
  }
  if (!expect.accepts(v)) fail(key, formatNumber(v), expect.describe(v, "integer"));
  value = static_cast<int>(v);
}

void YamlIn::field(const char* key, bool& value, const Expect&) {
  if (!has(key)) return;
  const YAML::Node n = node_[key];
  bool v = false;
  if (!n.IsScalar() || !YAML::convert<bool>::decode(n, v)) {
    fail(key, nodeText(n), "true or false");
  }
  value = v;
}

void YamlIn::field(const char* key, std::string& value, const Expect& expect) {
  if (!has(key)) return;
  const YAML::Node n = node_[key];
  if (!n.IsScalar())
    fail(key, nodeText(n), expect.choices.empty() ? "a text" : expect.describe(""));
  if (!expect.accepts(n.Scalar())) fail(key, nodeText(n), expectedText(expect, n.Scalar()));
  value = n.Scalar();
}

void YamlIn::field(const char* key, std::vector<std::string>& value, const Expect& expect) {
  if (!has(key)) return;
  const YAML::Node seq = node_[key];
  checkSequence(key, seq, 0, 1000);
  std::vector<std::string> items;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const YAML::Node item = seq[i];
    const std::string at = fmt::format("{}[{}]", key, i);
    if (!item.IsScalar()) {
      throw InputError(fmt::format("{}: {}: {}: expected {}", where(item), fieldPath(at),
                                   nodeText(item),
                                   expect.choices.empty() ? "a text" : expect.describe("")));
    }
    if (!expect.accepts(item.Scalar())) {
      throw InputError(fmt::format("{}: {}: {}: expected {}", where(item), fieldPath(at),
                                   nodeText(item), expectedText(expect, item.Scalar())));
    }
    if (std::find(items.begin(), items.end(), item.Scalar()) != items.end()) {
      throw InputError(fmt::format("{}: {}: '{}' is listed twice: expected each once", where(item),
                                   fieldPath(at), item.Scalar()));
    }
    items.push_back(item.Scalar());
  }
  value = std::move(items);
}

void YamlIn::field(const char* key, std::vector<std::array<std::string, 2>>& value, const Expect&) {
  if (!has(key)) return;
  const YAML::Node seq = node_[key];
  checkSequence(key, seq, 0, 1000);
  std::vector<std::array<std::string, 2>> pairs;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const YAML::Node item = seq[i];
    const std::string at = fmt::format("{}[{}]", key, i);
    if (!item.IsSequence() || item.size() != 2 || !item[0].IsScalar() || !item[1].IsScalar() ||
        item[0].Scalar() == item[1].Scalar()) {
      throw InputError(fmt::format("{}: {}: {}: expected a pair of two different names, [a, b]",
                                   where(item), fieldPath(at), nodeText(item)));
    }
    const std::array<std::string, 2> pair{item[0].Scalar(), item[1].Scalar()};
    for (const auto& p : pairs) {
      if ((p[0] == pair[0] && p[1] == pair[1]) || (p[0] == pair[1] && p[1] == pair[0])) {
        throw InputError(fmt::format("{}: {}: [{}, {}] is listed twice: expected each pair once",
                                     where(item), fieldPath(at), pair[0], pair[1]));
      }
    }
    pairs.push_back(pair);
  }
  value = std::move(pairs);
}

void YamlIn::field(const char* key, FilePath& value, const Expect&) {
  if (!has(key)) return;
  const YAML::Node n = node_[key];
  if (!n.IsScalar() || n.Scalar().empty()) fail(key, nodeText(n), "a file path");
  value.as_written = n.Scalar();
  std::filesystem::path p(value.as_written);
  if (p.is_relative()) p = file_.parent_path() / p;
  value.resolved = std::filesystem::absolute(p).lexically_normal();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(value.resolved, ec)) {
    fail(key,
         fmt::format("'{}' ({}) {}", value.as_written, value.resolved.string(),
                     std::filesystem::exists(value.resolved, ec) ? "is not a regular file"
                                                                 : "does not exist"),
         "an existing file (relative paths start at the folder of " + file_.filename().string() +
             ")");
  }
}

void YamlIn::numbers(const char* key,
                     std::vector<double>& values,
                     std::size_t count,
                     const Expect& expect,
                     bool integers) {
  if (!has(key)) return;
  const YAML::Node seq = node_[key];
  const std::string kind = integers ? "integers" : "numbers";
  if (!seq.IsSequence() || seq.size() != count) {
    fail(key, nodeText(seq) + (seq.IsSequence() ? fmt::format(" of {}", seq.size()) : ""),
         fmt::format("a list of {} {}, e.g. [{}]", count, kind,
                     fmt::join(std::vector<std::string>(count, "0"), ", ")));
  }
  for (std::size_t i = 0; i < count; ++i) {
    double v = 0.0;
    const YAML::Node item = seq[i];
    const std::string sub = fmt::format("{}[{}]", key, i);
    const bool number = item.IsScalar() && parseDouble(item.Scalar(), v);
    if (!number || (integers && std::floor(v) != v)) {
      throw InputError(fmt::format(
          "{}: {}: {} is not a {}: expected {}", where(item), fieldPath(sub), nodeText(item),
          number ? "whole number" : "number", expect.describe(integers ? "integer" : "number")));
    }
    if (!expect.accepts(v)) {
      throw InputError(fmt::format("{}: {}: {}: expected {}", where(item), fieldPath(sub),
                                   formatNumber(v), expect.describe(v, "number")));
    }
    if (const std::string limit = beyondMagnitude(key, v); !limit.empty()) {
      throw InputError(fmt::format("{}: {}: {}: expected {}", where(item), fieldPath(sub),
                                   formatNumber(v), limit));
    }
    values[i] = v;
  }
}

void YamlIn::checkSequence(const char* key,
                           const YAML::Node& seq,
                           std::size_t min_size,
                           std::size_t max_size) const {
  if (!seq.IsSequence()) fail(key, nodeText(seq), "a list");
  if (seq.size() < min_size || seq.size() > max_size) {
    fail(key, fmt::format("a list of {}", seq.size()),
         min_size == max_size ? fmt::format("exactly {} entries", min_size)
                              : fmt::format("{} to {} entries", min_size, max_size));
  }
}

YamlIn YamlIn::child_(const std::string& key,
                      const YAML::Node& node,
                      YAML::NodeType::value type,
                      const char* what) const {
  if (node.Type() != type) {
    throw InputError(
        fmt::format("{}: {}: {}: expected {}", where(node), fieldPath(key), nodeText(node), what));
  }
  return YamlIn(node, fieldPath(key), file_, overrides_);
}

void YamlIn::finish() const {
  const auto unknown = unknownKeys();
  for (const std::string& m : missing_) {
    for (const auto& [key, key_node] : unknown) {
      if (suggestKey(key, {m}) == m) unknownKey(key, key_node, m);
    }
    missing(m);
  }
  for (const auto& [key, key_node] : unknown) unknownKey(key, key_node, suggestKey(key, known_));
}

void YamlOut::writeScalar(double v) { out_ << formatNumber(v); }

void YamlOut::field(const char* key, double value, const Expect&) {
  out_ << YAML::Key << key << YAML::Value;
  writeScalar(value);
}
void YamlOut::field(const char* key, int value, const Expect&) {
  out_ << YAML::Key << key << YAML::Value << value;
}
void YamlOut::field(const char* key, bool value, const Expect&) {
  out_ << YAML::Key << key << YAML::Value << value;
}
void YamlOut::field(const char* key, const std::string& value, const Expect&) {
  out_ << YAML::Key << key << YAML::Value << value;
}
void YamlOut::field(const char* key, const std::vector<std::string>& value, const Expect&) {
  out_ << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const std::string& v : value) out_ << v;
  out_ << YAML::EndSeq;
}
void YamlOut::field(const char* key,
                    const std::vector<std::array<std::string, 2>>& value,
                    const Expect&) {
  out_ << YAML::Key << key << YAML::Value << YAML::BeginSeq;
  for (const auto& pair : value)
    out_ << YAML::Flow << YAML::BeginSeq << pair[0] << pair[1] << YAML::EndSeq;
  out_ << YAML::EndSeq;
}
void YamlOut::field(const char* key, const FilePath& value, const Expect&) {
  out_ << YAML::Key << key << YAML::Value
       << (paths_as_written_ ? value.as_written : value.resolved.string());
}
void YamlOut::fail(const std::string&, const std::string&, const std::string&) const {
  throw std::logic_error("YamlOut::fail: writing never validates");
}

}  // namespace scanplan::config
