// `--set key.path=value`: an override sets a value in the job's YAML tree before it is read, so
// the reader validates it like any value of the file, and its errors name the override.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <regex>
#include <set>
#include <sstream>
#include <type_traits>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <scanplan/config/detail/job_sections.h>
#include <scanplan/config/robot_urdf.h>
#include <scanplan/config/text.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/placement.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/programs/programs.h>

namespace scanplan::config {
namespace {

[[noreturn]] void badOverride(const std::string& text, const std::string& why) {
  const std::string quoted = clipForMessage(text);  // a hostile value is not echoed whole
  throw InputError(
      fmt::format("--set '{}': {}: expected key.path=value, e.g. "
                  "planner.ray.horizon=20 or scan.paths[0].height_mm=60",
                  quoted, why));
}

// The key node of `key` in `map`, recorded as the override's when the override created it.
void recordOverrideKey(const YAML::Node& map,
                       const std::string& key,
                       const std::string& text,
                       OverrideOrigins& origins) {
  for (auto it = map.begin(); it != map.end(); ++it) {
    if (it->first.IsScalar() && it->first.Scalar() == key) origins.add(it->first, text);
  }
}

// A step of an override's key path: a key, or a list index (key empty).
using OverrideStep = std::pair<std::string, int>;

// The steps of one '.'-separated segment of the key path: "paths[0]" → paths, [0].
void appendSegmentSteps(const std::string& text,
                        std::size_t eq,
                        const std::string& segment,
                        std::vector<OverrideStep>& steps) {
  std::string key = segment;
  std::vector<int> indices;
  const std::size_t bracket = segment.find('[');
  if (bracket != std::string::npos) {
    key = segment.substr(0, bracket);
    std::string rest = segment.substr(bracket);
    while (!rest.empty()) {
      const std::size_t close = rest.find(']');
      if (rest[0] != '[' || close == std::string::npos) {
        badOverride(text, "'" + segment + "' is malformed");
      }
      const auto index = parseFiniteNumber(rest.substr(1, close - 1));
      if (!index || *index < 0 || *index != std::floor(*index)) {
        badOverride(text, "'" + segment + "' has a bad list index");
      }
      indices.push_back(static_cast<int>(*index));
      rest = rest.substr(close + 1);
    }
  }
  if (key.empty()) badOverride(text, "an empty key in '" + text.substr(0, eq) + "'");
  steps.emplace_back(key, -1);
  for (int i : indices) steps.emplace_back("", i);
}

// The node an override sets a value in, and its path as the messages print it.
struct OverrideParent {
  YAML::Node node;
  std::string where;
};

// Walks all steps but the last from `root`, creating the mappings on the way.
OverrideParent overrideParent(YAML::Node root,
                              const std::vector<OverrideStep>& steps,
                              const std::string& text,
                              OverrideOrigins& origins) {
  YAML::Node node = root;
  std::string where;
  for (std::size_t i = 0; i + 1 < steps.size(); ++i) {
    const auto& [key, index] = steps[i];
    YAML::Node next;
    if (key.empty()) {
      if (!node.IsSequence() || static_cast<std::size_t>(index) >= node.size()) {
        badOverride(text, fmt::format("{} has no item [{}]", where, index));
      }
      next.reset(node[static_cast<std::size_t>(index)]);
      where += fmt::format("[{}]", index);
    } else {
      if (node.IsDefined() && !node.IsNull() && !node.IsMap()) {
        badOverride(text, where + " is not a mapping");
      }
      if (!node[key].IsDefined()) {
        node[key] = YAML::Node(YAML::NodeType::Map);
        recordOverrideKey(node, key, text, origins);
        origins.add(node[key], text);
      }
      next.reset(node[key]);
      where += (where.empty() ? "" : ".") + key;
    }
    node.reset(next);
  }
  return {node, where};
}

// The override's value: a flow sequence or mapping is YAML, anything else a scalar.
YAML::Node overrideValue(const std::string& text, const std::string& value) {
  const bool yaml = !value.empty() && (value[0] == '[' || value[0] == '{');
  YAML::Node v;
  try {
    if (yaml) {
      std::istringstream in(value);
      if (const auto second = secondDocumentStart(in)) {
        badOverride(text, fmt::format("the value holds a second YAML document at its line {}: "
                                      "expected one value (the rest would be dropped)",
                                      second->line + 1));
      }
    }
    v = yaml ? YAML::Load(value) : YAML::Node(value);
  } catch (const YAML::Exception& e) {
    badOverride(text, "the value is malformed YAML: " + e.msg);
  }
  try {
    checkYamlSize(v, "the value");
  } catch (const InputError& e) {
    badOverride(text, e.what());
  }
  return v;
}

}  // namespace

// "planner.ray.horizon=20", "scan.paths[0].height_mm=60": sets that value in the YAML tree
// (creating mappings on the way), so the reader validates it like any value of the file. The
// value, and every key and mapping the override created, go into `origins`, so errors about
// them name the override.
void applyOverride(YAML::Node root, const std::string& text, OverrideOrigins& origins) {
  const std::size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0) badOverride(text, "no key");
  const std::string value = text.substr(eq + 1);
  std::vector<OverrideStep> steps;
  std::stringstream keys(text.substr(0, eq));
  for (std::string segment; std::getline(keys, segment, '.');) {
    appendSegmentSteps(text, eq, segment, steps);
  }
  OverrideParent parent = overrideParent(root, steps, text, origins);
  YAML::Node& node = parent.node;
  const std::string& where = parent.where;
  const auto& [key, index] = steps.back();
  YAML::Node v = overrideValue(text, value);
  if (key.empty()) {
    if (!node.IsSequence() || static_cast<std::size_t>(index) >= node.size()) {
      badOverride(text, fmt::format("{} has no item [{}]", where, index));
    }
    node[static_cast<std::size_t>(index)] = v;
  } else {
    if (node.IsDefined() && !node.IsNull() && !node.IsMap()) {
      badOverride(text, where + " is not a mapping");
    }
    const bool created = !node[key].IsDefined();
    node[key] = v;
    if (created) recordOverrideKey(node, key, text, origins);
  }
  origins.add(v, text);
}

}  // namespace scanplan::config
