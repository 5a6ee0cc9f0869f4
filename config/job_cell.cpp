// The cell sections of a job file: table, part, obstacles, sensors, clearance and constraints;
// their YAML keys (describe) and their conversion to the library's SI models (buildCell,
// loadPartMesh, clearanceConfig, constraintSettings).
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
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/placement.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/programs/programs.h>

namespace scanplan::config {
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

inline const std::vector<std::string> kUpAxes = {"z", "y", "x", "-z", "-y", "-x"};

// The rotation that turns the file's `up` direction into +z (a quarter or half turn).
Eigen::Matrix3d upRotation(const std::string& up) {
  using Eigen::AngleAxisd;
  using Eigen::Vector3d;
  const double q = std::numbers::pi / 2;
  if (up == "y") return AngleAxisd(q, Vector3d::UnitX()).matrix();    // +y → +z
  if (up == "-y") return AngleAxisd(-q, Vector3d::UnitX()).matrix();  // −y → +z
  if (up == "x") return AngleAxisd(-q, Vector3d::UnitY()).matrix();   // +x → +z
  if (up == "-x") return AngleAxisd(q, Vector3d::UnitY()).matrix();   // −x → +z
  if (up == "-z") return AngleAxisd(2 * q, Vector3d::UnitX()).matrix();
  return Eigen::Matrix3d::Identity();
}

inline const std::vector<std::string> kPlacements = {"none", "table"};

template <class A>
void describePart(A& a, PartSpec& s) {
  a.require("mesh");
  a.field("mesh", s.mesh);
  a.field("units", s.units, Expect::oneOf(kLengthUnits));
  a.field("scale", s.scale, Expect::positive());
  a.field("up_axis", s.up_axis, Expect::oneOf(kUpAxes));
  a.field("place", s.place, Expect::oneOf(kPlacements));
  a.section("pose", s.pose);
}

inline const std::vector<std::string> kCarriers = {"world", "table"};

// Names of the cell's own bodies and of the pair rules' groups (collision/scene.h).
inline const std::vector<std::string> kReservedBodyNames = {"base", "scanner", "table",
                                                            "part", "robot",   "obstacles"};

template <class A>
void describeObstacle(A& a, ObstacleSpec& s) {
  a.require("name");
  a.field("name", s.name);
  if constexpr (A::kReading) {
    // Pair rules address bodies by name, glob and group: an obstacle must be addressable.
    const bool link = s.name.size() > 4 && s.name.starts_with("link") &&
                      s.name.find_first_not_of("0123456789", 4) == std::string::npos;
    if (s.name.empty() || link || s.name.find_first_of("*?[]") != std::string::npos ||
        std::find(kReservedBodyNames.begin(), kReservedBodyNames.end(), s.name) !=
            kReservedBodyNames.end()) {
      a.fail("name", s.name,
             "a name of its own: not a body or group name (base, link1 … link6, scanner, table, "
             "part, robot, obstacles) and no glob characters (* ? [ ])");
    }
  }
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
      if (v == 0.0)
        a.fail("size_mm", "a zero side",
               "non-zero sides (negative ones extend from the corner the other way)");
    }
    if (a.has("pose"))
      a.fail("pose", "given with corner_mm",
             "either corner_mm + size_mm or a centred box with pose");
  }
}

inline const std::vector<std::string> kSensorKinds = {"presence", "distance"};
inline const std::vector<std::string> kSensorShapes = {"box", "sphere", "cylinder"};
inline const std::vector<std::string> kSensorRules = {"any", "never", "always", "during",
                                                      "not_during"};
// A sensor's lengths: positive and at most a kilometre (as every length of a job).
inline const Expect kSensorLength{0.0, 1e6, true, false, {}};

