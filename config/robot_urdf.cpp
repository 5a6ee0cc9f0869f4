#include <scanplan/config/robot_urdf.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <mutex>
#include <numbers>
#include <sstream>
#include <string_view>

#include <console_bridge/console.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <urdf_parser/urdf_parser.h>

#include <scanplan/config/detail/describe.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/serial_chain.h>
#include <scanplan/kinematics/units.h>

namespace scanplan::config {
namespace {

using kinematics::kNumJoints;
namespace fs = std::filesystem;

// A URDF is a few hundred kB at most; a bigger file is not one (and urdfdom reads it whole).
constexpr std::uintmax_t kMaxUrdfBytes = 64u << 20;
// An opw_kinematics file's values that differ from the chain's by no more than this are the
// chain's, written with fewer digits (ROS-I files give offsets like -1.5707963).
constexpr double kOpwRoundingTol = 1e-6;  // m and rad

// urdfdom says why a file does not parse through console_bridge: collected for the error.
class CollectedLog : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) lines.push_back(text);
  }
  std::vector<std::string> lines;
};

std::string readUrdfText(const fs::path& file) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) {
    throw InputError(
        fmt::format("{}: {}: expected a URDF file", file.string(),
                    fs::exists(file, ec) ? "is not a regular file" : "does not exist"));
  }
  if (fs::file_size(file, ec) > kMaxUrdfBytes) {
    throw InputError(fmt::format("{}: {} bytes: expected a URDF file of at most {} bytes",
                                 file.string(), fs::file_size(file, ec), kMaxUrdfBytes));
  }
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) throw InputError(fmt::format("{}: cannot be read", file.string()));
  return text.str();
}

// A link's parent joint, and the link that joint hangs it from.
struct ParentJoint {
  std::string joint;
  std::string link;
};

// Following parents up from every link must end at the root. A loop of links each the child of
// one joint (disconnected from the root, so urdfdom still finds one) never ends: refused naming
// the link that is its own ancestor and the joints of the loop. Each link is walked up once.
void requireNoLoop(const std::map<std::string, ParentJoint>& parent, const fs::path& file) {
  std::map<std::string, std::pair<std::size_t, std::size_t>> reached;  // link → walk, step
  std::size_t walk = 0;
  for (const auto& [start, unused] : parent) {
    ++walk;
    std::vector<std::string> joints;  // the joints this walk went up through
    for (std::string link = start;;) {
      const auto [it, fresh] = reached.emplace(link, std::pair{walk, joints.size()});
      if (!fresh && it->second.first != walk) break;  // an earlier walk went on from here
      if (!fresh) {
        const auto loop = joints.begin() + static_cast<std::ptrdiff_t>(it->second.second);
        throw InputError(fmt::format(
            "{}: link '{}' is its own ancestor: the joints '{}' lead from it back to it (a "
            "closed chain): expected a tree of links (URDF has no closed chains)",
            file.string(), link,
            clipForMessage(fmt::format("{}", fmt::join(loop, joints.end(), "', '")), 300)));
      }
      const auto up = parent.find(link);
      if (up == parent.end()) break;  // the root
      joints.push_back(up->second.joint);
      link = up->second.link;
    }
  }
}

// A URDF is a tree: each link the child of one joint at most, none its own parent or ancestor.
// urdfdom keeps the last of two joints naming one child, which can close a loop its walks never
// leave.
void requireTree(const urdf::ModelInterface& model, const fs::path& file) {
  std::map<std::string, ParentJoint> parent;  // child link → the joint naming it
  for (const auto& [name, joint] : model.joints_) {
    if (!joint) continue;
    if (joint->parent_link_name == joint->child_link_name) {
      throw InputError(
          fmt::format("{}: joint '{}': link '{}' is its own parent: expected a tree "
                      "of links (URDF has no closed chains)",
                      file.string(), name, joint->child_link_name));
    }
    const auto [it, first] =
        parent.emplace(joint->child_link_name, ParentJoint{name, joint->parent_link_name});
    if (!first) {
      throw InputError(fmt::format(
          "{}: link '{}' is the child of two joints, '{}' and '{}': expected a tree of links "
          "(a closed chain is not a URDF scanplan can model)",
          file.string(), joint->child_link_name, it->second.joint, name));
    }
  }
  requireNoLoop(parent, file);
}

