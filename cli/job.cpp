#include "cli/job.h"

#include <fmt/format.h>

#include "kinematics/error.h"
#include "kinematics/units.h"

namespace scanplan::cli {
namespace {

template <class A>
void describeTable(A& a, TableSpec& s) {
  a.section("axis", s.axis);
  a.field("radius_mm", s.radius_mm, Expect::positive());
  a.field("height_mm", s.height_mm, Expect::positive());
  a.field("continuous", s.continuous);
  a.field("min_deg", s.min_deg, Expect::range(-3600.0, 3600.0));
  a.field("max_deg", s.max_deg, Expect::range(-3600.0, 3600.0));
  a.field("max_speed_deg_s", s.max_speed_deg_s, Expect::positive());
  a.field("max_accel_deg_s2", s.max_accel_deg_s2, Expect::positive());
  a.field("eccentricity_mm", s.eccentricity_mm);
  a.field("tilt_deg", s.tilt_deg, Expect::range(-10.0, 10.0));
  if constexpr (A::kReading) {
    if (!(s.min_deg < s.max_deg)) {
      a.fail("max_deg", formatNumber(s.max_deg),
             fmt::format("a limit greater than min_deg ({})", formatNumber(s.min_deg)));
    }
  }
}

template <class A>
void describePart(A& a, PartSpec& s) {
  a.require("mesh");
  a.field("mesh", s.mesh);
  a.field("units", s.units, Expect::oneOf(kLengthUnits));
  a.field("scale", s.scale, Expect::positive());
  a.section("pose", s.pose);
}

template <class A>
void describeScanner(A& a, ScannerSpec& s) {
  a.section("mount", s.mount);
  a.list("body", s.body, 0, 64);
}

template <class A>
void describeJob(A& a, JobSpec& s) {
  a.field("name", s.name);
  a.require("robot");
  if constexpr (A::kReading) {
    const YAML::Node robot = a.node()["robot"];
    if (robot.IsScalar()) {
      a.field("robot", s.robot_file);
      s.robot = loadRobotFile(s.robot_file.resolved);
    } else if (robot.IsMap()) {
      YamlIn inline_robot(robot, "robot", a.file());
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
}

}  // namespace

void describe(YamlIn& a, TableSpec& s) { describeTable(a, s); }
void describe(YamlOut& a, TableSpec& s) { describeTable(a, s); }
void describe(YamlIn& a, PartSpec& s) { describePart(a, s); }
void describe(YamlOut& a, PartSpec& s) { describePart(a, s); }
void describe(YamlIn& a, ScannerSpec& s) { describeScanner(a, s); }
void describe(YamlOut& a, ScannerSpec& s) { describeScanner(a, s); }

JobSpec loadJob(const std::filesystem::path& file) {
  JobSpec job;
  job.source = std::filesystem::absolute(file).lexically_normal();
  YamlIn in(loadYamlFile(file), "", file);
  describeJob(in, job);
  in.finish();
  return job;
}

std::string jobToYaml(const JobSpec& job) {
  JobSpec copy = job;
  YAML::Emitter out;
  out.SetIndent(2);
  out << YAML::Comment(fmt::format("scanplan job, fully resolved from {}", job.source.string()));
  out << YAML::BeginMap;
  YamlOut writer(out);
  describeJob(writer, copy);
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

kinematics::CellModel buildCell(const JobSpec& job) {
  const std::string robot_source =
      job.robot_file.resolved.empty() ? job.source.string() : job.robot_file.resolved.string();
  kinematics::CellModel cell(job.name, buildRobotModel(job.robot, robot_source));
  cell.X_WB = toIsometry(job.robot_base);

  const TableSpec& t = job.table;
  cell.table.X_WA = toIsometry(t.axis);
  cell.table.eccentricity = Eigen::Vector2d(t.eccentricity_mm[0], t.eccentricity_mm[1]) * kMmToM;
  cell.table.tilt = Eigen::Vector2d(t.tilt_deg[0], t.tilt_deg[1]) * kDegToRad;
  cell.table.radius = mm(t.radius_mm);
  cell.table.height = mm(t.height_mm);
  cell.table.continuous = t.continuous;
  cell.table.min = deg(t.min_deg);
  cell.table.max = deg(t.max_deg);
  cell.table.max_speed = deg(t.max_speed_deg_s);
  cell.table.max_accel = deg(t.max_accel_deg_s2);

  cell.part.mesh = {job.part.mesh.resolved, {toLengthUnit(job.part.units), job.part.scale}};
  cell.part.X_RP = toIsometry(job.part.pose);

  cell.scanner.X_FS = toIsometry(job.scanner.mount);
  for (const ShapeSpec& shape : job.scanner.body) cell.scanner.body.push_back(toShape(shape));
  return cell;
}

}  // namespace scanplan::cli