template <class A>
void describeSensor(A& a, SensorSpec& s) {
  a.require("name");
  a.field("name", s.name);
  if constexpr (A::kReading) {
    // The name heads sensors.csv's columns and the report's lines.
    static const std::regex kName("[A-Za-z_][A-Za-z0-9_.-]{0,63}");
    if (!std::regex_match(s.name, kName)) {
      a.fail("name", "'" + clipForMessage(s.name) + "'",
             "a letter or _, then letters, digits, _, . or -, at most 64 characters");
    }
  }
  a.require("kind");
  a.field("kind", s.kind, Expect::oneOf(kSensorKinds));
  a.field("carrier", s.carrier);
  if constexpr (A::kReading) {
    if (s.carrier.empty()) a.fail("carrier", "''", "world or the name of a body of the cell");
  }
  a.section("pose", s.pose);
  if (s.kind == "presence") {
    a.require("shape");
    a.field("shape", s.shape, Expect::oneOf(kSensorShapes));
    if (s.shape == "box") {
      a.require("size_mm");
      a.field("size_mm", s.size_mm, kSensorLength);
    } else {
      a.require("radius_mm");
      a.field("radius_mm", s.radius_mm, kSensorLength);
      if (s.shape == "cylinder") {
        a.require("length_mm");
        a.field("length_mm", s.length_mm, kSensorLength);
      }
    }
  } else {
    a.require("max_range_mm");
    a.field("min_range_mm", s.min_range_mm, Expect::range(0.0, 1e6));
    a.field("max_range_mm", s.max_range_mm, kSensorLength);
    if constexpr (A::kReading) {
      s.has_receiver = a.has("receiver_mm");
      if (!(s.min_range_mm < s.max_range_mm)) {
        a.fail("max_range_mm", formatNumber(s.max_range_mm),
               "a range above min_range_mm (" + formatNumber(s.min_range_mm) + ")");
      }
    }
    if (s.has_receiver) a.field("receiver_mm", s.receiver_mm, Expect::range(-1e6, 1e6));
  }
  a.field("expect", s.expect, Expect::oneOf(kSensorRules));
  if (s.expect == "during" || s.expect == "not_during") {
    a.require("window_s");
    a.field("window_s", s.window_s, Expect::range(0.0, 1e9));
    if constexpr (A::kReading) {
      if (!(s.window_s[0] <= s.window_s[1])) {
        a.fail("window_s",
               "[" + formatNumber(s.window_s[0]) + ", " + formatNumber(s.window_s[1]) + "]",
               "[t0_s, t1_s] with t0_s <= t1_s");
      }
    }
  }
}

template <class A>
void describeRamp(A& a, RampSpec& s) {
  a.field("low", s.low, Expect::range(0.0, 1.0));
  a.field("high", s.high, Expect::range(0.0, 1.0));
  a.field("gamma", s.gamma, Expect::positive());
  if constexpr (A::kReading) {
    if (!(s.low < s.high))
      a.fail("high", formatNumber(s.high), "a value above low (" + formatNumber(s.low) + ")");
  }
}

