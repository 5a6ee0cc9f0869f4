#pragma once
// The YAML side of the job and robot files: private to config/ (only its .cpp files, and the sweep
// reader of cli/batch/, include this). Everything else sees the plain spec structs of spec.h,
// robot_file.h and job.h.

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <istream>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include <scanplan/config/spec.h>
#include <scanplan/config/text.h>

namespace scanplan::config {

/// What a value must satisfy; part of every error message ("expected …").
struct Expect {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false;
  bool hi_open = false;
  std::vector<std::string> choices;

  static Expect positive() {
    return {0.0, std::numeric_limits<double>::infinity(), true, false, {}};
  }
  static Expect nonNegative() {
    return {0.0, std::numeric_limits<double>::infinity(), false, false, {}};
  }
  static Expect range(double lo, double hi) { return {lo, hi, false, false, {}}; }
  static Expect oneOf(std::vector<std::string> choices) {
    Expect e;
    e.choices = std::move(choices);
    return e;
  }
  /// Finite, in range and normal (0 or a normal double: a denormal is refused).
  bool accepts(double v) const;
  bool accepts(const std::string& v) const;
  std::string describe(const char* kind) const;
  /// describe(kind), saying why when `v` is a denormal.
  std::string describe(double v, const char* kind) const;
};

/// The nodes of a YAML tree that came from the command line (`--set key.path=value`), each with
/// the override's text: errors about them name the override, not a place in the file.
class OverrideOrigins {
 public:
  /// Records `node` and everything under it as given by the override `text`.
  void add(const YAML::Node& node, const std::string& text);
  /// The override that gave `node`, or nullptr when the file did.
  const std::string* find(const YAML::Node& node) const;

 private:
  std::vector<std::pair<YAML::Node, std::string>> nodes_;
};

/// Reads one YAML mapping into a spec struct, field by field, validating as it goes.
/// Every error names the file, line and column (or the --set override that gave the value),
/// the field path, the bad value and what was expected. finish() rejects keys nobody asked
/// for, and must be called (section(), list() and the loaders do). Spec structs hold their
/// defaults, so a missing optional key keeps the default.
class YamlIn {
 public:
  static constexpr bool kReading = true;

  /// `overrides`: which nodes came from --set (nullptr: all from the file); shared by every
  /// child mapping.
  YamlIn(YAML::Node node,
         std::string path,
         std::filesystem::path file,
         std::shared_ptr<const OverrideOrigins> overrides = nullptr);

  bool has(const char* key) const;
  void field(const char* key, double& value, const Expect& expect = {});
  void field(const char* key, int& value, const Expect& expect = {});
  void field(const char* key, bool& value, const Expect& expect = {});
  void field(const char* key, std::string& value, const Expect& expect = {});
  void field(const char* key, FilePath& value, const Expect& expect = {});
  /// A list of texts, each checked against `expect` (e.g. oneOf); duplicates are errors.
  void field(const char* key, std::vector<std::string>& value, const Expect& expect = {});
  /// A list of name pairs, `[[a, b], …]`: each two different texts, no pair twice (either order).
  void field(const char* key, std::vector<std::array<std::string, 2>>& value, const Expect& = {});
  template <std::size_t N>
  void field(const char* key, std::array<double, N>& value, const Expect& expect = {}) {
    std::vector<double> v(value.begin(), value.end());
    numbers(key, v, N, expect);
    std::copy(v.begin(), v.end(), value.begin());
  }
  template <std::size_t N>
  void field(const char* key, std::array<int, N>& value, const Expect& expect = {}) {
    std::vector<double> v(value.begin(), value.end());
    numbers(key, v, N, expect, true);
    for (std::size_t i = 0; i < N; ++i) value[i] = static_cast<int>(v[i]);
  }
  /// Marks a key as required: missing → error. When an unknown key of this mapping is a near
  /// miss of it (hieght_mm for height_mm), finish() reports that key instead, with the
  /// suggestion, at its position.
  void require(const char* key) const;

  /// A nested mapping, described by `describe(YamlIn&, S&)`.
  template <class S>
  void section(const char* key, S& spec) {
    if (!has(key)) return;
    YamlIn child = child_(key, node_[key], YAML::NodeType::Map, "a mapping");
    describe(child, spec);
    child.finish();
  }
  /// A sequence of mappings.
  template <class S>
  void list(const char* key, std::vector<S>& items, std::size_t min_size, std::size_t max_size) {
    if (!has(key)) return;
    const YAML::Node seq = node_[key];
    checkSequence(key, seq, min_size, max_size);
    items.assign(seq.size(), S{});
    for (std::size_t i = 0; i < seq.size(); ++i) {
      YamlIn child =
          child_(key + ("[" + std::to_string(i) + "]"), seq[i], YAML::NodeType::Map, "a mapping");
      describe(child, items[i]);
      child.finish();
    }
  }

  /// Throws the standard error for `key` (or this mapping when key is empty).
  [[noreturn]] void fail(const std::string& key,
                         const std::string& value,
                         const std::string& expected) const;
  /// Rejects keys that no field() / section() / list() asked for.
  void finish() const;

