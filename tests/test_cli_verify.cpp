// `validate`, `simulate` and `export` end to end, on a trajectory planned from the (lightened)
// demo: a valid plan passes, an obstacle in its way is caught with time and contact point, a
// malformed row names its line, the cloud lies on the part, programs read back and validate.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <scanplan/config/job.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/trajectory.h>
#include <scanplan/kinematics/units.h>
#include "cli/io/program_files.h"
#include "cli/report/verify_report.h"
#include "cli_support.h"
#include "geometry_support.h"
#include "test_support.h"
#include "tests/io_support.h"

namespace {

using namespace scanplan;
using namespace scanplan::test;

const fs::path kSourceDir = SCANPLAN_SOURCE_DIR;
const std::string kDemoJob = (kSourceDir / "data/jobs/demo_rings.yaml").string();

std::vector<std::string> withLightDemo(std::vector<std::string> args) {
  for (const std::string& o : kLightDemo) {
    args.push_back("--set");
    args.push_back(o);
  }
  return args;
}

class CliVerify : public Cli {
 protected:
  // One planned trajectory for the whole suite (planning takes about a second).
  static void SetUpTestSuite() {
    planned_ = fs::temp_directory_path() / ("scanplan_test_verify_" + std::to_string(::getpid()));
    fs::remove_all(planned_);
  }
  static void TearDownTestSuite() { fs::remove_all(planned_); }

  fs::path plannedTrajectory() {
    if (!fs::exists(planned_ / "trajectory.csv")) {
      const Result run = scanplan(withLightDemo(
          {"plan", kDemoJob, "-o", planned_.string(), "--set", "simulation.enabled=false"}));
      EXPECT_EQ(run.exit_code, 0) << describe(run);
    }
    return planned_ / "trajectory.csv";
  }

