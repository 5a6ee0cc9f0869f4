#include <scanplan/config/job.h>

#include <scanplan/config/robot_file.h>
#include <scanplan/config/text.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/mesh.h>
#include "tests/test_support.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <string>
#include <system_error>
#include <variant>
#include <vector>

namespace scanplan::cli {
namespace {

namespace fs = std::filesystem;

const fs::path kSource = SCANPLAN_SOURCE_DIR;

// Lengths come out of mm → m conversions of small integers; 1e-12 m is far below any rounding
// that could matter and far above double noise at this scale.
constexpr double kLengthTol = 1e-12;

// The Viper s650 kinematics of data/robots/viper_s650.yaml without links, so tests own their
// robot files. Line 1 is `name:`, lines 3–8 the six DH rows, lines 10–11 the OPW mapping;
// links appended by linksWith() start at line 12, so link 1's first shape is on line 16.
const std::string kRobot = R"(name: test arm
dh:
  - {a_mm: 75,  d_mm: 335, alpha_deg: -90, min_deg: -170, max_deg: 170, max_speed_deg_s: 328}
  - {a_mm: 270, d_mm: 0,   alpha_deg: 0,   min_deg: -190, max_deg: 45,  max_speed_deg_s: 300}
  - {a_mm: -90, d_mm: 0,   alpha_deg: 90,  min_deg: -29,  max_deg: 256, max_speed_deg_s: 375}
  - {a_mm: 0,   d_mm: 295, alpha_deg: -90, min_deg: -190, max_deg: 190, max_speed_deg_s: 375}
  - {a_mm: 0,   d_mm: 0,   alpha_deg: 90,  min_deg: -120, max_deg: 120, max_speed_deg_s: 375}
  - {a_mm: 0,   d_mm: 80,  alpha_deg: 0,   min_deg: -360, max_deg: 360, max_speed_deg_s: 600}
opw:
  {a1_mm: 75, a2_mm: -90, b_mm: 0, c1_mm: 335, c2_mm: 270, c3_mm: 295, c4_mm: 80,
   offsets_deg: [0, -90, 90, 0, 0, 0], signs: [1, 1, 1, 1, 1, 1]}
)";

// Seven links; link 1 (index 1) carries the shapes under test.
std::string linksWith(const std::string& link1_shapes) {
  std::string s =
      "links:\n  - {name: base, shapes: []}\n  - name: link1\n    shapes:\n" + link1_shapes;
  for (int i = 2; i <= 6; ++i) s += "  - {name: link" + std::to_string(i) + "}\n";
  return s;
}

// `text` with its one occurrence of `from` replaced; empty (so the test fails loudly) if absent.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  if (at == std::string::npos) return "";
  return text.replace(at, from.size(), to);
}

std::string indented(const std::string& text) {
  std::string out = "  ";
  for (char c : text) out += c == '\n' ? std::string("\n  ") : std::string(1, c);
  return out;
}

using test::throwsInputError;

::testing::AssertionResult loadFails(const fs::path& job,
                                     std::initializer_list<std::string> parts) {
  return throwsInputError([&] { config::loadJob(job); }, parts);
}

class JobFile : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("scanplan_test_job_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    write("part.stl", "solid empty\nendsolid empty\n");  // file paths must exist to load
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  fs::path write(const std::string& relative, const std::string& text) const {
    const fs::path file = (dir_ / relative).lexically_normal();
    fs::create_directories(file.parent_path());
    std::ofstream(file) << text;
    return file;
  }
  // A job naming robot.yaml (written from `robot`) with `rest` appended.
  fs::path writeJob(const std::string& rest, const std::string& robot = kRobot) const {
    write("robot.yaml", robot);
    return write("job.yaml", "robot: robot.yaml\npart: {mesh: part.stl}\n" + rest);
  }
  // "DIR/name:where", the start of an error message located in one of this test's files.
  std::string at(const std::string& name, const std::string& where) const {
    return (dir_ / name).lexically_normal().string() + ":" + where;
  }

  fs::path dir_;
};

TEST_F(JobFile, BundledDemoJobAndRobotsLoadAndBuild) {
  const config::JobSpec demo = config::loadJob(kSource / "data/jobs/demo_rings.yaml");
  EXPECT_EQ(demo.name, "demo_rings");
  EXPECT_EQ(demo.robot_file.resolved, (kSource / "data/robots/viper_s650.yaml").lexically_normal());
  EXPECT_EQ(demo.part.mesh.resolved, (kSource / "data/parts/demo_housing.stl").lexically_normal());
  const kinematics::CellModel cell = config::buildCell(demo);
  EXPECT_EQ(cell.robot.name(), "Adept Viper s650");
  EXPECT_DOUBLE_EQ(cell.table.radius, 0.2);
  ASSERT_EQ(cell.scanner.body.size(), 1u);

  const fs::path kuka = kSource / "data/robots/kuka_kr6_r900_sixx.yaml";
  const config::RobotSpec spec = config::loadRobotFile(kuka);
  EXPECT_EQ(spec.dh.size(), 6u);
  EXPECT_EQ(spec.links.size(), 7u);
  EXPECT_EQ(config::buildRobotModel(spec, kuka.string()).name(), "KUKA KR6 R900 sixx");
}

// `part.up_axis` turns the file's up direction into +z at load: the part's extents permute.
TEST_F(JobFile, PartUpAxisRotatesTheMeshAtLoad) {
  const config::JobSpec z = config::loadJob(kSource / "data/jobs/demo_rings.yaml");
  // `-> Eigen::Vector3d`: a deduced return type would be Eigen's expression for max − min of a
  // box that dies with the lambda (AddressSanitizer: stack-use-after-scope).
  const Eigen::Vector3d size_z = [&]() -> Eigen::Vector3d {
    const kinematics::CellModel cell = config::buildCell(z);
    return kinematics::loadMesh(cell.part.mesh.path, cell.part.mesh.options).mesh.bounds().sizes();
  }();
  const std::vector<std::pair<const char*, Eigen::Vector3d>> cases{
      {"y", {size_z.x(), size_z.z(), size_z.y()}},
      {"-x", {size_z.z(), size_z.y(), size_z.x()}},
      {"-z", size_z}};
  for (const auto& [up, expect] : cases) {
    SCOPED_TRACE(up);
    const config::JobSpec job =
        config::loadJob(kSource / "data/jobs/demo_rings.yaml", {std::string("part.up_axis=") + up});
    const kinematics::CellModel cell = config::buildCell(job);
    const auto mesh = kinematics::loadMesh(cell.part.mesh.path, cell.part.mesh.options).mesh;
    EXPECT_LT((mesh.bounds().sizes() - expect).norm(), 1e-9);
    // The file's up direction becomes +z.
    const Eigen::Matrix3d& R = cell.part.mesh.options.rotation;
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
  }
  EXPECT_THROW(config::loadJob(kSource / "data/jobs/demo_rings.yaml", {"part.up_axis=w"}),
               InputError);
}