// A document type declaration (entities, an external DTD): URDF uses none, and urdfdom's XML
// reader would not expand it but report the robot element missing.
void refuseDoctype(const std::string& text, const fs::path& file) {
  const auto at = text.find("<!DOCTYPE");
  if (at == std::string::npos) return;
  const auto line =
      1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n');
  throw InputError(fmt::format(
      "{}:{}: a <!DOCTYPE> declaration{}: URDF uses none and scanplan does not expand entities; "
      "expected plain URDF XML",
      file.string(), line, text.find("<!ENTITY", at) != std::string::npos ? " with entities" : ""));
}

urdf::ModelInterfaceSharedPtr parseUrdf(const fs::path& file) {
  const std::string text = readUrdfText(file);
  refuseDoctype(text, file);
  static std::mutex mutex;  // console_bridge's output handler is global
  const std::lock_guard lock(mutex);
  CollectedLog log;
  console_bridge::useOutputHandler(&log);
  urdf::ModelInterfaceSharedPtr model;
  try {
    model = urdf::parseURDF(text);
  } catch (const std::exception& e) {
    log.lines.push_back(e.what());
  }
  console_bridge::restorePreviousOutputHandler();
  if (!model) {
    throw InputError(fmt::format(
        "{}: not a valid URDF: {}", file.string(),
        log.lines.empty() ? "urdfdom could not parse it"
                          : clipForMessage(fmt::format("{}", fmt::join(log.lines, "; ")), 400)));
  }
  requireTree(*model, file);
  return model;
}

Eigen::Isometry3d toIsometry(const urdf::Pose& pose) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() << pose.position.x, pose.position.y, pose.position.z;
  const urdf::Rotation& r = pose.rotation;
  X.linear() = Eigen::Quaterniond(r.w, r.x, r.y, r.z).normalized().toRotationMatrix();
  return X;
}

// A pose of the file: finite (urdfdom reads "nan" as a number), else InputError naming `what`.
Eigen::Isometry3d toIsometry(const urdf::Pose& pose,
                             const fs::path& file,
                             const std::string& what) {
  const urdf::Vector3& p = pose.position;
  const urdf::Rotation& r = pose.rotation;
  for (double v : {p.x, p.y, p.z, r.x, r.y, r.z, r.w}) {
    if (!std::isfinite(v)) {
      throw InputError(
          fmt::format("{}: {} <origin>: xyz ({} {} {}), quaternion ({} {} {} {}): "
                      "expected finite numbers",
                      file.string(), what, p.x, p.y, p.z, r.x, r.y, r.z, r.w));
    }
  }
  return toIsometry(pose);
}

std::string linkList(const urdf::ModelInterface& model) {
  std::vector<std::string> names;
  for (const auto& [name, link] : model.links_) names.push_back(name);
  return clipForMessage(fmt::format("{}", fmt::join(names, ", ")), 300);
}

urdf::LinkConstSharedPtr findLink(const urdf::ModelInterface& model,
                                  const std::string& name,
                                  const char* key,
                                  const fs::path& file) {
  urdf::LinkConstSharedPtr link = model.getLink(name);
  if (!link) {
    throw InputError(fmt::format("{}: {} '{}': no such link; the URDF's links: {}", file.string(),
                                 key, name, linkList(model)));
  }
  return link;
}

// The joints from base_link down to tip_link, in order.
std::vector<urdf::JointConstSharedPtr> chainPath(const urdf::ModelInterface& model,
                                                 const UrdfRobotSource& source) {
  const auto base = findLink(model, source.base_link, "base_link", source.urdf);
  auto link = findLink(model, source.tip_link, "tip_link", source.urdf);
  std::vector<urdf::JointConstSharedPtr> path;
  while (link != base) {
    if (!link->parent_joint) {
      throw InputError(fmt::format(
          "{}: tip_link '{}' is not below base_link '{}' (its parents end at the root link '{}'); "
          "expected a tip_link that base_link carries",
          source.urdf.string(), source.tip_link, source.base_link, link->name));
    }
    if (link->parent_joint->mimic) {
      throw InputError(fmt::format(
          "{}: joint '{}' has <mimic joint=\"{}\">: it follows another joint, which scanplan's "
          "chain of independent joints does not model; expected no <mimic> between base_link "
          "'{}' and tip_link '{}'",
          source.urdf.string(), link->parent_joint->name, link->parent_joint->mimic->joint_name,
          source.base_link, source.tip_link));
    }
    path.push_back(link->parent_joint);
    link = model.getLink(link->parent_joint->parent_link_name);
    if (path.size() > model.joints_.size()) {
      throw InputError(
          fmt::format("{}: the links above tip_link '{}' form a loop: expected a "
                      "tree of links",
                      source.urdf.string(), source.tip_link));
    }
  }
  std::reverse(path.begin(), path.end());
  return path;
}