  static fs::path planned_;
};
fs::path CliVerify::planned_;

TEST_F(CliVerify, ValidPlanValidatesAndWritesItsReport) {
  const fs::path trajectory = plannedTrajectory();
  const Result run = scanplan(withLightDemo(
      {"validate", kDemoJob, "-t", trajectory.string(), "-o", (dir_ / "v").string()}));
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_TRUE(contains(run.out, "validation valid")) << run.out;
  const YAML::Node r = YAML::LoadFile((dir_ / "v" / "validation.json").string());
  EXPECT_TRUE(r["validation"]["valid"].as<bool>());
  EXPECT_EQ(r["validation"]["violations"].size(), 0u);
  EXPECT_GT(r["validation"]["proven_clearance_mm"].as<double>(), 0.0);
}

// A post placed where the scanner passes halfway through the plan: validation must find the
// collision, say when and where, and exit 3.
TEST_F(CliVerify, ObstacleInThePathIsACollisionWithTimeAndContactPoint) {
  const fs::path file = plannedTrajectory();
  const kinematics::Trajectory t = kinematics::parseTrajectoryCsv(readFile(file), file.string());
  const config::JobSpec job = config::loadJob(kDemoJob, kLightDemo);
  const kinematics::CellModel cell = config::buildCell(job);
  const auto& mid = t.samples[t.samples.size() / 2];
  // The scanner's origin in the world at that sample, 40 mm back along its axis (inside the
  // housing, clear of the part).
  const Eigen::Isometry3d X_WS = cell.X_WB * cell.robot.fk(mid.q) * cell.scanner.X_FS;
  const Eigen::Vector3d p = (X_WS * Eigen::Vector3d(0, 0, -0.04)) * kMToMm;
  const std::string post = fmt::format(
      "obstacles=[{{name: post, type: box, size_mm: [20, 20, 20], pose: {{xyz_mm: [{:.3f}, {:.3f}, "
      "{:.3f}]}}}}]",
      p.x(), p.y(), p.z());
  const Result run =
      scanplan(withLightDemo({"validate", kDemoJob, "-t", file.string(), "--json", "--set", post}));
  EXPECT_EQ(run.exit_code, 3) << describe(run);
  const YAML::Node r = YAML::Load(run.out)["validation"];
  EXPECT_FALSE(r["valid"].as<bool>());
  bool found = false;
  for (const auto& v : r["violations"]) {
    if (v["kind"].as<std::string>() != "collision") continue;
    if (!contains(v["what"].as<std::string>(), "post")) continue;
    found = true;
    EXPECT_LE(v["start_s"].as<double>(), mid.t + 1e-9);
    // The contact point lies on the 20 mm post (within the 0.1 mm resolution and GJK slack).
    const Eigen::Vector3d c(v["contact_mm"][0].as<double>(), v["contact_mm"][1].as<double>(),
                            v["contact_mm"][2].as<double>());
    EXPECT_LT((c - p).cwiseAbs().maxCoeff(), 10.0 + 0.5) << c.transpose();
  }
  EXPECT_TRUE(found) << run.out;
}

TEST_F(CliVerify, MalformedTrajectoryRowIsAnInputErrorNamingTheLine) {
  std::string text = readFile(plannedTrajectory());
  // Break the third data row (line 4 of the file): a joint that is not a number.
  std::size_t at = 0;
  for (int line = 1; line < 4; ++line) at = text.find('\n', at) + 1;
  const std::size_t comma = text.find(',', text.find(',', text.find(',', at) + 1) + 1);
  text.insert(comma + 1, "x");
  const fs::path broken = dir_ / "broken.csv";
  writeFile(broken, text);
  for (const char* cmd : {"validate", "simulate", "export"}) {
    SCOPED_TRACE(cmd);
    const Result run =
        scanplan({cmd, kDemoJob, "-t", broken.string(), "-o", (dir_ / "o").string()});
    EXPECT_EQ(run.exit_code, 4) << describe(run);
    EXPECT_TRUE(contains(run.err, broken.string() + ":4: column j2_deg")) << run.err;
  }
  EXPECT_TRUE(tmpFiles(dir_).empty());
}

// Robustness catalogue: a trajectory too long to densify at the frame rate was
// refused without naming the trajectory file.
TEST_F(CliVerify, TrajectoryTooLongToCheckIsAnInputErrorNamingItsFile) {
  std::string text = readFile(plannedTrajectory());
  while (text.back() == '\n') text.pop_back();
  const std::size_t last = text.rfind('\n') + 1;
  text.replace(last, text.find(',', last) - last, "100000");
  const fs::path file = dir_ / "long.csv";
  writeFile(file, text + "\n");
  for (const char* cmd : {"validate", "simulate"}) {
    SCOPED_TRACE(cmd);
    const Result run = scanplan({cmd, kDemoJob, "-t", file.string(), "-o", (dir_ / "o").string()});
    EXPECT_EQ(run.exit_code, 4) << describe(run);
    EXPECT_TRUE(contains(run.err, file.string() + ": the trajectory's 100000 s")) << run.err;
  }
}

TEST_F(CliVerify, SimulatedCloudLiesOnThePartAndCoverageIsReported) {
  const fs::path out = dir_ / "sim";
  const Result run = scanplan(withLightDemo(
      {"simulate", kDemoJob, "-t", plannedTrajectory().string(), "-o", out.string()}));
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  for (const char* f : {"cloud.ply", "coverage.ply", "cloud.png", "simulation.json"}) {
    EXPECT_TRUE(fs::exists(out / f)) << f;
  }
  std::ifstream in(out / "cloud.ply", std::ios::binary);
  const test::PlyVertices cloud = test::readPlyVertices(in, "cloud.ply");
  ASSERT_GT(cloud.count, 1000u);
  EXPECT_EQ(cloud.format, "binary_little_endian");
  // Points in the part frame, mm: inside the part's box grown by a hair, or on the table top
  // (z ≈ 0) around it.
  const config::JobSpec job = config::loadJob(kDemoJob);
  const kinematics::CellModel cell = config::buildCell(job);
  const auto part = kinematics::loadMesh(cell.part.mesh.path, cell.part.mesh.options).mesh;
  const Eigen::AlignedBox3d box = part.bounds();
  std::size_t on_part_box = 0, on_table = 0;
  for (std::size_t i = 0; i < cloud.count; ++i) {
    const Eigen::Vector3d p(cloud.column("x")[i], cloud.column("y")[i], cloud.column("z")[i]);
    const Eigen::Vector3d m = p * kMmToM;
    if (box.exteriorDistance(m) < 1e-6) {
      ++on_part_box;
    } else if (std::abs(p.z()) < 1e-3) {
      ++on_table;
    }
  }
  EXPECT_EQ(on_part_box + on_table, cloud.count);
  EXPECT_GT(on_part_box, cloud.count / 2);
  const YAML::Node r = YAML::LoadFile((out / "simulation.json").string())["simulation"];
  EXPECT_GT(r["coverage"]["covered_fraction"].as<double>(), 0.05);
  EXPECT_LE(r["coverage"]["covered_fraction"].as<double>(), 1.0);
  EXPECT_EQ(r["points"].as<std::size_t>(), cloud.count);
}

// Image mode end to end: the cloud and its report as in geometric mode, plus the profile
// images (camera image beside the same with the stripe marked, 2 × 2 per pixel); with sensor
// noise, the same seed gives the same cloud.ply bytes.
TEST_F(CliVerify, ImageModeWritesTheCloudAndProfileImagesDeterministically) {
  const std::vector<std::string> image = {"--set",
                                          "simulation.mode=image",
                                          "--set",
                                          "scanner.camera={rows: 64, columns: 50, "
                                          "noise_grey: 3}",
                                          "--set",
                                          "simulation.profile_images=3",
                                          "--set",
                                          "scanner.frame_rate_hz=20"};
  std::vector<std::string> args[2];
  for (int k = 0; k < 2; ++k) {
    args[k] = withLightDemo({"simulate", kDemoJob, "-t", plannedTrajectory().string(), "-o",
                             (dir_ / ("image" + std::to_string(k))).string()});
    args[k].insert(args[k].end(), image.begin(), image.end());
    const Result run = scanplan(args[k]);
    ASSERT_EQ(run.exit_code, 0) << describe(run);
    EXPECT_NE(run.out.find("camera images"), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("profiles/"), std::string::npos) << run.out;
  }
  const fs::path out = dir_ / "image0";
  const YAML::Node r = YAML::LoadFile((out / "simulation.json").string())["simulation"];
  EXPECT_EQ(r["pixel_rays"].as<std::size_t>(), r["profiles"].as<std::size_t>() * 64 * 50);
  EXPECT_GT(r["points"].as<std::size_t>(), 1000u);
  std::size_t pngs = 0;
  for (const auto& entry : fs::directory_iterator(out / "profiles")) {
    ++pngs;
    EXPECT_EQ(entry.path().extension(), ".png");
    std::ifstream in(entry.path(), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), {});
    const cli::RgbImage picture = test::decodePng(bytes);
    EXPECT_EQ(picture.width, 2 * (2 * 50 + 4));
    EXPECT_EQ(picture.height, 2 * 64);
  }
  EXPECT_EQ(pngs, 3u);
  const auto bytes = [](const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), {});
  };
  EXPECT_TRUE(bytes(out / "cloud.ply") == bytes(dir_ / "image1" / "cloud.ply"));
}