// The comment line names the job the text was resolved from, so it differs between the two
// files; everything after it must match byte for byte.
TEST_F(JobFile, JobToYamlRoundTripsAndSpellsOutEveryDefault) {
  const std::string first =
      config::jobToYaml(config::loadJob(kSource / "data/jobs/demo_rings.yaml"));
  for (const char* key : {"max_accel_deg_s2", "eccentricity_mm", "tilt_deg", "robot_base",
                          "dh:", "opw:", "theta_offset_deg", "direction", "signs",
                          "links:", "units: mm", "scale: 1", "continuous: true"}) {
    EXPECT_NE(first.find(key), std::string::npos) << key << " missing from:\n" << first;
  }
  const fs::path resolved = write("resolved.yaml", first);
  const config::JobSpec again = config::loadJob(resolved);
  EXPECT_TRUE(again.robot_file.as_written.empty()) << "robot should be inline";
  EXPECT_EQ(again.robot.dh.size(), 6u);
  const std::string second = config::jobToYaml(again);
  EXPECT_EQ(second.substr(second.find('\n')), first.substr(first.find('\n')));
  EXPECT_NE(second.find(resolved.string()), std::string::npos);
  EXPECT_NO_THROW(config::buildCell(again));
}

// Every writer branch: inline robot with mesh/sphere/box/length capsule shapes, odd names.
TEST_F(JobFile, JobToYamlRoundTripsNonDefaultValues) {
  const std::string shapes =
      "      - {type: mesh, file: meshes/l1.stl, units: m, scale: 0.5}\n"
      "      - {type: sphere, radius_mm: 12.5, pose: {xyz_mm: [1, 2, 3], rpy_deg: [0, 90, 0]}}\n"
      "      - {type: capsule, radius_mm: 5, length_mm: 0}\n";
  write("meshes/l1.stl", "");
  const std::string robot = replaced(kRobot, "test arm", "'arm: #2'") + linksWith(shapes);
  const fs::path job = write(
      "job.yaml",
      "name: 'yes'\n"
      "robot:\n" +
          indented(robot) +
          "\n"
          "robot_base: {xyz_mm: [0, 0, -0.25], rpy_deg: [0, 0, 180]}\n"
          "table: {continuous: false, min_deg: -90, max_deg: 270, eccentricity_mm: [0.1, -1e-05],"
          " tilt_deg: [0.01, 0]}\n"
          "part: {mesh: part.stl, units: m, scale: 1000}\n"
          "scanner: {body: [{type: box, size_mm: [1, 2, 3]}]}\n");
  const config::JobSpec loaded = config::loadJob(job);
  EXPECT_EQ(loaded.name, "yes");
  EXPECT_EQ(loaded.robot.name, "arm: #2");
  const std::string first = config::jobToYaml(loaded);
  const config::JobSpec again = config::loadJob(write("resolved.yaml", first));
  EXPECT_EQ(again.name, "yes");
  EXPECT_EQ(again.robot.name, "arm: #2");
  EXPECT_FALSE(again.table.continuous);
  EXPECT_EQ(again.table.eccentricity_mm[1], -1e-05);
  const std::string second = config::jobToYaml(again);
  EXPECT_EQ(second.substr(second.find('\n')), first.substr(first.find('\n')));
}

TEST_F(JobFile, PathsResolveAgainstTheFileThatNamesThem) {
  for (const char* mesh : {"meshes/l1.stl", "parts/p.stl", "jobs/l1.stl", "jobs/p.stl"}) {
    write(mesh, "");
  }
  write("robots/x.yaml", kRobot + linksWith("      - {type: mesh, file: ../meshes/l1.stl}\n"));
  const fs::path job =
      write("jobs/job.yaml", "robot: ../robots/x.yaml\npart: {mesh: ../parts/p.stl}\n");
  const config::JobSpec spec = config::loadJob(job);
  EXPECT_EQ(spec.robot_file.as_written, "../robots/x.yaml");
  EXPECT_EQ(spec.robot_file.resolved, dir_ / "robots/x.yaml");
  const kinematics::CellModel cell = config::buildCell(spec);
  EXPECT_EQ(cell.part.mesh.path, dir_ / "parts/p.stl");
  const auto& links = cell.robot.definition().links;
  EXPECT_EQ(std::get<kinematics::MeshFile>(links[1].shapes[0].geometry).path,
            dir_ / "meshes/l1.stl");

  // Inline, the robot's paths are relative to the job file.
  const fs::path inline_job =
      write("jobs/inline.yaml",
            "robot:\n" + indented(kRobot + linksWith("      - {type: mesh, file: l1.stl}\n")) +
                "\npart: {mesh: p.stl}\n");
  const kinematics::CellModel inline_cell = config::buildCell(config::loadJob(inline_job));
  const auto& inline_links = inline_cell.robot.definition().links;
  EXPECT_EQ(std::get<kinematics::MeshFile>(inline_links[1].shapes[0].geometry).path,
            dir_ / "jobs/l1.stl");
  EXPECT_EQ(inline_cell.part.mesh.path, dir_ / "jobs/p.stl");
}

TEST_F(JobFile, MissingFilesNameTheFieldAndTheResolvedPath) {
  EXPECT_TRUE(loadFails(
      write("job.yaml", "robot: robots/nope.yaml\npart: {mesh: part.stl}\n"),
      {at("job.yaml", "1:8: robot: 'robots/nope.yaml' ("),
       (dir_ / "robots/nope.yaml").string() + ") does not exist", "expected an existing file"}));
  EXPECT_TRUE(loadFails(writeJob("", kRobot + linksWith("      - {type: mesh, file: gone.stl}\n")),
                        {at("robot.yaml", "16:"), "links[1].shapes[0].file: 'gone.stl'",
                         "does not exist", "relative paths start at the folder of robot.yaml"}));
  write("robot.yaml", kRobot);
  EXPECT_TRUE(loadFails(write("job.yaml", "robot: robot.yaml\npart: {mesh: parts}\n"),
                        {at("job.yaml", "2:14: part.mesh: 'parts'"), "does not exist"}));
  EXPECT_TRUE(loadFails(write("job.yaml", "robot: .\npart: {mesh: part.stl}\n"),
                        {at("job.yaml", "1:8: robot: '.'"), "is not a regular file"}));
}