const char* jointTypeName(int type) {
  if (type == urdf::Joint::PRISMATIC) return "prismatic";
  if (type == urdf::Joint::FLOATING) return "floating";
  return type == urdf::Joint::PLANAR ? "planar" : "of unknown type";
}

void setLimits(kinematics::ChainJoint& c, const urdf::Joint& j, const fs::path& file) {
  if (!j.limits || !(j.limits->velocity > 0.0) || !std::isfinite(j.limits->velocity)) {
    throw InputError(
        fmt::format("{}: joint '{}': <limit velocity=\"{}\">: expected a velocity "
                    "limit > 0 rad/s",
                    file.string(), j.name, j.limits ? j.limits->velocity : 0.0));
  }
  c.max_speed = j.limits->velocity;
  if (j.type == urdf::Joint::CONTINUOUS) {
    c.min = -2.0 * std::numbers::pi;  // a turn either way: scanplan's joints have end stops
    c.max = 2.0 * std::numbers::pi;
    return;
  }
  c.min = j.limits->lower;
  c.max = j.limits->upper;
  if (!(c.min < c.max) || c.min < -4.0 * std::numbers::pi || c.max > 4.0 * std::numbers::pi) {
    throw InputError(
        fmt::format("{}: joint '{}': <limit lower=\"{}\" upper=\"{}\">: expected "
                    "lower < upper, within ±4π rad",
                    file.string(), j.name, c.min, c.max));
  }
}

kinematics::SerialChain serialChain(const std::vector<urdf::JointConstSharedPtr>& path,
                                    const UrdfRobotSource& source) {
  kinematics::SerialChain chain;
  std::vector<std::string> revolute;
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  for (const auto& j : path) {
    X = X * toIsometry(j->parent_to_joint_origin_transform, source.urdf,
                       fmt::format("joint '{}'", j->name));
    if (j->type == urdf::Joint::FIXED) continue;
    if (j->type != urdf::Joint::REVOLUTE && j->type != urdf::Joint::CONTINUOUS) {
      throw InputError(
          fmt::format("{}: joint '{}' is {}: expected revolute, continuous or fixed joints between "
                      "base_link '{}' and tip_link '{}'",
                      source.urdf.string(), j->name, jointTypeName(j->type), source.base_link,
                      source.tip_link));
    }
    revolute.push_back(j->name);
    if (revolute.size() > kNumJoints) continue;
    kinematics::ChainJoint& c = chain.joints[revolute.size() - 1];
    c.name = j->name;
    c.X_prev = X;
    c.axis = Eigen::Vector3d(j->axis.x, j->axis.y, j->axis.z);
    setLimits(c, *j, source.urdf);
    X = Eigen::Isometry3d::Identity();
  }
  if (revolute.size() != kNumJoints) {
    throw InputError(fmt::format(
        "{}: {} revolute joints between base_link '{}' and tip_link '{}' ({}): expected 6 (a "
        "6-axis arm)",
        source.urdf.string(), revolute.size(), source.base_link, source.tip_link,
        revolute.empty() ? "none" : fmt::format("{}", fmt::join(revolute, ", "))));
  }
  chain.X_J6T = X;
  return chain;
}

// Numbers as a robot file writes them: the derivation's rounding (1e-9 mm or degree) removed.
double clean(double v) { return std::round(v * 1e9) / 1e9 + 0.0; }

JointSpec toJointSpec(const kinematics::DhJoint& j) {
  return {
      clean(toMm(j.a)), clean(toMm(j.d)),    clean(toDeg(j.alpha)), clean(toDeg(j.theta_offset)),
      j.direction,      clean(toDeg(j.min)), clean(toDeg(j.max)),   clean(toDeg(j.max_speed))};
}

