// The clouds in the tools their users open them with: CloudCompare's command line, MeshLab's
// server mode, Open3D (both readers) and PCL each load cloud.ply, uncovered.ply and coverage.ply
// written by scanner/cloud_io.h, and keep the per-point fields docs/outputs.md says they keep, with
// the written values. Each test skips where its tool is not installed (Debian: cloudcompare,
// meshlab with xvfb, python3-open3d, pcl-tools; ./bootstrap.sh installs them).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <scanplan/kinematics/units.h>
#include <scanplan/scanner/cloud_io.h>
#include <scanplan/scanner/coverage.h>
#include "tests/io_support.h"
#include "tests/test_support.h"

namespace {

namespace fs = std::filesystem;
using namespace scanplan;
using scanner::CloudPoint;

bool installed(const std::string& command) {
  return !test::runCommand("command -v " + command + " 2>/dev/null").empty();
}

// Four points with distinct values in every field (one on another body).
std::vector<CloudPoint> somePoints() {
  std::vector<CloudPoint> points(4);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double k = static_cast<double>(i);
    points[i].p_P = Eigen::Vector3d(0.001 * k, -0.002 * k, 0.003 + k * 1e-4);
    points[i].n_P = Eigen::Vector3d(0.0, 0.6, 0.8);
    points[i].t = 0.5 + k;
    points[i].profile = static_cast<std::uint32_t>(10 + i);
    points[i].ray = static_cast<std::uint32_t>(100 + i);
    points[i].range = 0.15 + 0.001 * k;
    points[i].incidence = deg(10.0 * k);
    points[i].part_triangle = i == 3 ? -1 : static_cast<std::int32_t>(7 * i);
  }
  return points;
}

// The written value of each cloud field for point i, as the viewers name them.
std::map<std::string, double> fieldsOf(const CloudPoint& p) {
  return {{"time", p.t},
          {"profile", static_cast<double>(p.profile)},
          {"ray", static_cast<double>(p.ray)},
          {"range_mm", 1000.0 * p.range},
          {"incidence_deg", toDeg(p.incidence)},
          {"part_triangle", static_cast<double>(p.part_triangle)}};
}

class CloudReaders : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("scanplan_readers_" + std::to_string(getpid()));
    fs::create_directories(dir_);
    points_ = somePoints();
    std::ofstream cloud(dir_ / "cloud.ply", std::ios::binary);
    scanner::writeCloudPly(cloud, points_);
    std::ofstream uncovered(dir_ / "uncovered.ply", std::ios::binary);
    scanner::writeLabelledSamplesPly(
        uncovered, {Eigen::Vector3d(0.01, 0, 0), Eigen::Vector3d(0, 0.01, 0)},
        {Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX()}, {1, 3},
        {"covered", "scannable_not_covered", "faces_table", "occluded"});
    // coverage.ply: two triangles, 4 points on the first (2 mm²), none on the second.
    kinematics::TriangleMesh mesh;
    mesh.vertices = {{0, 0, 0}, {0.002, 0, 0}, {0, 0.002, 0}, {0.002, 0.002, 0.001}};
    mesh.triangles = {{0, 1, 2}, {1, 3, 2}};
    std::vector<CloudPoint> on(4);
    for (CloudPoint& p : on) p.part_triangle = 0;
    std::ofstream coverage(dir_ / "coverage.ply", std::ios::binary);
    scanner::writeCoveragePly(coverage, mesh, scanner::computeCoverage(mesh, on));
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path dir_;
  std::vector<CloudPoint> points_;
};

// CloudCompare's header line "//X Y Z f1 f2 … Nx Ny Nz" and its rows, by column name.
std::map<std::string, std::vector<double>> readAsc(const fs::path& file) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  std::istringstream header(line.substr(line.rfind('/') + 1));
  std::vector<std::string> names;
  for (std::string name; header >> name;) names.push_back(name);
  std::map<std::string, std::vector<double>> columns;
  while (std::getline(in, line)) {
    std::istringstream row(line);
    for (const std::string& name : names) {
      double v = 0.0;
      row >> v;
      columns[name].push_back(v);
    }
  }
  return columns;
}