TEST_F(JobFile, MalformedEmptyAndNonMappingFilesAreRejected) {
  EXPECT_TRUE(
      loadFails(writeJob("table: {radius_mm: [1, 2}\n"), {at("job.yaml", "3:"), "malformed YAML"}));
  EXPECT_TRUE(loadFails(write("empty.yaml", ""),
                        {at("empty.yaml", " the file holds nothing"), "expected a YAML mapping"}));
  EXPECT_TRUE(loadFails(write("list.yaml", "- robot: r.yaml\n"),
                        {at("list.yaml", " the file holds a list"), "mapping"}));
}

// A second YAML document would be dropped (yaml-cpp reads one): refused naming the file and the
// line and column where it starts, be it after `---` or after a `...` that ended the first, empty
// or not, in a job or in its robot file. One document with its own leading `---`, or its
// closing `...`, is fine.
TEST_F(JobFile, ASecondYamlDocumentIsRefusedNamingWhereItStarts) {
  const std::string second = "a second YAML document starts here";
  EXPECT_TRUE(loadFails(writeJob("---\ntable: {radius_mm: 200}\n"),
                        {at("job.yaml", "3:1: " + second), "expected one YAML document"}));
  EXPECT_TRUE(loadFails(writeJob("---\n"), {at("job.yaml", "3:1: " + second)}));
  EXPECT_TRUE(
      loadFails(writeJob("...\ntable: {radius_mm: 200}\n"), {at("job.yaml", "4:1: " + second)}));
  EXPECT_TRUE(loadFails(writeJob("name: a\n---\nname: b\n---\nname: c\n"),
                        {at("job.yaml", "4:1: " + second)}));
  const auto robot_lines = std::count(kRobot.begin(), kRobot.end(), '\n');
  EXPECT_TRUE(loadFails(writeJob("", kRobot + "---\nname: other\n"),
                        {at("robot.yaml", std::to_string(robot_lines + 1) + ":1: " + second)}));
  std::ifstream plain(writeJob(""));
  const std::string text((std::istreambuf_iterator<char>(plain)), std::istreambuf_iterator<char>());
  EXPECT_NO_THROW(config::loadJob(write("lead.yaml", "---\n" + text)));
  EXPECT_NO_THROW(config::loadJob(write("end.yaml", "---\n" + text + "...\n")));
}

TEST_F(JobFile, UnknownKeysAreNamedWithLineAndSuggestion) {
  EXPECT_TRUE(loadFails(writeJob("tabel: {}\n"), {at("job.yaml", "3:1: tabel: unknown key"),
                                                  "did you mean 'table'", "scanner"}));
  EXPECT_TRUE(
      loadFails(writeJob("table:\n  radius_mm: 250\n  radius_m: 0.25\n"),
                {at("job.yaml", "5:3: table.radius_m: unknown key"), "did you mean 'radius_mm'"}));
  EXPECT_TRUE(loadFails(write("job.yaml", "robot:\n" + indented(kRobot + "payload_kg: 5\n") +
                                              "\npart: {mesh: part.stl}\n"),
                        {at("job.yaml", "13:3: robot.payload_kg: unknown key"),
                         "expected one of: allowed_collisions, controller, dh, links"}));
}

TEST_F(JobFile, WrongTypesSayWhatWasExpected) {
  EXPECT_TRUE(loadFails(
      writeJob("table: {radius_mm: abc}\n"),
      {at("job.yaml", "3:20: table.radius_mm: 'abc' is not a number"), "a finite number > 0"}));
  EXPECT_TRUE(loadFails(writeJob("table:\n  radius_mm: \"250 mm\"\n"),
                        {at("job.yaml", "4:14: table.radius_mm: '250 mm' is not a number"),
                         "the unit is part of the key name, radius_mm"}));
  EXPECT_TRUE(
      loadFails(writeJob("table: {continuous: maybe}\n"),
                {at("job.yaml", "3:"), "table.continuous: 'maybe'", "expected true or false"}));
  EXPECT_TRUE(
      loadFails(writeJob("robot_base: {xyz_mm: [1, 2]}\n"),
                {at("job.yaml", "3:"), "robot_base.xyz_mm: a list of 2", "a list of 3 numbers"}));
  EXPECT_TRUE(loadFails(writeJob("table: {axis: 5}\n"),
                        {at("job.yaml", "3:"), "table.axis: '5': expected a mapping"}));
}

TEST_F(JobFile, YamlThatParsesButIsAmbiguousIsRejected) {
  // yaml-cpp keeps the first of two equal keys; a job file must say which one it means.
  EXPECT_TRUE(loadFails(writeJob("table: {radius_mm: 100, radius_mm: 300}\n"),
                        {at("job.yaml", "3:"), "table.radius_mm: duplicate key", "line 3"}));
  EXPECT_TRUE(loadFails(writeJob("part: {mesh: part.stl, scale: 0}\n"),
                        {at("job.yaml", "3:1: part: duplicate key (first given on line 2)")}));
  EXPECT_TRUE(loadFails(writeJob("[1, 2]: 3\n"),
                        {at("job.yaml", "3:1:"), "a list used as a key", "a plain key name"}));
  EXPECT_TRUE(loadFails(writeJob("table: {~: 1}\n"), {"table:", "used as a key"}));
  // An empty value is not "use the default": the user wrote the key for a reason.
  EXPECT_TRUE(loadFails(writeJob("table:\n  radius_mm:\n"),
                        {at("job.yaml", "4:"), "table.radius_mm: empty value",
                         "leave the key out to use the default"}));
  // A fraction where a whole number belongs is a number, just not a whole one.
  EXPECT_TRUE(throwsInputError(
      [&] {
        config::loadRobotFile(
            write("r.yaml", replaced(kRobot, "signs: [1, 1,", "signs: [1, 1.5,")));
      },
      {"opw.signs[1]: '1.5' is not a whole number"}));
  // Too large is out of range, not a unit problem.
  EXPECT_TRUE(loadFails(writeJob("table: {radius_mm: 1e400}\n"), {"table.radius_mm"}));
  try {
    config::loadJob(writeJob("table: {radius_mm: 1e400}\n"));
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).find("unit"), std::string::npos) << e.what();
  }
}