// Coverage on area, recomputed independently from what a user gets: cloud.ply's points on the
// part (the table top, z = 0, left out as the simulation leaves out points on other bodies)
// against this test's own area samples (random by area, not systematic), nearest point through a
// voxel hash instead of a k-d tree, at the report's point spacing: within 1 % of the report.
TEST_F(CliVerify, AreaCoverageRecomputedFromTheCloudFileMatchesTheReport) {
  const fs::path out = dir_ / "sim";
  ASSERT_EQ(scanplan(withLightDemo({"simulate", kDemoJob, "-t", plannedTrajectory().string(), "-o",
                                    out.string()}))
                .exit_code,
            0);
  const YAML::Node c = YAML::LoadFile((out / "simulation.json").string())["simulation"]["coverage"];
  const double reported = c["area_fraction"].as<double>();
  const double radius_mm = c["point_spacing_mm"].as<double>();
  ASSERT_GT(radius_mm, 0.0);
  std::ifstream in(out / "cloud.ply", std::ios::binary);
  const test::PlyVertices cloud = test::readPlyVertices(in, "cloud.ply");
  // Voxels of the radius: a point within the radius of a sample is in one of the 27 around it.
  std::unordered_map<std::int64_t, std::vector<Eigen::Vector3d>> voxels;
  const auto key = [&](const Eigen::Vector3d& p, int dx, int dy, int dz) {
    const auto q = [&](double v, int d) {
      return static_cast<std::int64_t>(std::floor(v / radius_mm)) + d + (1 << 20);
    };
    return (q(p.x(), dx) << 42) | (q(p.y(), dy) << 21) | q(p.z(), dz);
  };
  for (std::size_t i = 0; i < cloud.count; ++i) {
    const Eigen::Vector3d p(cloud.column("x")[i], cloud.column("y")[i], cloud.column("z")[i]);
    // Points on the table top (z = 0) are not the part's; a point counts within the incidence
    // limit (60° by default) only.
    if (std::abs(p.z()) >= 1e-3 && cloud.column("scalar_incidence_deg")[i] <= 60.0)
      voxels[key(p, 0, 0, 0)].push_back(p);
  }
  const config::JobSpec job = config::loadJob(kDemoJob);
  const kinematics::CellModel cell = config::buildCell(job);
  const auto part = kinematics::loadMesh(cell.part.mesh.path, cell.part.mesh.options).mesh;
  std::vector<double> areas;
  for (const auto& t : part.triangles) {
    const Eigen::Vector3d a = part.vertices[static_cast<std::size_t>(t.x())];
    areas.push_back(0.5 * (part.vertices[static_cast<std::size_t>(t.y())] - a)
                              .cross(part.vertices[static_cast<std::size_t>(t.z())] - a)
                              .norm());
  }
  std::mt19937 rng(5);
  std::discrete_distribution<std::size_t> pick(areas.begin(), areas.end());
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  constexpr int kSamples = 60000;  // binomial σ ≈ 0.002: 1 % is about 4.5 σ with the report's
  int covered = 0;
  for (int i = 0; i < kSamples; ++i) {
    const auto& t = part.triangles[pick(rng)];
    double u = u01(rng), v = u01(rng);
    if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
    const Eigen::Vector3d a = part.vertices[static_cast<std::size_t>(t.x())];
    const Eigen::Vector3d s =
        toMm(1.0) * (a + u * (part.vertices[static_cast<std::size_t>(t.y())] - a) +
                     v * (part.vertices[static_cast<std::size_t>(t.z())] - a));
    bool hit = false;
    for (int dx = -1; dx <= 1 && !hit; ++dx) {
      for (int dy = -1; dy <= 1 && !hit; ++dy) {
        for (int dz = -1; dz <= 1 && !hit; ++dz) {
          const auto it = voxels.find(key(s, dx, dy, dz));
          if (it == voxels.end()) continue;
          for (const auto& p : it->second) hit = hit || (p - s).norm() <= radius_mm;
        }
      }
    }
    covered += hit ? 1 : 0;
  }
  EXPECT_NEAR(static_cast<double>(covered) / kSamples, reported, 0.01)
      << "report " << reported << " at " << radius_mm << " mm";
  // And the triangle count overstates it (the reason for measuring on area).
  EXPECT_GE(c["covered_fraction"].as<double>(), reported);
  // The part's underside (downward triangles on the table top, z = 0) faces the table; the
  // reported share is at least its area (minus sampling noise) and far from all of it.
  double underside = 0.0, total = 0.0;
  for (std::size_t i = 0; i < part.triangles.size(); ++i) {
    const auto& t = part.triangles[i];
    const Eigen::Vector3d a = part.vertices[static_cast<std::size_t>(t.x())];
    const Eigen::Vector3d b = part.vertices[static_cast<std::size_t>(t.y())];
    const Eigen::Vector3d d = part.vertices[static_cast<std::size_t>(t.z())];
    const Eigen::Vector3d n = (b - a).cross(d - a).normalized();
    total += areas[i];
    if (n.z() < -0.999 && std::max({a.z(), b.z(), d.z()}) < 1e-9) underside += areas[i];
  }
  const double facing = c["faces_table_fraction"].as<double>();
  EXPECT_GT(underside / total, 0.05);
  EXPECT_GE(facing, underside / total - 0.005);
  EXPECT_LT(facing, 0.5);
}