// CloudCompare, command line: the properties named scalar_… load as scalar fields named without
// the prefix (what the GUI also does), with their values; coverage.ply is a mesh, whose vertices
// CloudCompare extracts as a cloud with the fields.
TEST_F(CloudReaders, CloudCompareLoadsEveryFieldOfEachCloud) {
  if (!installed("CloudCompare")) GTEST_SKIP() << "CloudCompare is not installed";
  for (const char* name : {"cloud", "uncovered", "coverage"}) {
    const fs::path in = dir_ / (std::string(name) + ".ply"),
                   out = dir_ / (std::string(name) + ".txt");
    test::runCommand("cd '" + dir_.string() +
                     "' && QT_QPA_PLATFORM=offscreen timeout 120 CloudCompare -SILENT -AUTO_SAVE "
                     "OFF -O '" +
                     in.string() + "'" +
                     (std::string(name) == "coverage" ? " -EXTRACT_VERTICES" : "") +  // a mesh
                     " -C_EXPORT_FMT ASC -ADD_HEADER -EXT txt -SAVE_CLOUDS FILE '" + out.string() +
                     "' 2>&1");
    ASSERT_TRUE(fs::exists(out)) << name;
    const auto columns = readAsc(out);
    if (std::string(name) == "uncovered") {
      ASSERT_EQ(columns.count("reason"), 1u) << "reason dropped";
      EXPECT_EQ(columns.at("reason"), (std::vector<double>{1.0, 3.0}));
      continue;
    }
    if (std::string(name) == "coverage") {  // per vertex, three per triangle
      ASSERT_EQ(columns.count("points"), 1u) << "points dropped";
      ASSERT_EQ(columns.count("density_per_mm2"), 1u) << "density_per_mm2 dropped";
      EXPECT_EQ(columns.at("points"), (std::vector<double>{4, 4, 4, 0, 0, 0}));
      EXPECT_NEAR(columns.at("density_per_mm2")[0], 2.0, 1e-6);  // 4 points on 2 mm²
      continue;
    }
    for (std::size_t i = 0; i < points_.size(); ++i) {
      for (const auto& [field, value] : fieldsOf(points_[i])) {
        ASSERT_EQ(columns.count(field), 1u) << field << " dropped";
        EXPECT_NEAR(columns.at(field)[i], value, 1e-4 * (1.0 + std::abs(value))) << field;
      }
      EXPECT_NEAR(columns.at("X")[i], 1000.0 * points_[i].p_P.x(), 1e-4);
      EXPECT_NEAR(columns.at("Nz")[i], points_[i].n_P.z(), 1e-2);  // CloudCompare packs normals
    }
  }
}

// MeshLab, server mode (under a virtual display: it needs OpenGL): it keeps one scalar per
// vertex, `quality`, which cloud.ply sets to the incidence and uncovered.ply to the reason.
TEST_F(CloudReaders, MeshLabKeepsTheQualityAndTheNormals) {
  if (!installed("meshlabserver") || !installed("xvfb-run"))
    GTEST_SKIP() << "meshlabserver or xvfb-run is not installed";
  const fs::path out = dir_ / "meshlab.ply";
  const std::string log =
      test::runCommand("cd '" + dir_.string() + "' && timeout 120 xvfb-run -a meshlabserver -i '" +
                       (dir_ / "cloud.ply").string() + "' -o '" + out.string() + "' -m vq vn 2>&1");
  ASSERT_TRUE(fs::exists(out)) << log;
  std::ifstream in(out, std::ios::binary);
  const test::PlyVertices v = test::readPlyVertices(in, out.string());
  ASSERT_EQ(v.count, points_.size());
  for (std::size_t i = 0; i < points_.size(); ++i) {
    EXPECT_NEAR(v.column("quality")[i], toDeg(points_[i].incidence), 1e-4);
    EXPECT_NEAR(v.column("nz")[i], points_[i].n_P.z(), 1e-6);
  }
}