TEST_F(JobFile, MissingRequiredFieldsAreNamed) {
  write("robot.yaml", kRobot);
  EXPECT_TRUE(loadFails(write("job.yaml", "robot: robot.yaml\n"),
                        {at("job.yaml", "1:1: part: required field is missing")}));
  EXPECT_TRUE(loadFails(writeJob("", replaced(kRobot, "  - {a_mm: 270, d_mm: 0,", "  - {d_mm: 0,")),
                        {at("robot.yaml", "4:"), "dh[1].a_mm: required field is missing"}));
  write("robot.yaml", kRobot);
  EXPECT_TRUE(loadFails(write("job.yaml", "robot: robot.yaml\npart: {units: m}\n"),
                        {at("job.yaml", "2:7: part.mesh: required field is missing")}));
  EXPECT_TRUE(loadFails(write("job.yaml", "part: {mesh: part.stl}\n"),
                        {at("job.yaml", "1:1: robot: required field is missing")}));
  EXPECT_TRUE(loadFails(writeJob("scanner: {body: [{size_mm: [1, 1, 1]}]}\n"),
                        {at("job.yaml", "3:"), "scanner.body[0].type: required field is missing"}));
  EXPECT_TRUE(
      loadFails(writeJob("scanner: {body: [{type: box}]}\n"),
                {at("job.yaml", "3:"), "scanner.body[0].size_mm: required field is missing"}));
}

TEST_F(JobFile, OutOfRangeValuesAreRejected) {
  EXPECT_TRUE(
      loadFails(writeJob("table: {radius_mm: -5}\n"),
                {at("job.yaml", "3:"), "table.radius_mm: -5: expected a finite number > 0"}));
  EXPECT_TRUE(loadFails(
      writeJob("table: {min_deg: 90, max_deg: 90}\n"),
      {at("job.yaml", "3:"), "table.max_deg: 90: expected a limit greater than min_deg (90)"}));
  EXPECT_TRUE(
      loadFails(writeJob("table: {height_mm: .nan}\n"),
                {at("job.yaml", "3:"), "table.height_mm: nan: expected a finite number > 0"}));
  EXPECT_TRUE(
      loadFails(writeJob("robot_base: {xyz_mm: [0, .inf, 0]}\n"),
                {at("job.yaml", "3:"), "robot_base.xyz_mm[1]: inf: expected a finite number"}));
  EXPECT_TRUE(loadFails(
      writeJob("table: {tilt_deg: [0, 11]}\n"),
      {at("job.yaml", "3:"), "table.tilt_deg[1]: 11: expected a finite number in [-10, 10]"}));
  EXPECT_TRUE(
      loadFails(writeJob("", replaced(kRobot, "max_deg: 45,", "max_deg: -190,")),
                {at("robot.yaml", "4:"), "dh[1].max_deg: -190", "greater than min_deg (-190)"}));
  write("robot.yaml", kRobot);
  EXPECT_TRUE(loadFails(write("job.yaml", "robot: robot.yaml\npart: {mesh: part.stl, scale: 0}\n"),
                        {at("job.yaml", "2:"), "part.scale: 0: expected a finite number > 0"}));
  EXPECT_TRUE(
      loadFails(write("job.yaml", "robot: robot.yaml\npart: {mesh: part.stl, units: inch}\n"),
                {at("job.yaml", "2:31: part.units: 'inch': expected one of mm, m")}));
  EXPECT_TRUE(loadFails(writeJob("scanner: {body: [{type: cone}]}\n"),
                        {at("job.yaml", "3:"),
                         "scanner.body[0].type: 'cone': expected one of box, sphere, cylinder, "
                         "capsule, mesh"}));
  // How the maps measure link meshes.
  EXPECT_TRUE(loadFails(writeJob("constraints: {clearance: {link_meshes: convex}}\n"),
                        {at("job.yaml", "3:"),
                         "constraints.clearance.link_meshes: 'convex': expected one of auto, "
                         "pieces, hull, exact"}));
  EXPECT_TRUE(loadFails(writeJob("constraints: {clearance: {hull_vertices: 4}}\n"),
                        {at("job.yaml", "3:"), "constraints.clearance.hull_vertices: 4"}));
  EXPECT_TRUE(loadFails(writeJob("constraints: {clearance: {hull_margin_mm: -1}}\n"),
                        {at("job.yaml", "3:"), "constraints.clearance.hull_margin_mm: -1"}));
  EXPECT_TRUE(loadFails(writeJob("constraints: {clearance: {piece_margin_mm: 0.1}}\n"),
                        {at("job.yaml", "3:"), "constraints.clearance.piece_margin_mm: 0.1"}));
  EXPECT_TRUE(loadFails(writeJob("constraints: {clearance: {max_pieces: 0}}\n"),
                        {at("job.yaml", "3:"), "constraints.clearance.max_pieces: 0"}));
  // The programs' payload and trigger.
  EXPECT_TRUE(loadFails(writeJob("scanner: {mass_kg: -1}\n"),
                        {at("job.yaml", "3:"), "scanner.mass_kg: -1"}));
  EXPECT_TRUE(
      loadFails(writeJob("scanner: {cog_mm: [0, 0]}\n"), {at("job.yaml", "3:"), "scanner.cog_mm"}));
  EXPECT_TRUE(loadFails(writeJob("outputs: {trigger: {output: 5000}}\n"),
                        {at("job.yaml", "3:"), "outputs.trigger.output: 5000"}));
  EXPECT_TRUE(loadFails(
      writeJob("outputs: {trigger: {output: 1, rapid_signal: 9bad}}\n"),
      {at("job.yaml", "3:"), "outputs.trigger.rapid_signal: '9bad'", "a RAPID identifier"}));
  EXPECT_TRUE(loadFails(writeJob("outputs: {servo_period_s: 5}\n"),
                        {at("job.yaml", "3:"), "outputs.servo_period_s: 5"}));
}

