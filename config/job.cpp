// A job file as a whole: its top-level keys (the sections come from job_*.cpp), loading with
// overrides, the resolved YAML and its hash, the JSON Schema, and the files a job reads.
#include <scanplan/config/job.h>

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

// The bodies of the collision scene a job makes (collision::Scene's names: links with shapes by
// name or base/linkN, the scanner when it has a housing, table, part, obstacles): a sensor's
// carrier must be one of them.
std::vector<std::string> sceneBodyNames(const JobSpec& s) {
  std::vector<std::string> names;
  for (std::size_t k = 0; k < s.robot.links.size() && k <= kinematics::kNumJoints; ++k) {
    const LinkSpec& link = s.robot.links[k];
    if (link.shapes.empty()) continue;
    names.push_back(!link.name.empty() ? link.name
                    : k == 0           ? std::string("base")
                                       : "link" + std::to_string(k));
  }
  if (!s.scanner.body.empty()) names.emplace_back("scanner");
  names.emplace_back("table");
  names.emplace_back("part");
  for (const ObstacleSpec& o : s.obstacles) names.push_back(o.name);
  return names;
}

void checkSensorCarriers(const YamlIn& a, const JobSpec& s) {
  const std::vector<std::string> bodies = sceneBodyNames(s);
  for (std::size_t i = 0; i < s.sensors.size(); ++i) {
    const std::string& carrier = s.sensors[i].carrier;
    if (carrier == "world" || std::find(bodies.begin(), bodies.end(), carrier) != bodies.end()) {
      continue;
    }
    const YamlIn sensor(a.node()["sensors"][i], "sensors[" + std::to_string(i) + "]", a.file(),
                        a.overrides());
    sensor.fail("carrier", "'" + clipForMessage(carrier) + "'",
                fmt::format("world or a body of the cell: {}", fmt::join(bodies, ", ")));
  }
}

template <class A>
void describeJob(A& a, JobSpec& s) {
  a.field("name", s.name);
  a.require("robot");
  if constexpr (A::kReading) {
    const YAML::Node robot = a.node()["robot"];
    if (!robot.IsDefined()) {
      // Missing next to a near miss (robto:): finish() says which.
    } else if (robot.IsScalar()) {
      a.field("robot", s.robot_file);
      s.robot = loadRobotOrUrdf(s.robot_file.resolved);
    } else if (robot.IsMap() && robot["urdf"].IsDefined()) {
      YamlIn urdf_robot(robot, "robot", a.file(), a.overrides());
      s.robot = readUrdfRobot(urdf_robot);
    } else if (robot.IsMap()) {
      YamlIn inline_robot(robot, "robot", a.file(), a.overrides());
      s.robot = readRobot(inline_robot);
    } else {
      a.fail("robot", "a list", "a robot file path or an inline robot mapping");
    }
  } else {
    a.section("robot", s.robot);
  }
  a.section("robot_base", s.robot_base);
  a.section("table", s.table);
  a.require("part");
  a.section("part", s.part);
  a.section("scanner", s.scanner);
  a.list("obstacles", s.obstacles, 0, 10000);
  if constexpr (A::kReading) {
    std::set<std::string> names;
    for (const ObstacleSpec& o : s.obstacles) {
      if (!names.insert(o.name).second) {
        a.fail("obstacles", "two obstacles named '" + o.name + "'", "a unique name per obstacle");
      }
    }
  }
  a.list("sensors", s.sensors, 0, kMaxSensors);
  if constexpr (A::kReading) {
    std::set<std::string> names;
    for (const SensorSpec& sensor : s.sensors) {
      if (!names.insert(sensor.name).second) {
        a.fail("sensors", "two sensors named '" + sensor.name + "'", "a unique name per sensor");
      }
    }
    // sensors.csv heads its columns with the names: t_s, then per presence sensor NAME and
    // NAME_bodies, per distance sensor NAME_mm, NAME_status and NAME_body.
    std::set<std::string> columns{"t_s"};
    for (const SensorSpec& sensor : s.sensors) {
      const bool distance = sensor.kind == "distance";
      for (const char* suffix : distance ? std::vector<const char*>{"_mm", "_status", "_body"}
                                         : std::vector<const char*>{"", "_bodies"}) {
        if (!columns.insert(sensor.name + suffix).second) {
          a.fail("sensors",
                 "sensor '" + sensor.name + "' gives sensors.csv a second column '" + sensor.name +
                     suffix + "'",
                 "names whose columns (t_s; NAME, NAME_bodies; NAME_mm, NAME_status, "
                 "NAME_body) differ");
        }
      }
    }
    if constexpr (std::is_same_v<A, YamlIn>) checkSensorCarriers(a, s);
  }
  a.section("constraints", s.constraints);
  a.section("scan", s.scan);
  a.section("map", s.map);
  a.section("planner", s.planner);
  a.section("validation", s.validation);
  a.section("simulation", s.simulation);
  if constexpr (std::is_same_v<A, YamlIn>) checkImageMode(a, s);
  if constexpr (A::kReading) s.outputs.programs = defaultPrograms(s.robot);
  a.section("outputs", s.outputs);
}

}  // namespace