OpwSpec toOpwSpec(const kinematics::OpwParameters& p) {
  OpwSpec s{clean(toMm(p.a1)),
            clean(toMm(p.a2)),
            clean(toMm(p.b)),
            clean(toMm(p.c1)),
            clean(toMm(p.c2)),
            clean(toMm(p.c3)),
            clean(toMm(p.c4)),
            {},
            p.signs};
  for (std::size_t i = 0; i < kNumJoints; ++i) s.offsets_deg[i] = clean(toDeg(p.offsets[i]));
  return s;
}

PoseSpec cleanPose(const Eigen::Isometry3d& X) {
  PoseSpec p = toPoseSpec(X);
  for (double& v : p.xyz_mm) v = clean(v);
  for (double& v : p.rpy_deg) v = clean(v);
  return p;
}

// `package://PACKAGE/PATH` names a file inside the package. A PATH whose normal form climbs out
// of it ('..' past the package folder, or an absolute path), or no package name, would take
// whatever lies beside the folder the search finds, and write it into the robot file.
void requireInsidePackage(const std::string& uri,
                          const std::string& package,
                          const std::string& inside) {
  if (package.empty() || package == "." || package == "..") {
    throw InputError(fmt::format(
        "mesh '{}': package name '{}': expected package://PACKAGE/PATH naming a package folder",
        clipForMessage(uri), clipForMessage(package)));
  }
  const fs::path normal = fs::path(inside).lexically_normal();
  if (fs::path(inside).has_root_path() || (!normal.empty() && *normal.begin() == "..")) {
    throw InputError(fmt::format(
        "mesh '{}': the path '{}' leaves package '{}' (normalised: '{}'): expected a file "
        "inside the package (a mesh elsewhere: package:// of its own package, or a path "
        "relative to the URDF)",
        clipForMessage(uri, 300), clipForMessage(inside, 300), clipForMessage(package),
        clipForMessage(normal.generic_string(), 300)));
  }
}

// Where a shape of a URDF link comes from, for its error messages and mesh paths.
struct GeometryContext {
  const UrdfRobotSource& source;
  const std::vector<fs::path>& search;
  std::string link;
};

void requirePositive(const GeometryContext& c, const char* what, double v) {
  if (v > 0.0 && std::isfinite(v)) return;
  throw InputError(fmt::format("{}: link '{}' <collision>: {} {}: expected a finite number > 0 m",
                               c.source.urdf.string(), c.link, what, v));
}

ShapeSpec meshShape(const GeometryContext& c, const urdf::Mesh& mesh) {
  ShapeSpec s;
  s.type = "mesh";
  s.units = "m";  // URDF is SI: a mesh's numbers are metres, times its scale
  s.file.as_written = mesh.filename;
  try {
    s.file.resolved = resolveUrdfUri(mesh.filename, c.source.urdf.parent_path(), c.search);
  } catch (const InputError& e) {
    throw InputError(
        fmt::format("{}: link '{}' <collision>: {}", c.source.urdf.string(), c.link, e.what()));
  }
  const urdf::Vector3& k = mesh.scale;
  if (!(k.x > 0.0) || !std::isfinite(k.x) || std::abs(k.y - k.x) > 1e-12 * k.x ||
      std::abs(k.z - k.x) > 1e-12 * k.x) {
    throw InputError(
        fmt::format("{}: link '{}' <collision> mesh '{}': scale \"{} {} {}\": "
                    "expected the same scale > 0 on every axis",
                    c.source.urdf.string(), c.link, mesh.filename, k.x, k.y, k.z));
  }
  s.scale = k.x;
  return s;
}

// One <collision> element as a robot file's shape, in the frame X_DL puts the link in.
ShapeSpec shapeSpec(const GeometryContext& c,
                    const urdf::Collision& collision,
                    const Eigen::Isometry3d& X_DL) {
  ShapeSpec s;
  const urdf::Geometry& g = *collision.geometry;
  if (g.type == urdf::Geometry::SPHERE) {
    const double radius = dynamic_cast<const urdf::Sphere&>(g).radius;
    requirePositive(c, "sphere radius", radius);
    s.type = "sphere";
    s.radius_mm = toMm(radius);
  } else if (g.type == urdf::Geometry::BOX) {
    const urdf::Vector3& d = dynamic_cast<const urdf::Box&>(g).dim;
    for (double v : {d.x, d.y, d.z}) requirePositive(c, "box size", v);
    s.type = "box";
    s.size_mm = {toMm(d.x), toMm(d.y), toMm(d.z)};
  } else if (g.type == urdf::Geometry::CYLINDER) {
    const auto& cylinder = dynamic_cast<const urdf::Cylinder&>(g);
    requirePositive(c, "cylinder radius", cylinder.radius);
    requirePositive(c, "cylinder length", cylinder.length);
    s.type = "cylinder";
    s.radius_mm = toMm(cylinder.radius);
    s.length_mm = toMm(cylinder.length);
  } else {
    s = meshShape(c, dynamic_cast<const urdf::Mesh&>(g));
  }
  s.pose = cleanPose(X_DL * toIsometry(collision.origin, c.source.urdf,
                                       fmt::format("link '{}' <collision>", c.link)));
  return s;
}