// Pair rules address bodies by name, glob and group: an obstacle named like a body, a group or
// a glob could not be told apart, and two obstacles of one name neither.
TEST_F(JobFile, ObstacleNamesMustBeTheirOwn) {
  for (const std::string name : {"part", "table", "scanner", "base", "link3", "robot", "obstacles",
                                 "post*", "fixture?", "[ab]"}) {
    EXPECT_TRUE(
        loadFails(writeJob("obstacles: [{name: '" + name + "', type: sphere, radius_mm: 20}]\n"),
                  {at("job.yaml", "3:"), "obstacles[0].name: " + name, "a name of its own"}))
        << name;
  }
  EXPECT_TRUE(loadFails(writeJob("obstacles: [{name: post, type: sphere, radius_mm: 20}, "
                                 "{name: post, type: box, size_mm: [10, 10, 10]}]\n"),
                        {at("job.yaml", "3:"), "two obstacles named 'post'"}));
  // Names that only look alike are fine.
  EXPECT_NO_THROW(config::loadJob(writeJob(
      "obstacles: [{name: link_plate, type: sphere, radius_mm: 20}, {name: parts_bin, type: "
      "sphere, radius_mm: 20}, {name: link, type: sphere, radius_mm: 5}]\n")));
}

// Changing c2 (upper arm length) in the OPW block alone moves the OPW flange 30 mm away from
// the DH flange; the check runs when the model is built.
TEST_F(JobFile, RobotFilesWhoseOpwDisagreesWithDhOrWithFiveRowsAreRejected) {
  const std::string bad_opw = replaced(kRobot, "c2_mm: 270", "c2_mm: 300");
  const fs::path robot = write("robot.yaml", bad_opw);
  const config::JobSpec job =
      config::loadJob(write("job.yaml", "robot: robot.yaml\npart: {mesh: part.stl}\n"));
  EXPECT_TRUE(throwsInputError(
      [&] { config::buildCell(job); },
      {robot.string() + ": robot 'test arm'", "the OPW parameters disagree with the DH chain"}));
  // Inline, the job file is the source.
  const config::JobSpec inline_job = config::loadJob(
      write("inline.yaml", "robot:\n" + indented(bad_opw) + "\npart: {mesh: part.stl}\n"));
  EXPECT_TRUE(throwsInputError([&] { config::buildCell(inline_job); },
                               {at("inline.yaml", " robot 'test arm'"), "OPW", "disagree"}));

  const std::size_t row6 = kRobot.find("  - {a_mm: 0,   d_mm: 80");
  const std::string five_rows = kRobot.substr(0, row6) + kRobot.substr(kRobot.find('\n', row6) + 1);
  EXPECT_TRUE(
      throwsInputError([&] { config::loadRobotFile(write("five.yaml", five_rows)); },
                       {at("five.yaml", "3:3: dh: a list of 5"), "expected exactly 6 entries"}));
}

// `controller:` says which program language the robot runs; `plan` writes that one and the CSV
// unless outputs.programs says otherwise.
TEST_F(JobFile, TheRobotsControllerChoosesTheDefaultPrograms) {
  const config::JobSpec demo = config::loadJob(kSource / "data/jobs/demo_rings.yaml");
  EXPECT_EQ(demo.robot.controller, "adept_vplus");
  EXPECT_EQ(demo.outputs.programs, (std::vector<std::string>{"vplus", "csv"}));
  const config::JobSpec kuka = config::loadJob(kSource / "data/jobs/kuka_demo.yaml");
  EXPECT_EQ(kuka.robot.controller, "kuka_krl");
  EXPECT_EQ(kuka.outputs.programs, (std::vector<std::string>{"krl", "csv"}));

  // No controller key: none, the CSV alone.
  const config::JobSpec plain = config::loadJob(writeJob(""));
  EXPECT_EQ(plain.robot.controller, "none");
  EXPECT_EQ(plain.outputs.programs, std::vector<std::string>{"csv"});
  EXPECT_TRUE(config::foreignPrograms(plain.robot, {"vplus", "krl"}).empty())
      << "no vendor, none foreign";

  const std::vector<std::pair<std::string, std::string>> languages = {{"adept_vplus", "vplus"},
                                                                      {"kuka_krl", "krl"},
                                                                      {"abb_rapid", "rapid"},
                                                                      {"ur_script", "urscript"}};
  for (const auto& [controller, language] : languages) {
    SCOPED_TRACE(controller);
    const config::JobSpec job =
        config::loadJob(writeJob("", "controller: " + controller + "\n" + kRobot));
    EXPECT_EQ(job.outputs.programs, (std::vector<std::string>{language, "csv"}));
    EXPECT_EQ(config::controllerProgramFormat(controller), language);
  }

  // outputs.programs overrides; another vendor's language is found (the CSV is nobody's).
  const config::JobSpec over = config::loadJob(kSource / "data/jobs/demo_rings.yaml",
                                               {"outputs.programs=[krl, vplus, csv, rapid]"});
  EXPECT_EQ(over.outputs.programs, (std::vector<std::string>{"krl", "vplus", "csv", "rapid"}));
  EXPECT_EQ(config::foreignPrograms(over.robot, over.outputs.programs),
            (std::vector<std::string>{"krl", "rapid"}));
  // export's --format names are case-insensitive.
  EXPECT_EQ(config::foreignPrograms(over.robot, {"VPLUS", "KRL"}), std::vector<std::string>{"KRL"});
  EXPECT_TRUE(config::loadJob(kSource / "data/jobs/demo_rings.yaml", {"outputs.programs=[]"})
                  .outputs.programs.empty());

  // `job show` prints it, and the printed job loads back to the same programs.
  const std::string shown = config::jobToYaml(kuka);
  EXPECT_NE(shown.find("controller: kuka_krl"), std::string::npos) << shown;
  EXPECT_EQ(config::loadJob(write("shown.yaml", shown)).outputs.programs, kuka.outputs.programs);
}

TEST_F(JobFile, AnUnknownControllerIsRejectedWithASuggestion) {
  const std::string expected = "expected one of adept_vplus, kuka_krl, abb_rapid, ur_script, none";
  EXPECT_TRUE(loadFails(writeJob("", "controller: adept\n" + kRobot),
                        {at("robot.yaml", "1:13: controller: 'adept': "), expected,
                         "(did you mean 'adept_vplus'?)"}));
  EXPECT_TRUE(loadFails(writeJob("", "controller: rapid\n" + kRobot),
                        {"controller: 'rapid'", "(did you mean 'abb_rapid'?)"}));
  EXPECT_TRUE(
      loadFails(writeJob("", "controller: fanuc\n" + kRobot), {"controller: 'fanuc'", expected}));
  EXPECT_TRUE(loadFails(writeJob("", "controller: [adept_vplus]\n" + kRobot),
                        {"controller: a list", expected}));
  // Inline robots too, their path under `robot`.
  EXPECT_TRUE(loadFails(
      write("inline.yaml",
            "robot:\n" + indented("controller: kuka\n" + kRobot) + "\npart: {mesh: part.stl}\n"),
      {at("inline.yaml", "2:15: robot.controller: 'kuka'"), "(did you mean 'kuka_krl'?)"}));
}