// The cloud `plan` writes lies on the part: every sampled point off the table top is within
// 1e-4 mm of the part mesh (brute force over all triangles; the file stores float mm, so the
// bound is the float rounding of a ~100 mm coordinate, ~4e-6 mm, well inside it).
TEST_F(CliVerify, PlannedCloudPointsLieOnThePartSurface) {
  plannedTrajectory();
  const fs::path out = dir_ / "sim";
  ASSERT_EQ(scanplan(withLightDemo({"simulate", kDemoJob, "-t",
                                    (planned_ / "trajectory.csv").string(), "-o", out.string()}))
                .exit_code,
            0);
  std::ifstream in(out / "cloud.ply", std::ios::binary);
  const test::PlyVertices cloud = test::readPlyVertices(in, "cloud.ply");
  const config::JobSpec job = config::loadJob(kDemoJob);
  const kinematics::CellModel cell = config::buildCell(job);
  const auto part = kinematics::loadMesh(cell.part.mesh.path, cell.part.mesh.options).mesh;
  std::size_t checked = 0;
  double worst_mm = 0.0;
  for (std::size_t i = 0; i < cloud.count && checked < 300; i += cloud.count / 600 + 1) {
    const Eigen::Vector3d p(cloud.column("x")[i], cloud.column("y")[i], cloud.column("z")[i]);
    if (std::abs(p.z()) < 1e-3) continue;  // the table top around the part
    double best = std::numeric_limits<double>::infinity();
    for (const auto& t : part.triangles) {
      best = std::min(
          best, pointTriangleDistance(p * kMmToM, part.vertices[static_cast<std::size_t>(t.x())],
                                      part.vertices[static_cast<std::size_t>(t.y())],
                                      part.vertices[static_cast<std::size_t>(t.z())]));
    }
    worst_mm = std::max(worst_mm, toMm(best));
    ++checked;
  }
  EXPECT_GT(checked, 100u);
  EXPECT_LT(worst_mm, 1e-4);
}