  const std::filesystem::path& file() const { return file_; }
  const std::string& path() const { return path_; }
  const YAML::Node& node() const { return node_; }
  const std::shared_ptr<const OverrideOrigins>& overrides() const { return overrides_; }

 private:
  YamlIn child_(const std::string& key,
                const YAML::Node& node,
                YAML::NodeType::value type,
                const char* what) const;
  void numbers(const char* key,
               std::vector<double>& values,
               std::size_t count,
               const Expect& expect,
               bool integers = false);
  void checkSequence(const char* key,
                     const YAML::Node& seq,
                     std::size_t min_size,
                     std::size_t max_size) const;
  std::string where(const YAML::Node& node) const;
  std::string fieldPath(const std::string& key) const;
  /// The keys of this mapping no field() / section() / list() asked for (so far).
  std::vector<std::pair<std::string, YAML::Node>> unknownKeys() const;
  [[noreturn]] void missing(const std::string& key) const;
  [[noreturn]] void unknownKey(const std::string& key,
                               const YAML::Node& key_node,
                               const std::string& suggestion) const;

  YAML::Node node_;
  std::string path_;
  std::filesystem::path file_;
  std::shared_ptr<const OverrideOrigins> overrides_;
  mutable std::vector<std::string> known_;
  /// Required keys that were missing while an unknown key looked like a misspelling of them;
  /// finish() decides which of the two to report.
  mutable std::vector<std::string> missing_;
};

/// Writes a spec struct back as YAML through the same describe() functions, so `job show`
/// prints exactly the fields and defaults the reader used.
class YamlOut {
 public:
  static constexpr bool kReading = false;

  /// `paths_as_written`: file paths as the job file wrote them, not resolved (for a hash that
  /// does not depend on where the checkout lives).
  explicit YamlOut(YAML::Emitter& out, bool paths_as_written = false)
      : out_(out), paths_as_written_(paths_as_written) {}

  bool has(const char*) const { return true; }
  void field(const char* key, double value, const Expect& = {});
  void field(const char* key, int value, const Expect& = {});
  void field(const char* key, bool value, const Expect& = {});
  void field(const char* key, const std::string& value, const Expect& = {});
  void field(const char* key, const FilePath& value, const Expect& = {});
  void field(const char* key, const std::vector<std::string>& value, const Expect& = {});
  void field(const char* key,
             const std::vector<std::array<std::string, 2>>& value,
             const Expect& = {});
  template <class T, std::size_t N>
  void field(const char* key, const std::array<T, N>& value, const Expect& = {}) {
    out_ << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (const T& v : value) writeScalar(static_cast<double>(v));
    out_ << YAML::EndSeq;
  }
  void require(const char*) const {}
  template <class S>
  void section(const char* key, S& spec) {
    out_ << YAML::Key << key << YAML::Value << YAML::BeginMap;
    describe(*this, spec);
    out_ << YAML::EndMap;
  }
  template <class S>
  void list(const char* key, std::vector<S>& items, std::size_t, std::size_t) {
    out_ << YAML::Key << key << YAML::Value << YAML::BeginSeq;
    for (S& item : items) {
      out_ << YAML::BeginMap;
      describe(*this, item);
      out_ << YAML::EndMap;
    }
    out_ << YAML::EndSeq;
  }
  [[noreturn]] void fail(const std::string&, const std::string&, const std::string&) const;
  void finish() const {}

 private:
  void writeScalar(double v);
  YAML::Emitter& out_;
  bool paths_as_written_ = false;
};

/// Limits on a YAML document, counted as a reader visits it (an alias each time it is used): a
/// billion-laughs alias bomb or runaway nesting stops here, not in an allocation.
inline constexpr std::size_t kMaxYamlNodes = 1'000'000;
inline constexpr std::size_t kMaxYamlDepth = 64;
/// Job, robot and sweep files: at most this many bytes (a job is a few kB).
inline constexpr std::uintmax_t kMaxYamlFileBytes = 64u << 20;
/// Throws InputError naming `where` when `root` exceeds them.
void checkYamlSize(const YAML::Node& root, const std::string& where);

/// Loads a YAML file (a mapping at the top), turning parse errors into InputError with
/// file:line:column.
YAML::Node loadYamlFile(const std::filesystem::path& file);

/// The one YAML document of a file (a null node when it holds none), parse errors as InputError
/// with file:line:column; a file of more than one document (another `---` after the first, or
/// text after a `...` that ends it; an empty one too) is an InputError naming file:line:column
/// where the second starts: its keys would otherwise be dropped.
YAML::Node loadOneDocument(const std::filesystem::path& file);

/// Where the second YAML document of `in` starts (read up to there, no tree built), or none when
/// it holds at most one; a malformed text throws YAML::Exception.
std::optional<YAML::Mark> secondDocumentStart(std::istream& in);

/// Throws InputError naming `file` unless it is a regular file of at most kMaxYamlFileBytes (a
/// FIFO or device would be read until it ends, which may be never).
void requireYamlFile(const std::filesystem::path& file);

}  // namespace scanplan::config
