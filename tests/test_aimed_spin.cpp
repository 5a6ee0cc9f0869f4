// Aimed spins (scanner/scan_passes.h, aimedSpin()): the head holds a witness's pose in the world
// while the table turns. On a square box centred on the table axis, a whole turn sees all four
// side walls alike (the box maps onto itself every 90°), where the straight aimed pass through
// the same witness sees one; a tall block beside the box stops the turn where the housing would
// meet it, and the arc left is not turned by a tour.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "geometry_support.h"
#include "pass_support.h"

#include <scanplan/kinematics/mesh.h>
#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/scanner/area_coverage.h>
#include <scanplan/scanner/laser_model.h>
#include <scanplan/scanner/part_on_table.h>
#include <scanplan/scanner/pass_selection.h>
#include <scanplan/scanner/scan_passes.h>
#include <scanplan/scanner/scannability.h>

namespace {

using Eigen::Isometry3d;
using Eigen::Vector3d;
using scanplan::deg;
using scanplan::kinematics::TriangleMesh;
using scanplan::scanner::PartOnTable;
using scanplan::scanner::PassSettings;
using scanplan::scanner::ScanPass;

constexpr double kPi = std::numbers::pi;
constexpr scanplan::scanner::TableTop kTable = scanplan::test::kDemoTable;

// The demo head, its table turning at up to 0.4 rad/s.
PassSettings demoHead() {
  PassSettings s = scanplan::test::demoHead();
  s.max_spin_rate = 0.4;
  return s;
}

// An axis-aligned box [lo, hi] (m) appended to `m`.
void addBox(TriangleMesh& m, const Vector3d& lo, const Vector3d& hi) {
  const TriangleMesh cube = scanplan::test::centredCube(1.0);
  const auto base = static_cast<int>(m.vertices.size());
  for (const Vector3d& v : cube.vertices)
    m.vertices.push_back(0.5 * (lo + hi) + (hi - lo).cwiseProduct(v));
  for (const Eigen::Vector3i& f : cube.triangles) m.triangles.push_back(f.array() + base);
}

// Looking at the +x wall of an 80 mm box (40 mm tall) from 150 mm, level, moving along +y.
Isometry3d wallWitness() {
  return scanplan::kinematics::frameFromAxes(Vector3d(0.04 + 0.15, 0.0, 0.02),
                                             Vector3d(-1.0, 0.0, 0.0), Vector3d(0.0, 1.0, 0.0));
}

// The fraction of each side wall's samples (outward normal ±x, ±y) a pass covers.
std::vector<double> wallCoverage(const scanplan::scanner::AreaSampling& sampling,
                                 const ScanPass& pass) {
  std::vector<double> covered(4, 0.0), all(4, 0.0);
  std::vector<char> hit(sampling.samples.size(), 0);
  for (std::uint32_t i : pass.covers) hit[i] = 1;
  const Vector3d normals[4] = {Vector3d::UnitX(), Vector3d::UnitY(), -Vector3d::UnitX(),
                               -Vector3d::UnitY()};
  for (std::size_t i = 0; i < sampling.samples.size(); ++i)
    for (std::size_t w = 0; w < 4; ++w)
      if (sampling.samples[i].n.dot(normals[w]) > 0.99 && sampling.samples[i].p.z() < 0.04) {
        all[w] += 1.0;
        covered[w] += hit[i];
      }
  for (std::size_t w = 0; w < 4; ++w) covered[w] /= std::max(1.0, all[w]);
  return covered;
}

TEST(AimedSpin, AWholeTurnSeesEverySideOfABoxOnTheAxisWhereTheStripSeesOne) {
  TriangleMesh mesh;
  addBox(mesh, Vector3d(-0.04, -0.04, 0.0), Vector3d(0.04, 0.04, 0.04));
  const PartOnTable scene(mesh, Isometry3d::Identity(), kTable);
  const PassSettings settings = demoHead();
  const auto sampling = scanplan::scanner::sampleArea(scene.part(), 0.002);
  const scanplan::scanner::SampleIndex index(sampling);

  ScanPass spin = scanplan::scanner::aimedSpin(scene, settings, wallWitness());
  ASSERT_EQ(spin.X_RS.size(), 181u);  // 2° stations, the last closing the turn
  EXPECT_TRUE(spin.turnable());
  EXPECT_NEAR(spin.azimuth.back() - spin.azimuth.front(), 2.0 * kPi, 1e-12);
  for (std::size_t k = 0; k < spin.X_RS.size(); ++k) {
    // The head holds the witness in the world: turned back by its azimuth, every key is it.
    const Isometry3d world = Eigen::AngleAxisd(-spin.azimuth[k], Vector3d::UnitZ()) * spin.X_RS[k];
    EXPECT_LT((world.matrix() - wallWitness().matrix()).norm(), 1e-12) << k;
  }
  scanplan::scanner::evaluatePass(spin, scene, settings, index);
  ScanPass strip = scanplan::scanner::aimedPass(scene, settings, wallWitness());
  scanplan::scanner::evaluatePass(strip, scene, settings, index);

  const std::vector<double> by_spin = wallCoverage(sampling, spin);
  const std::vector<double> by_strip = wallCoverage(sampling, strip);
  // Alike on all four walls, where the strip sees its own wall only.
  const auto [least, most] = std::minmax_element(by_spin.begin(), by_spin.end());
  EXPECT_GT(*least, 0.6);
  EXPECT_LT(*most - *least, 0.05);
  EXPECT_GT(by_strip[0], 0.5);
  for (std::size_t w = 1; w < 4; ++w) EXPECT_LT(by_strip[w], 0.05) << "wall " << w;
  // Timed by the table: a turn takes at least 2π / max_spin_rate.
  EXPECT_GE(spin.duration(), 2.0 * kPi / settings.max_spin_rate - 1e-9);
}

TEST(AimedSpin, ABlockBesideTheBoxStopsTheTurnWhereTheHousingWouldMeetIt) {
  TriangleMesh mesh;
  addBox(mesh, Vector3d(-0.04, -0.04, 0.0), Vector3d(0.04, 0.04, 0.04));
  // A tall block at azimuth 180°, where the head would stand after half a turn.
  addBox(mesh, Vector3d(-0.22, -0.02, 0.0), Vector3d(-0.16, 0.02, 0.12));
  const PartOnTable scene(mesh, Isometry3d::Identity(), kTable);
  PassSettings settings = demoHead();
  // The head's body: a box around the laser origin, 60 mm along x_S, 30 mm along the line
  // (vertical here, clear of the table top), from 80 mm behind the origin to 20 mm before it.
  settings.housing = {
      Eigen::AlignedBox3d(Vector3d(-0.03, -0.015, -0.08), Vector3d(0.03, 0.015, 0.02))};
  const scanplan::scanner::HousingCheck housing(scene, settings.housing, settings.housing_spacing);
  ASSERT_TRUE(housing.fits(wallWitness()));
  const Isometry3d half_turn(Eigen::AngleAxisd(kPi, Vector3d::UnitZ()));
  ASSERT_FALSE(housing.fits(half_turn * wallWitness()));

  const ScanPass arc = scanplan::scanner::aimedSpin(scene, settings, wallWitness());
  ASSERT_GE(arc.X_RS.size(), 2u);
  EXPECT_FALSE(arc.turnable());
  // The witness is inside the arc, every key fits, and one station beyond either end does not.
  EXPECT_LE(arc.azimuth.front(), 0.0);
  EXPECT_GE(arc.azimuth.back(), 0.0);
  EXPECT_LT(arc.azimuth.back() - arc.azimuth.front(), 2.0 * kPi);
  for (const Isometry3d& X : arc.X_RS) EXPECT_TRUE(housing.fits(X));
  for (const double beyond : {arc.azimuth.front() - deg(2.0), arc.azimuth.back() + deg(2.0)})
    EXPECT_FALSE(
        housing.fits(Isometry3d(Eigen::AngleAxisd(beyond, Vector3d::UnitZ())) * wallWitness()));
  // A tour never turns it to start elsewhere (that would scan something else).
  std::vector<ScanPass> passes{arc};
  const ScanPass step = scanplan::scanner::stepPass(passes, {0, false, 1.0});
  for (std::size_t k = 0; k < arc.X_RS.size(); ++k)
    EXPECT_LT((step.X_RS[k].matrix() - arc.X_RS[k].matrix()).norm(), 1e-15);

  // At most max_arc, still around the witness.
  const ScanPass quarter =
      scanplan::scanner::aimedSpin(scene, settings, wallWitness(), 0.35, kPi / 2);
  EXPECT_LE(quarter.azimuth.back() - quarter.azimuth.front(), kPi / 2 + 1e-12);
  EXPECT_LE(quarter.azimuth.front(), 0.0);
  EXPECT_GE(quarter.azimuth.back(), 0.0);
}

TEST(AimedSpin, NoneWithoutATableThatTurns) {
  TriangleMesh mesh;
  addBox(mesh, Vector3d(-0.04, -0.04, 0.0), Vector3d(0.04, 0.04, 0.04));
  const PartOnTable scene(mesh, Isometry3d::Identity(), kTable);
  PassSettings settings = demoHead();
  settings.max_spin_rate = 0.0;
  EXPECT_TRUE(scanplan::scanner::aimedSpin(scene, settings, wallWitness()).X_RS.empty());
}

}  // namespace
