#include <scanplan/config/robot_file.h>

#include <algorithm>
#include <cctype>
#include <sstream>

#include <fmt/format.h>

#include <scanplan/config/detail/describe.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/units.h>

namespace scanplan::config {
namespace {

template <class A>
void describeJoint(A& a, JointSpec& s) {
  a.require("a_mm");
  a.require("d_mm");
  a.require("alpha_deg");
  a.require("min_deg");
  a.require("max_deg");
  a.require("max_speed_deg_s");
  a.field("a_mm", s.a_mm);
  a.field("d_mm", s.d_mm);
  a.field("alpha_deg", s.alpha_deg, Expect::range(-360.0, 360.0));
  a.field("theta_offset_deg", s.theta_offset_deg, Expect::range(-360.0, 360.0));
  a.field("direction", s.direction, Expect::range(-1.0, 1.0));
  a.field("min_deg", s.min_deg, Expect::range(-720.0, 720.0));
  a.field("max_deg", s.max_deg, Expect::range(-720.0, 720.0));
  a.field("max_speed_deg_s", s.max_speed_deg_s, Expect::positive());
  if constexpr (A::kReading) {
    if (s.direction == 0) a.fail("direction", "0", "1 or -1");
    if (!(s.min_deg < s.max_deg)) {
      a.fail("max_deg", formatNumber(s.max_deg),
             fmt::format("a limit greater than min_deg ({})", formatNumber(s.min_deg)));
    }
  }
}

template <class A>
void describeOpw(A& a, OpwSpec& s) {
  for (const char* k : {"a1_mm", "a2_mm", "b_mm", "c1_mm", "c2_mm", "c3_mm", "c4_mm"}) {
    a.require(k);
  }
  a.field("a1_mm", s.a1_mm);
  a.field("a2_mm", s.a2_mm);
  a.field("b_mm", s.b_mm);
  a.field("c1_mm", s.c1_mm);
  a.field("c2_mm", s.c2_mm, Expect::positive());
  a.field("c3_mm", s.c3_mm);
  a.field("c4_mm", s.c4_mm);
  a.field("offsets_deg", s.offsets_deg, Expect::range(-360.0, 360.0));
  a.field("signs", s.signs, Expect::range(-1.0, 1.0));
  if constexpr (A::kReading) {
    for (std::size_t i = 0; i < s.signs.size(); ++i) {
      if (s.signs[i] == 0) a.fail("signs", fmt::format("signs[{}] = 0", i), "each sign 1 or -1");
    }
  }
}

template <class A>
void describeLink(A& a, LinkSpec& s) {
  a.require("name");
  a.field("name", s.name);
  a.list("shapes", s.shapes, 0, 64);
}

// Every name in allowed_collisions is one of the robot's links (base, link1 … link6, or the
// names its links: give).
template <class A>
void checkAllowedCollisions(A& a, const RobotSpec& s) {
  std::vector<std::string> names;
  for (std::size_t k = 0; k < 7; ++k) {
    const std::string fallback = k == 0 ? "base" : "link" + std::to_string(k);
    names.push_back(k < s.links.size() && !s.links[k].name.empty() ? s.links[k].name : fallback);
  }
  for (const auto& pair : s.allowed_collisions) {
    for (const std::string& name : pair) {
      if (std::find(names.begin(), names.end(), name) == names.end()) {
        a.fail("allowed_collisions", fmt::format("'{}'", name),
               fmt::format("a link of this robot: {}", fmt::join(names, ", ")));
      }
    }
  }
}

template <class A>
void describeRobot(A& a, RobotSpec& s) {
  a.require("name");
  a.require("dh");
  a.require("opw");
  a.field("name", s.name);
  a.field("controller", s.controller, Expect::oneOf(kControllers));
  a.list("dh", s.dh, 6, 6);
  a.section("opw", s.opw);
  a.list("links", s.links, 0, 7);
  if constexpr (A::kReading) {
    if (!s.links.empty() && s.links.size() != 7) {
      a.fail("links", fmt::format("a list of {}", s.links.size()),
             "7 links (base, then link 1 … link 6) or none");
    }
  }
  if (A::kReading || !s.allowed_collisions.empty()) {
    a.field("allowed_collisions", s.allowed_collisions);
  }
  if constexpr (A::kReading) checkAllowedCollisions(a, s);
}

}  // namespace

void describe(YamlIn& a, JointSpec& s) { describeJoint(a, s); }
void describe(YamlOut& a, JointSpec& s) { describeJoint(a, s); }
void describe(YamlIn& a, OpwSpec& s) { describeOpw(a, s); }
void describe(YamlOut& a, OpwSpec& s) { describeOpw(a, s); }
void describe(YamlIn& a, LinkSpec& s) { describeLink(a, s); }
void describe(YamlOut& a, LinkSpec& s) { describeLink(a, s); }
void describe(YamlIn& a, RobotSpec& s) { describeRobot(a, s); }
void describe(YamlOut& a, RobotSpec& s) { describeRobot(a, s); }

std::string controllerProgramFormat(const std::string& controller) {
  if (controller == "adept_vplus") return "vplus";
  if (controller == "kuka_krl") return "krl";
  if (controller == "abb_rapid") return "rapid";
  if (controller == "ur_script") return "urscript";
  return "";
}

std::vector<std::string> defaultPrograms(const RobotSpec& robot) {
  const std::string own = controllerProgramFormat(robot.controller);
  if (own.empty()) return {"csv"};
  return {own, "csv"};
}

std::vector<std::string> foreignPrograms(const RobotSpec& robot,
                                         const std::vector<std::string>& formats) {
  const std::string own = controllerProgramFormat(robot.controller);
  std::vector<std::string> foreign;
  if (own.empty()) return foreign;
  for (const std::string& f : formats) {
    std::string name = f;
    for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (name != own && name != "csv") foreign.push_back(f);
  }
  return foreign;
}

RobotSpec readRobot(YamlIn& in) {
  RobotSpec spec;
  describe(in, spec);
  in.finish();
  return spec;
}

RobotSpec loadRobotFile(const std::filesystem::path& file) {
  YamlIn in(loadYamlFile(file), "", file);
  return readRobot(in);
}

namespace {

std::string robotYamlText(const RobotSpec& spec, bool paths_as_written) {
  RobotSpec copy = spec;
  YAML::Emitter out;
  out.SetIndent(2);
  out << YAML::BeginMap;
  YamlOut writer(out, paths_as_written);
  describe(writer, copy);
  out << YAML::EndMap;
  return out.c_str();
}

}  // namespace

std::string robotToYaml(const RobotSpec& spec, const std::string& header) {
  std::string text;
  std::istringstream lines(header);
  for (std::string line; std::getline(lines, line);) text += "# " + line + "\n";
  return text + robotYamlText(spec, true) + "\n";
}

void checkAsRobotFile(const RobotSpec& spec, const std::string& source) {
  try {
    YamlIn in(YAML::Load(robotYamlText(spec, false)), "", "imported robot file");
    readRobot(in);
  } catch (const InputError& e) {
    throw InputError(
        fmt::format("{}: the robot it describes is not a valid robot file: {}", source, e.what()));
  }
}

kinematics::RobotModel buildRobotModel(const RobotSpec& spec, const std::string& source) {
  kinematics::RobotDefinition def;
  def.name = spec.name;
  for (std::size_t i = 0; i < kinematics::kNumJoints; ++i) {
    const JointSpec& j = spec.dh[i];
    def.joints[i] = {mm(j.a_mm),  mm(j.d_mm),     deg(j.alpha_deg), deg(j.theta_offset_deg),
                     j.direction, deg(j.min_deg), deg(j.max_deg),   deg(j.max_speed_deg_s)};
  }
  const OpwSpec& o = spec.opw;
  def.opw = {mm(o.a1_mm), mm(o.a2_mm), mm(o.b_mm), mm(o.c1_mm), mm(o.c2_mm),
             mm(o.c3_mm), mm(o.c4_mm), {},         o.signs};
  for (std::size_t i = 0; i < 6; ++i) def.opw.offsets[i] = deg(o.offsets_deg[i]);
  for (std::size_t i = 0; i < spec.links.size(); ++i) {
    def.links[i].name = spec.links[i].name;
    for (const ShapeSpec& shape : spec.links[i].shapes)
      def.links[i].shapes.push_back(toShape(shape));
  }
  def.allowed_collisions = spec.allowed_collisions;
  try {
    return kinematics::RobotModel(std::move(def));
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: robot '{}': {}", source, spec.name, e.what()));
  }
}

}  // namespace scanplan::config
