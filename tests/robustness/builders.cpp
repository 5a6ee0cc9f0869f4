#include "tests/robustness/builders.h"

#include <sys/stat.h>

#include <cctype>
#include <cstdlib>
#include <random>
#include <set>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

namespace scanplan::robustness {

std::string expand(const std::string& text) {
  const std::string src = "@src/", fix = "@fix/", plan = "@fix/plan", programs = "@fix/programs";
  if (text.rfind(programs, 0) == 0) {  // a plan that writes every program language
    return planFixture("programs", {"outputs.programs=[vplus, krl, rapid, urscript]"}).string() +
           text.substr(programs.size());
  }
  if (text.rfind(plan, 0) == 0) return planFixture().string() + text.substr(plan.size());
  if (text.rfind(src, 0) == 0)
    return (fs::path(SCANPLAN_SOURCE_DIR) / text.substr(src.size())).string();
  if (text.rfind(fix, 0) == 0) return (fixtureDir() / text.substr(fix.size())).string();
  return text;
}

InputFile text(const std::string& name, std::string content) {
  return {name, [content](const fs::path& file) { writeText(file, content); }};
}

InputFile copyOf(const std::string& name, const std::string& source) {
  return {name, [source](const fs::path& file) { writeText(file, readText(expand(source))); }};
}

InputFile truncated(const std::string& name, const std::string& source, double fraction) {
  return {name, [source, fraction](const fs::path& file) {
            const std::string all = readText(expand(source));
            writeText(file, all.substr(0, static_cast<std::size_t>(static_cast<double>(all.size()) *
                                                                   fraction)));
          }};
}

InputFile transformed(const std::string& name,
                      const std::string& source,
                      std::function<std::string(std::string)> change) {
  return {name, [source, change](const fs::path& file) {
            writeText(file, change(readText(expand(source))));
          }};
}

InputFile garbage(const std::string& name, std::size_t bytes, unsigned seed) {
  return {name, [bytes, seed](const fs::path& file) {
            std::mt19937 random(seed);
            std::string data(bytes, '\0');
            for (char& c : data) c = static_cast<char>(random() & 0xff);
            writeText(file, data);
          }};
}

InputFile fifo(const std::string& name) {
  return {name, [](const fs::path& file) { ::mkfifo(file.c_str(), 0644); }};
}

InputFile folder(const std::string& name) {
  return {name, [](const fs::path& file) { fs::create_directories(file); }};
}

InputFile symlinkTo(const std::string& name, const std::string& target) {
  return {name, [target](const fs::path& file) { fs::create_symlink(expand(target), file); }};
}

InputFile readOnlyFolder(const std::string& name) {
  return {name, [](const fs::path& file) {
            fs::create_directories(file);
            fs::permissions(file, fs::perms::owner_read | fs::perms::owner_exec |
                                      fs::perms::group_read | fs::perms::group_exec |
                                      fs::perms::others_read | fs::perms::others_exec);
          }};
}

namespace {

// "scan.paths[0].height_mm" → scan, paths, 0, height_mm (indices as numbers).
std::vector<std::string> segments(const std::string& key) {
  std::vector<std::string> parts;
  std::string part;
  for (char c : key) {
    if (c == '.' || c == '[' || c == ']') {
      if (!part.empty()) parts.push_back(part);
      part.clear();
    } else {
      part += c;
    }
  }
  if (!part.empty()) parts.push_back(part);
  return parts;
}

void edit(YAML::Node root, const std::string& key, const std::string& value) {
  const std::vector<std::string> parts = segments(key);
  YAML::Node node = root;
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    const bool index = std::isdigit(static_cast<unsigned char>(parts[i][0])) != 0;
    node.reset(index ? node[std::stoi(parts[i])] : node[parts[i]]);
  }
  const std::string& last = parts.back();
  const YAML::Node parsed = YAML::Load(value);
  if (std::isdigit(static_cast<unsigned char>(last[0]))) {
    node[std::stoi(last)] = parsed;
  } else {
    node[last] = parsed;
  }
}

InputFile edited(const std::string& name, const std::string& base, const Edits& edits) {
  return {name, [base, edits](const fs::path& file) {
            YAML::Node root = YAML::Load(readText(expand(base)));
            for (const auto& [key, value] : edits) edit(root, key, value);
            YAML::Emitter out;
            out << root;
            writeText(file, std::string(out.c_str()) + "\n");
          }};
}

std::string normalised(const std::string& key) {
  std::string text;
  bool in_index = false;
  for (char c : key) {
    if (c == '[') in_index = true;
    if (!in_index) text += c;
    if (c == ']') in_index = false, text += "[]";
  }
  return text;
}

bool isNumber(const YAML::Node& node) {
  if (!node.IsScalar()) return false;
  const std::string& s = node.Scalar();
  char* end = nullptr;
  std::strtod(s.c_str(), &end);
  return !s.empty() && end == s.c_str() + s.size();
}

struct KeyWalk {
  std::set<std::string> seen;
  std::vector<std::pair<std::string, std::string>> leaves;
  std::vector<std::string> lists;

  void leaf(const std::string& key, const std::string& value) {
    if (seen.insert(normalised(key)).second) leaves.emplace_back(key, value);
  }
  void walk(const YAML::Node& node, const std::string& key) {
    if (isNumber(node)) return leaf(key, node.Scalar());
    if (node.IsMap()) {
      for (const auto& kv : node) {
        walk(kv.second, key.empty() ? kv.first.Scalar() : key + "." + kv.first.Scalar());
      }
    } else if (node.IsSequence()) {
      bool numbers = node.size() > 0;
      for (const auto& e : node) numbers = numbers && isNumber(e);
      if (numbers && seen.insert(normalised(key) + "*").second) lists.push_back(key);
      for (std::size_t i = 0; i < node.size(); ++i) {
        walk(node[i], key + "[" + std::to_string(i) + "]");
      }
    }
  }
};

KeyWalk walkResolved() {
  KeyWalk walk;
  walk.walk(YAML::Load(readText(fixtureDir() / "resolved.yaml")), "");
  return walk;
}

}  // namespace

InputFile jobWith(const std::string& name, const Edits& edits) {
  return edited(name, "@fix/light.yaml", edits);
}

InputFile resolvedWith(const std::string& name, const Edits& edits) {
  return edited(name, "@fix/resolved.yaml", edits);
}

InputFile robotWith(const std::string& name, const Edits& edits) {
  return edited(name, "@src/data/robots/viper_s650.yaml", edits);
}

InputFile jobAppended(const std::string& name, const std::string& extra) {
  return {name, [extra](const fs::path& file) {
            writeText(file, readText(fixtureDir() / "light.yaml") + extra);
          }};
}

std::vector<std::pair<std::string, std::string>> numericKeys() { return walkResolved().leaves; }

std::vector<std::string> numericListKeys() { return walkResolved().lists; }

}  // namespace scanplan::robustness
