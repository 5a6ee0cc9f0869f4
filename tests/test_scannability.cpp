// The scannability certificate (scanner/scannability.h) on synthetic parts whose answers follow
// from the geometry: a cube on the table is scannable everywhere but its bottom, the walls deep
// in a narrow hole are occluded, a housing that cannot fit makes lines of sight useless.
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "geometry_support.h"

#include <scanplan/scanner/scannability.h>

namespace {

using Eigen::Vector3d;
using scanplan::kinematics::TriangleMesh;
using scanplan::scanner::AreaSampling;
using scanplan::scanner::classifyScannability;
using scanplan::scanner::PartOnTable;
using scanplan::scanner::sampleArea;
using scanplan::scanner::SampleClass;
using scanplan::scanner::sampleClassName;
using scanplan::scanner::ScannabilitySettings;
using scanplan::scanner::TableTop;

constexpr double kMm = 1e-3;
constexpr TableTop kTable{0.2, 0.15};

// Appends the planar quad p0 p1 p2 p3 (in order around it) as two triangles wound so that their
// normal points along `outward`.
void addQuad(TriangleMesh& m,
             const Vector3d& p0,
             const Vector3d& p1,
             const Vector3d& p2,
             const Vector3d& p3,
             const Vector3d& outward) {
  const int v = static_cast<int>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), {p0, p1, p2, p3});
  if ((p1 - p0).cross(p2 - p0).dot(outward) > 0) {
    m.triangles.emplace_back(v, v + 1, v + 2);
    m.triangles.emplace_back(v, v + 2, v + 3);
  } else {
    m.triangles.emplace_back(v, v + 2, v + 1);
    m.triangles.emplace_back(v, v + 3, v + 2);
  }
}

// The axis-aligned rectangle x0..x1 × y0..y1 at height z, facing up (+1) or down (−1).
void addLevel(TriangleMesh& m, double x0, double x1, double y0, double y1, double z, double up) {
  addQuad(m, {x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}, {0, 0, up});
}

// The wall x = x0 (axis 0) or y = x0 (axis 1) over u0..u1 along the other horizontal axis and
// z0..z1, facing along `outward`.
void addWall(TriangleMesh& m,
             int axis,
             double x0,
             double u0,
             double u1,
             double z0,
             double z1,
             const Vector3d& outward) {
  const auto at = [&](double u, double z) {
    return axis == 0 ? Vector3d(x0, u, z) : Vector3d(u, x0, z);
  };
  addQuad(m, at(u0, z0), at(u1, z0), at(u1, z1), at(u0, z1), outward);
}

// A block `w` square and `h` tall standing on z = 0, centred on the z axis, with a blind square
// hole `hole` wide and `depth` deep sunk from its top along the axis. Closed surface, outward
// winding (the hole's walls face into the hole).
TriangleMesh blockWithHole(double w, double h, double hole, double depth) {
  TriangleMesh m;
  const double o = 0.5 * w, i = 0.5 * hole, floor = h - depth;
  addLevel(m, -o, o, -o, o, 0.0, -1.0);
  addWall(m, 0, o, -o, o, 0.0, h, Vector3d::UnitX());
  addWall(m, 0, -o, -o, o, 0.0, h, -Vector3d::UnitX());
  addWall(m, 1, o, -o, o, 0.0, h, Vector3d::UnitY());
  addWall(m, 1, -o, -o, o, 0.0, h, -Vector3d::UnitY());
  // The top: four strips around the hole's mouth.
  addLevel(m, -o, o, i, o, h, 1.0);
  addLevel(m, -o, o, -o, -i, h, 1.0);
  addLevel(m, i, o, -i, i, h, 1.0);
  addLevel(m, -o, -i, -i, i, h, 1.0);
  // The hole: walls facing its axis, and its floor.
  addWall(m, 0, -i, -i, i, floor, h, Vector3d::UnitX());
  addWall(m, 0, i, -i, i, floor, h, -Vector3d::UnitX());
  addWall(m, 1, -i, -i, i, floor, h, Vector3d::UnitY());
  addWall(m, 1, i, -i, i, floor, h, -Vector3d::UnitY());
  addLevel(m, -i, i, -i, i, floor, 1.0);
  return m;
}