// Every link fixed to a body of the chain, with its geometry in that body's DH frame X_BD[body]
// (at q = 0, where URDF's joint frames are their origins).
void collectBodies(const urdf::ModelInterface& model,
                   const UrdfRobotSource& source,
                   const std::vector<urdf::JointConstSharedPtr>& path,
                   const std::array<Eigen::Isometry3d, kNumJoints + 1>& X_BD,
                   UrdfRobot& out) {
  std::vector<std::string> revolute;  // the chain's moving joints: each starts the next body
  for (const auto& j : path) {
    if (j->type != urdf::Joint::FIXED) revolute.push_back(j->name);
  }
  const std::vector<fs::path> search = packageSearchPath(source.package_path);
  struct Item {
    urdf::LinkConstSharedPtr link;
    Eigen::Isometry3d X_BL;
    std::size_t body;
  };
  std::vector<Item> stack{{model.getLink(source.base_link), Eigen::Isometry3d::Identity(), 0}};
  while (!stack.empty()) {
    const Item item = stack.back();
    stack.pop_back();
    out.body_links[item.body].push_back(item.link->name);
    const GeometryContext context{source, search, item.link->name};
    const Eigen::Isometry3d X_DL = X_BD[item.body].inverse() * item.X_BL;
    for (const auto& collision : item.link->collision_array) {
      if (collision && collision->geometry) {
        out.spec.links[item.body].shapes.push_back(shapeSpec(context, *collision, X_DL));
      }
    }
    for (const auto& j : item.link->child_joints) {
      const auto k = std::find(revolute.begin(), revolute.end(), j->name);
      std::size_t body = item.body;
      if (k != revolute.end()) {
        body = static_cast<std::size_t>(k - revolute.begin()) + 1;
      } else if (j->type != urdf::Joint::FIXED) {
        spdlog::warn(
            "{}: link '{}' moves with joint '{}', which is not in the chain {} → {}: "
            "its collision geometry is left out",
            source.urdf.string(), j->child_link_name, j->name, source.base_link, source.tip_link);
        continue;
      }
      stack.push_back({model.getLink(j->child_link_name),
                       item.X_BL * toIsometry(j->parent_to_joint_origin_transform, source.urdf,
                                              fmt::format("joint '{}'", j->name)),
                       body});
    }
  }
}

// A ROS-Industrial opw_kinematics parameter file (m, rad).
struct OpwGeometry {
  double a1 = 0, a2 = 0, b = 0, c1 = 0, c2 = 0, c3 = 0, c4 = 0;
};
struct OpwFile {
  OpwGeometry geometry;
  std::array<double, kNumJoints> offsets{};
  std::array<int, kNumJoints> signs{1, 1, 1, 1, 1, 1};
};

void describe(YamlIn& a, OpwGeometry& g) {
  const std::pair<const char*, double*> keys[] = {{"a1", &g.a1}, {"a2", &g.a2}, {"b", &g.b},
                                                  {"c1", &g.c1}, {"c2", &g.c2}, {"c3", &g.c3},
                                                  {"c4", &g.c4}};
  for (const auto& [key, value] : keys) {
    a.require(key);
    a.field(key, *value, Expect::range(-100.0, 100.0));
  }
}

void describe(YamlIn& a, OpwFile& f) {
  a.require("opw_kinematics_geometric_parameters");
  a.section("opw_kinematics_geometric_parameters", f.geometry);
  a.field("opw_kinematics_joint_offsets", f.offsets, Expect::range(-7.0, 7.0));
  a.field("opw_kinematics_joint_sign_corrections", f.signs, Expect::range(-1.0, 1.0));
  for (std::size_t i = 0; i < kNumJoints; ++i) {
    if (f.signs[i] == 0) {
      a.fail("opw_kinematics_joint_sign_corrections", fmt::format("element {} = 0", i),
             "each sign 1 or -1");
    }
  }
}

