// The job file's JSON Schema (`scanplan job schema`): its shape, and — with ajv, a JSON Schema
// validator from npm (web/node_modules, installed by bootstrap.sh; skipped without node or it)
// — that every bundled job and every resolved job (`job show`) is valid, and that misspelt
// keys, wrong types, out-of-range values and unknown choices are not.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <scanplan/config/job.h>
#include <scanplan/kinematics/error.h>
#include "test_support.h"

namespace {

using namespace scanplan;
namespace fs = std::filesystem;
using Json = nlohmann::json;

// Every object in the schema refuses unknown keys.
void expectClosedObjects(const Json& s, const std::string& where) {
  if (s.contains("properties")) {
    EXPECT_EQ(s.value("additionalProperties", true), false) << where;
    for (const auto& [key, value] : s["properties"].items()) {
      expectClosedObjects(value, where + "." + key);
    }
  }
  if (s.contains("items")) expectClosedObjects(s["items"], where + "[]");
}

TEST(JobSchema, NamesEverySectionAndRefusesUnknownKeysEverywhere) {
  const Json schema = Json::parse(config::jobSchema());
  EXPECT_EQ(schema["$schema"], "http://json-schema.org/draft-07/schema#");
  for (const char* section :
       {"name", "robot", "robot_base", "table", "part", "scanner", "obstacles", "constraints",
        "scan", "map", "planner", "validation", "simulation", "outputs"}) {
    EXPECT_TRUE(schema["properties"].contains(section)) << section;
  }
  EXPECT_EQ(schema["required"], Json::parse(R"(["robot", "part"])"));
  expectClosedObjects(schema, "job");
  // Ranges and choices are the reader's.
  const Json& trigger = schema["properties"]["outputs"]["properties"]["trigger"];
  EXPECT_EQ(trigger["properties"]["output"]["maximum"], 4096.0);
  const Json& paths = schema["properties"]["scan"]["properties"]["paths"]["items"];
  EXPECT_EQ(paths["properties"]["type"]["enum"],
            Json::parse(R"(["ring", "raster", "waypoints", "file"])"));
  EXPECT_EQ(paths["required"], Json::parse(R"(["type"])"));  // height_mm only for rings
}

void writeFile(const fs::path& file, const std::string& text) {
  std::ofstream(file, std::ios::binary) << text;
}

TEST(JobSchema, AjvValidatesEveryBundledJobAndRejectsMisspeltKeys) {
  const fs::path modules = test::sourceDir() / "web/node_modules";
  if (test::runCommand("command -v node").empty() || !fs::exists(modules / "ajv") ||
      !fs::exists(modules / "yaml")) {
    GTEST_SKIP() << "node or web/node_modules (ajv, yaml) absent: run ./bootstrap.sh";
  }
  const fs::path dir = fs::temp_directory_path() / ("scanplan_schema_" + std::to_string(getpid()));
  fs::create_directories(dir);
  writeFile(dir / "job.schema.json", config::jobSchema());
  // file → whether it must be valid
  std::vector<std::pair<fs::path, bool>> cases;
  for (const auto& entry : fs::directory_iterator(test::sourceDir() / "data/jobs")) {
    cases.emplace_back(entry.path(), true);
    // Its resolved form too, where it loads (bunny_shared.yaml needs ../shared).
    config::JobSpec job;
    try {
      job = config::loadJob(entry.path());
    } catch (const InputError& e) {
      if (fs::exists(test::sharedDataDir())) ADD_FAILURE() << e.what();
      continue;
    }
    const fs::path shown = dir / ("shown_" + entry.path().filename().string());
    writeFile(shown, config::jobToYaml(job));
    cases.emplace_back(shown, true);
  }
  const std::string base = "robot: r.yaml\npart: {mesh: p.stl}\n";
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"top_level", "planer: {type: dp}\n"},
      {"nested", "scanner: {mass_kgg: 1}\n"},
      {"list_item", "scan: {paths: [{type: ring, hieght_mm: 30}]}\n"},
      {"type", "table: {radius_mm: big}\n"},
      {"range", "outputs: {servo_period_s: 5}\n"},
      {"choice", "outputs: {programs: [vplux]}\n"},
      {"array_size", "scanner: {cog_mm: [1, 2]}\n"},
  };
  for (const auto& [name, text] : bad) {
    writeFile(dir / ("bad_" + name + ".yaml"), base + text);
    cases.emplace_back(dir / ("bad_" + name + ".yaml"), false);
  }
  writeFile(dir / "good_minimal.yaml", base + "outputs: {trigger: {output: 2}}\n");
  cases.emplace_back(dir / "good_minimal.yaml", true);

  std::string command = "SCANPLAN_WEB_MODULES='" + modules.string() + "' node '" +
                        (test::sourceDir() / "tests/js/validate_jobs.mjs").string() + "' '" +
                        (dir / "job.schema.json").string() + "'";
  for (const auto& [file, valid] : cases) command += " '" + file.string() + "'";
  std::istringstream lines(test::runCommand(command + " 2>&1"));
  std::size_t checked = 0;
  for (std::string line; std::getline(lines, line);) {
    const Json result = Json::parse(line, nullptr, false);
    ASSERT_FALSE(result.is_discarded()) << line;
    ASSERT_LT(checked, cases.size());
    EXPECT_EQ(result["file"], cases[checked].first.string());
    EXPECT_EQ(result["valid"], cases[checked].second) << line;
    ++checked;
  }
  EXPECT_EQ(checked, cases.size());
  fs::remove_all(dir);
}

}  // namespace
