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

inline const std::vector<std::string> kCarriers = {"world", "table"};

template <class A>
void describeObstacle(A& a, ObstacleSpec& s) {
  a.require("name");
  a.field("name", s.name);
  a.field("carrier", s.carrier, Expect::oneOf(kCarriers));
  if constexpr (A::kReading) s.by_corner = a.has("corner_mm");
  if (!s.by_corner) {
    describe(a, s.shape);
    return;
  }
  // Corner + size, as workcell tools write boxes: sizes may be negative (normalised later).
  a.require("type");
  a.require("size_mm");
  a.field("type", s.shape.type, Expect::oneOf({"box"}));
  a.field("corner_mm", s.corner_mm);
  a.field("size_mm", s.shape.size_mm);
  if constexpr (A::kReading) {
    for (double v : s.shape.size_mm) {
      if (v == 0.0) a.fail("size_mm", "a zero side", "non-zero sides (negative ones extend from the corner the other way)");
    }
    if (a.has("pose")) a.fail("pose", "given with corner_mm", "either corner_mm + size_mm or a centred box with pose");
  }
}

template <class A>
void describeRamp(A& a, RampSpec& s) {
  a.field("low", s.low, Expect::range(0.0, 1.0));
  a.field("high", s.high, Expect::range(0.0, 1.0));
  a.field("gamma", s.gamma, Expect::positive());
  if constexpr (A::kReading) {
    if (!(s.low < s.high)) a.fail("high", formatNumber(s.high), "a value above low (" + formatNumber(s.low) + ")");
  }
}

template <class A>
void describeLengthRamp(A& a, LengthRampSpec& s) {
  a.field("low_mm", s.low_mm, Expect::nonNegative());
  a.field("high_mm", s.high_mm, Expect::positive());
  a.field("gamma", s.gamma, Expect::positive());
  if constexpr (A::kReading) {
    if (!(s.low_mm < s.high_mm)) a.fail("high_mm", formatNumber(s.high_mm), "a value above low_mm (" + formatNumber(s.low_mm) + ")");
  }
}

template <class A>
void describePairRule(A& a, PairRuleSpec& s) {
  a.require("a");
  a.require("b");
  a.field("a", s.a);
  a.field("b", s.b);
  a.field("exclude", s.exclude);
  a.field("include", s.include);
  if constexpr (A::kReading) {
    if (s.exclude && s.include) a.fail("include", "true together with exclude", "at most one of exclude, include");
  }
  if (!A::kReading && s.d_low_mm < 0.0 && s.d_high_mm < 0.0 && s.gamma < 0.0) return;
  if (A::kReading || s.d_low_mm >= 0.0) a.field("d_low_mm", s.d_low_mm, Expect::nonNegative());
  if (A::kReading || s.d_high_mm >= 0.0) a.field("d_high_mm", s.d_high_mm, Expect::positive());
  if (A::kReading || s.gamma >= 0.0) a.field("gamma", s.gamma, Expect::positive());
}

template <class A>
void describeClearance(A& a, ClearanceSpec& s) {
  a.field("d_low_mm", s.d_low_mm, Expect::nonNegative());
  a.field("d_high_mm", s.d_high_mm, Expect::positive());
  a.field("gamma", s.gamma, Expect::positive());
  a.list("pairs", s.pairs, 0, 1000);
  if constexpr (A::kReading) {
    if (!(s.d_low_mm < s.d_high_mm)) {
      a.fail("d_high_mm", formatNumber(s.d_high_mm), "a distance above d_low_mm (" + formatNumber(s.d_low_mm) + ")");
    }
  }
}

template <class A>
void describeConstraints(A& a, ConstraintsSpec& s) {
  a.field("joint_limit_gamma", s.joint_limit_gamma, Expect::positive());
  a.section("wrist", s.wrist);
  a.section("elbow", s.elbow);
  a.section("shoulder", s.shoulder);
  a.section("clearance", s.clearance);
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
  a.list("obstacles", s.obstacles, 0, 10000);
  a.section("constraints", s.constraints);
}

}  // namespace