TEST_F(CliVerify, BrokenPartMeshIsAnInputErrorWithNoOutputs) {
  const fs::path mesh = dir_ / "broken.stl";
  writeFile(mesh, "solid broken\n  facet normal 0 0 1\n    outer loop\n      vertex 0 0\n");
  const fs::path out = dir_ / "out";
  const Result run = scanplan(
      withLightDemo({"plan", kDemoJob, "-o", out.string(), "--set", "part.mesh=" + mesh.string()}));
  EXPECT_EQ(run.exit_code, 4) << describe(run);
  EXPECT_TRUE(contains(run.err, mesh.string())) << run.err;
  EXPECT_FALSE(fs::exists(out / "trajectory.csv"));
  EXPECT_TRUE(tmpFiles(dir_).empty());
}

TEST_F(CliVerify, ExportedProgramsReadBackAndValidate) {
  const fs::path trajectory = plannedTrajectory();
  const fs::path out = dir_ / "programs";
  const Result run = scanplan({"export", kDemoJob, "-t", trajectory.string(), "-o", out.string(),
                               "--format", "vplus,krl,rapid,urscript,csv"});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  for (const char* f :
       {"scan.v2", "scan_table.csv", "scan.src", "scan.mod", "scan.script", "scan.csv"}) {
    EXPECT_TRUE(fs::exists(out / f)) << f;
    EXPECT_TRUE(contains(run.out, f)) << "the summary names " << f << "\n" << run.out;
  }
  EXPECT_TRUE(contains(run.out, "programs   " + out.string() + ": ")) << "the folder as given\n"
                                                                      << run.out;
  // Every program loads back and passes validation (the seed's §7.3 point).
  for (const char* f : {"scan.v2", "scan.src", "scan.mod", "scan.script", "scan.csv"}) {
    SCOPED_TRACE(f);
    const Result v = scanplan(withLightDemo({"validate", kDemoJob, "-t", (out / f).string()}));
    EXPECT_EQ(v.exit_code, 0) << describe(v);
  }
  const Result bad = scanplan({"export", kDemoJob, "-t", trajectory.string(), "-o",
                               (dir_ / "x").string(), "--format", "vplus,gcode"});
  EXPECT_EQ(bad.exit_code, 4) << describe(bad);
  EXPECT_TRUE(contains(bad.err, "gcode")) << bad.err;
}

// A URScript program over the size a UR controller loads: `export` refuses it naming the limit
// (exit 4, nothing written); `plan` writes the rest of its programs and says which it left out.
TEST_F(CliVerify, AnOversizeUrscriptIsRefusedByExportAndLeftOutByPlan) {
  const config::JobSpec job = config::loadJob(kDemoJob);
  const pipeline::ScanProblem problem = config::toProblem(job);
  kinematics::Trajectory long_run;
  for (int k = 0; k < 9000; ++k) {  // about 130 bytes a row: 1.2 MB
    kinematics::TrajectorySample s;
    s.t = 0.1 * k;
    s.q << 0.1, -0.2 + 1e-5 * k, 2.0, 0.0, 0.5, 0.0;
    s.theta = 1e-3 * k;
    long_run.samples.push_back(s);
  }
  const fs::path csv = dir_ / "long.csv";
  writeFile(csv, kinematics::trajectoryToCsv(long_run));
  const Result run = scanplan({"export", kDemoJob, "-t", csv.string(), "-o", (dir_ / "ur").string(),
                               "--format", "urscript,csv"});
  EXPECT_EQ(run.exit_code, 4) << describe(run);
  EXPECT_TRUE(contains(run.err, "expected at most 1000000 bytes")) << run.err;
  EXPECT_FALSE(fs::exists(dir_ / "ur" / "scan.script"));

  const fs::path out = dir_ / "plan_programs";
  const std::string summary =
      cli::writePrograms(out, "programs/", job, problem.cell, long_run, {"urscript", "csv"}, true);
  EXPECT_TRUE(fs::exists(out / "scan.csv"));
  EXPECT_FALSE(fs::exists(out / "scan.script"));
  EXPECT_TRUE(contains(summary, "urscript NOT written (URScript program: ")) << summary;
}