// Open3D: the tensor reader keeps every property with its values; the usual o3d.io reader keeps
// the points and normals only (docs/outputs.md says so and names the tensor reader).
TEST_F(CloudReaders, Open3dTensorReaderKeepsEveryFieldAndTheLegacyOneThePoints) {
  if (!test::runCommand("/usr/bin/python3 -c 'import open3d' 2>/dev/null && echo yes")
           .starts_with("yes")) {
    GTEST_SKIP() << "Open3D is not installed (Debian: python3-open3d)";
  }
  const std::string file = (dir_ / "cloud.ply").string();
  const std::string script =
      "import json, numpy, open3d as o3d\n"
      "pc = o3d.t.io.read_point_cloud('" +
      file +
      "')\n"
      "legacy = o3d.io.read_point_cloud('" +
      file +
      "')\n"
      "d = {k: pc.point[k].numpy().tolist() for k in pc.point}\n"
      "d['legacy_points'] = numpy.asarray(legacy.points).tolist()\n"
      "d['legacy_normals'] = len(legacy.normals)\n"
      "cov = o3d.t.io.read_point_cloud('" +
      (dir_ / "coverage.ply").string() +
      "')\n"
      "d['coverage_points'] = cov.point['scalar_points'].numpy().ravel().tolist()\n"
      "print(json.dumps(d))\n";
  const std::string out = test::runCommand("/usr/bin/python3 -c \"" + script + "\" 2>/dev/null");
  const auto doc = nlohmann::json::parse(out, nullptr, false);
  ASSERT_TRUE(doc.is_object()) << out;
  for (std::size_t i = 0; i < points_.size(); ++i) {
    for (const auto& [field, value] : fieldsOf(points_[i])) {
      const std::string key = "scalar_" + field;
      ASSERT_TRUE(doc.contains(key)) << key << " dropped: " << out;
      EXPECT_NEAR(doc[key][i][0].get<double>(), value, 1e-4 * (1.0 + std::abs(value))) << key;
    }
    EXPECT_NEAR(doc["quality"][i][0].get<double>(), toDeg(points_[i].incidence), 1e-4);
    for (Eigen::Index a = 0; a < 3; ++a) {
      const auto ai = static_cast<std::size_t>(a);
      EXPECT_NEAR(doc["positions"][i][ai].get<double>(), 1000.0 * points_[i].p_P[a], 1e-4);
      EXPECT_NEAR(doc["normals"][i][ai].get<double>(), points_[i].n_P[a], 1e-6);
      EXPECT_NEAR(doc["legacy_points"][i][ai].get<double>(), 1000.0 * points_[i].p_P[a], 1e-4);
    }
  }
  EXPECT_EQ(doc["legacy_normals"].get<std::size_t>(), points_.size());
  ASSERT_TRUE(doc.contains("coverage_points")) << out;  // an int: the tensor reader refuses uint
  EXPECT_EQ(doc["coverage_points"], nlohmann::json({4, 4, 4, 0, 0, 0}));
}

// PCL (pcl_ply2pcd): every property becomes a PCD field, ints as I, floats as F.
TEST_F(CloudReaders, PclKeepsEveryFieldWithItsType) {
  if (!installed("pcl_ply2pcd")) GTEST_SKIP() << "PCL's tools are not installed (pcl-tools)";
  const fs::path out = dir_ / "cloud.pcd";
  const std::string log =
      test::runCommand("timeout 120 pcl_ply2pcd '" + (dir_ / "cloud.ply").string() + "' '" +
                       out.string() + "' 2>&1");
  ASSERT_TRUE(fs::exists(out)) << log;
  std::ifstream in(out, std::ios::binary);
  std::map<std::string, std::vector<std::string>> header;
  for (std::string line; std::getline(in, line) && line.rfind("DATA", 0) != 0;) {
    std::istringstream words(line);
    std::string key;
    words >> key;
    for (std::string w; words >> w;) header[key].push_back(w);
  }
  const std::vector<std::string> want = {"x",
                                         "y",
                                         "z",
                                         "normal_x",
                                         "normal_y",
                                         "normal_z",
                                         "scalar_time",
                                         "scalar_profile",
                                         "scalar_ray",
                                         "scalar_range_mm",
                                         "scalar_incidence_deg",
                                         "scalar_part_triangle",
                                         "quality"};
  EXPECT_EQ(header["FIELDS"], want) << log;
  EXPECT_EQ(header["TYPE"], (std::vector<std::string>{"F", "F", "F", "F", "F", "F", "F", "I", "I",
                                                      "F", "F", "I", "F"}));
  EXPECT_EQ(header["POINTS"], std::vector<std::string>{"4"});
}

}  // namespace