void describe(YamlIn& a, TableSpec& s) { describeTable(a, s); }
void describe(YamlOut& a, TableSpec& s) { describeTable(a, s); }
void describe(YamlIn& a, PartSpec& s) { describePart(a, s); }
void describe(YamlOut& a, PartSpec& s) { describePart(a, s); }
void describe(YamlIn& a, ScannerSpec& s) { describeScanner(a, s); }
void describe(YamlOut& a, ScannerSpec& s) { describeScanner(a, s); }
void describe(YamlIn& a, ObstacleSpec& s) { describeObstacle(a, s); }
void describe(YamlOut& a, ObstacleSpec& s) { describeObstacle(a, s); }
void describe(YamlIn& a, RampSpec& s) { describeRamp(a, s); }
void describe(YamlOut& a, RampSpec& s) { describeRamp(a, s); }
void describe(YamlIn& a, LengthRampSpec& s) { describeLengthRamp(a, s); }
void describe(YamlOut& a, LengthRampSpec& s) { describeLengthRamp(a, s); }
void describe(YamlIn& a, PairRuleSpec& s) { describePairRule(a, s); }
void describe(YamlOut& a, PairRuleSpec& s) { describePairRule(a, s); }
void describe(YamlIn& a, ClearanceSpec& s) { describeClearance(a, s); }
void describe(YamlOut& a, ClearanceSpec& s) { describeClearance(a, s); }
void describe(YamlIn& a, ConstraintsSpec& s) { describeConstraints(a, s); }
void describe(YamlOut& a, ConstraintsSpec& s) { describeConstraints(a, s); }

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

  for (const ObstacleSpec& o : job.obstacles) {
    kinematics::Obstacle obstacle;
    obstacle.name = o.name;
    obstacle.carrier = o.carrier == "table" ? kinematics::Carrier::kTable : kinematics::Carrier::kWorld;
    if (o.by_corner) {
      const Eigen::Vector3d corner = Eigen::Vector3d(o.corner_mm.data()) * kMmToM;
      const Eigen::Vector3d size = Eigen::Vector3d(o.shape.size_mm.data()) * kMmToM;
      kinematics::Shape box;
      box.geometry = kinematics::Box{size.cwiseAbs()};
      box.X_BG.translation() = corner + 0.5 * size;  // the centre, whichever way sizes point
      obstacle.shapes.push_back(box);
    } else {
      obstacle.shapes.push_back(toShape(o.shape));
    }
    cell.obstacles.push_back(std::move(obstacle));
  }
  return cell;
}

collision::ClearanceConfig clearanceConfig(const JobSpec& job) {
  const ClearanceSpec& c = job.constraints.clearance;
  collision::ClearanceConfig config;
  config.defaults = {mm(c.d_low_mm), mm(c.d_high_mm), c.gamma};
  for (const PairRuleSpec& r : c.pairs) {
    collision::PairRule rule;
    rule.a = r.a;
    rule.b = r.b;
    rule.action = r.exclude   ? collision::PairRule::Action::kExclude
                  : r.include ? collision::PairRule::Action::kInclude
                              : collision::PairRule::Action::kSet;
    rule.d_low = r.d_low_mm >= 0.0 ? mm(r.d_low_mm) : -1.0;
    rule.d_high = r.d_high_mm >= 0.0 ? mm(r.d_high_mm) : -1.0;
    rule.gamma = r.gamma > 0.0 ? r.gamma : -1.0;
    config.rules.push_back(rule);
  }
  return config;
}

planner::ConstraintSettings constraintSettings(const JobSpec& job) {
  const ConstraintsSpec& c = job.constraints;
  planner::ConstraintSettings s;
  s.joint_gamma = c.joint_limit_gamma;
  s.wrist = {c.wrist.low, c.wrist.high, c.wrist.gamma};
  s.elbow = {c.elbow.low, c.elbow.high, c.elbow.gamma};
  s.shoulder = {mm(c.shoulder.low_mm), mm(c.shoulder.high_mm), c.shoulder.gamma};
  return s;
}

}  // namespace scanplan::cli