// The demo head (data/jobs/demo_rings.yaml): camera 100 mm beside the laser, depth window
// 107 … 196 mm, housing 170 × 70 × 90 mm around laser and camera.
ScannabilitySettings demoHead() {
  ScannabilitySettings s;
  s.window.z_min = 0.107;
  s.window.z_max = 0.196;
  s.cameras = {Vector3d(0.1, 0.0, 0.0)};
  const Vector3d centre(0.05, 0.0, -0.025), half(0.085, 0.035, 0.045);
  s.housing = {Eigen::AlignedBox3d(centre - half, centre + half)};
  return s;
}

// A cube of edge `a` resting on the table, centred on its axis.
PartOnTable cubeOnTable(double a) {
  return PartOnTable(scanplan::test::centredCube(a),
                     Eigen::Isometry3d(Eigen::Translation3d(0.0, 0.0, 0.5 * a)), kTable);
}

// The table is the cylinder it says, whatever the stack held before: rays straight down beside
// the part land on the top at z = 0 inside the radius and miss outside it; level rays towards
// the axis meet the side at the radius (less the tessellation's chord). The table's pose once
// came from an uninitialised transform, which made plans differ from run to run.
TEST(PartOnTable, TheTableIsACylinderUnderTheTopOnTheAxis) {
  const PartOnTable scene = cubeOnTable(60 * kMm);
  const double r = kTable.radius, h = kTable.height;
  for (int k = 0; k < 24; ++k) {
    const double a = 2.0 * 3.141592653589793 * (k + 0.25) / 24.0;
    const Vector3d u(std::cos(a), std::sin(a), 0.0);
    const auto top = scene.cast(0.9 * r * u + Vector3d(0, 0, 0.5), -Vector3d::UnitZ());
    ASSERT_TRUE(top) << "angle " << a;
    EXPECT_NEAR(top->distance, 0.5, 1e-6);
    EXPECT_GT(top->normal.z(), 0.999);
    EXPECT_FALSE(scene.cast(1.05 * r * u + Vector3d(0, 0, 0.5), -Vector3d::UnitZ()));
    for (const double z : {-0.01 * h, -0.5 * h, -0.99 * h}) {
      const auto side = scene.cast(2.0 * r * u + Vector3d(0, 0, z), -u);
      ASSERT_TRUE(side) << "angle " << a << " z " << z;
      EXPECT_GE(side->distance, r - 1e-6);
      EXPECT_LE(side->distance, r + 1e-4 + 1e-6);  // inscribed within the 0.1 mm chord tolerance
    }
    EXPECT_FALSE(scene.cast(2.0 * r * u + Vector3d(0, 0, -1.01 * h), -u));
  }
}

// Every sample of a 60 mm cube on the table: its bottom lies on the table (facesTable), every
// other face is seen from straight on or, near the table, from above at up to 60°, with the
// camera on the far side of the laser and the housing clear of the table (checked by hand for
// the lowest side samples: laser 60° up, head turned half a turn, the housing's lowest corner
// 45 mm above the top).
TEST(Scannability, ACubeOnTheTableIsScannableExceptItsBottom) {
  const PartOnTable scene = cubeOnTable(60 * kMm);
  const AreaSampling s = sampleArea(scene.part(), 5 * kMm);
  const auto classes = classifyScannability(s, scene, demoHead());
  ASSERT_EQ(classes.size(), s.samples.size());
  std::size_t bottom = 0;
  for (std::size_t k = 0; k < s.samples.size(); ++k) {
    const bool on_bottom = s.samples[k].n.z() < -0.5;
    bottom += on_bottom ? 1 : 0;
    const SampleClass want = on_bottom ? SampleClass::kFacesTable : SampleClass::kScannable;
    ASSERT_EQ(classes[k], want) << "sample " << k << " at " << s.samples[k].p.transpose() << ": "
                                << sampleClassName(classes[k]);
  }
  EXPECT_NEAR(static_cast<double>(bottom), static_cast<double>(s.samples.size()) / 6.0,
              2.0);  // one face of six
}

