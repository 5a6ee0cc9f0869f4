// Every numeric key of the job (fix/resolved.yaml: `job show` of a job with one of everything,
// robot inline) × hostile values, written into the file. The values a key can never take (not
// finite, over the ±1e9 limit, the wrong type) must be refused naming the file and the key; the
// plausible ones (-1, 0, 1e8) may be accepted, and when refused must name them too.
#include <string>

#include "tests/robustness/builders.h"
#include "tests/robustness/cases.h"

namespace scanplan::robustness {
namespace {

// A gtest-safe name for a key: robot.dh[0].a_mm → robot_dh_0_a_mm.
std::string identifier(const std::string& text) {
  std::string id;
  for (char c : text) {
    const bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
    if (keep)
      id += c;
    else if (!id.empty() && id.back() != '_')
      id += '_';
  }
  while (!id.empty() && id.back() == '_') id.pop_back();
  return id;
}

struct Hostile {
  const char* label;
  const char* yaml;
  bool never_valid;
};

// The values for a number; never_valid ones must be refused.
const std::vector<Hostile> kScalarValues = {{"nan", ".nan", true},
                                            {"inf", ".inf", true},
                                            {"minus_inf", "-.inf", true},
                                            {"1e300", "1e300", true},
                                            {"minus_1e300", "-1e300", true},
                                            {"text", "abc", true},
                                            {"list", "[1, 2]", true},
                                            {"mapping", "{a: 1}", true},
                                            {"null", "~", true},
                                            {"minus_1", "-1", false},
                                            {"zero", "0", false},
                                            {"1e8", "1e8", false}};

// The values for a list of numbers (besides each element's, above).
const std::vector<Hostile> kListValues = {{"scalar", "5", true},
                                          {"empty", "[]", true},
                                          {"too_long", "[1, 2, 3, 4, 5, 6, 7, 8, 9]", true},
                                          {"nested", "[[1], [2]]", true}};

// Commands that read the job without doing work before the first error; a key's cases rotate
// over them (a value that may be valid runs `job show` only, which does no work).
std::vector<std::string> commandFor(std::size_t i, bool never_valid) {
  static const std::vector<std::vector<std::string>> commands{
      {"job", "show", "job.yaml"},
      {"path", "job.yaml", "-o", "out"},
      {"check", "job.yaml", "--table", "0", "--joints=0,-90,180,0,90,0"},
      {"map", "job.yaml", "-o", "out"},
      {"plan", "job.yaml", "-o", "out"},
      {"validate", "job.yaml", "-t", "@fix/plan/trajectory.csv"},
      {"fk", "--job", "job.yaml", "--joints=0,-90,180,0,90,0"}};
  return never_valid ? commands[i % commands.size()] : commands[0];
}

// What an error must name besides the file: the key; for a plausible value of a robot's DH or
// OPW table, which is checked against the other table as a whole, "robot".
std::string plausibleName(const std::string& key, const Hostile& value) {
  const bool table = key.rfind("robot.dh", 0) == 0 || key.rfind("robot.opw", 0) == 0;
  return !value.never_valid && table ? "robot" : key;
}

Case mutation(const std::string& key, const Hostile& value, std::size_t i) {
  const auto args = commandFor(i, value.never_valid);
  const bool writes = args.back() == "out";
  return Case{.name = "key_" + identifier(key) + "_" + value.label,
              .group = "numeric keys",
              .args = args,
              .files = {resolvedWith("job.yaml", {{key, value.yaml}})},
              .exits = value.never_valid ? std::vector<int>{4} : std::vector<int>{0, 4},
              .names = {"job.yaml", plausibleName(key, value)},
              .out = !writes ? OutState::kNone
                     : i % 2 ? OutState::kExisting
                             : OutState::kAbsent};
}

}  // namespace

std::vector<Case> generatedCases() {
  std::vector<Case> cases;
  std::size_t i = 0;
  for (const auto& [key, original] : numericKeys()) {
    for (const Hostile& value : kScalarValues) cases.push_back(mutation(key, value, i++));
  }
  for (const std::string& key : numericListKeys()) {
    for (const Hostile& value : kListValues) cases.push_back(mutation(key, value, i++));
  }
  for (const std::string& key : {std::string("table.radius_mm"), std::string("scan.dt_s"),
                                 std::string("robot.dh[0].a_mm")}) {
    Case deep = mutation(key, {"deep", "", true}, i++);
    deep.files = {resolvedWith("job.yaml", {{key, nestedText(100)}})};
    deep.names = {"job.yaml"};
    cases.push_back(std::move(deep));
  }
  return cases;
}

std::vector<Case> allCases() {
  std::vector<Case> all;
  for (auto part : {reportedCases(), fileCases(), pathCases(), commandCases(), modelLimitCases(),
                    generatedCases()}) {
    all.insert(all.end(), part.begin(), part.end());
  }
  return all;
}

}  // namespace scanplan::robustness