// from (0, 0, 0) → to (30, 40, 0) mm is a 3-4-5 triangle: length 50 mm, centred at (15, 20, 0)
// with z along (0.6, 0.8, 0); the cylinder along z from 10 to 130 mm is 120 mm long.
TEST_F(JobFile, EndPointShapesGetTheirLengthAndFrame) {
  const std::string shapes =
      "      - {type: capsule, radius_mm: 5, from_mm: [0, 0, 0], to_mm: [30, 40, 0]}\n"
      "      - {type: cylinder, radius_mm: 7, from_mm: [0, 0, 10], to_mm: [0, 0, 130]}\n";
  const kinematics::CellModel cell =
      config::buildCell(config::loadJob(writeJob("", kRobot + linksWith(shapes))));
  const auto& link = cell.robot.definition().links[1];
  EXPECT_EQ(link.name, "link1");
  ASSERT_EQ(link.shapes.size(), 2u);
  const auto& capsule = std::get<kinematics::Capsule>(link.shapes[0].geometry);
  EXPECT_NEAR(capsule.radius, 0.005, kLengthTol);
  EXPECT_NEAR(capsule.length, 0.05, kLengthTol);
  EXPECT_TRUE(link.shapes[0].X_BG.translation().isApprox(Eigen::Vector3d(0.015, 0.02, 0.0)));
  EXPECT_TRUE(link.shapes[0].X_BG.linear().col(2).isApprox(Eigen::Vector3d(0.6, 0.8, 0.0)));
  const auto& cylinder = std::get<kinematics::Cylinder>(link.shapes[1].geometry);
  EXPECT_NEAR(cylinder.length, 0.12, kLengthTol);
  EXPECT_NEAR(link.shapes[1].X_BG.translation().z(), 0.07, kLengthTol);
}

TEST_F(JobFile, EndPointsTogetherWithLengthOrPoseAreRejected) {
  const std::string both =
      "      - {type: capsule, radius_mm: 5, from_mm: [0, 0, 0], to_mm: [0, 0, 1], length_mm: 1}\n";
  EXPECT_TRUE(loadFails(
      writeJob("", kRobot + linksWith(both)),
      {at("robot.yaml", "16:"), "links[1].shapes[0].from_mm: given with length_mm or pose",
       "either from_mm + to_mm or length_mm + pose"}));
  const std::string zero =
      "      - {type: cylinder, radius_mm: 5, from_mm: [1, 1, 1], to_mm: [1, 1, 1]}\n";
  EXPECT_TRUE(loadFails(
      writeJob("", kRobot + linksWith(zero)),
      {at("robot.yaml", "16:"), "links[1].shapes[0].to_mm: equal to from_mm", "positive length"}));
  EXPECT_TRUE(
      loadFails(writeJob("", kRobot + linksWith("      - {type: capsule, radius_mm: 5, "
                                                "from_mm: [0, 0, 0]}\n")),
                {at("robot.yaml", "16:"), "links[1].shapes[0].to_mm: required field is missing"}));
}

// A misspelt required key is reported as the unknown key it is, at its position, with the
// suggestion; a valid key that merely looks like the missing one is not blamed.
TEST_F(JobFile, AMisspeltRequiredKeyIsReportedAsTheUnknownKey) {
  EXPECT_TRUE(loadFails(
      writeJob("scan:\n  paths:\n    - {type: ring, height_mm: 35}\n"
               "    - {type: ring, hieght_mm: 70, tilt_deg: 35}\n"),
      {at("job.yaml", "6:20: scan.paths[1].hieght_mm: unknown key (did you mean 'height_mm'?)"),
       "expected one of:"}));
  EXPECT_TRUE(loadFails(
      writeJob("scan: {paths: [{type: ring, height: 70}]}\n"),
      {at("job.yaml", "3:29: scan.paths[0].height: unknown key (did you mean 'height_mm'?)")}));
  // No near miss: the missing key, as before.
  EXPECT_TRUE(
      loadFails(writeJob("scan: {paths: [{type: ring, colour: red}]}\n"),
                {at("job.yaml", "3:"), "scan.paths[0].height_mm: required field is missing"}));
  // `b` is one edit from `a`, but a valid key of a pair rule.
  EXPECT_TRUE(loadFails(writeJob("constraints: {clearance: {pairs: [{b: part, exclude: true}]}}\n"),
                        {at("job.yaml", "3:"),
                         "constraints.clearance.pairs[0].a: required field is "
                         "missing"}));
  EXPECT_TRUE(loadFails(write("job.yaml", "robto: robot.yaml\npart: {mesh: part.stl}\n"),
                        {at("job.yaml", "1:1: robto: unknown key (did you mean 'robot'?)")}));
}

TEST_F(JobFile, SuggestionsCoverAKeyWithoutItsUnitOrPluralEnding) {
  EXPECT_TRUE(loadFails(
      writeJob("scanner: {optics: {phi: 60}}\n"),
      {at("job.yaml", "3:20: scanner.optics.phi: unknown key (did you mean 'phi_deg'?)")}));
  EXPECT_TRUE(loadFails(writeJob("table: {max_speed: 20}\n"),
                        {"table.max_speed: unknown key (did you mean 'max_speed_deg_s'?)"}));
  EXPECT_EQ(config::suggestKey("repeat", {"jobs", "set", "vary", "cases", "repeats"}), "repeats");
  EXPECT_EQ(config::suggestKey("radius", {"axis", "radius_mm", "height_mm"}), "radius_mm");
  EXPECT_EQ(config::suggestKey("radius_m", {"axis", "radius_mm", "height_mm"}), "radius_mm");
  EXPECT_EQ(config::suggestKey("colour", {"axis", "radius_mm", "height_mm"}), "");
}