template <class A>
void describeLengthRamp(A& a, LengthRampSpec& s) {
  a.field("low_mm", s.low_mm, Expect::nonNegative());
  a.field("high_mm", s.high_mm, Expect::positive());
  a.field("gamma", s.gamma, Expect::positive());
  if constexpr (A::kReading) {
    if (!(s.low_mm < s.high_mm))
      a.fail("high_mm", formatNumber(s.high_mm),
             "a value above low_mm (" + formatNumber(s.low_mm) + ")");
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
    if (s.exclude && s.include)
      a.fail("include", "true together with exclude", "at most one of exclude, include");
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
  a.field("link_meshes", s.link_meshes, Expect::oneOf({"auto", "pieces", "hull", "exact"}));
  a.field("hull_vertices", s.hull_vertices, Expect::range(8, 1000));
  a.field("hull_margin_mm", s.hull_margin_mm, Expect::nonNegative());
  a.field("piece_margin_mm", s.piece_margin_mm, Expect::range(0.5, 50.0));
  a.field("max_pieces", s.max_pieces, Expect::range(1, 1000));
  if constexpr (A::kReading) {
    if (!(s.d_low_mm < s.d_high_mm)) {
      a.fail("d_high_mm", formatNumber(s.d_high_mm),
             "a distance above d_low_mm (" + formatNumber(s.d_low_mm) + ")");
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

// The job's part placed on the table (kinematics::placedOnTable); errors name the job file.
Eigen::Isometry3d placedPart(const JobSpec& job, const kinematics::PartModel& part) {
  return kinematics::placedOnTable(loadPartMesh(job, part).mesh, toIsometry(job.part.pose));
}

// A part larger than any length a job may hold (lengths within ±1e6 mm, the reader's bound)
// cannot be scanned in any cell; refused here, at load, its probes and maps would otherwise
// grow with it before anything said why.
constexpr double kMaxPartSizeMm = 1e6;

void checkPartSize(const JobSpec& job, const kinematics::TriangleMesh& mesh) {
  const double size_mm = toMm(mesh.bounds().sizes().maxCoeff());
  if (size_mm <= kMaxPartSizeMm) return;
  throw InputError(fmt::format(
      "{}: part.scale: {}: the part is {:.6g} mm across (part.units {} × part.scale): expected "
      "a part at most {:.0f} mm across; check part.units and part.scale",
      job.source.string(), formatNumber(job.part.scale), size_mm, job.part.units, kMaxPartSizeMm));
}

kinematics::Sensor toSensor(const SensorSpec& spec) {
  using kinematics::Sensor;
  using Rule = kinematics::SensorExpectation::Kind;
  Sensor sensor;
  sensor.name = spec.name;
  sensor.kind = spec.kind == "distance" ? Sensor::Kind::kDistance : Sensor::Kind::kPresence;
  sensor.carrier = spec.carrier;
  sensor.X_CS = toIsometry(spec.pose);
  if (spec.shape == "sphere") {
    sensor.volume.geometry = kinematics::Sphere{mm(spec.radius_mm)};
  } else if (spec.shape == "cylinder") {
    sensor.volume.geometry = kinematics::Cylinder{mm(spec.radius_mm), mm(spec.length_mm)};
  } else {
    sensor.volume.geometry = kinematics::Box{Eigen::Vector3d(spec.size_mm.data()) * kMmToM};
  }
  sensor.min_range = mm(spec.min_range_mm);
  sensor.max_range = mm(spec.max_range_mm);
  if (spec.has_receiver) sensor.p_SR = Eigen::Vector3d(spec.receiver_mm.data()) * kMmToM;
  const std::vector<std::pair<std::string, Rule>> rules = {{"any", Rule::kAny},
                                                           {"never", Rule::kNever},
                                                           {"always", Rule::kAlways},
                                                           {"during", Rule::kDuring},
                                                           {"not_during", Rule::kNotDuring}};
  for (const auto& [name, rule] : rules) {
    if (spec.expect == name) sensor.expect.kind = rule;
  }
  sensor.expect.t0 = spec.window_s[0];
  sensor.expect.t1 = spec.window_s[1];
  return sensor;
}

// The arm can reach the part at some table angle: an error when none of it is within reach, a
// warning when some of it is not (kinematics::partReach is a necessary condition only).
void checkInReach(const JobSpec& job,
                  const kinematics::CellModel& cell,
                  const kinematics::TriangleMesh& mesh) {
  const scanner::LaserWindow window = scanner::laserWindow(laserOptics(job));
  const double lever = cell.robot.definition().opw.c4 + cell.scanner.X_FS.translation().norm() +
                       std::hypot(window.z_max, window.y_far);
  const kinematics::PartReach reach = kinematics::partReach(cell, mesh, lever);
  const double mount = cell.scanner.X_FS.translation().norm();
  if (mount > reach.arm_reach - lever) {  // the arm's own stretch, shoulder to flange
    throw InputError(fmt::format(
        "{}: scanner.mount: the laser frame sits {:.0f} mm from the flange, more than the arm's "
        "whole stretch of {:.0f} mm: expected the scanner's offset on the flange (xyz_mm, mm)",
        job.source.string(), toMm(mount), toMm(reach.arm_reach - lever)));
  }
  if (reach.nearest_excess > 0.0) {
    throw InputError(fmt::format(
        "{}: part: no point of the part ({:.0f} mm across) is within the arm's reach at any "
        "table angle: the nearest stays {:.0f} mm beyond the {:.0f} mm the arm, the scanner "
        "and its depth window can stretch from the shoulder; expected the table (table.axis) "
        "within reach of the robot and the part's size as meant (part.units, part.scale)",
        job.source.string(), toMm(mesh.bounds().diagonal().norm()), toMm(reach.nearest_excess),
        toMm(reach.arm_reach)));
  }
  if (reach.beyond_fraction > 0.0) {
    spdlog::warn(
        "{}: part: {:.1f} % of the part's vertices are beyond the arm's reach at every "
        "table angle; they cannot be scanned",
        job.source.filename().string(), 100.0 * reach.beyond_fraction);
  }
}

// The part on the table top: none of it below (beyond a rounding hair), and a warning when it
// overhangs the table.
void checkOnTable(const JobSpec& job,
                  const kinematics::CellModel& cell,
                  const kinematics::TriangleMesh& mesh) {
  constexpr double kSunkTolerance = 1e-5;  // m: 0.01 mm, far above the float rounding of a mesh
  const auto [lowest, widest] = kinematics::partExtent(mesh, cell.part.X_RP);
  if (lowest < -kSunkTolerance) {
    throw InputError(fmt::format(
        "{}: part.pose: the part reaches {:.2f} mm below the table top (its lowest point is at "
        "z = {:.2f} mm on the table): expected it to rest on the table; raise pose.xyz_mm z by "
        "{:.2f}, or set part.place: table",
        job.source.string(), toMm(-lowest), toMm(lowest), toMm(-lowest)));
  }
  if (widest > cell.table.radius) {
    spdlog::warn(
        "{}: part: the part reaches {:.1f} mm from the table axis, beyond the table's "
        "radius of {:.1f} mm",
        job.source.filename().string(), toMm(widest), toMm(cell.table.radius));
  }
  checkInReach(job, cell, mesh);
}

}  // namespace

void describe(YamlIn& a, TableSpec& s) { describeTable(a, s); }
void describe(YamlOut& a, TableSpec& s) { describeTable(a, s); }
void describe(SchemaOut& a, TableSpec& s) { describeTable(a, s); }
void describe(YamlIn& a, PartSpec& s) { describePart(a, s); }
void describe(YamlOut& a, PartSpec& s) { describePart(a, s); }
void describe(SchemaOut& a, PartSpec& s) { describePart(a, s); }
void describe(YamlIn& a, ObstacleSpec& s) { describeObstacle(a, s); }
void describe(YamlOut& a, ObstacleSpec& s) { describeObstacle(a, s); }
void describe(SchemaOut& a, ObstacleSpec& s) { describeObstacle(a, s); }
void describe(YamlIn& a, SensorSpec& s) { describeSensor(a, s); }
void describe(YamlOut& a, SensorSpec& s) { describeSensor(a, s); }
void describe(SchemaOut& a, SensorSpec& s) { describeSensor(a, s); }
void describe(YamlIn& a, RampSpec& s) { describeRamp(a, s); }
void describe(YamlOut& a, RampSpec& s) { describeRamp(a, s); }
void describe(SchemaOut& a, RampSpec& s) { describeRamp(a, s); }
void describe(YamlIn& a, LengthRampSpec& s) { describeLengthRamp(a, s); }
void describe(YamlOut& a, LengthRampSpec& s) { describeLengthRamp(a, s); }
void describe(SchemaOut& a, LengthRampSpec& s) { describeLengthRamp(a, s); }
void describe(YamlIn& a, PairRuleSpec& s) { describePairRule(a, s); }
void describe(YamlOut& a, PairRuleSpec& s) { describePairRule(a, s); }
void describe(SchemaOut& a, PairRuleSpec& s) { describePairRule(a, s); }
void describe(YamlIn& a, ClearanceSpec& s) { describeClearance(a, s); }
void describe(YamlOut& a, ClearanceSpec& s) { describeClearance(a, s); }
void describe(SchemaOut& a, ClearanceSpec& s) { describeClearance(a, s); }
void describe(YamlIn& a, ConstraintsSpec& s) { describeConstraints(a, s); }
void describe(YamlOut& a, ConstraintsSpec& s) { describeConstraints(a, s); }
void describe(SchemaOut& a, ConstraintsSpec& s) { describeConstraints(a, s); }

// The job's JSON Schema (jobSchema): the same describe() functions, written by SchemaOut.
template <>
std::vector<ShapeSpec> schemaVariants<ShapeSpec>() {
  std::vector<ShapeSpec> out;
  for (const std::string& type : kShapeTypes) {
    ShapeSpec s;
    s.type = type;
    out.push_back(s);
    if (type == "cylinder" || type == "capsule") {
      s.by_end_points = true;
      out.push_back(s);
    }
  }
  return out;
}

template <>
std::vector<ObstacleSpec> schemaVariants<ObstacleSpec>() {
  std::vector<ObstacleSpec> out;
  for (const ShapeSpec& shape : schemaVariants<ShapeSpec>()) {
    ObstacleSpec s;
    s.shape = shape;
    out.push_back(s);
  }
  return out;
}

template <>
std::vector<SensorSpec> schemaVariants<SensorSpec>() {
  std::vector<SensorSpec> out;
  for (const char* rule : {"any", "during"}) {
    SensorSpec s;
    s.expect = rule;
    for (const std::string& shape : kSensorShapes) {
      s.kind = "presence";
      s.shape = shape;
      out.push_back(s);
    }
    s.kind = "distance";
    out.push_back(s);
  }
  return out;
}

kinematics::LoadedMesh loadPartMesh(const JobSpec& job, const kinematics::PartModel& part) {
  kinematics::LoadedMesh mesh;
  try {
    mesh = kinematics::loadMesh(part.mesh.path, part.mesh.options);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: part.mesh: {}", job.source.string(), e.what()));
  }
  checkPartSize(job, mesh.mesh);
  return mesh;
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

  cell.part.mesh = {job.part.mesh.resolved,
                    {toLengthUnit(job.part.units), job.part.scale, upRotation(job.part.up_axis)}};
  cell.part.X_RP = toIsometry(job.part.pose);
  if (job.part.place == "table") cell.part.X_RP = placedPart(job, cell.part);

  cell.scanner.X_FS = toIsometry(job.scanner.mount);
  for (const ShapeSpec& shape : job.scanner.body) cell.scanner.body.push_back(toShape(shape));

  for (const ObstacleSpec& o : job.obstacles) {
    kinematics::Obstacle obstacle;
    obstacle.name = o.name;
    obstacle.carrier =
        o.carrier == "table" ? kinematics::Carrier::kTable : kinematics::Carrier::kWorld;
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
  for (const SensorSpec& spec : job.sensors) cell.sensors.push_back(toSensor(spec));
  return cell;
}

namespace {

// Where a robot's fitted link pieces are kept: beside its robot file (beside the job for a
// robot given inline), in a folder named after it.
std::filesystem::path pieceCacheFolder(const JobSpec& job) {
  const std::filesystem::path& owner =
      job.robot_file.resolved.empty() ? job.source : job.robot_file.resolved;
  if (owner.empty()) return {};
  return owner.parent_path() / (owner.stem().string() + ".pieces");
}

}  // namespace

collision::ClearanceConfig clearanceConfig(const JobSpec& job) {
  const ClearanceSpec& c = job.constraints.clearance;
  collision::ClearanceConfig config;
  config.defaults = {mm(c.d_low_mm), mm(c.d_high_mm), c.gamma};
  config.link_meshes = c.link_meshes == "exact"    ? collision::LinkMeshes::kExact
                       : c.link_meshes == "hull"   ? collision::LinkMeshes::kHull
                       : c.link_meshes == "pieces" ? collision::LinkMeshes::kPieces
                                                   : collision::LinkMeshes::kAuto;
  config.max_hull_margin = mm(c.hull_margin_mm);
  config.hull_vertices = static_cast<std::size_t>(c.hull_vertices);
  config.piece_margin = mm(c.piece_margin_mm);
  config.max_pieces = static_cast<std::size_t>(c.max_pieces);
  config.piece_cache = pieceCacheFolder(job);
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

kinematics::LoadedMesh loadPart(const JobSpec& job, const kinematics::CellModel& cell) {
  kinematics::LoadedMesh part = loadPartMesh(job, cell.part);
  for (const std::string& w : part.report.warnings) {
    spdlog::warn("{}: part.mesh: {}", job.source.filename().string(), w);
  }
  // Inside out, every surface would face away from the scanner: say so, not "nothing seen".
  if (part.mesh.isClosed() && part.mesh.signedVolume() < 0.0) {
    throw InputError(fmt::format(
        "{}: part.mesh: {} is closed but inside out: its triangles' winding puts their normals "
        "into the part (volume {:.0f} mm³ by the winding): expected outward normals; reverse "
        "the winding of every face in a mesh tool",
        job.source.string(), job.part.mesh.as_written, part.mesh.signedVolume() * 1e9));
  }
  checkOnTable(job, cell, part.mesh);
  return part;
}

}  // namespace scanplan::config