// A 40 mm block, 80 mm tall, with an 8 mm square hole 60 mm deep. A laser ray from a wall sample
// at depth t within 60° of the wall's normal rises at most tan 60° per unit across the hole, so
// it crosses the 8 mm to the opposite wall before leaving: t > 8 mm · tan 60° ≈ 13.9 mm is
// occluded (tested below 20 mm). On the floor (60 mm down) every ray that leaves the mouth is
// within atan(8√2 / 60) ≈ 11° of the axis, so laser and camera are within 22° of each other,
// while the camera (100 mm beside a laser at most 196 mm away) is at least 27° off the laser.
// The top is seen from straight above.
TEST(Scannability, TheWallsDeepInANarrowHoleAreOccluded) {
  const double h = 80 * kMm;
  const PartOnTable scene(blockWithHole(40 * kMm, h, 8 * kMm, 60 * kMm),
                          Eigen::Isometry3d::Identity(), kTable);
  const AreaSampling s = sampleArea(scene.part(), 3 * kMm);
  const auto classes = classifyScannability(s, scene, demoHead());
  std::size_t deep = 0, floor = 0, top = 0;
  for (std::size_t k = 0; k < s.samples.size(); ++k) {
    const Vector3d& p = s.samples[k].p;
    const Vector3d& n = s.samples[k].n;
    const bool in_hole = p.head<2>().lpNorm<Eigen::Infinity>() <= 4 * kMm + 1e-9;
    SampleClass want;
    if (in_hole && std::abs(n.z()) < 0.5 && p.z() < h - 20 * kMm) {
      want = SampleClass::kOccluded;
      ++deep;
    } else if (in_hole && n.z() > 0.5 && p.z() < h - 59 * kMm) {
      want = SampleClass::kOccluded;
      ++floor;
    } else if (n.z() > 0.5 && p.z() > h - 1e-9) {
      want = SampleClass::kScannable;
      ++top;
    } else {
      continue;
    }
    ASSERT_EQ(classes[k], want) << "sample " << k << " at " << p.transpose() << " n "
                                << n.transpose() << ": " << sampleClassName(classes[k]);
  }
  // 1280 mm² of deep wall, 64 mm² of floor, 1536 mm² of top at 9 mm² per sample.
  EXPECT_GT(deep, 100u);
  EXPECT_GT(floor, 3u);
  EXPECT_GT(top, 120u);
}

// A housing 2 m across around the laser origin holds the whole scene at every pose: its middle
// segment along the laser runs through the sample itself. Every sample that does not face the
// table has lines of sight (the cube case above) but no room: kNoStandoff.
TEST(Scannability, AHousingThatCannotFitLeavesNoStandoff) {
  const PartOnTable scene = cubeOnTable(60 * kMm);
  const AreaSampling s = sampleArea(scene.part(), 10 * kMm);
  ScannabilitySettings head = demoHead();
  head.housing = {Eigen::AlignedBox3d(Vector3d::Constant(-1.0), Vector3d::Constant(1.0))};
  // 20 intervals (0.1 m would risk 21 from rounding): a segment runs along the box's middle.
  head.housing_spacing = 0.101;
  head.directions = 6;  // fewer poses: every one of them is tried, none fits
  head.rolls = 4;
  const auto classes = classifyScannability(s, scene, head);
  for (std::size_t k = 0; k < s.samples.size(); ++k) {
    const SampleClass want =
        s.samples[k].n.z() < -0.5 ? SampleClass::kFacesTable : SampleClass::kNoStandoff;
    ASSERT_EQ(classes[k], want) << "sample " << k << ": " << sampleClassName(classes[k]);
  }
}