// A bad value given with --set is blamed on the override, never on a made-up place in the file.
TEST_F(JobFile, OverrideErrorsNameTheOverride) {
  const fs::path job = writeJob("scan: {paths: [{type: raster}]}\n");
  const auto fails = [&](const std::string& override, std::initializer_list<std::string> parts) {
    return throwsInputError([&] { config::loadJob(job, {override}); }, parts);
  };
  EXPECT_TRUE(fails("table.radius_m=5", {"--set table.radius_m=5: table.radius_m: unknown key "
                                         "(did you mean 'radius_mm'?)"}));
  EXPECT_TRUE(fails("table.axis.xyz_mm=[600,0]",
                    {"--set table.axis.xyz_mm=[600,0]: table.axis.xyz_mm: a list of 2",
                     "expected a list of 3 numbers"}));
  EXPECT_TRUE(fails("table.axis.xyz_mm=[600,x,0]",
                    {"--set table.axis.xyz_mm=[600,x,0]: table.axis.xyz_mm[1]: 'x' is not a "
                     "number"}));
  EXPECT_TRUE(fails("table.radius_mm=abc",
                    {"--set table.radius_mm=abc: table.radius_mm: 'abc' is not a number",
                     "expected a finite number > 0"}));
  EXPECT_TRUE(fails("planner.nope.x=1", {"--set planner.nope.x=1: planner.nope: unknown key"}));
  EXPECT_TRUE(fails("scan.paths[0]={type: ring}",
                    {"--set scan.paths[0]={type: ring}: scan.paths[0].height_mm: required field "
                     "is missing"}));
  // A second YAML document inside a value would be dropped: refused, naming its line.
  EXPECT_TRUE(fails("table.axis.xyz_mm=[600,0,0]\n---\n[1,2,3]",
                    {"the value holds a second YAML document at its line 2"}));
  EXPECT_NO_THROW(config::loadJob(job, {"table.axis.xyz_mm=[600,0,0]\n...\n"}));
  for (const std::string o : {"table.radius_m=5", "table.axis.xyz_mm=[600,0]"}) {
    try {
      config::loadJob(job, {o});
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).find("job.yaml"), std::string::npos) << e.what();
    }
  }
  // Errors in the file itself keep their place, overrides or not.
  EXPECT_TRUE(throwsInputError(
      [&] { config::loadJob(writeJob("table: {radius_mm: -5}\n"), {"table.height_mm=100"}); },
      {at("job.yaml", "3:20: table.radius_mm: -5")}));
}

// The job path in messages and in JobSpec::source is the one the caller gave.
TEST_F(JobFile, SourceIsThePathAsGiven) {
  const fs::path job = writeJob("");
  const fs::path relative = fs::relative(job);
  ASSERT_TRUE(relative.is_relative());
  EXPECT_EQ(config::loadJob(relative).source, relative);
  EXPECT_NE(config::jobToYaml(config::loadJob(relative)).find(job.string()), std::string::npos)
      << "job show names the resolved file";
}

// Numbers no cell can mean stop at the reader, before they reach Embree or FCL (a ring height of
// 1e300 mm aborted inside Embree): lengths within a kilometre, everything within 1e9.
// Image mode's keys (docs/job-file.md): each bad value is refused naming its key; image mode
// with two cameras or with point noise names the scanner key it conflicts with.
TEST(JobImageMode, BadKeysAreRefusedNamingTheKey) {
  const fs::path demo = kSource / "data/jobs/demo_rings.yaml";
  const auto fails = [&](std::vector<std::string> overrides,
                         std::initializer_list<std::string> parts) {
    return throwsInputError([&] { config::loadJob(demo, overrides); }, parts);
  };
  EXPECT_TRUE(fails({"simulation.mode=raytrace"}, {"simulation.mode", "raytrace", "image"}));
  EXPECT_TRUE(fails({"scanner.camera.rows=1"}, {"scanner.camera.rows", "1"}));
  EXPECT_TRUE(fails({"scanner.camera.columns=-3"}, {"scanner.camera.columns", "-3"}));
  EXPECT_TRUE(fails({"scanner.camera.noise_grey=-1"}, {"scanner.camera.noise_grey"}));
  EXPECT_TRUE(fails({"scanner.camera.threshold_grey=300"}, {"scanner.camera.threshold_grey"}));
  EXPECT_TRUE(fails({"scanner.camera.detection=median"},
                    {"scanner.camera.detection", "median", "cog", "gauss"}));
  EXPECT_TRUE(fails({"scanner.camera.pixels=3"}, {"scanner.camera", "pixels"}));
  EXPECT_TRUE(fails({"scanner.laser.thickness_mm=0"}, {"scanner.laser.thickness_mm", "0"}));
  EXPECT_TRUE(fails({"simulation.reflectance.lambert=-0.5"}, {"simulation.reflectance.lambert"}));
  EXPECT_TRUE(fails({"simulation.reflectance.shininess=-2"}, {"simulation.reflectance.shininess"}));
  EXPECT_TRUE(fails({"simulation.profile_images=-1"}, {"simulation.profile_images"}));
  EXPECT_TRUE(fails({"simulation.mode=image", "scanner.cameras=both"},
                    {"scanner.cameras", "both", "simulation.mode: image"}));
  EXPECT_TRUE(fails({"simulation.mode=image", "scanner.noise.longitudinal_mm=0.02"},
                    {"scanner.noise.longitudinal_mm", "0.02", "noise_grey"}));
  // Bounded work: an image of more than 2048 × 2048 pixels, named by the key that made it.
  EXPECT_TRUE(fails({"simulation.mode=image", "scanner.camera={rows: 4096, columns: 2048}"},
                    {"scanner.camera.columns", "8388608 pixels", "4194304"}));
  EXPECT_TRUE(fails({"simulation.mode=image", "scanner.rays_per_profile=20000"},
                    {"scanner.rays_per_profile", "5120000 pixels"}));
  // The kept profile images together, and a threshold the ambient light already reaches.
  EXPECT_TRUE(fails({"simulation.mode=image", "scanner.camera={rows: 2048, columns: 2048}",
                     "simulation.profile_images=20"},
                    {"simulation.profile_images", "20 images", "67108864"}));
  EXPECT_TRUE(fails({"simulation.mode=image", "scanner.camera={ambient_grey: 50}"},
                    {"scanner.camera.threshold_grey", "40", "ambient_grey (50)"}));
  // The same keys with good values load.
  const config::JobSpec job = config::loadJob(
      demo, {"simulation.mode=image",
             "scanner.camera={rows: 300, columns: 150, noise_grey: 2, "
             "detection: gauss}",
             "scanner.laser.thickness_mm=0.8",
             "simulation.reflectance={lambert: 0.5, specular: 0.3, shininess: 40}"});
  EXPECT_EQ(job.simulation.mode, "image");
  EXPECT_EQ(job.scanner.camera.rows, 300);
  EXPECT_EQ(job.scanner.camera.columns, 150);
  EXPECT_EQ(job.scanner.camera.detection, "gauss");
  EXPECT_DOUBLE_EQ(job.scanner.laser.thickness_mm, 0.8);
  EXPECT_DOUBLE_EQ(job.simulation.reflectance.specular, 0.3);
}