void describe(SchemaOut& a, JobSpec& s) { describeJob(a, s); }

std::string jobSchema() {
  SchemaOut::Json schema = {
      {"$schema", "http://json-schema.org/draft-07/schema#"},
      {"$id", "https://scanplan.invalid/job.schema.json"},
      {"title", "scanplan job file"},
      {"description",
       "A scanplan job: robot, table, part, scanner, constraints, scan, map, planner, "
       "validation, simulation, outputs. Every key is documented in docs/job-file.md; "
       "scanplan job show prints the defaults."}};
  const JobSpec defaults;
  schema.update(SchemaOut::ofAll(defaults));
  schema["properties"]["robot"] = {
      {"description",
       "a robot file (.yaml, or .urdf with base_link and tip_link) relative to this "
       "file, or an inline robot mapping (docs/robots.md: Robot files)"},
      {"type", {"string", "object"}}};
  return schema.dump(2) + "\n";
}

JobSpec loadJob(const std::filesystem::path& file, const std::vector<std::string>& overrides) {
  JobSpec job;
  // As the user gave it, like every other message about the file.
  job.source = file.lexically_normal();
  YAML::Node root = loadYamlFile(file);
  auto origins = std::make_shared<OverrideOrigins>();
  for (const std::string& o : overrides) applyOverride(root, o, *origins);
  YamlIn in(root, "", file, origins);
  describeJob(in, job);
  in.finish();
  spdlog::debug("job {} ({}): robot {} ({}), part {}", job.name, file.string(), job.robot.name,
                job.robot_file.resolved.empty() ? "inline" : job.robot_file.resolved.string(),
                job.part.mesh.resolved.string());
  for (const std::string& o : overrides) spdlog::debug("job {}: --set {}", job.name, o);
  return job;
}

std::string jobToYaml(const JobSpec& job) {
  JobSpec copy = job;
  YAML::Emitter out;
  out.SetIndent(2);
  out << YAML::Comment(
      fmt::format("scanplan job, fully resolved from {}",
                  std::filesystem::absolute(job.source).lexically_normal().string()));
  out << YAML::BeginMap;
  YamlOut writer(out);
  describeJob(writer, copy);
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

std::string jobHash(const JobSpec& job) {
  JobSpec copy = job;
  YAML::Emitter out;
  out << YAML::BeginMap;
  YamlOut writer(out, true);
  describeJob(writer, copy);
  out << YAML::EndMap;
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a
  for (const char c : std::string(out.c_str())) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ull;
  }
  return fmt::format("{:016x}", h);
}

std::vector<std::filesystem::path> jobInputFiles(const JobSpec& job) {
  std::vector<std::filesystem::path> files{job.source};
  const auto add = [&](const FilePath& f) {
    if (!f.resolved.empty()) files.push_back(f.resolved);
  };
  add(job.robot_file);
  add(job.part.mesh);
  for (const LinkSpec& link : job.robot.links) {
    for (const ShapeSpec& shape : link.shapes) add(shape.file);
  }
  for (const ShapeSpec& shape : job.scanner.body) add(shape.file);
  for (const ObstacleSpec& obstacle : job.obstacles) add(obstacle.shape.file);
  for (const PathElementSpec& path : job.scan.paths) add(path.file);
  return files;
}

}  // namespace scanplan::config