// `plan` writes the robot controller's program and the CSV: for the Viper (adept_vplus) the V+
// program with its table list, and the CSV; no other vendor's language.
TEST_F(CliVerify, PlanWritesTheControllersProgramAndTheCsv) {
  const fs::path programs = plannedTrajectory().parent_path() / "programs";
  std::set<std::string> files;
  for (const auto& e : fs::directory_iterator(programs)) files.insert(e.path().filename().string());
  EXPECT_EQ(files, (std::set<std::string>{"scan.v2", "scan_table.csv", "scan.csv"}));
}

// The KUKA (kuka_krl) gets KRL and the CSV; outputs.programs overrides, with a warning on
// stderr and in the summary for another vendor's language.
TEST_F(CliVerify, ExportDefaultsToTheControllersLanguageAndWarnsOnAnotherVendors) {
  const fs::path trajectory = plannedTrajectory();
  const std::string kuka_job = (kSourceDir / "data/jobs/kuka_demo.yaml").string();
  const fs::path kuka = dir_ / "kuka";
  const Result run = scanplan({"export", kuka_job, "-t", trajectory.string(), "-o", kuka.string()});
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  std::set<std::string> files;
  for (const auto& e : fs::directory_iterator(kuka)) files.insert(e.path().filename().string());
  EXPECT_EQ(files, (std::set<std::string>{"scan.src", "scan.csv"}));
  EXPECT_FALSE(contains(run.out + run.err, "WARNING")) << describe(run);

  const fs::path mixed = dir_ / "mixed";
  const Result over = scanplan({"export", kDemoJob, "-t", trajectory.string(), "-o", mixed.string(),
                                "--set", "outputs.programs=[vplus, krl, csv]"});
  ASSERT_EQ(over.exit_code, 0) << describe(over);
  EXPECT_TRUE(fs::exists(mixed / "scan.src"));
  const std::string warning =
      "krl is not the language of robot 'Adept Viper s650' (controller adept_vplus, writes vplus)";
  EXPECT_TRUE(contains(over.out, "; WARNING: " + warning)) << over.out;
  EXPECT_TRUE(contains(over.err, "programs: " + warning)) << over.err;
}

TEST_F(CliVerify, UnwritableOutputFolderIsAnInputErrorWithNoPartialFiles) {
  // A folder inside a regular file cannot be created.
  const fs::path blocker = dir_ / "blocker";
  writeFile(blocker, "x");
  const Result run = scanplan(withLightDemo({"plan", kDemoJob, "-o", (blocker / "out").string()}));
  EXPECT_EQ(run.exit_code, 4) << describe(run);
  EXPECT_TRUE(contains(run.err, "scanplan: error:")) << run.err;
  EXPECT_TRUE(tmpFiles(dir_).empty());
}

}  // namespace

namespace {

// A closest approach nothing was measured for (every pair beyond its d_high) has no distance, no
// pair and no time in report.json: all null, never a time of 0.
TEST(ValidationJson, AnUnmeasuredClosestApproachIsNullThroughout) {
  scanplan::planner::ValidationReport r;
  r.valid = true;
  r.min_cell_distance = std::numeric_limits<double>::infinity();
  r.min_self_distance = r.min_distance = 0.0253;
  r.min_self_distance_pair = r.min_distance_pair = "link4 - link6";
  r.min_self_distance_t = r.min_distance_t = 1.5;
  const scanplan::cli::Json j = scanplan::cli::validationJson(r);
  EXPECT_TRUE(j["min_cell_distance_mm"].is_null());
  EXPECT_TRUE(j["min_cell_distance_pair"].is_null());
  EXPECT_TRUE(j["min_cell_distance_time_s"].is_null());
  EXPECT_NEAR(j["min_self_distance_mm"].get<double>(), 25.3, 1e-9);
  EXPECT_EQ(j["min_self_distance_pair"], "link4 - link6");
  EXPECT_EQ(j["min_self_distance_time_s"].get<double>(), 1.5);
  EXPECT_EQ(j["min_distance_time_s"].get<double>(), 1.5);
}

}  // namespace