TEST(JobLimits, HugeNumbersAreRefusedNamingTheKey) {
  const auto error = [](const std::string& set) {
    try {
      config::loadJob(kSource / "data/jobs/demo_rings.yaml", {set});
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string ring = error("scan.paths[0].height_mm=1e300");
  EXPECT_NE(ring.find("scan.paths[0].height_mm: 1e+300: expected a number within ±1e+06"),
            std::string::npos)
      << ring;
  const std::string base = error("robot_base.xyz_mm=[0, 2e6, 0]");
  EXPECT_NE(base.find("robot_base.xyz_mm[1]"), std::string::npos) << base;
  EXPECT_NE(base.find("±1e+06"), std::string::npos) << base;
  const std::string rate = error("scanner.frame_rate_hz=1e12");
  EXPECT_NE(rate.find("scanner.frame_rate_hz"), std::string::npos) << rate;
  EXPECT_EQ(error("scan.paths[0].height_mm=900000"), "no error");  // within: it may not see the
                                                                   // part, the path says so
}

// A billion-laughs alias bomb in a 340-byte --set value took all memory ("internal error:
// std::bad_alloc" under a 4 GB limit); runaway nesting too. Both stop at the reader, quickly.
TEST(JobLimits, AliasBombsAndDeepNestingAreRefused) {
  std::string bomb = "{a: &a [x,x,x,x,x,x,x,x,x,x]";
  std::string previous = "a";
  for (const std::string k : {"b", "c", "d", "e", "f", "g", "h", "i"}) {
    bomb += ", " + k + ": &" + k + " [";
    for (int n = 0; n < 10; ++n) bomb += (n ? ",*" : "*") + previous;
    bomb += "]";
    previous = k;
  }
  bomb += "}";
  try {
    config::loadJob(kSource / "data/jobs/demo_rings.yaml", {"name=" + bomb});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("expands to more than 1000000 nodes"), std::string::npos) << what;
    EXPECT_LT(what.size(), 400u) << "the value is quoted clipped";
  }
  const fs::path deep = fs::temp_directory_path() / "scanplan_test_deep.yaml";
  std::ofstream(deep) << "name: " << std::string(200, '[') << std::string(200, ']') << "\n";
  try {
    config::loadJob(deep);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("nests deeper than 64 levels"), std::string::npos)
        << e.what();
  }
  fs::remove(deep);
}

// Robustness catalogue: part.scale = 1e7 was accepted and refused only later, by a
// ring that never saw the part, without naming the scale. The part's size is checked at load.
TEST_F(JobFile, APartLargerThanTheLengthLimitIsRefusedNamingTheScale) {
  write("tri.off", "OFF\n3 1 0\n0 0 0\n100 0 0\n0 100 0\n3 0 1 2\n");  // 100 mm across
  for (const char* place : {"table", "none"}) {
    SCOPED_TRACE(place);
    const fs::path file =
        write("big.yaml", std::string("robot: robot.yaml\npart: {mesh: tri.off, scale: 1e7, ") +
                              "place: " + place + "}\n");
    write("robot.yaml", kRobot);
    const config::JobSpec job = config::loadJob(file);
    EXPECT_TRUE(
        throwsInputError([&] { config::loadPartMesh(job, config::buildCell(job).part); },
                         {file.string() + ": part.scale: 1e+07: the part is 1e+09 mm across",
                          "expected a part at most 1000000 mm across"}));
  }
  write("fine.yaml", "robot: robot.yaml\npart: {mesh: tri.off, scale: 1e4}\n");  // 1 km: within
  const config::JobSpec fine = config::loadJob(dir_ / "fine.yaml");
  EXPECT_NO_THROW(config::loadPartMesh(fine, config::buildCell(fine).part));
}

// Robustness catalogue: a FIFO as the job file was read until a writer came, forever.
TEST_F(JobFile, FifoAsJobOrRobotFileIsRefusedNotReadForever) {
  const fs::path fifo = dir_ / "job.yaml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  EXPECT_TRUE(loadFails(fifo, {"job.yaml", "not a regular file"}));
  EXPECT_TRUE(
      throwsInputError([&] { config::loadRobotFile(fifo); }, {"job.yaml", "not a regular file"}));
}

// What a terminal would not show is shown: a byte-order mark, zero-width and no-break spaces,
// control characters and bytes that are not UTF-8; printable UTF-8 and line breaks stay.
TEST(VisibleText, InvisibleCharactersAreNamedAndPrintableTextKept) {
  EXPECT_EQ(visibleText("\xEF\xBB\xBFrobot.yaml"), "<U+FEFF>robot.yaml");
  EXPECT_EQ(visibleText("a\xE2\x80\x8B"
                        "b\xC2\xA0"
                        "c"),
            "a<U+200B>b<U+00A0>c");
  EXPECT_EQ(visibleText("0.1\r\tx\x01\x7F"), "0.1\\r\\tx\\x01\\x7F");
  EXPECT_EQ(visibleText("x\xFF\xC3"), "x\\xFF\\xC3");         // not UTF-8, and a cut sequence
  EXPECT_EQ(visibleText("\xC0\xAF"), "\\xC0\\xAF");           // an overlong '/'
  EXPECT_EQ(visibleText("\xED\xA0\x80"), "\\xED\\xA0\\x80");  // a surrogate
  const std::string plain =
      "90\xC2\xB0 \xE2\x80\xA6 2\xC3\x97"
      "3\nnext line \xF0\x9F\x99\x82";
  EXPECT_EQ(visibleText(plain), plain);
  // Every InputError's message is shown so, wherever it is printed.
  EXPECT_STREQ(InputError("part.mesh: '\xEF\xBB\xBFm.stl'").what(), "part.mesh: '<U+FEFF>m.stl'");
}

}  // namespace
}  // namespace scanplan::cli