// A 6 mm box 20 mm beyond the sample along the laser (one standoff, so always there): for a top
// sample within 7 mm of the axis of the 60 mm cube it lies inside the cube at every laser
// direction (at 60° it moves 17.3 mm sideways and 10 mm down; its corners reach 5.2 mm further),
// where no segment through it crosses a surface: only the inside test finds it. Near the top's
// rim a laser tilted inward puts it outside, beside the cube.
TEST(Scannability, AHousingBoxBuriedInThePartDoesNotFit) {
  const PartOnTable scene = cubeOnTable(60 * kMm);
  const AreaSampling s = sampleArea(scene.part(), 2 * kMm);
  ScannabilitySettings head = demoHead();
  head.standoffs = 1;
  const double beyond = 0.5 * (head.window.z_min + head.window.z_max) + 20 * kMm;
  head.housing = {Eigen::AlignedBox3d(Vector3d(-3 * kMm, -3 * kMm, beyond - 3 * kMm),
                                      Vector3d(3 * kMm, 3 * kMm, beyond + 3 * kMm))};
  const auto classes = classifyScannability(s, scene, head);
  std::size_t centre = 0, rim = 0;
  for (std::size_t k = 0; k < s.samples.size(); ++k) {
    const Vector3d& p = s.samples[k].p;
    if (s.samples[k].n.z() < 0.5) continue;
    const double off_axis = p.head<2>().lpNorm<Eigen::Infinity>();
    if (off_axis < 7 * kMm) {
      EXPECT_EQ(classes[k], SampleClass::kNoStandoff) << p.transpose();
      ++centre;
    } else if (off_axis > 25 * kMm) {
      EXPECT_EQ(classes[k], SampleClass::kScannable) << p.transpose();
      ++rim;
    }
  }
  EXPECT_GT(centre, 30u);  // 196 mm² at 4 mm² per sample
  EXPECT_GT(rim, 200u);
}

// The same 6 mm box 130 mm beyond a top sample of the cube: 65 … 130 mm below the top (laser at
// 60° … 0°), i.e. 5 … 70 mm under the table top, at most 113 mm + 42 mm from the axis: always
// inside the table (radius 200 mm, 150 mm thick), which only the inside test finds.
TEST(Scannability, AHousingBoxBuriedInTheTableDoesNotFit) {
  const PartOnTable scene = cubeOnTable(60 * kMm);
  const AreaSampling s = sampleArea(scene.part(), 10 * kMm);
  ScannabilitySettings head = demoHead();
  head.standoffs = 1;
  const double beyond = 0.5 * (head.window.z_min + head.window.z_max) + 130 * kMm;
  head.housing = {Eigen::AlignedBox3d(Vector3d(-3 * kMm, -3 * kMm, beyond - 3 * kMm),
                                      Vector3d(3 * kMm, 3 * kMm, beyond + 3 * kMm))};
  const auto classes = classifyScannability(s, scene, head);
  std::size_t top = 0;
  for (std::size_t k = 0; k < s.samples.size(); ++k) {
    if (s.samples[k].n.z() < 0.5) continue;
    EXPECT_EQ(classes[k], SampleClass::kNoStandoff) << s.samples[k].p.transpose();
    ++top;
  }
  EXPECT_GT(top, 30u);  // 3600 mm² at 100 mm² per sample
}

// The camera is at least atan(100 mm / 196 mm) ≈ 27° off the laser ray at the sample (it sits
// 100 mm beside the laser origin, at most 196 mm away). With a 10° incidence limit the laser and
// the camera ray cannot both be within 10° of the normal: nothing is seen, though every line of
// sight on a free-standing cube is free.
TEST(Scannability, ACameraBeyondTheIncidenceLimitSeesNothing) {
  const PartOnTable scene = cubeOnTable(60 * kMm);
  const AreaSampling s = sampleArea(scene.part(), 10 * kMm);
  ScannabilitySettings head = demoHead();
  head.max_incidence = 10.0 * 3.141592653589793 / 180.0;
  const auto classes = classifyScannability(s, scene, head);
  for (std::size_t k = 0; k < s.samples.size(); ++k) {
    const SampleClass want =
        s.samples[k].n.z() < -0.5 ? SampleClass::kFacesTable : SampleClass::kOccluded;
    ASSERT_EQ(classes[k], want) << "sample " << k << ": " << sampleClassName(classes[k]);
  }
}