kinematics::OpwParameters readOpwFile(const fs::path& file) {
  YamlIn in(loadYamlFile(file), "", file);
  OpwFile f;
  describe(in, f);
  in.finish();
  const OpwGeometry& g = f.geometry;
  kinematics::OpwParameters p{g.a1, g.a2, g.b, g.c1, g.c2, g.c3, g.c4, f.offsets, f.signs};
  return p;
}

bool sameUpToRounding(const kinematics::OpwParameters& a, const kinematics::OpwParameters& b) {
  const double lengths[] = {a.a1 - b.a1, a.a2 - b.a2, a.b - b.b,  a.c1 - b.c1,
                            a.c2 - b.c2, a.c3 - b.c3, a.c4 - b.c4};
  for (double d : lengths) {
    if (std::abs(d) > kOpwRoundingTol) return false;
  }
  for (std::size_t i = 0; i < kNumJoints; ++i) {
    const double d = std::remainder(a.offsets[i] - b.offsets[i], 2.0 * std::numbers::pi);
    if (a.signs[i] != b.signs[i] || std::abs(d) > kOpwRoundingTol) return false;
  }
  return true;
}

std::string opwText(const kinematics::OpwParameters& p) {
  return fmt::format(
      "a1 {:.6g}, a2 {:.6g}, b {:.6g}, c1 {:.6g}, c2 {:.6g}, c3 {:.6g}, c4 {:.6g} m, offsets "
      "[{:.9g}] rad, signs [{}]",
      p.a1, p.a2, p.b, p.c1, p.c2, p.c3, p.c4, fmt::join(p.offsets, ", "),
      fmt::join(p.signs, ", "));
}

// The OPW parameters: the chain's, or the opw file's when it describes the same arm (exactly,
// or up to the digits it was written with).
kinematics::OpwParameters chooseOpw(const UrdfRobotSource& source,
                                    const kinematics::SerialChain& chain,
                                    const std::array<kinematics::DhJoint, kNumJoints>& dh) {
  const std::string chain_text =
      fmt::format("{} → {} of {}", source.base_link, source.tip_link, source.urdf.string());
  kinematics::OpwParameters derived;
  try {
    derived = kinematics::opwFromChain(chain);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: chain {} → {}: {}", source.urdf.string(), source.base_link,
                                 source.tip_link, e.what()));
  }
  if (source.opw_parameters.empty()) return derived;
  const kinematics::OpwParameters given = readOpwFile(source.opw_parameters);
  try {
    kinematics::RobotModel({source.name, dh, given, {}, {}});
    return given;
  } catch (const InputError& e) {
    if (sameUpToRounding(given, derived)) {
      spdlog::debug("{}: within {} of the chain's OPW parameters: using the chain's",
                    source.opw_parameters.string(), kOpwRoundingTol);
      return derived;
    }
    throw InputError(fmt::format(
        "{}: these OPW parameters ({}) disagree with the URDF chain {}: {}; the chain's own "
        "are {}",
        source.opw_parameters.string(), opwText(given), chain_text, e.what(), opwText(derived)));
  }
}

}  // namespace

// A job's `robot:` naming a URDF: the file and how to read it (docs/robots.md).
RobotSpec readUrdfRobot(YamlIn& a) {
  UrdfRobotSource source;
  FilePath urdf, opw;
  std::vector<std::string> packages;
  a.require("urdf");
  a.field("urdf", urdf);
  a.field("base_link", source.base_link);
  a.field("tip_link", source.tip_link);
  a.field("package_path", packages);
  a.field("opw_parameters", opw);
  a.field("name", source.name);
  a.field("controller", source.controller, Expect::oneOf(kControllers));
  a.finish();
  for (const std::string& dir : packages) {
    fs::path p(dir);
    if (p.is_relative()) p = a.file().parent_path() / p;
    std::error_code ec;
    if (!fs::is_directory(p, ec)) {
      a.fail("package_path", fmt::format("'{}' ({})", dir, p.lexically_normal().string()),
             "existing folders (relative paths start at the folder of " +
                 a.file().filename().string() + ")");
    }
    source.package_path.push_back(p.lexically_normal());
  }
  source.urdf = urdf.resolved;
  source.opw_parameters = opw.resolved;
  return importUrdf(source).spec;
}