// A roof 45 mm above an upward sample on the axis, low enough that every laser origin and
// camera centre is above it (both at least 107 mm away within 60° of the normal: ≥ 53.5 mm up),
// with square holes (mm, at the roof): A = [−7.5, 7.5]² straight above, B = [22.5, 42.5] ×
// [−7.5, 7.5] toward +x (26.6° … 43.4° off the normal). Through A the laser goes straight up and
// the camera, 100 mm along +x from a laser origin 107 … 196 mm up (27° … 43° off the laser),
// looks through B. Through B alone the laser and the camera would have to share the hole, but B
// spans 22.7° seen from the sample (corner to corner), under the 27° between them: occluded,
// though through B alone a camera still sees the sample.
TEST(Scannability, TheLaserAndACameraEachNeedAFreeLine) {
  const double z = 46 * kMm, far = 0.3, a = 7.5 * kMm, b0 = 22.5 * kMm, b1 = 42.5 * kMm;
  const auto roof = [&](bool hole_above) {
    TriangleMesh m;
    addLevel(m, -far, far, a, far, z, -1.0);
    addLevel(m, -far, far, -far, -a, z, -1.0);
    addLevel(m, -far, hole_above ? -a : b0, -a, a, z, -1.0);
    if (hole_above) addLevel(m, a, b0, -a, a, z, -1.0);
    addLevel(m, b1, far, -a, a, z, -1.0);
    return m;
  };
  AreaSampling one;  // a lone sample just above the table top, facing up
  one.samples.push_back({Vector3d(0.0, 0.0, 1 * kMm), Vector3d::UnitZ(), -1});
  ScannabilitySettings head = demoHead();
  head.housing.clear();  // the head would meet the roof: only lines of sight here
  const auto classify = [&](bool hole_above) {
    const PartOnTable scene(roof(hole_above), Eigen::Isometry3d::Identity(), kTable);
    return classifyScannability(one, scene, head).front();
  };
  EXPECT_EQ(classify(true), SampleClass::kScannable);
  EXPECT_EQ(classify(false), SampleClass::kOccluded);
}

TEST(Scannability, IsDeterministic) {
  const PartOnTable scene(blockWithHole(40 * kMm, 80 * kMm, 8 * kMm, 60 * kMm),
                          Eigen::Isometry3d::Identity(), kTable);
  const AreaSampling s = sampleArea(scene.part(), 4 * kMm);
  const auto a = classifyScannability(s, scene, demoHead());
  const auto b = classifyScannability(s, scene, demoHead());
  EXPECT_EQ(a, b);
}

TEST(Scannability, RejectsBadSettings) {
  const PartOnTable scene = cubeOnTable(60 * kMm);
  const AreaSampling s = sampleArea(scene.part(), 20 * kMm);
  const auto throws = [&](auto change) {
    ScannabilitySettings head = demoHead();
    change(head);
    EXPECT_THROW(classifyScannability(s, scene, head), std::invalid_argument);
  };
  throws([](ScannabilitySettings& h) { h.directions = 0; });
  throws([](ScannabilitySettings& h) { h.rolls = 0; });
  throws([](ScannabilitySettings& h) { h.standoffs = 0; });
  throws([](ScannabilitySettings& h) { h.max_incidence = std::nan(""); });
  throws(
      [](ScannabilitySettings& h) { h.max_incidence = std::numeric_limits<double>::infinity(); });
  throws([](ScannabilitySettings& h) { h.max_incidence = 2.0; });
  throws([](ScannabilitySettings& h) { h.window.z_min = 0.0; });
  throws([](ScannabilitySettings& h) { h.window.z_max = 0.1; });  // below z_min
  throws([](ScannabilitySettings& h) { h.cameras.clear(); });
  throws([](ScannabilitySettings& h) { h.housing.emplace_back(); });  // empty box
  throws([](ScannabilitySettings& h) { h.housing_spacing = 0.0; });
  throws([](ScannabilitySettings& h) { h.housing_spacing = 1e-6; });  // 10¹⁰ segments
}

TEST(Scannability, ClassNames) {
  EXPECT_STREQ(sampleClassName(SampleClass::kScannable), "scannable");
  EXPECT_STREQ(sampleClassName(SampleClass::kFacesTable), "faces_table");
  EXPECT_STREQ(sampleClassName(SampleClass::kOccluded), "occluded");
  EXPECT_STREQ(sampleClassName(SampleClass::kNoStandoff), "no_standoff");
}

}  // namespace