UrdfRobot importUrdf(const UrdfRobotSource& source) {
  const urdf::ModelInterfaceSharedPtr model = parseUrdf(source.urdf);
  const auto path = chainPath(*model, source);
  const kinematics::SerialChain chain = serialChain(path, source);
  std::array<kinematics::DhJoint, kNumJoints> dh;
  try {
    dh = kinematics::dhFromChain(chain);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: chain {} → {}: {}", source.urdf.string(), source.base_link,
                                 source.tip_link, e.what()));
  }
  UrdfRobot out;
  out.spec.name = source.name.empty() ? model->getName() : source.name;
  out.spec.controller = source.controller;
  out.spec.opw = toOpwSpec(chooseOpw(source, chain, dh));
  std::array<Eigen::Isometry3d, kNumJoints + 1> X_BD;
  X_BD[0] = Eigen::Isometry3d::Identity();
  for (std::size_t i = 0; i < kNumJoints; ++i) {
    out.spec.dh.push_back(toJointSpec(dh[i]));
    X_BD[i + 1] = X_BD[i] * kinematics::dhTransform(dh[i], 0.0);
  }
  out.spec.links.resize(kNumJoints + 1);
  for (std::size_t i = 0; i < out.spec.links.size(); ++i) {
    out.spec.links[i].name = i == 0 ? "base" : fmt::format("link{}", i);
  }
  collectBodies(*model, source, path, X_BD, out);
  checkAsRobotFile(out.spec, source.urdf.string());  // ranges a robot file would be held to
  return out;
}

std::vector<fs::path> packageSearchPath(const std::vector<fs::path>& explicit_paths) {
  std::vector<fs::path> search = explicit_paths;
  if (const char* env = std::getenv("SCANPLAN_PACKAGE_PATH")) {
    std::stringstream list(env);
    for (std::string dir; std::getline(list, dir, ':');) {
      if (!dir.empty()) search.emplace_back(dir);
    }
  }
  return search;
}

fs::path resolveUrdfUri(const std::string& uri,
                        const fs::path& urdf_dir,
                        const std::vector<fs::path>& search) {
  std::error_code ec;
  constexpr std::string_view kPackage = "package://", kFile = "file://";
  if (uri.rfind(kFile, 0) == 0) return resolveUrdfUri(uri.substr(kFile.size()), urdf_dir, search);
  if (uri.rfind(kPackage, 0) != 0) {
    const fs::path file = fs::path(uri).is_absolute() ? fs::path(uri) : urdf_dir / uri;
    if (fs::is_regular_file(file, ec)) return file.lexically_normal();
    throw InputError(fmt::format("mesh '{}': {} does not exist", clipForMessage(uri),
                                 file.lexically_normal().string()));
  }
  const std::string rest = uri.substr(kPackage.size());
  const std::string package = rest.substr(0, rest.find('/'));
  const std::string inside = rest.size() > package.size() ? rest.substr(package.size() + 1) : "";
  requireInsidePackage(uri, package, inside);
  std::vector<std::string> searched;
  for (fs::path dir : search) {
    if (dir.filename().empty()) dir = dir.parent_path();  // "meshes/" names "meshes"
    for (const fs::path& root : {dir / package, dir}) {
      if (root.filename() != package || !fs::is_directory(root, ec)) continue;
      const fs::path file = (root / inside).lexically_normal();
      if (fs::is_regular_file(file, ec)) return file;
      throw InputError(fmt::format("mesh '{}': package '{}' is {}, but it has no file {}",
                                   clipForMessage(uri), package, root.string(), file.string()));
    }
    searched.push_back(dir.string());
  }
  throw InputError(fmt::format(
      "mesh '{}': package '{}' not found; searched {} (give the folder holding {}/ with "
      "--package-path, package_path in the job, or SCANPLAN_PACKAGE_PATH)",
      clipForMessage(uri), package,
      searched.empty() ? "no folders" : fmt::format("{}", fmt::join(searched, ", ")), package));
}

bool isUrdfFile(const fs::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".urdf";
}

RobotSpec loadRobotOrUrdf(const fs::path& file) {
  if (!isUrdfFile(file)) return loadRobotFile(file);
  UrdfRobotSource source;
  source.urdf = file;
  return importUrdf(source).spec;
}

}  // namespace scanplan::config
